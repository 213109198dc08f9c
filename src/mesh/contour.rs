//! Crack-boundary tracing: takes a [`BitMask`] and gives its boundary loops along pixel
//! edges (vertices at integer pixel corners), outer loops with positive signed area and hole
//! loops with negative signed area, plus the 8-connected pieces of the mask.
//!
//! Saddle corners (two inside pixels touching only diagonally) are where the tracer has a
//! choice. It always turns *right* there (away from the inside it is following), which
//! joins the two diagonal pixels into one loop: inside is 8-connected, outside 4-connected.
//! The mesh then shares one vertex at that corner, so the pieces of the mesh (vertex
//! connectivity) are exactly the 8-connected pieces of the mask and the Euler
//! characteristic is `pieces − hole loops`. Saddle corners are reported per loop so the
//! simplifier keeps them.
//!
//! Each loop starts at its first corner in raster order (smallest y, then smallest x), and
//! loops come out in raster order of their first edge, so the output is deterministic.

use glam::DVec2;

use super::bitmask::run_end;
use super::BitMask;

/// One traced crack loop: only the corners where the direction changes (plus saddle
/// corners), in order; the closing edge is implied.
#[derive(Clone, Debug, PartialEq)]
pub struct CrackLoop {
    pub points: Vec<DVec2>,
    /// `anchor[i]`: `points[i]` is a saddle corner and must survive simplification.
    pub anchor: Vec<bool>,
    /// Twice the signed area (integer for crack loops): > 0 outer, < 0 hole.
    pub doubled_area: i64,
}

impl CrackLoop {
    pub fn is_hole(&self) -> bool {
        self.doubled_area < 0
    }
}

/// Direction of a directed crack edge; the inside pixel is on its left in raw (x right,
/// y down) coordinates with the math convention, i.e. `left(d) = (-d.y, d.x)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dir {
    East,
    South,
    West,
    North,
}

impl Dir {
    fn step(self) -> (i64, i64) {
        match self {
            Dir::East => (1, 0),
            Dir::South => (0, 1),
            Dir::West => (-1, 0),
            Dir::North => (0, -1),
        }
    }

    fn right(self) -> Dir {
        match self {
            Dir::East => Dir::North,
            Dir::North => Dir::West,
            Dir::West => Dir::South,
            Dir::South => Dir::East,
        }
    }

    fn left(self) -> Dir {
        self.right().right().right()
    }

    /// Pixels to the left (inside) and right (outside) of the edge leaving corner (cx, cy).
    fn sides(self, cx: i64, cy: i64) -> ((i64, i64), (i64, i64)) {
        match self {
            Dir::East => ((cx, cy), (cx, cy - 1)),
            Dir::South => ((cx - 1, cy), (cx, cy)),
            Dir::West => ((cx - 1, cy - 1), (cx - 1, cy)),
            Dir::North => ((cx, cy - 1), (cx - 1, cy - 1)),
        }
    }

    /// Bit of the inside pixel's side this edge runs along.
    fn side_bit(self) -> u8 {
        match self {
            Dir::East => 1,
            Dir::South => 2,
            Dir::West => 4,
            Dir::North => 8,
        }
    }
}

fn is_boundary_edge(mask: &BitMask, cx: i64, cy: i64, dir: Dir) -> bool {
    let ((lx, ly), (rx, ry)) = dir.sides(cx, cy);
    mask.get(lx, ly) && !mask.get(rx, ry)
}

fn is_saddle(mask: &BitMask, cx: i64, cy: i64) -> bool {
    let nw = mask.get(cx - 1, cy - 1);
    let ne = mask.get(cx, cy - 1);
    let sw = mask.get(cx - 1, cy);
    let se = mask.get(cx, cy);
    nw == se && ne == sw && nw != ne
}

