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

use crate::raster::{weights_if_strictly_inside, PointGrid};

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
    grid: PointGrid,
    candidates: Vec<(u32, u32)>,
    /// Per candidate: the topmost lower triangle so far and its depth there.
    best: Vec<Option<(f64, Beneath)>>,
}

impl CandidateGrid {
    /// Buckets the candidates' placed positions (the grid covers their bounding box).
    fn build(&mut self, placed: &[DVec2]) {
        self.grid
            .build(self.candidates.iter().map(|&(_, v)| placed[v as usize]));
        self.best.clear();
        self.best.resize(self.candidates.len(), None);
    }

    /// Offers triangle `triangle` to the candidates strictly inside its box.
    fn sweep_triangle(&mut self, (placed, depth): (&[DVec2], &[f32]), triangle: [u32; 3]) {
        let corners = triangle.map(|i| placed[i as usize]);
        let [a, b, c] = corners;
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        let (candidates, best) = (&self.candidates, &mut self.best);
        self.grid.near_box(min, max, |k| {
            let (slot, vertex) = candidates[k];
            let p = placed[vertex as usize];
            let in_box = p.x > min.x && p.y > min.y && p.x < max.x && p.y < max.y;
            if !in_box || triangle.contains(&vertex) {
                return;
            }
            let Some(weights) = weights_if_strictly_inside(corners, p) else {
                return;
            };
            let d: f64 = (0..3)
                .map(|j| weights[j] * f64::from(depth[triangle[j] as usize]))
                .sum();
            // Triangles come in index order, so `>=` keeps the later one on equal depth.
            let lower = d < f64::from(depth[vertex as usize]);
            if lower && best[k].is_none_or(|(top, _)| d >= top) {
                let hit = Beneath {
                    vertex,
                    slot,
                    triangle,
                    weights,
                };
                best[k] = Some((d, hit));
            }
        });
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
