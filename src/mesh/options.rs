//! [`MeshOptions`] (the knobs of `mesh_mask` / `mesh_polygons`, with documented defaults) and
//! [`MeshResult`] / [`MeshStats`] (the mesh plus warnings and timing-free statistics).

use glam::DVec2;

use super::{Mesh, MeshError};
use crate::util::number_text;

/// Meshing parameters. See [`MeshOptions::default`] for the defaults and why.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Maximum boundary edge length in pixels (seam quality: the membrane matches the target
    /// only at boundary vertices).
    pub density: f64,
    /// Douglas–Peucker tolerance in pixels for the crack boundary (geometry); 0 keeps every
    /// crack corner. Polygon input is never simplified.
    pub simplify_tolerance: f64,
    /// Minimum triangle angle the refinement aims for, degrees (0–35). Input angles below it
    /// stay, and spade's refinement leaves the odd triangle below it next to a one-pixel
    /// boundary step (19.4° at 25° on the 800² spiral; `MeshStats::min_angle_deg` reports the
    /// mesh's own).
    pub min_angle_deg: f64,
    /// Vertex budget for the whole mesh; refinement stops when it is reached.
    pub max_vertices: usize,
    /// Pieces (8-connected) with fewer pixels than this are dropped with a warning.
    pub min_piece_area: f64,
    /// Where a mask mesh's boundary runs (polygon input ignores it).
    pub boundary: BoundaryPlacement,
    /// Largest triangle area refinement leaves, px²; `None`: only the angle bound grades
    /// the interior (dense at the boundary, coarse inside). The outside-centres boundary
    /// never splits its edges, so a triangle next to the boundary may stay larger.
    pub max_area: Option<f64>,
    /// Gauss–Seidel sweeps moving interior vertices towards their neighbours' mean, applied
    /// by the clone stage once the boundary is in place (`mesh::relax_interior`; no angle
    /// falls below `min_angle_deg` or where it already was); 0: none.
    pub relax_sweeps: usize,
}

/// Where `mesh_mask` (and so `mesh_from_mask`) puts the boundary of a
/// mask mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum BoundaryPlacement {
    /// The pixel cracks, simplified by `simplify_tolerance` and subdivided to `density`.
    /// The clone stage then moves it half a pixel out (`clone::expand_boundary`).
    Cracks,
    /// The default. Exactly the centres of the outside 4-neighbours of the mask, the pixels where the
    /// pixel-grid clone fixes its values, in crack order: with `density` ≤ √2 px every such
    /// pixel is a boundary vertex; coarser densities drop centres where the boundary is
    /// straight to within half a pixel (`simplify_tolerance` does not apply). Boundary
    /// edges are never split, so every boundary vertex samples one Dirichlet pixel (those of
    /// a cut are the exception, see `mesh_mask`). Loops that would touch (a one-pixel gap
    /// between pieces, say) get quarter-pixel points there; if they still cannot be meshed,
    /// the mask is meshed on its cracks with a warning.
    #[default]
    OutsideCentres,
}

impl BoundaryPlacement {
    /// The name [`FromStr`](std::str::FromStr) reads: `cracks` or `outside-centres`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Cracks => "cracks",
            Self::OutsideCentres => "outside-centres",
        }
    }
}

impl std::str::FromStr for BoundaryPlacement {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text {
            "cracks" => Ok(Self::Cracks),
            "outside-centres" | "outside-centers" => Ok(Self::OutsideCentres),
            other => Err(format!(
                "unknown boundary placement {other:?} (expected cracks or outside-centres)"
            )),
        }
    }
}

/// The most relaxation sweeps accepted (a guard against runaway work; 5 already converge
/// what matters on the spiral).
pub const MAX_RELAX_SWEEPS: usize = 1000;

/// The smallest `max_area` accepted, px²: below it refinement would need more vertices than
/// its size-based budget allows.
pub const MIN_MAX_AREA: f64 = 0.25;

