//! The coverage query: takes the placed mesh, per-vertex depth and candidate (boundary)
//! vertices and gives those lying under the patch's own front layer — strictly inside a
//! placed triangle that does not contain the vertex (strictly inside its bounding box, and
//! all three edge functions of the triangle's sign), whose interpolated depth there is
//! strictly greater than the vertex's own. Independent of the pixel grid; candidates are
//! reported in the order given, so the answer is deterministic.
//!
//! A uniform grid over the placed bounding box, rebuilt per call into reusable buffers,
//! makes each query look at the few triangles near the vertex. Each triangle's bounding
//! box and cell span are computed once per call (the grid's two passes and the queries
//! share them), and a query rejects a triangle by its box before any edge function: on
//! graded meshes a cell near the boundary lists dozens of small triangles, and most of
//! them are rejected by two comparisons.

use glam::DVec2;

use super::RasterError;

/// Reusable buffers of the spatial grid.
#[derive(Default, Debug)]
pub struct CoverageGrid {
    cell_start: Vec<u32>,
    cell_triangles: Vec<u32>,
    cursor: Vec<u32>,
    /// Per triangle: bounding box `[min x, min y, max x, max y]`.
    boxes: Vec<[f64; 4]>,
    /// Per triangle: cell span `[first column, first row, last column, last row]`.
    spans: Vec<[u32; 4]>,
    origin: DVec2,
    inverse_cell: f64,
    columns: usize,
    rows: usize,
}

impl CoverageGrid {
    pub fn new() -> CoverageGrid {
        CoverageGrid::default()
    }

    fn build(&mut self, placed: &[DVec2], triangles: &[[u32; 3]]) {
        self.boxes.clear();
        self.boxes.extend(triangles.iter().map(|tri| {
            let [a, b, c] = tri.map(|v| placed[v as usize]);
            let (min, max) = (a.min(b).min(c), a.max(b).max(c));
            [min.x, min.y, max.x, max.y]
        }));
        let (min, max) = bounds(&self.boxes);
        let extent = (max - min).max(DVec2::splat(1e-9));
        // About one triangle per cell on average.
        let cell = ((extent.x * extent.y) / triangles.len().max(1) as f64)
            .sqrt()
            .max(1e-9);
        self.columns = ((extent.x / cell).ceil() as usize).clamp(1, 4096);
        self.rows = ((extent.y / cell).ceil() as usize).clamp(1, 4096);
        self.origin = min;
        self.inverse_cell = 1.0 / (extent.x / self.columns as f64).max(extent.y / self.rows as f64);
        let cells = self.columns * self.rows;
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        let mut spans = std::mem::take(&mut self.spans);
        spans.clear();
        spans.extend(self.boxes.iter().map(|b| {
            let (c0, r0) = self.cell_of(DVec2::new(b[0], b[1]));
            let (c1, r1) = self.cell_of(DVec2::new(b[2], b[3]));
            // Cells are at most 4096 per side, so the indices fit u32.
            [c0, r0, c1, r1].map(|i| i as u32)
        }));
        for &[c0, r0, c1, r1] in &spans {
            for r in r0..=r1 {
                let row = r as usize * self.columns;
                for c in c0..=c1 {
                    self.cell_start[row + c as usize + 1] += 1;
                }
            }
        }
        for i in 0..cells {
            self.cell_start[i + 1] += self.cell_start[i];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.cell_start[..cells]);
        self.cell_triangles.clear();
        self.cell_triangles
            .resize(self.cell_start[cells] as usize, 0);
        for (index, &[c0, r0, c1, r1]) in spans.iter().enumerate() {
            for r in r0..=r1 {
                let row = r as usize * self.columns;
                for c in c0..=c1 {
                    let slot = &mut self.cursor[row + c as usize];
                    self.cell_triangles[*slot as usize] = index as u32;
                    *slot += 1;
                }
            }
        }
        self.spans = spans;
    }

    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.origin) * self.inverse_cell;
        let c = (q.x.max(0.0) as usize).min(self.columns - 1);
        let r = (q.y.max(0.0) as usize).min(self.rows - 1);
        (c, r)
    }

    fn triangles_near(&self, p: DVec2) -> &[u32] {
        let (c, r) = self.cell_of(p);
        let cell = r * self.columns + c;
        &self.cell_triangles[self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize]
    }

    /// Whether `p` lies strictly inside triangle `t`'s bounding box (a strictly inside
    /// point always does).
    #[inline]
    fn box_holds(&self, t: usize, p: DVec2) -> bool {
        let b = &self.boxes[t];
        p.x > b[0] && p.y > b[1] && p.x < b[2] && p.y < b[3]
    }
}

/// Bounding box of the triangles' boxes.
fn bounds(boxes: &[[f64; 4]]) -> (DVec2, DVec2) {
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for b in boxes {
        min = min.min(DVec2::new(b[0], b[1]));
        max = max.max(DVec2::new(b[2], b[3]));
    }
    (min, max)
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
    if triangles.is_empty() {
        return Ok(());
    }
    grid.build(placed, triangles);
    for &v in candidates {
        let p = placed[v as usize];
        let own = depth[v as usize];
        let covered = grid.triangles_near(p).iter().any(|&t| {
            let tri = triangles[t as usize];
            grid.box_holds(t as usize, p)
                && !tri.contains(&v)
                && depth_if_strictly_inside(
                    tri.map(|i| placed[i as usize]),
                    tri.map(|i| depth[i as usize]),
                    p,
                )
                .is_some_and(|d| d > f64::from(own))
        });
        if covered {
            out.push(v);
        }
    }
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
