//! The coverage query: takes the placed mesh, per-vertex depth and candidate (boundary)
//! vertices and gives those lying under the patch's own front layer — strictly inside a
//! placed triangle that does not contain the vertex (strictly inside its bounding box, and
//! all three edge functions of the triangle's sign), whose interpolated depth there is
//! strictly greater than the vertex's own. Independent of the pixel grid; candidates are
//! reported in the order given, so the answer is deterministic.
//!
//! A uniform grid over the candidates ([`PointGrid`]) lets each triangle look only at the
//! candidates near it: a few slice look-ups plus a box test per nearby candidate. The candidates
//! are about a fifth of the vertices and sit along the boundary, so this visits far fewer
//! (candidate, triangle) pairs than a grid over the triangles queried per candidate, and a
//! candidate found covered is not tested again. The predicate of each pair is unchanged, so
//! the answer is too.

use glam::DVec2;

use super::point_grid::PointGrid;
use super::RasterError;

/// Reusable buffers of the candidates' grid.
#[derive(Default, Debug)]
pub struct CoverageGrid {
    grid: PointGrid,
    /// Per slot: found covered.
    covered: Vec<bool>,
}

impl CoverageGrid {
    pub fn new() -> CoverageGrid {
        CoverageGrid::default()
    }

    /// Buckets the candidates' placed positions (the grid covers their bounding box).
    fn build(&mut self, placed: &[DVec2], candidates: &[u32]) {
        self.grid
            .build(candidates.iter().map(|&v| placed[v as usize]));
        self.covered.clear();
        self.covered.resize(candidates.len(), false);
    }

    /// Marks the candidates that triangle `tri` covers (see the module doc).
    fn sweep_triangle(&mut self, query: &Query, tri: [u32; 3]) {
        let corners = tri.map(|i| query.placed[i as usize]);
        let [a, b, c] = corners;
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        let depth = tri.map(|i| query.depth[i as usize]);
        let covered = &mut self.covered;
        self.grid.near_box(min, max, |slot| {
            if covered[slot] {
                return;
            }
            let v = query.candidates[slot];
            let p = query.placed[v as usize];
            let in_box = p.x > min.x && p.y > min.y && p.x < max.x && p.y < max.y;
            covered[slot] = in_box
                && !tri.contains(&v)
                && depth_if_strictly_inside(corners, depth, p)
                    .is_some_and(|d| d > f64::from(query.depth[v as usize]));
        });
    }
}

/// What the sweep reads.
struct Query<'a> {
    placed: &'a [DVec2],
    depth: &'a [f32],
    candidates: &'a [u32],
}

/// Writes into `out` (cleared first) the candidates covered by the patch's front layer.
pub fn covered_boundary_vertices(
    placed: &[DVec2],
    triangles: &[[u32; 3]],
    depth: &[f32],
    candidates: &[u32],
    grid: &mut CoverageGrid,
    out: &mut Vec<u32>,
) -> Result<(), RasterError> {
    validate(placed, triangles, depth, candidates)?;
    out.clear();
    if triangles.is_empty() || candidates.is_empty() {
        return Ok(());
    }
    grid.build(placed, candidates);
    let query = Query {
        placed,
        depth,
        candidates,
    };
    for &tri in triangles {
        grid.sweep_triangle(&query, tri);
    }
    let covered = candidates.iter().zip(&grid.covered);
    out.extend(covered.filter(|(_, &hit)| hit).map(|(&v, _)| v));
    Ok(())
}

/// Interpolated depth at `p` when it lies strictly inside the (either-oriented) triangle.
#[inline]
fn depth_if_strictly_inside(corners: [DVec2; 3], depth: [f32; 3], p: DVec2) -> Option<f64> {
    let [wa, wb, wc] = weights_if_strictly_inside(corners, p)?;
    Some(wa * f64::from(depth[0]) + wb * f64::from(depth[1]) + wc * f64::from(depth[2]))
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