/// Traces every crack loop of `mask`.
pub fn trace_crack_loops(mask: &BitMask) -> Vec<CrackLoop> {
    let mut visited = vec![0u8; mask.width * mask.height];
    let mut loops = Vec::new();
    for_each_edge_pixel(mask, |x, y| {
        let (x, y) = (x as i64, y as i64);
        // The four sides of pixel (x, y) as edges with the pixel on their left.
        let starts = [
            (x, y, Dir::East),
            (x + 1, y, Dir::South),
            (x + 1, y + 1, Dir::West),
            (x, y + 1, Dir::North),
        ];
        for (cx, cy, dir) in starts {
            let bit = dir.side_bit();
            if visited[y as usize * mask.width + x as usize] & bit == 0
                && is_boundary_edge(mask, cx, cy, dir)
            {
                loops.push(trace_one(mask, &mut visited, cx, cy, dir));
            }
        }
    });
    loops
}

/// Calls `visit(x, y)` for every inside pixel with a crack edge (an outside 4-neighbour, the
/// image border counting as outside), in raster order. Eight pixels at a time away from the
/// border: interior and outside pixels, nearly all of a mask, cost a few instructions per
/// eight.
pub fn for_each_edge_pixel(mask: &BitMask, mut visit: impl FnMut(usize, usize)) {
    let (w, h) = (mask.width, mask.height);
    let inside = mask.as_slice();
    let bytes = mask.as_bytes();
    let word = |at: usize| {
        // invariant: callers pass `at + 8 ≤ bytes.len()`.
        u64::from_le_bytes(bytes[at..at + 8].try_into().expect("eight bytes"))
    };
    let has_edge = |x: usize, y: usize| {
        let i = y * w + x;
        inside[i]
            && !(y > 0
                && y + 1 < h
                && x > 0
                && x + 1 < w
                && inside[i - w]
                && inside[i + 1]
                && inside[i + w]
                && inside[i - 1])
    };
    for y in 0..h {
        let mut x = 0;
        while x < w {
            // Pixels x..x + 8 with all four neighbours in the image: one word test.
            if y > 0 && y + 1 < h && x > 0 && x + 9 <= w {
                let i = y * w + x;
                let all_neighbours = word(i - 1) & word(i + 1) & word(i - w) & word(i + w);
                let edges = word(i) & !all_neighbours;
                if edges != 0 {
                    for k in 0..8 {
                        if (edges >> (8 * k)) & 1 != 0 {
                            visit(x + k, y);
                        }
                    }
                }
                x += 8;
                continue;
            }
            if has_edge(x, y) {
                visit(x, y);
            }
            x += 1;
        }
    }
}

fn mark_visited(mask: &BitMask, visited: &mut [u8], cx: i64, cy: i64, dir: Dir) {
    let ((lx, ly), _) = dir.sides(cx, cy);
    visited[ly as usize * mask.width + lx as usize] |= dir.side_bit();
}

fn trace_one(
    mask: &BitMask,
    visited: &mut [u8],
    start_x: i64,
    start_y: i64,
    start_dir: Dir,
) -> CrackLoop {
    let (mut cx, mut cy, mut dir) = (start_x, start_y, start_dir);
    let mut corners: Vec<(i64, i64, bool)> = Vec::new();
    let mut doubled_area = 0i64;
    loop {
        mark_visited(mask, visited, cx, cy, dir);
        let (dx, dy) = dir.step();
        let (nx, ny) = (cx + dx, cy + dy);
        doubled_area += cx * ny - nx * cy;
        cx = nx;
        cy = ny;
        let next = [dir.right(), dir, dir.left()]
            .into_iter()
            .find(|&d| is_boundary_edge(mask, cx, cy, d));
        let next = next.expect("crack loop continues"); // invariant: every corner on a crack loop has as many outgoing as incoming boundary edges.
        let saddle = is_saddle(mask, cx, cy);
        if next != dir || saddle {
            corners.push((cx, cy, saddle));
        }
        dir = next;
        if (cx, cy, dir) == (start_x, start_y, start_dir) {
            break;
        }
    }
    let first = corners
        .iter()
        .enumerate()
        .min_by_key(|(_, &(x, y, _))| (y, x))
        .map(|(i, _)| i)
        .unwrap_or(0);
    corners.rotate_left(first);
    CrackLoop {
        points: corners
            .iter()
            .map(|&(x, y, _)| DVec2::new(x as f64, y as f64))
            .collect(),
        anchor: corners.iter().map(|&(_, _, s)| s).collect(),
        doubled_area,
    }
}

