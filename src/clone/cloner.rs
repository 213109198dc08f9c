//! The per-patch cloning engine: takes a source image and its patch mesh once, then, per
//! call, a placement (and optionally deformed positions with depth) and a canvas, and
//! composites the seamless clone onto the canvas.
//!
//! Built once: the mesh, the factored Laplacian, the source (grey in monochrome mode), raster
//! and coverage scratch. Per call, on the calling thread: place the vertices, find boundary
//! vertices hidden under the patch's own front layer, switch constraints, one 3-RHS solve
//! (and, where the patch lies over itself, the glue's few back-substitutions: [`Glue`]), then
//! one [`draw_patch`] with the solved membrane.

use std::time::Instant;

use glam::DVec2;

use super::glue::{Glue, GlueFrame};
use super::membrane::{MembraneSolver, MembraneStats};
use super::{BoundaryData, CloneError, Placement};
use crate::mesh::Mesh;
use crate::pixels::{Canvas, FloatImage};
use crate::raster::{
    boundary_layers, draw_patch, Beneath, CoverageGrid, Patch, RasterOptions, RasterScratch,
    RasterStats,
};
use crate::solve::LaplacianKind;

/// How the source's colours enter the clone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CloneMode {
    /// The paper: the source's colours plus the membrane.
    #[default]
    Normal,
    /// The source turned grey first (like OpenCV's MONOCHROME_TRANSFER): only its texture
    /// is transferred, the colour comes from the target through the membrane.
    Monochrome,
}

impl CloneMode {
    /// The name used in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            CloneMode::Normal => "normal",
            CloneMode::Monochrome => "monochrome",
        }
    }

    /// The mode named `name` (`normal`, `monochrome`), as the CLI and scenes spell it.
    pub fn from_name(name: &str) -> Option<Self> {
        [CloneMode::Normal, CloneMode::Monochrome]
            .into_iter()
            .find(|k| k.name() == name)
    }
}

/// Settings fixed for the life of a [`PatchCloner`] (changing them means a new cloner).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloneOptions {
    /// Which Laplacian the membrane solves with.
    pub laplacian: LaplacianKind,
    /// Whether the source keeps its colour or turns grey first.
    pub mode: CloneMode,
    /// Width in px of the soft outer edge (0: a crisp anti-aliased edge).
    pub feather: f32,
    /// How the membrane's boundary values are taken from `target − source`.
    pub boundary_data: BoundaryData,
}

impl Default for CloneOptions {
    fn default() -> Self {
        Self {
            laplacian: LaplacianKind::Combinatorial,
            mode: CloneMode::Normal,
            feather: 0.0,
            boundary_data: BoundaryData::default(),
        }
    }
}

/// What one clone did and how long its parts took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CloneStats {
    /// Membrane figures (constraints, switches, solve).
    pub membrane: MembraneStats,
    /// Raster figures (triangles, pixels, timings).
    pub raster: RasterStats,
    /// Hidden-vertex query ([`clone_deformed`](PatchCloner::clone_deformed) only), constraint
    /// switches and back-substitution.
    pub solve_ms: f64,
    /// The raster's draw.
    pub raster_ms: f64,
}

/// Everything kept between clones of one patch. See the module doc.
pub struct PatchCloner {
    source: FloatImage,
    mode: CloneMode,
    mesh: Mesh,
    membrane: MembraneSolver,
    raster_options: RasterOptions,
    placed: Vec<DVec2>,
    hidden: HiddenVertices,
    glue: Glue,
    raster_scratch: RasterScratch,
}

impl PatchCloner {
    /// Assembles and factors the patch's Laplacian and samples the source along the rest
    /// boundary.
    pub fn new(source: FloatImage, mesh: Mesh, options: &CloneOptions) -> Result<Self, CloneError> {
        if !crate::limits::feather_in_range(f64::from(options.feather)) {
            return Err(CloneError::BadOption(format!(
                "feather must lie in [0, {}], not {:?}",
                crate::limits::MAX_FEATHER,
                options.feather
            )));
        }
        let source = match options.mode {
            CloneMode::Normal => source,
            CloneMode::Monochrome => source.to_grey(),
        };
        let membrane =
            MembraneSolver::new(&mesh, &source, options.laplacian, options.boundary_data)?;
        let n = mesh.vertex_count();
        let glue = Glue::new(&mesh, membrane.boundary_vertices(), options.boundary_data);
        Ok(Self {
            source,
            mode: options.mode,
            mesh,
            membrane,
            raster_options: RasterOptions {
                feather: options.feather,
                ..RasterOptions::default()
            },
            placed: Vec::with_capacity(n),
            hidden: HiddenVertices {
                marks: vec![false; n],
                covered: Vec::new(),
                beneath: Vec::new(),
                grid: CoverageGrid::new(),
            },
            glue,
            raster_scratch: RasterScratch::new(),
        })
    }

