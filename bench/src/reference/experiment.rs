//! The paper's comparison (Table I, Fig. 5) as library code. It takes a mask, a source and
//! a target image of the same size (the patch is placed at identity, so mesh, grid and
//! images share one pixel frame) and gives, per mesh:
//!
//! - the combinatorial and cotangent membranes ([`MembraneSolver`] with each
//!   [`LaplacianKind`]) and the MVC membrane ([`MvcWeights::from_mesh`]; "n/a" for holes or
//!   above a weight budget), each read back at the mask pixel centres by [`MeshSampler`];
//! - each compared with the pixel-grid reference ([`GridPoisson`], built once per mask in
//!   [`Experiment::new`]) by [`MembraneComparison`]: PSNR, seam step, uncovered pixels;
//! - timings, best of `repeats`: pre-processing (ours: Laplacian + Cholesky factor + the
//!   first solve, which switches every boundary constraint on; MVC: the weights) and
//!   membrane (ours: sampling the target at the boundary + constraint check +
//!   back-substitution; MVC: the same sampling + the dense weights × values product).
//!
//! Boundary values are the product's: `target − source`, both bilinear at the boundary
//! vertices (pixel-crack corners). The grid reference pins `target − source` at the outside
//! pixel centres (see [`poisson_membrane`](fn@super::poisson_membrane)): that half-pixel offset is part of what
//! the PSNR measures.
//!
//! [`reclone_ms`] times the interactive path, a re-clone at a moved placement through
//! [`PatchCloner`] (switches + solve + raster).

use std::time::Instant;

use glam::DVec2;
use thiserror::Error;

use super::mesh_sampler::MeshSampler;
use super::metrics::ComparisonInput;
use super::{
    GridMask, GridPoisson, MaskError, MembraneComparison, MetricError, MvcError, MvcWeights,
    PoissonError,
};
use lapclone::clone::{
    BoundaryData, BoundarySampler, CloneError, CloneOptions, MembraneSolver, PatchCloner, Placement,
};
use lapclone::mesh::{mesh_mask, BitMask, Mesh, MeshError, MeshOptions};
use lapclone::pixels::{Canvas, FloatImage};
use lapclone::solve::LaplacianKind;

/// Colour channels compared (alpha is never cloned).
pub const CHANNELS: usize = 3;

