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

use super::BitMask;

/// One traced crack loop: only the corners where the direction changes (plus saddle
/// corners), in order; the closing edge is implied.
#[derive(Clone, Debug, PartialEq)]
pub struct CrackLoop {
    pub points: Vec<DVec2>,
    /// `anchor[i]`: points[i] is a saddle corner and must survive simplification.
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
    for y in 0..mask.height as i64 {
        for x in 0..mask.width as i64 {
            if !mask.get(x, y) {
                continue;
            }
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
        }
    }
    loops
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
        // invariant: every corner on a crack loop has as many outgoing as incoming boundary edges.
        let next = next.expect("crack loop continues");
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
pub fn label_pieces(mask: &BitMask) -> (Vec<u32>, Vec<usize>) {
    let (w, h) = (mask.width as i64, mask.height as i64);
    let mut labels = vec![u32::MAX; mask.width * mask.height];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let index = (y * w + x) as usize;
            if !mask.get(x, y) || labels[index] != u32::MAX {
                continue;
            }
            let label = sizes.len() as u32;
            let mut size = 0usize;
            labels[index] = label;
            stack.push((x, y));
            while let Some((px, py)) = stack.pop() {
                size += 1;
                for (dx, dy) in [
                    (-1, -1),
                    (0, -1),
                    (1, -1),
                    (-1, 0),
                    (1, 0),
                    (-1, 1),
                    (0, 1),
                    (1, 1),
                ] {
                    let (qx, qy) = (px + dx, py + dy);
                    if mask.get(qx, qy) && labels[(qy * w + qx) as usize] == u32::MAX {
                        labels[(qy * w + qx) as usize] = label;
                        stack.push((qx, qy));
                    }
                }
            }
            sizes.push(size);
        }
    }
    (labels, sizes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask_from(rows: &[&str]) -> BitMask {
        BitMask::from_fn(rows[0].len(), rows.len(), |x, y| {
            rows[y].as_bytes()[x] == b'#'
        })
    }

    #[test]
    fn single_pixel_is_a_unit_square() {
        let loops = trace_crack_loops(&mask_from(&["#"]));
        assert_eq!(loops.len(), 1);
        let pts: Vec<_> = loops[0].points.iter().map(|p| (p.x, p.y)).collect();
        assert_eq!(pts, vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        assert_eq!(loops[0].doubled_area, 2);
    }

    #[test]
    fn ring_has_outer_and_hole() {
        let loops = trace_crack_loops(&mask_from(&["###", "#.#", "###"]));
        assert_eq!(loops.len(), 2);
        assert_eq!(loops[0].doubled_area, 18);
        assert_eq!(loops[1].doubled_area, -2);
    }

    #[test]
    fn diagonal_pixels_join_into_one_loop_through_the_saddle() {
        let loops = trace_crack_loops(&mask_from(&["#.", ".#"]));
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].doubled_area, 4);
        let saddle = DVec2::new(1.0, 1.0);
        let hits: Vec<bool> = loops[0]
            .points
            .iter()
            .zip(&loops[0].anchor)
            .filter(|(p, _)| **p == saddle)
            .map(|(_, &a)| a)
            .collect();
        assert_eq!(hits, vec![true, true]);
    }

    #[test]
    fn diamond_of_diagonal_pixels_encloses_a_hole() {
        let loops = trace_crack_loops(&mask_from(&[".#.", "#.#", ".#."]));
        let holes = loops.iter().filter(|l| l.is_hole()).count();
        assert_eq!((loops.len(), holes), (2, 1));
        let (_, sizes) = label_pieces(&mask_from(&[".#.", "#.#", ".#."]));
        assert_eq!(sizes, vec![4]);
    }

    #[test]
    fn labels_count_separate_pieces() {
        let (labels, sizes) = label_pieces(&mask_from(&["#..#", "....", "##.."]));
        assert_eq!(sizes, vec![1, 1, 2]);
        assert_eq!(labels[0], 0);
        assert_eq!(labels[3], 1);
        assert_eq!(labels[8], 2);
    }
}