    /// Shades each draw on `threads` threads (the caller's and the raster's worker pool's; 1
    /// by default; at most [`MAX_RASTER_THREADS`](crate::MAX_RASTER_THREADS) per draw): for a
    /// one-shot clone of a large patch. The pixels are the same for any count.
    pub fn set_raster_threads(&mut self, threads: usize) {
        self.raster_options.threads = threads.max(1);
    }

    /// The patch mesh in rest (source) coordinates.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Replaces the source (the next frame of an animated source; the mesh, and so the
    /// factor, stay): resamples it along the rest boundary.
    pub fn set_source(&mut self, source: FloatImage) {
        let source = match self.mode {
            CloneMode::Normal => source,
            CloneMode::Monochrome => source.to_grey(),
        };
        self.membrane.resample_source(&self.mesh, &source);
        self.source = source;
    }

    /// Factorisations of the cloning Laplacian so far: the first, plus any rebuild a
    /// guard of the rank-1 updates made.
    pub fn factorisations(&self) -> usize {
        self.membrane.factorisations()
    }

    /// The source image the patch is cut from.
    pub fn source(&self) -> &FloatImage {
        &self.source
    }

    /// Where the vertices went in the last clone (canvas pixels).
    pub fn placed(&self) -> &[DVec2] {
        &self.placed
    }

    internal_fn! {
        /// The membrane of the last clone.
        fn membrane(&self) -> &MembraneSolver {
            &self.membrane
        }
    }

    /// The glued vertices of the last clone (the glue's internals, for lapclone's own tests).
    #[cfg(feature = "internals")]
    #[doc(hidden)]
    pub fn glue(&self) -> &Glue {
        &self.glue
    }

    /// Clones the undeformed patch onto `canvas` at `placement`.
    pub fn clone_onto(
        &mut self,
        canvas: &mut Canvas,
        placement: &Placement,
    ) -> Result<CloneStats, CloneError> {
        self.prepare_rigid(placement)?;
        self.clone_prepared(canvas, None)
    }

    /// Clones the patch with its vertices moved to `deformed` (rest frame) and then placed.
    /// With `depth`, overlapping parts are depth-ordered and boundary vertices under the
    /// patch's own front layer lose their constraint.
    pub fn clone_deformed(
        &mut self,
        canvas: &mut Canvas,
        placement: &Placement,
        deformed: &[DVec2],
        depth: Option<&[f32]>,
    ) -> Result<CloneStats, CloneError> {
        self.place_deformed(placement, deformed, depth)?;
        self.clone_placed(canvas, depth, HiddenBy::Query)
    }

    /// The canvas-independent half of [`clone_onto`](Self::clone_onto): places the vertices.
    /// Patches of one frame can prepare in parallel, then clone in layer order.
    pub fn prepare_rigid(&mut self, placement: &Placement) -> Result<(), CloneError> {
        check_placement(placement)?;
        placement.apply(&self.mesh.positions, &mut self.placed);
        self.hidden.marks.fill(false);
        self.glue.clear();
        Ok(())
    }

    /// The canvas-independent half of [`clone_deformed`](Self::clone_deformed): places the
    /// deformed vertices and finds the boundary vertices hidden under the patch itself and
    /// those glued over it.
    pub fn prepare_deformed(
        &mut self,
        placement: &Placement,
        deformed: &[DVec2],
        depth: Option<&[f32]>,
    ) -> Result<(), CloneError> {
        self.place_deformed(placement, deformed, depth)?;
        self.find_layers(depth)
    }

    /// The boundary vertices hidden under the patch itself and those glued over a lower
    /// layer of it, at the placed positions (none without `depth`).
    fn find_layers(&mut self, depth: Option<&[f32]>) -> Result<(), CloneError> {
        let boundary = self.membrane.boundary_vertices();
        let frame = (&self.placed[..], &self.mesh.triangles[..]);
        self.hidden.find(frame, boundary, depth)?;
        let rest = &self.mesh.positions[..];
        let beneath = &self.hidden.beneath;
        find_glue(&mut self.glue, rest, frame, depth, beneath, &self.source);
        Ok(())
    }

