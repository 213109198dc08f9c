//! The beneath query: takes the placed mesh, per-vertex depth and candidate (boundary)
//! vertices, and gives for each candidate that lies over a lower layer of the same patch that
//! layer's triangle and the candidate's barycentric weights in it. The triangle is the topmost
//! (largest interpolated depth; on equal depth the later one, as the raster draws) of those
//! that strictly contain the candidate's placed point, do not have the candidate as a corner,
//! and whose interpolated depth there is strictly smaller than the candidate's own — the mirror
//! of the raster's coverage query, which looks for a strictly larger depth. Independent of the
//! pixel grid; candidates are answered in the order given, so the answer is deterministic.
//!
//! As in the coverage query, a uniform grid over the candidates (rebuilt per call into
//! reusable buffers, about four cells per candidate) lets each triangle look only at the
//! candidates near it: the candidates lie along the boundary, so most triangles meet only
//! empty cells and cost a box and a few slice look-ups.

use glam::DVec2;

/// A candidate over a lower layer: the triangle beneath it and its weights there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beneath {
    pub vertex: u32,
    /// The candidate's slot: the number given with it to [`find_beneath`].
    pub slot: u32,
    pub triangle: [u32; 3],
    /// Barycentric weights of the vertex's placed point in `triangle`'s placed corners.
    pub weights: [f64; 3],
}

/// Reusable buffers of the candidates' grid and the best triangle found for each.
#[derive(Default, Debug)]
pub struct CandidateGrid {
    /// Per cell (and one past the last): the first of its candidates in `cell_candidates`.
    cell_start: Vec<u32>,
    /// Indices into `candidates`, grouped by cell.
    cell_candidates: Vec<u32>,
    cell_of_candidate: Vec<u32>,
    candidates: Vec<(u32, u32)>,
    /// Per candidate: the topmost lower triangle so far and its depth there.
    best: Vec<Option<(f64, Beneath)>>,
    min: DVec2,
    max: DVec2,
    inverse_cell: f64,
    columns: usize,
    rows: usize,
}

impl CandidateGrid {
    /// Buckets the candidates' placed positions (the grid covers their bounding box).
    fn build(&mut self, placed: &[DVec2]) {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &(_, v) in &self.candidates {
            let p = placed[v as usize];
            (min, max) = (min.min(p), max.max(p));
        }
        (self.min, self.max) = (min, max);
        let extent = (max - min).max(DVec2::splat(1e-9));
        // The coverage query's sizing: about four cells per candidate, and a flat box kept
        // at about 4n cells per side.
        let slots = 4.0 * self.candidates.len() as f64;
        let cell = ((extent.x * extent.y) / slots)
            .sqrt()
            .max(extent.max_element() / slots)
            .max(1e-9);
        self.columns = ((extent.x / cell).ceil() as usize).clamp(1, 4096);
        self.rows = ((extent.y / cell).ceil() as usize).clamp(1, 4096);
        self.inverse_cell = 1.0 / (extent.x / self.columns as f64).max(extent.y / self.rows as f64);
        let cells = self.columns * self.rows;
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        self.cell_of_candidate.clear();
        for k in 0..self.candidates.len() {
            let (c, r) = self.cell_of(placed[self.candidates[k].1 as usize]);
            // At most 4096² cells, so the index fits u32.
            let cell = (r * self.columns + c) as u32;
            self.cell_of_candidate.push(cell);
            self.cell_start[cell as usize + 1] += 1;
        }
        for i in 0..cells {
            self.cell_start[i + 1] += self.cell_start[i];
        }
        // Counting sort: the start serves as the cursor, then shifting one cell restores it.
        self.cell_candidates.clear();
        self.cell_candidates.resize(self.candidates.len(), 0);
        for (k, &cell) in self.cell_of_candidate.iter().enumerate() {
            let cursor = &mut self.cell_start[cell as usize];
            self.cell_candidates[*cursor as usize] = k as u32;
            *cursor += 1;
        }
        self.cell_start.copy_within(0..cells, 1);
        self.cell_start[0] = 0;
        self.best.clear();
        self.best.resize(self.candidates.len(), None);
    }

    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.min) * self.inverse_cell;
        let c = (q.x.max(0.0) as usize).min(self.columns - 1);
        let r = (q.y.max(0.0) as usize).min(self.rows - 1);
        (c, r)
    }

    /// Offers triangle `triangle` to the candidates strictly inside its box.
    fn sweep_triangle(&mut self, (placed, depth): (&[DVec2], &[f32]), triangle: [u32; 3]) {
        let corners = triangle.map(|i| placed[i as usize]);
        let [a, b, c] = corners;
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        if !(max.x > self.min.x && max.y > self.min.y && min.x < self.max.x && min.y < self.max.y) {
            return;
        }
        let ((c0, r0), (c1, r1)) = (self.cell_of(min), self.cell_of(max));
        for r in r0..=r1 {
            let row = r * self.columns;
            let range = self.cell_start[row + c0] as usize..self.cell_start[row + c1 + 1] as usize;
            for i in range {
                let k = self.cell_candidates[i] as usize;
                let (slot, vertex) = self.candidates[k];
                let p = placed[vertex as usize];
                let in_box = p.x > min.x && p.y > min.y && p.x < max.x && p.y < max.y;
                if !in_box || triangle.contains(&vertex) {
                    continue;
                }
                let Some(weights) = weights_if_strictly_inside(corners, p) else {
                    continue;
                };
                let d: f64 = (0..3)
                    .map(|j| weights[j] * f64::from(depth[triangle[j] as usize]))
                    .sum();
                // Triangles come in index order, so `>=` keeps the later one on equal depth.
                let lower = d < f64::from(depth[vertex as usize]);
                if lower && self.best[k].is_none_or(|(top, _)| d >= top) {
                    let hit = Beneath {
                        vertex,
                        slot,
                        triangle,
                        weights,
                    };
                    self.best[k] = Some((d, hit));
                }
            }
        }
    }
}

/// Writes into `out` (cleared first) every candidate `(slot, vertex)` that lies over a lower
/// layer, with the triangle beneath it (see the module doc), in the candidates' order. The
/// caller checks lengths and indices (the coverage query validates the same inputs first).
pub fn find_beneath(
    (placed, triangles): (&[DVec2], &[[u32; 3]]),
    depth: &[f32],
    candidates: impl Iterator<Item = (u32, u32)>,
    grid: &mut CandidateGrid,
    out: &mut Vec<Beneath>,
) {
    out.clear();
    grid.candidates.clear();
    grid.candidates.extend(candidates);
    if triangles.is_empty() || grid.candidates.is_empty() {
        return;
    }
    grid.build(placed);
    for &triangle in triangles {
        grid.sweep_triangle((placed, depth), triangle);
    }
    out.extend(grid.best.iter().flatten().map(|&(_, hit)| hit));
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