impl Default for MeshOptions {
    /// - `density` 3 px: on the spiral, PSNR against the pixel-grid clone saturates with
    ///   boundary density (`lapclone-bench paper --sweep`, docs/quality.md; outside centres,
    ///   combinatorial / cotangent: 39.3 / 43.3 dB at 4 px, 38.6 / 43.8 at 3, 41.6 / 48.6
    ///   at 2, 42.0 / 49.5 at 1 with 2 × the vertices of 3 px), while
    ///   vertices, meshing, factor and re-clone time grow as 1/density; 3 px keeps an
    ///   interactive re-clone cheap. Seam-critical work can ask for `density` 1–2.
    /// - `simplify_tolerance` 0.9 px: keeps every mask pixel centre within 0.5 px of the
    ///   mesh (a centre is 0.5 px inside the crack boundary) and every mesh point within
    ///   0.9 px of the mask.
    /// - `min_angle_deg` 25°: the usual Ruppert bound that still terminates reliably.
    /// - `max_vertices` 2 000 000: a guard against runaway refinement, not a quality knob.
    /// - `min_piece_area` 4 px: drops isolated specks of 1–3 pixels.
    /// - `relax_sweeps` 2: evens out the interior beyond the boundary's first ring, for the
    ///   combinatorial Laplacian's accuracy (+0.7 dB on the paper's spiral, +1.7 on the palm;
    ///   the seam and the angle bound unchanged, about 0.4 M instructions on the 400² spiral).
    /// - `boundary` outside centres: every boundary vertex samples exactly one of the pixels
    ///   where the pixel-grid clone fixes its values, instead of the crack's bilinear mix of
    ///   inside and outside pixels. At 3 px, against the crack boundary with the same angle
    ///   and relaxation, it gives PSNR +0.6 / +2.2 dB on the spiral (combinatorial /
    ///   cotangent) and +1.8 to +2.9 dB cotangent on every Table I model, with about as many
    ///   vertices; the first clone costs about 0.2 ms more on the 400² spiral
    ///   (docs/quality.md).
    fn default() -> Self {
        Self {
            density: 3.0,
            simplify_tolerance: 0.9,
            min_angle_deg: 25.0,
            max_vertices: crate::limits::MAX_MESH_VERTICES,
            min_piece_area: 4.0,
            boundary: BoundaryPlacement::OutsideCentres,
            max_area: None,
            relax_sweeps: 2,
        }
    }
}

/// Minimum angle of [`MeshOptions::seam_quality`], degrees.
pub const SEAM_QUALITY_MIN_ANGLE_DEG: f64 = 29.0;
/// Relaxation sweeps of [`MeshOptions::seam_quality`] (more changed nothing measurable).
pub const SEAM_QUALITY_RELAX_SWEEPS: usize = 5;

impl MeshOptions {
    /// Reaches 45 dB (combinatorial) and 52 dB (cotangent) on the 770×743 spiral against the
    /// pixel-grid clone (measured 45.8 / 54.3) at about three times the default's vertices and
    /// re-clone time (docs/quality.md): boundary vertices on every Dirichlet pixel centre, a
    /// 29° angle bound, 5 relaxation sweeps.
    pub fn seam_quality() -> Self {
        Self {
            density: 1.0,
            boundary: BoundaryPlacement::OutsideCentres,
            min_angle_deg: SEAM_QUALITY_MIN_ANGLE_DEG,
            relax_sweeps: SEAM_QUALITY_RELAX_SWEEPS,
            ..Self::default()
        }
    }

