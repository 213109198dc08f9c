//! The beneath query: takes the placed mesh, per-vertex depth and candidate (boundary)
//! vertices, and gives for each candidate that lies over a lower layer of the same patch that
//! layer's triangle and the candidate's barycentric weights in it. The triangle is the topmost
//! (largest interpolated depth; on equal depth the later one, as the raster draws) of those
//! that strictly contain the candidate's placed point, do not have the candidate as a corner,
//! and whose interpolated depth there is strictly smaller than the candidate's own — the mirror
//! of the raster's coverage query, which looks for a strictly larger depth. Independent of the
//! pixel grid; candidates are answered in the order given, so the answer is deterministic.
//!
//! A uniform grid over the placed triangles' bounding boxes (cells about one triangle's size,
//! each triangle listed in every cell its box touches), rebuilt per call into reusable
//! buffers, lets each candidate test only the triangles of its own cell.

use glam::DVec2;

/// A candidate over a lower layer: the triangle beneath it and its weights there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beneath {
    pub vertex: u32,
    /// The candidate's index in the list given to [`find_beneath`].
    pub slot: u32,
    pub triangle: [u32; 3],
    /// Barycentric weights of the vertex's placed point in `triangle`'s placed corners.
    pub weights: [f64; 3],
}

/// Reusable buffers of the triangles' grid.
#[derive(Default, Debug)]
pub struct TriangleGrid {
    /// Per cell (and one past the last): the first of its triangles in `cell_triangles`.
    cell_start: Vec<u32>,
    cell_triangles: Vec<u32>,
    min: DVec2,
    inverse_cell: f64,
    columns: usize,
    rows: usize,
}

/// Cells per side at most, so the grid stays small for any mesh.
const MAX_CELLS_PER_SIDE: usize = 1024;

impl TriangleGrid {
    /// Buckets the placed triangles by their bounding boxes (two passes: count, then fill).
    fn build(&mut self, placed: &[DVec2], triangles: &[[u32; 3]]) {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in placed {
            (min, max) = (min.min(*p), max.max(*p));
        }
        let extent = (max - min).max(DVec2::splat(1e-9));
        let cell = ((extent.x * extent.y) / triangles.len().max(1) as f64)
            .sqrt()
            .max(extent.max_element() / MAX_CELLS_PER_SIDE as f64)
            .max(1e-9);
        self.min = min;
        self.columns = ((extent.x / cell).ceil() as usize).clamp(1, MAX_CELLS_PER_SIDE);
        self.rows = ((extent.y / cell).ceil() as usize).clamp(1, MAX_CELLS_PER_SIDE);
        self.inverse_cell = 1.0 / (extent.x / self.columns as f64).max(extent.y / self.rows as f64);
        let cells = self.columns * self.rows;
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        for tri in triangles {
            self.for_cells(placed, tri, |grid, cell| grid.cell_start[cell + 1] += 1);
        }
        for i in 0..cells {
            self.cell_start[i + 1] += self.cell_start[i];
        }
        self.cell_triangles.clear();
        self.cell_triangles
            .resize(self.cell_start[cells] as usize, 0);
        // Counting sort as in the coverage query: the start serves as the cursor, then the
        // starts are restored by shifting one cell.
        for (t, tri) in triangles.iter().enumerate() {
            self.for_cells(placed, tri, |grid, cell| {
                let cursor = &mut grid.cell_start[cell];
                grid.cell_triangles[*cursor as usize] = t as u32;
                *cursor += 1;
            });
        }
        self.cell_start.copy_within(0..cells, 1);
        self.cell_start[0] = 0;
    }

    fn for_cells(
        &mut self,
        placed: &[DVec2],
        tri: &[u32; 3],
        mut visit: impl FnMut(&mut Self, usize),
    ) {
        let [a, b, c] = tri.map(|v| placed[v as usize]);
        let ((c0, r0), (c1, r1)) = (self.cell_of(a.min(b).min(c)), self.cell_of(a.max(b).max(c)));
        for r in r0..=r1 {
            for col in c0..=c1 {
                visit(self, r * self.columns + col);
            }
        }
    }

    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.min) * self.inverse_cell;
        let c = (q.x.max(0.0) as usize).min(self.columns - 1);
        let r = (q.y.max(0.0) as usize).min(self.rows - 1);
        (c, r)
    }

    /// The triangles whose boxes touch the cell of `p` (a point of the grid's box).
    fn near(&self, p: DVec2) -> &[u32] {
        let (c, r) = self.cell_of(p);
        let cell = r * self.columns + c;
        &self.cell_triangles[self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize]
    }
}

/// Writes into `out` (cleared first) every candidate `(slot, vertex)` that lies over a lower
/// layer, with the triangle beneath it (see the module doc). The caller checks lengths and
/// indices (the coverage query's validation runs on the same inputs first).
pub fn find_beneath(
    (placed, triangles): (&[DVec2], &[[u32; 3]]),
    depth: &[f32],
    candidates: impl Iterator<Item = (u32, u32)>,
    grid: &mut TriangleGrid,
    out: &mut Vec<Beneath>,
) {
    out.clear();
    if triangles.is_empty() {
        return;
    }
    grid.build(placed, triangles);
    for (slot, vertex) in candidates {
        let p = placed[vertex as usize];
        let own = f64::from(depth[vertex as usize]);
        let mut best: Option<(f64, Beneath)> = None;
        for &t in grid.near(p) {
            let triangle = triangles[t as usize];
            if triangle.contains(&vertex) {
                continue;
            }
            let corners = triangle.map(|i| placed[i as usize]);
            let Some(weights) = weights_if_strictly_inside(corners, p) else {
                continue;
            };
            let d: f64 = (0..3)
                .map(|k| weights[k] * f64::from(depth[triangle[k] as usize]))
                .sum();
            // Triangles come in index order, so `>=` keeps the later one on equal depth.
            if d < own && best.is_none_or(|(top, _)| d >= top) {
                let hit = Beneath {
                    vertex,
                    slot,
                    triangle,
                    weights,
                };
                best = Some((d, hit));
            }
        }
        out.extend(best.map(|(_, hit)| hit));
    }
}

/// Barycentric weights of `p` when it lies strictly inside the (either-oriented) triangle,
/// by the coverage query's predicate (edge functions of the area's strict sign, then the
/// quotients strictly positive).
pub fn weights_if_strictly_inside(corners: [DVec2; 3], p: DVec2) -> Option<[f64; 3]> {
    let [a, b, c] = corners;
    let area = (b - a).perp_dot(c - a);
    let edges = [
        (c - b).perp_dot(p - b),
        (a - c).perp_dot(p - c),
        (b - a).perp_dot(p - a),
    ];
    let same_sign = |e: f64| if area > 0.0 { e > 0.0 } else { e < 0.0 };
    if area == 0.0 || !edges.iter().all(|&e| same_sign(e)) {
        return None;
    }
    let weights = edges.map(|e| e / area);
    weights.iter().all(|&w| w > 0.0).then_some(weights)
}