/// 8-connected pieces of the mask: a label per pixel (`u32::MAX` outside) and each
/// piece's pixel count, labels in raster order of each piece's first pixel.
///
/// Works on runs of inside pixels: a union–find joins each run with the runs of the row
/// above that touch it (diagonals included); the root of a piece is its first run in
/// raster order, which gives the label order.
pub fn label_pieces(mask: &BitMask) -> (Vec<u32>, Vec<usize>) {
    let pieces = RunPieces::of(mask);
    let mut labels = vec![u32::MAX; mask.width * mask.height];
    for (run, &label) in pieces.runs.iter().zip(&pieces.label) {
        labels[run.y * mask.width + run.x0..run.y * mask.width + run.x1].fill(label);
    }
    (labels, pieces.sizes)
}

/// The pixel counts of [`label_pieces`], without the per-pixel labels.
pub(crate) fn piece_sizes(mask: &BitMask) -> Vec<usize> {
    RunPieces::of(mask).sizes
}

/// A mask's runs of inside pixels with the piece label of each, and each piece's size.
struct RunPieces {
    runs: Vec<Run>,
    label: Vec<u32>,
    sizes: Vec<usize>,
}

impl RunPieces {
    fn of(mask: &BitMask) -> RunPieces {
        let (runs, row_start) = inside_runs(mask);
        let mut parent: Vec<u32> = (0..runs.len() as u32).collect();
        for y in 1..mask.height {
            let above = row_start[y - 1]..row_start[y];
            let mut first_candidate = above.start;
            for current in row_start[y]..row_start[y + 1] {
                let (x0, x1) = (runs[current].x0, runs[current].x1);
                while first_candidate < above.end && runs[first_candidate].x1 < x0 {
                    first_candidate += 1;
                }
                let mut other = first_candidate;
                while other < above.end && runs[other].x0 <= x1 {
                    union(&mut parent, current as u32, other as u32);
                    other += 1;
                }
            }
        }
        let mut label_of_root = vec![u32::MAX; runs.len()];
        let mut label = Vec::with_capacity(runs.len());
        let mut sizes = Vec::new();
        for (index, run) in runs.iter().enumerate() {
            let root = find(&mut parent, index as u32) as usize;
            if label_of_root[root] == u32::MAX {
                label_of_root[root] = sizes.len() as u32;
                sizes.push(0);
            }
            label.push(label_of_root[root]);
            sizes[label_of_root[root] as usize] += run.x1 - run.x0;
        }
        RunPieces { runs, label, sizes }
    }
}

/// A maximal horizontal run of inside pixels: row `y`, columns `x0..x1`.
struct Run {
    y: usize,
    x0: usize,
    x1: usize,
}

/// Runs in raster order, and `row_start[y]..row_start[y + 1]`, the runs of row `y`.
fn inside_runs(mask: &BitMask) -> (Vec<Run>, Vec<usize>) {
    let mut runs = Vec::new();
    let mut row_start = Vec::with_capacity(mask.height + 1);
    for y in 0..mask.height {
        row_start.push(runs.len());
        let row = mask.row_bytes(y);
        let mut x = run_end(row, 0, 0);
        while x < row.len() {
            let x1 = run_end(row, x, 1);
            runs.push(Run { y, x0: x, x1 });
            x = run_end(row, x1, 0);
        }
    }
    row_start.push(runs.len());
    (runs, row_start)
}

fn find(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        parent[v as usize] = parent[parent[v as usize] as usize];
        v = parent[v as usize];
    }
    v
}

/// Joins two sets, keeping the smaller index as the root.
fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}
