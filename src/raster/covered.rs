//! The layer queries: take the placed mesh, per-vertex depth and candidate (boundary)
//! vertices, and give those lying under the patch's own front layer (*covered*: strictly
//! inside a placed triangle that does not contain the vertex — strictly inside its bounding
//! box, and all three edge functions of the triangle's sign — whose interpolated depth there
//! is strictly greater than the vertex's own) and, for each candidate not covered that lies
//! over a lower layer, that layer's triangle and the candidate's barycentric weights in it
//! (*beneath*: the topmost — largest interpolated depth, on equal depth the later triangle,
//! as the raster draws — of the triangles under the same rule whose depth there is strictly
//! smaller). Independent of the pixel grid; candidates are reported in the order given, so the
//! answer is deterministic.
//!
//! A uniform grid over the candidates ([`PointGrid`]) lets each triangle look only at the
//! candidates near it: a few slice look-ups plus a box test per nearby candidate. The candidates
//! are about a fifth of the vertices and sit along the boundary, so this visits far fewer
//! (candidate, triangle) pairs than a grid over the triangles queried per candidate, and a
//! candidate found covered is not tested again. Both answers come from one sweep: they test
//! the same pairs and differ only in the depth comparison. The predicate of each pair is
//! unchanged, so the answer is too.

use glam::DVec2;

use super::point_grid::PointGrid;
use super::RasterError;

/// A candidate over a lower layer: the triangle beneath it and its weights there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beneath {
    pub vertex: u32,
    /// The candidate's slot: its index in the candidates given to [`boundary_layers`].
    pub slot: u32,
    pub triangle: [u32; 3],
    /// Barycentric weights of the vertex's placed point in `triangle`'s placed corners.
    pub weights: [f64; 3],
}

/// Reusable buffers of the candidates' grid.
#[derive(Default, Debug)]
pub struct CoverageGrid {
    grid: PointGrid,
    /// Per slot: found covered.
    covered: Vec<bool>,
    /// Per slot: the topmost lower triangle so far and its depth there.
    lower: Vec<Option<(f64, Beneath)>>,
}

impl CoverageGrid {
    pub fn new() -> CoverageGrid {
        CoverageGrid::default()
    }

    /// Empties the per-slot answers for `candidates` and, unless there is nothing to sweep,
    /// buckets their placed positions (the grid covers their bounding box).
    fn build(&mut self, placed: &[DVec2], candidates: &[u32], sweeping: bool) {
        if sweeping {
            self.grid
                .build(candidates.iter().map(|&v| placed[v as usize]));
        }
        self.covered.clear();
        self.covered.resize(candidates.len(), false);
        self.lower.clear();
        self.lower.resize(candidates.len(), None);
    }

    /// Marks the candidates that triangle `tri` covers and offers it as the layer beneath
    /// the others (see the module doc).
    fn sweep_triangle(&mut self, query: &Query, tri: [u32; 3]) {
        let corners = tri.map(|i| query.placed[i as usize]);
        let [a, b, c] = corners;
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        let depth = tri.map(|i| query.depth[i as usize]);
        let (covered, lower) = (&mut self.covered, &mut self.lower);
        self.grid.near_box(min, max, |slot| {
            if covered[slot] {
                return;
            }
            let v = query.candidates[slot];
            let p = query.placed[v as usize];
            let in_box = p.x > min.x && p.y > min.y && p.x < max.x && p.y < max.y;
            if !in_box || tri.contains(&v) {
                return;
            }
            let Some(weights) = weights_if_strictly_inside(corners, p) else {
                return;
            };
            let [wa, wb, wc] = weights;
            let d = wa * f64::from(depth[0]) + wb * f64::from(depth[1]) + wc * f64::from(depth[2]);
            let own = f64::from(query.depth[v as usize]);
            if d > own {
                covered[slot] = true;
            } else if d < own {
                // Triangles come in index order, so `>=` keeps the later one on equal depth.
                if lower[slot].is_none_or(|(top, _)| d >= top) {
                    let slot32 = slot as u32;
                    let hit = Beneath { vertex: v, slot: slot32, triangle: tri, weights };
                    lower[slot] = Some((d, hit));
                }
            }
        });
    }
}

