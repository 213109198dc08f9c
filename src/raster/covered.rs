//! The coverage query: takes the placed mesh, per-vertex depth and candidate (boundary)
//! vertices and gives those lying under the patch's own front layer — strictly inside a
//! placed triangle that does not contain the vertex (strictly inside its bounding box, and
//! all three edge functions of the triangle's sign), whose interpolated depth there is
//! strictly greater than the vertex's own. Independent of the pixel grid; candidates are
//! reported in the order given, so the answer is deterministic.
//!
//! A uniform grid over the candidates, rebuilt per call into reusable buffers, lets each
//! triangle look only at the candidates near it: per grid row that its bounding box spans,
//! the candidates of its cells are one contiguous slice (cells are numbered row by row), so
//! a triangle costs a few slice look-ups plus a box test per nearby candidate. The candidates
//! are about a fifth of the vertices and sit along the boundary, so this visits far fewer
//! (candidate, triangle) pairs than a grid over the triangles queried per candidate, and a
//! candidate found covered is not tested again. The predicate of each pair is unchanged, so
//! the answer is too.

use glam::DVec2;

use super::RasterError;

/// Reusable buffers of the candidates' grid.
#[derive(Default, Debug)]
pub struct CoverageGrid {
    /// Per cell (and one past the last): the first of its candidates in `cell_candidates`.
    cell_start: Vec<u32>,
    /// Candidate slots (indices into the candidate list), grouped by cell.
    cell_candidates: Vec<u32>,
    /// Per slot: its cell.
    cell_of_slot: Vec<u32>,
    /// Per slot: found covered.
    covered: Vec<bool>,
    /// The candidates' bounding box.
    min: DVec2,
    max: DVec2,
    inverse_cell: f64,
    columns: usize,
    rows: usize,
}

impl CoverageGrid {
    pub fn new() -> CoverageGrid {
        CoverageGrid::default()
    }

    /// Buckets the candidates' placed positions (the grid covers their bounding box).
    fn build(&mut self, placed: &[DVec2], candidates: &[u32]) {
        self.min = DVec2::splat(f64::INFINITY);
        self.max = DVec2::splat(f64::NEG_INFINITY);
        for &v in candidates {
            let p = placed[v as usize];
            self.min = self.min.min(p);
            self.max = self.max.max(p);
        }
        let extent = (self.max - self.min).max(DVec2::splat(1e-9));
        // About four cells per candidate: boundary candidates line up along curves, so an
        // occupied cell holds a few, and a small boundary triangle's box spans one or two
        // cells. The second bound keeps a box that is flat (candidates on a line) at about
        // 4n cells per side, so never more than about 12n cells.
        let slots = 4.0 * candidates.len() as f64;
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
        self.cell_of_slot.clear();
        for &v in candidates {
            let (c, r) = self.cell_of(placed[v as usize]);
            // Cells are at most 4096² < 2³², so the index fits u32.
            let cell = (r * self.columns + c) as u32;
            self.cell_of_slot.push(cell);
            self.cell_start[cell as usize + 1] += 1;
        }
        for i in 0..cells {
            self.cell_start[i + 1] += self.cell_start[i];
        }
        // Counting sort: `cell_start[cell]` serves as the cell's cursor, so afterwards each
        // entry holds the next cell's start, and shifting by one cell restores the starts.
        self.cell_candidates.clear();
        self.cell_candidates.resize(candidates.len(), 0);
        for (slot, &cell) in self.cell_of_slot.iter().enumerate() {
            let cursor = &mut self.cell_start[cell as usize];
            self.cell_candidates[*cursor as usize] = slot as u32;
            *cursor += 1;
        }
        self.cell_start.copy_within(0..cells, 1);
        self.cell_start[0] = 0;
        self.covered.clear();
        self.covered.resize(candidates.len(), false);
    }

    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.min) * self.inverse_cell;
        let c = (q.x.max(0.0) as usize).min(self.columns - 1);
        let r = (q.y.max(0.0) as usize).min(self.rows - 1);
        (c, r)
    }

    /// Marks the candidates that triangle `tri` covers (see the module doc).
    fn sweep_triangle(&mut self, query: &Query, tri: [u32; 3]) {
        let corners = tri.map(|i| query.placed[i as usize]);
        let [a, b, c] = corners;
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        if !(max.x > self.min.x && max.y > self.min.y && min.x < self.max.x && min.y < self.max.y) {
            return; // no candidate strictly inside the box
        }
        // A point strictly inside the triangle is strictly inside its box, and the cell map
        // is monotone, so the box's corner cells bound every cell such a point falls in.
        let ((c0, r0), (c1, r1)) = (self.cell_of(min), self.cell_of(max));
        let depth = tri.map(|i| query.depth[i as usize]);
        for r in r0..=r1 {
            let row = r * self.columns;
            let slots = self.cell_start[row + c0] as usize..self.cell_start[row + c1 + 1] as usize;
            for k in slots {
                let slot = self.cell_candidates[k] as usize;
                if self.covered[slot] {
                    continue;
                }
                let v = query.candidates[slot];
                let p = query.placed[v as usize];
                let in_box = p.x > min.x && p.y > min.y && p.x < max.x && p.y < max.y;
                self.covered[slot] = in_box
                    && !tri.contains(&v)
                    && depth_if_strictly_inside(corners, depth, p)
                        .is_some_and(|d| d > f64::from(query.depth[v as usize]));
            }
        }
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
///
/// Most triangles near a vertex do not contain it, so the three edge functions are tested
/// against the area's sign first, without dividing: `e / area > 0` needs `e` and `area` of
/// the same strict sign. Only then are the barycentric weights formed and tested exactly as
/// before (a quotient can still underflow to 0), so the answer is the same as testing the
/// weights alone (tests compare with a brute force).
#[inline]
fn depth_if_strictly_inside(corners: [DVec2; 3], depth: [f32; 3], p: DVec2) -> Option<f64> {
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
    let [wa, wb, wc] = edges.map(|e| e / area);
    (wa > 0.0 && wb > 0.0 && wc > 0.0)
        .then(|| wa * f64::from(depth[0]) + wb * f64::from(depth[1]) + wc * f64::from(depth[2]))
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