    /// Checks every option is in its documented range.
    pub fn validate(&self) -> Result<(), MeshError> {
        let bad = |what: String| Err(MeshError::InvalidOption(what));
        if !(self.density.is_finite() && self.density >= 0.05) {
            return bad(format!(
                "density must be a length ≥ 0.05 px, got {}",
                number_text(self.density)
            ));
        }
        if !(self.simplify_tolerance.is_finite() && self.simplify_tolerance >= 0.0) {
            return bad(format!(
                "simplify_tolerance must be ≥ 0, got {}",
                number_text(self.simplify_tolerance)
            ));
        }
        if !(self.min_angle_deg.is_finite() && (0.0..=35.0).contains(&self.min_angle_deg)) {
            return bad(format!(
                "min angle must be in [0, 35] degrees, got {}",
                number_text(self.min_angle_deg)
            ));
        }
        if self.max_vertices < 3 {
            return bad(format!(
                "max_vertices must be at least 3, got {}",
                self.max_vertices
            ));
        }
        if !(self.min_piece_area.is_finite() && self.min_piece_area >= 0.0) {
            return bad(format!(
                "min_piece_area must be ≥ 0, got {}",
                number_text(self.min_piece_area)
            ));
        }
        if self.relax_sweeps > MAX_RELAX_SWEEPS {
            return bad(format!(
                "relax_sweeps must be at most {MAX_RELAX_SWEEPS}, got {}",
                self.relax_sweeps
            ));
        }
        if let Some(area) = self.max_area {
            if !(area.is_finite() && area >= MIN_MAX_AREA) {
                return bad(format!(
                    "max_area must be an area ≥ {MIN_MAX_AREA} px², got {}",
                    number_text(area)
                ));
            }
        }
        Ok(())
    }
}

/// Statistics of a meshing run (no timings, so they are deterministic).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MeshStats {
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Vertices on a boundary loop.
    pub boundary_vertices: usize,
    /// Connected pieces.
    pub pieces: usize,
    /// Holes over all pieces.
    pub holes: usize,
    /// Smallest triangle angle in the mesh, degrees.
    pub min_angle_deg: f64,
    /// Largest distance from the input boundary (crack corners) to the simplified boundary.
    pub max_boundary_deviation_px: f64,
    /// False when simplification made loops touch and the raw crack boundary was meshed.
    pub simplified: bool,
    /// spade's `refinement_complete` (false: the vertex budget ran out).
    pub refinement_complete: bool,
    /// Pieces dropped as smaller than `min_piece_area`.
    pub dropped_pieces: usize,
    /// Mask pixels in the dropped pieces.
    pub dropped_pixels: usize,
    /// Where the boundary ended up (`OutsideCentres` falls back to `Cracks` when the centre
    /// loops cannot be meshed, with a warning).
    pub boundary: BoundaryPlacement,
    /// With `OutsideCentres`: boundary vertices a quarter pixel outside a crack instead of on
    /// an outside centre (pixels reached from two sides of a 1-px notch, gap or hole).
    pub off_centre_boundary_vertices: usize,
}

/// A mesh with warnings (dropped pieces, budget exhausted, fallbacks) and statistics.
#[derive(Clone, Debug)]
pub struct MeshResult {
    /// The triangle mesh.
    pub mesh: Mesh,
    /// Non-fatal notes (e.g. dropped pieces), one sentence each.
    pub warnings: Vec<String>,
    /// Sizes and what was dropped.
    pub stats: MeshStats,
}

/// Smallest interior angle over all triangles, degrees (180 for an empty mesh).
///
/// A triangle's smallest angle is opposite its shortest edge and is at most 60°, where
/// sin² is increasing; so the scan compares sin² of that one angle per triangle and takes a
/// single `atan2` at the end.
pub fn min_angle_deg(mesh: &Mesh) -> f64 {
    let mut smallest: Option<(f64, DVec2, DVec2)> = None;
    for t in &mesh.triangles {
        let p = t.map(|v| mesh.positions[v as usize]);
        // Edge k is opposite vertex k.
        let lengths = [0, 1, 2].map(|k| p[(k + 1) % 3].distance_squared(p[(k + 2) % 3]));
        let k = (0..3)
            .min_by(|&i, &j| lengths[i].total_cmp(&lengths[j]))
            .unwrap_or(0);
        let (u, w) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
        let cross = u.perp_dot(w);
        let denominator = u.length_squared() * w.length_squared();
        let sin2 = if denominator > 0.0 {
            cross * cross / denominator
        } else {
            0.0
        };
        if smallest.is_none_or(|(s, _, _)| sin2 < s) {
            smallest = Some((sin2, u, w));
        }
    }
    smallest
        .map_or(std::f64::consts::PI, |(_, u, w)| {
            u.perp_dot(w).abs().atan2(u.dot(w))
        })
        .to_degrees()
}