/// What the sweep reads.
struct Query<'a> {
    placed: &'a [DVec2],
    depth: &'a [f32],
    candidates: &'a [u32],
}

/// Writes into `out` (cleared first) the candidates covered by the patch's front layer:
/// [`boundary_layers`]' first answer alone.
pub fn covered_boundary_vertices(
    placed: &[DVec2],
    triangles: &[[u32; 3]],
    depth: &[f32],
    candidates: &[u32],
    grid: &mut CoverageGrid,
    out: &mut Vec<u32>,
) -> Result<(), RasterError> {
    let geometry = (placed, triangles, depth);
    boundary_layers(geometry, candidates, grid, out, &mut Vec::new())
}

/// Writes into `covered` (cleared first) the candidates covered by the patch's front layer,
/// and into `beneath` (cleared first) every other candidate that lies over a lower layer,
/// with the triangle beneath it, in the candidates' order: both answers of the module doc
/// from one sweep.
pub fn boundary_layers(
    (placed, triangles, depth): (&[DVec2], &[[u32; 3]], &[f32]),
    candidates: &[u32],
    grid: &mut CoverageGrid,
    covered: &mut Vec<u32>,
    beneath: &mut Vec<Beneath>,
) -> Result<(), RasterError> {
    sweep((placed, triangles, depth), candidates, grid)?;
    covered.clear();
    let hits = candidates.iter().zip(&grid.covered);
    covered.extend(hits.filter(|(_, &hit)| hit).map(|(&v, _)| v));
    beneath.clear();
    let lower = grid.lower.iter().zip(&grid.covered);
    beneath.extend(lower.filter(|(_, &hit)| !hit).filter_map(|(found, _)| found.map(|(_, b)| b)));
    Ok(())
}

/// Validates the input and runs every triangle past the candidates' grid.
fn sweep(
    (placed, triangles, depth): (&[DVec2], &[[u32; 3]], &[f32]),
    candidates: &[u32],
    grid: &mut CoverageGrid,
) -> Result<(), RasterError> {
    validate(placed, triangles, depth, candidates)?;
    let sweeping = !(triangles.is_empty() || candidates.is_empty());
    grid.build(placed, candidates, sweeping);
    if !sweeping {
        return Ok(());
    }
    let query = Query {
        placed,
        depth,
        candidates,
    };
    for &tri in triangles {
        grid.sweep_triangle(&query, tri);
    }
    Ok(())
}

/// Barycentric weights of `p` when it lies strictly inside the (either-oriented) triangle:
/// the rule of the coverage query and of the clone's beneath query alike.
///
/// Most triangles near a vertex do not contain it, so the three edge functions are tested
/// against the area's sign first, without dividing: `e / area > 0` needs `e` and `area` of
/// the same strict sign. Only then are the weights formed and tested (a quotient can still
/// underflow to 0), so the answer is the same as testing the weights alone (tests compare
/// with a brute force).
#[inline]
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

fn validate(
    placed: &[DVec2],
    triangles: &[[u32; 3]],
    depth: &[f32],
    candidates: &[u32],
) -> Result<(), RasterError> {
    let n = placed.len();
    if depth.len() != n {
        return Err(RasterError::LengthMismatch {
            what: "depth",
            expected: n,
            actual: depth.len(),
        });
    }
    if let Some(index) = placed.iter().position(|p| !p.is_finite()) {
        return Err(RasterError::NonFinite {
            what: "placed",
            index,
        });
    }
    if let Some(index) = depth.iter().position(|d| !d.is_finite()) {
        return Err(RasterError::NonFinite {
            what: "depth",
            index,
        });
    }
    for (triangle, tri) in triangles.iter().enumerate() {
        if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= n) {
            return Err(RasterError::TriangleIndex {
                triangle,
                vertex,
                vertex_count: n,
            });
        }
    }
    if let Some(&vertex) = candidates.iter().find(|&&v| v as usize >= n) {
        return Err(RasterError::CandidateIndex {
            vertex,
            vertex_count: n,
        });
    }
    Ok(())
}