/// Why an experiment could not run.
#[derive(Debug, Error)]
pub enum ExperimentError {
    #[error("{what} is {got:?} but the mask is {mask:?}: they must have the same size")]
    SizeMismatch {
        what: &'static str,
        got: (usize, usize),
        mask: (usize, usize),
    },
    #[error("repeats must be at least 1")]
    NoRepeats,
    #[error(transparent)]
    Mask(#[from] MaskError),
    #[error("pixel-grid reference: {0}")]
    Reference(#[from] PoissonError),
    #[error("meshing: {0}")]
    Mesh(#[from] MeshError),
    #[error("cloning: {0}")]
    Clone(#[from] CloneError),
    #[error("MVC: {0}")]
    Mvc(#[from] MvcError),
    #[error("metrics: {0}")]
    Metric(#[from] MetricError),
}

/// Per-run settings besides the mesh options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunOptions {
    /// Timed repetitions; the best is reported.
    pub repeats: usize,
    /// MVC stores interior × boundary weights; above this many it is reported, not run.
    pub mvc_max_weights: usize,
    /// Keep the rasterised membranes in the result (for pictures).
    pub keep_membranes: bool,
    /// How every method takes its boundary values from `target − source`.
    pub boundary_data: BoundaryData,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            repeats: 3,
            mvc_max_weights: 40_000_000,
            keep_membranes: false,
            boundary_data: BoundaryData::default(),
        }
    }
}

/// One method's figures on one mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodFigures {
    pub comparison: MembraneComparison,
    pub preprocess_ms: f64,
    pub membrane_ms: f64,
    /// The membrane at the pixel centres (`width × height × 3`), if asked for.
    pub membrane: Option<Vec<f64>>,
}

/// MVC's outcome: measured, or why not.
#[derive(Clone, Debug, PartialEq)]
pub enum MvcOutcome {
    Measured(MethodFigures),
    /// MVC is undefined on a patch with holes.
    Holes {
        holes: usize,
    },
    /// The dense weight table would exceed [`RunOptions::mvc_max_weights`].
    TooLarge {
        weights: usize,
        limit: usize,
    },
}

impl MvcOutcome {
    pub fn figures(&self) -> Option<&MethodFigures> {
        match self {
            MvcOutcome::Measured(f) => Some(f),
            _ => None,
        }
    }

    /// The short reason shown in place of numbers ("n/a (holes)").
    pub fn not_run_reason(&self) -> Option<String> {
        match self {
            MvcOutcome::Measured(_) => None,
            MvcOutcome::Holes { .. } => Some("n/a (holes)".into()),
            MvcOutcome::TooLarge { weights, .. } => {
                Some(format!("n/a ({:.0}M weights)", *weights as f64 / 1e6))
            }
        }
    }
}

/// Everything measured on one mesh of the experiment's mask.
#[derive(Clone, Debug)]
pub struct MeshRun {
    pub mesh: Mesh,
    pub mesh_ms: f64,
    /// Mask pixels whose centre lies in no triangle.
    pub uncovered: usize,
    pub combinatorial: MethodFigures,
    pub cotangent: MethodFigures,
    pub mvc: MvcOutcome,
}

/// A mask with its images and its pixel-grid reference membrane (built once).
pub struct Experiment {
    width: usize,
    height: usize,
    inside: Vec<bool>,
    source: FloatImage,
    target: FloatImage,
    source_rgb: Vec<f32>,
    target_rgb: Vec<f32>,
    reference: Vec<f64>,
    reference_factor_ms: f64,
    reference_solve_ms: f64,
}

impl Experiment {
    /// Checks sizes, factors and solves the pixel-grid reference.
    pub fn new(
        mask: GridMask<'_>,
        source: FloatImage,
        target: FloatImage,
    ) -> Result<Self, ExperimentError> {
        let size = (mask.width(), mask.height());
        for (what, image) in [("source", &source), ("target", &target)] {
            let got = (image.width() as usize, image.height() as usize);
            if got != size {
                return Err(ExperimentError::SizeMismatch {
                    what,
                    got,
                    mask: size,
                });
            }
        }
        let source_rgb = rgb_samples(&source);
        // The solvers read the target through a canvas, quantised to its bit depth: compare
        // against the same quantised target.
        let target = Canvas::from_image(&target).to_float_image(target.format());
        let target_rgb = rgb_samples(&target);
        let difference: Vec<f32> = target_rgb
            .iter()
            .zip(&source_rgb)
            .map(|(t, s)| t - s)
            .collect();
        let started = Instant::now();
        let grid = GridPoisson::new(mask)?;
        let factored = Instant::now();
        let reference = grid.solve(&difference, CHANNELS)?.values;
        let solved = Instant::now();
        Ok(Self {
            width: size.0,
            height: size.1,
            inside: mask.as_slice().to_vec(),
            source,
            target,
            source_rgb,
            target_rgb,
            reference,
            reference_factor_ms: millis(factored - started),
            reference_solve_ms: millis(solved - factored),
        })
    }

    pub fn mask(&self) -> GridMask<'_> {
        let mask = GridMask::new(self.width, self.height, &self.inside);
        mask.expect("validated in new") // invariant: copied from a validated mask of this size
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn source(&self) -> &FloatImage {
        &self.source
    }

    pub fn target(&self) -> &FloatImage {
        &self.target
    }

    /// Interleaved RGB of the source and target, `width × height × 3`.
    pub fn source_rgb(&self) -> &[f32] {
        &self.source_rgb
    }

    pub fn target_rgb(&self) -> &[f32] {
        &self.target_rgb
    }

    /// The pixel-grid membrane, `width × height × 3` (0 outside the mask).
    pub fn reference(&self) -> &[f64] {
        &self.reference
    }

    /// Time to factor the grid Laplacian and to solve it once (3 channels), ms.
    pub fn reference_ms(&self) -> (f64, f64) {
        (self.reference_factor_ms, self.reference_solve_ms)
    }

    /// Meshes the mask with `mesh_options` (timed, best of `repeats`) and runs all methods.
    pub fn run(
        &self,
        mesh_options: &MeshOptions,
        run: &RunOptions,
    ) -> Result<MeshRun, ExperimentError> {
        if run.repeats == 0 {
            return Err(ExperimentError::NoRepeats);
        }
        let bits = BitMask::from_fn(self.width, self.height, |x, y| {
            self.inside[y * self.width + x]
        });
        // Time the mesh the product's clone uses (clone::mesh_from_mask): meshed, boundary on
        // the outside pixel centres, interior relaxed as asked.
        let mut mesh_ms = f64::INFINITY;
        let mut result = None;
        for _ in 0..run.repeats {
            let started = Instant::now();
            let mut fresh = mesh_mask(&bits, mesh_options)?;
            lapclone::clone::finish_mask_mesh(&mut fresh, mesh_options);
            mesh_ms = mesh_ms.min(millis(started.elapsed()));
            result = Some(fresh);
        }
        let result = result.expect("repeats ≥ 1"); // invariant: repeats ≥ 1 was checked, so the loop ran at least once.
        self.run_on_mesh(result.mesh, mesh_ms, run)
    }

    /// Runs all methods on a given mesh (pixel coordinates of the mask).
    pub fn run_on_mesh(
        &self,
        mesh: Mesh,
        mesh_ms: f64,
        run: &RunOptions,
    ) -> Result<MeshRun, ExperimentError> {
        if run.repeats == 0 {
            return Err(ExperimentError::NoRepeats);
        }
        let sampler = MeshSampler::new(&mesh, self.mask());
        let canvas = Canvas::from_image(&self.target);
        let combinatorial =
            self.laplacian_figures(&mesh, &sampler, &canvas, LaplacianKind::Combinatorial, run)?;
        let cotangent =
            self.laplacian_figures(&mesh, &sampler, &canvas, LaplacianKind::Cotangent, run)?;
        let mvc = self.mvc_figures(&mesh, &sampler, &canvas, run)?;
        Ok(MeshRun {
            uncovered: sampler.uncovered_count(),
            mesh,
            mesh_ms,
            combinatorial,
            cotangent,
            mvc,
        })
    }

    fn laplacian_figures(
        &self,
        mesh: &Mesh,
        sampler: &MeshSampler,
        canvas: &Canvas,
        kind: LaplacianKind,
        run: &RunOptions,
    ) -> Result<MethodFigures, ExperimentError> {
        let placed = &mesh.positions;
        let mut preprocess_ms = f64::INFINITY;
        let mut solver = None;
        for _ in 0..run.repeats {
            let started = Instant::now();
            let mut fresh = MembraneSolver::new(mesh, &self.source, kind, run.boundary_data)?;
            fresh.solve(placed, canvas, None)?;
            preprocess_ms = preprocess_ms.min(millis(started.elapsed()));
            solver = Some(fresh);
        }
        let mut solver = solver.expect("repeats ≥ 1"); // invariant: repeats ≥ 1 was checked, so the loop ran at least once.
        let mut membrane_ms = f64::INFINITY;
        for _ in 0..run.repeats {
            let started = Instant::now();
            solver.solve(placed, canvas, None)?;
            membrane_ms = membrane_ms.min(millis(started.elapsed()));
        }
        let flat: Vec<f32> = solver.membrane().iter().flatten().copied().collect();
        self.figures(sampler, &flat, preprocess_ms, membrane_ms, run)
    }

    fn mvc_figures(
        &self,
        mesh: &Mesh,
        sampler: &MeshSampler,
        canvas: &Canvas,
        run: &RunOptions,
    ) -> Result<MvcOutcome, ExperimentError> {
        let holes = mesh.hole_count();
        if holes > 0 {
            return Ok(MvcOutcome::Holes { holes });
        }
        let weights = mvc_weight_count(mesh);
        if weights > run.mvc_max_weights {
            return Ok(MvcOutcome::TooLarge {
                weights,
                limit: run.mvc_max_weights,
            });
        }
        let mut preprocess_ms = f64::INFINITY;
        let mut mvc = None;
        for _ in 0..run.repeats {
            let started = Instant::now();
            let fresh = MvcWeights::from_mesh(mesh)?;
            preprocess_ms = preprocess_ms.min(millis(started.elapsed()));
            mvc = Some(fresh);
        }
        let mvc = mvc.expect("repeats ≥ 1"); // invariant: repeats ≥ 1 was checked, so the loop ran at least once.
        let boundary = BoundarySampler::new(mesh, run.boundary_data);
        let rgb = |c: [f32; 4]| [c[0], c[1], c[2]];
        let mut source_at_boundary = vec![[0.0; 3]; boundary.boundary_vertices().len()];
        boundary.sample(
            &mesh.positions,
            |p| rgb(self.source.sample_bilinear(p.x, p.y)),
            &mut source_at_boundary,
        );
        let mut target_at_boundary = source_at_boundary.clone();
        let n = mesh.vertex_count();
        let mut values = vec![0.0f64; n * CHANNELS];
        let mut out = vec![0.0f64; n * CHANNELS];
        let mut membrane_ms = f64::INFINITY;
        for _ in 0..run.repeats {
            let started = Instant::now();
            boundary.sample(
                &mesh.positions,
                |p| rgb(canvas.sample_bilinear(p.x, p.y)),
                &mut target_at_boundary,
            );
            let pairs = source_at_boundary.iter().zip(&target_at_boundary);
            for (&v, (source, target)) in boundary.boundary_vertices().iter().zip(pairs) {
                for c in 0..CHANNELS {
                    values[v as usize * CHANNELS + c] = f64::from(target[c] - source[c]);
                }
            }
            mvc.apply(&values, CHANNELS, &mut out)?;
            membrane_ms = membrane_ms.min(millis(started.elapsed()));
        }
        let figures = self.figures(sampler, &out, preprocess_ms, membrane_ms, run)?;
        Ok(MvcOutcome::Measured(figures))
    }

    /// Reads per-vertex membrane values back at the pixels and compares with the reference.
    fn figures<T: Copy + Into<f64>>(
        &self,
        sampler: &MeshSampler,
        vertex_membrane: &[T],
        preprocess_ms: f64,
        membrane_ms: f64,
        run: &RunOptions,
    ) -> Result<MethodFigures, ExperimentError> {
        let mut pixels = vec![0.0; self.width * self.height * CHANNELS];
        sampler.interpolate(vertex_membrane, CHANNELS, &mut pixels);
        let comparison = MembraneComparison::new(ComparisonInput {
            mask: self.mask(),
            channels: CHANNELS,
            source: &self.source_rgb,
            target: &self.target_rgb,
            membrane: &pixels,
            covered: sampler.covered(),
            reference: &self.reference,
        })?;
        Ok(MethodFigures {
            comparison,
            preprocess_ms,
            membrane_ms,
            membrane: run.keep_membranes.then_some(pixels),
        })
    }
}

/// Interior × boundary entries MVC would store for this mesh (per piece).
pub fn mvc_weight_count(mesh: &Mesh) -> usize {
    mesh.loops
        .iter()
        .map(|l| {
            let interior = (0..mesh.vertex_count())
                .filter(|&v| !mesh.is_boundary[v] && mesh.piece[v] == l.piece)
                .count();
            interior * l.vertices.len()
        })
        .sum()
}

/// Best-of-`repeats` time (ms) of a re-clone — constraint switches, solve and raster — as
/// the patch alternates between two placements `nudge` px apart on a copy of `target`.
pub fn reclone_ms(
    source: &FloatImage,
    target: &FloatImage,
    mesh: Mesh,
    kind: LaplacianKind,
    boundary_data: BoundaryData,
    nudge: DVec2,
    repeats: usize,
) -> Result<f64, ExperimentError> {
    if repeats == 0 {
        return Err(ExperimentError::NoRepeats);
    }
    let options = CloneOptions {
        laplacian: kind,
        boundary_data,
        ..CloneOptions::default()
    };
    let mut cloner = PatchCloner::new(source.clone(), mesh, &options)?;
    let background = Canvas::from_image(target);
    let mut canvas = background.clone();
    let placements = [
        Placement::identity(),
        Placement::translate(DVec2::ZERO, nudge),
    ];
    cloner.clone_onto(&mut canvas, &placements[1])?;
    let mut best = f64::INFINITY;
    for i in 0..repeats {
        canvas.copy_from(&background);
        let stats = cloner.clone_onto(&mut canvas, &placements[i % 2])?;
        best = best.min(stats.solve_ms + stats.raster_ms);
    }
    Ok(best)
}

/// Interleaved RGB samples of an image.
pub fn rgb_samples(image: &FloatImage) -> Vec<f32> {
    image
        .pixels()
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

fn millis(duration: std::time::Duration) -> f64 {
    duration.as_secs_f64() * 1e3
}