    fn place_deformed(
        &mut self,
        placement: &Placement,
        deformed: &[DVec2],
        depth: Option<&[f32]>,
    ) -> Result<(), CloneError> {
        check_placement(placement)?;
        let n = self.mesh.vertex_count();
        if deformed.len() != n || depth.is_some_and(|d| d.len() != n) {
            return Err(CloneError::VertexCountMismatch(deformed.len(), n));
        }
        placement.apply(deformed, &mut self.placed);
        Ok(())
    }

    /// The canvas half: membrane constraints from `canvas` under the prepared placement, the
    /// membrane solve and the raster. `depth` must be the one given to the preparation.
    pub fn clone_prepared(
        &mut self,
        canvas: &mut Canvas,
        depth: Option<&[f32]>,
    ) -> Result<CloneStats, CloneError> {
        self.clone_placed(canvas, depth, HiddenBy::Preparation)
    }

    /// The hidden-vertex query (if it is still to do) and the membrane solve, then the draw.
    fn clone_placed(
        &mut self,
        canvas: &mut Canvas,
        depth: Option<&[f32]>,
        hidden_by: HiddenBy,
    ) -> Result<CloneStats, CloneError> {
        let n = self.mesh.vertex_count();
        if self.placed.len() != n || depth.is_some_and(|d| d.len() != n) {
            return Err(CloneError::VertexCountMismatch(self.placed.len(), n));
        }
        let started = Instant::now();
        if hidden_by == HiddenBy::Query {
            self.find_layers(depth)?;
        }
        let hidden = &self.hidden.marks;
        let mut membrane = self.membrane.solve(&self.placed, canvas, Some(hidden))?;
        let glued = self.membrane.solve_glue(&mut self.glue);
        (membrane.glued, membrane.glue_iterations) = (glued.glued, glued.iterations);
        let solved = Instant::now();
        let patch = Patch {
            rest: &self.mesh.positions,
            placed: &self.placed,
            triangles: &self.mesh.triangles,
            membrane: self.membrane.membrane(),
            depth,
            loops: &self.mesh.loops,
            source: &self.source,
        };
        let raster = draw_patch(
            canvas,
            &patch,
            &self.raster_options,
            &mut self.raster_scratch,
        )?;
        Ok(CloneStats {
            membrane,
            raster,
            solve_ms: millis(solved - started),
            raster_ms: millis(solved.elapsed()),
        })
    }
}

/// Where a clone's hidden boundary vertices come from.
#[derive(Clone, Copy, PartialEq, Eq)]
enum HiddenBy {
    /// Found by the preparation (or none: a rigid clone).
    Preparation,
    /// Found with the solve.
    Query,
}

/// The boundary vertices under the patch's own front layer, those over a lower layer, and
/// the query's buffers.
struct HiddenVertices {
    /// Per vertex: hidden.
    marks: Vec<bool>,
    covered: Vec<u32>,
    /// The boundary vertices not hidden that lie over a lower layer.
    beneath: Vec<Beneath>,
    grid: CoverageGrid,
}

impl HiddenVertices {
    /// Marks the `boundary` vertices of the placed `(positions, triangles)` under the
    /// patch's own front layer and lists the others over a lower layer (none without
    /// `depth`).
    fn find(
        &mut self,
        (placed, triangles): (&[DVec2], &[[u32; 3]]),
        boundary: &[u32],
        depth: Option<&[f32]>,
    ) -> Result<(), CloneError> {
        self.marks.fill(false);
        self.beneath.clear();
        if let Some(depth) = depth {
            let (grid, covered) = (&mut self.grid, &mut self.covered);
            let geometry = (placed, triangles, depth);
            boundary_layers(geometry, boundary, grid, covered, &mut self.beneath)?;
            for &v in covered.iter() {
                self.marks[v as usize] = true;
            }
        }
        Ok(())
    }
}

/// Placed positions and triangles.
type Frame<'a> = (&'a [DVec2], &'a [[u32; 3]]);

/// The glue of a deformed frame (none without depth: nothing is in front of anything).
fn find_glue(
    glue: &mut Glue,
    rest: &[DVec2],
    (placed, triangles): Frame,
    depth: Option<&[f32]>,
    beneath: &[Beneath],
    source: &FloatImage,
) {
    match depth {
        Some(depth) => {
            let frame = GlueFrame {
                rest,
                placed,
                triangles,
                depth,
            };
            glue.find(frame, beneath, source);
        }
        None => glue.clear(),
    }
}

fn check_placement(placement: &Placement) -> Result<(), CloneError> {
    if placement.is_finite() && placement.scale > 0.0 {
        Ok(())
    } else {
        Err(CloneError::BadPlacement(format!("{placement:?}")))
    }
}

pub(crate) fn millis(duration: std::time::Duration) -> f64 {
    duration.as_secs_f64() * 1e3
}
