//! The cloning membrane (paper §II-C): takes the placed boundary, the source and the canvas
//! being cloned onto, and gives the per-vertex membrane f solving L f = 0 with
//! f = target − source at every visible boundary vertex.
//!
//! Boundary vertices outside the canvas, or hidden under the patch's own front layer, are
//! switched off (rank-1 downdates of the kept factor) rather than clamped, and switched back
//! on when they return. Source colours at the rest boundary are sampled once per mesh (again
//! only when an animated source moves to its next frame); per frame only the canvas is sampled.

use glam::DVec2;

use super::glue::{Glue, GlueStats};
use super::{BoundaryData, BoundarySampler, CloneError};
use crate::mesh::Mesh;
use crate::pixels::{Canvas, FloatImage};
use crate::solve::{laplacian, LaplacianKind, PenaltyFactor, PenaltyOptions, SwitchStats};

pub use super::glue::MEMBRANE_CHANNELS;

/// The factored Laplacian of one patch mesh and the scratch buffers of its per-frame solve.
pub struct MembraneSolver {
    factor: PenaltyFactor,
    sampler: BoundarySampler,
    /// f_S's boundary data at the rest boundary, RGB, one per boundary vertex.
    source_at_boundary: Vec<[f32; 3]>,
    /// Scratch: f_T's boundary data where the boundary is placed.
    target_at_boundary: Vec<[f32; 3]>,
    wanted: Vec<bool>,
    values: Vec<f64>,
    membrane: Vec<[f32; 3]>,
}

/// What one membrane solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MembraneStats {
    /// Boundary vertices constrained in this solve.
    pub constrained: usize,
    /// Boundary vertices switched off because they fall outside the canvas.
    pub outside: usize,
    /// Boundary vertices switched off because the patch's own front layer covers them.
    pub hidden: usize,
    /// Front-layer boundary vertices over the patch itself, glued to what lies beneath.
    pub glued: usize,
    /// Back-substitutions the glue added.
    pub glue_iterations: usize,
    /// How the factor's constraint switches went.
    pub switches: SwitchStats,
}

impl MembraneSolver {
    /// Builds and factors the Laplacian of `mesh` (with every boundary constraint on, the
    /// usual state, so a first clone inside the target switches nothing) and samples the
    /// source at the rest boundary, `data` deciding how.
    pub fn new(
        mesh: &Mesh,
        source: &FloatImage,
        kind: LaplacianKind,
        data: BoundaryData,
    ) -> Result<Self, CloneError> {
        let sampler = BoundarySampler::new(mesh, data);
        let boundary = sampler.boundary_vertices();
        let mut wanted = vec![false; mesh.vertex_count()];
        for &v in boundary {
            wanted[v as usize] = true;
        }
        let l = laplacian(mesh, kind);
        let factor = PenaltyFactor::with_constrained(&l, &PenaltyOptions::default(), &wanted)?;
        let mut source_at_boundary = vec![[0.0; 3]; boundary.len()];
        sampler.sample(
            &mesh.positions,
            |p| rgb(source.sample_bilinear(p.x, p.y)),
            &mut source_at_boundary,
        );
        let n = mesh.vertex_count();
        Ok(Self {
            factor,
            target_at_boundary: vec![[0.0; 3]; boundary.len()],
            sampler,
            source_at_boundary,
            wanted,
            values: vec![0.0; n * MEMBRANE_CHANNELS],
            membrane: vec![[0.0; 3]; n],
        })
    }

    /// Samples a new source along the rest boundary (an animated source's next frame).
    pub fn resample_source(&mut self, mesh: &Mesh, source: &FloatImage) {
        self.sampler.sample(
            &mesh.positions,
            |p| rgb(source.sample_bilinear(p.x, p.y)),
            &mut self.source_at_boundary,
        );
    }

    /// Factorisations so far: the one at construction plus the guards' rebuilds.
    pub fn factorisations(&self) -> usize {
        1 + self.factor.refactor_count()
    }

    /// Solves the membrane for a patch whose vertices sit at `placed` on `canvas`.
    /// `hidden[v]` (if given) marks boundary vertices covered by the patch itself.
    pub fn solve(
        &mut self,
        placed: &[DVec2],
        canvas: &Canvas,
        hidden: Option<&[bool]>,
    ) -> Result<MembraneStats, CloneError> {
        let factor = &mut self.factor;
        let n = self.wanted.len();
        let mut stats = MembraneStats::default();
        let (width, height) = (f64::from(canvas.width()), f64::from(canvas.height()));
        self.sampler.sample(
            placed,
            |p| rgb(canvas.sample_bilinear(p.x, p.y)),
            &mut self.target_at_boundary,
        );
        let boundary = self.sampler.boundary_vertices();
        for (slot, &v) in boundary.iter().enumerate() {
            let v = v as usize;
            let p = placed[v];
            let inside = p.x >= 0.0 && p.y >= 0.0 && p.x <= width && p.y <= height;
            let covered = hidden.is_some_and(|h| h[v]);
            stats.outside += usize::from(!inside);
            stats.hidden += usize::from(inside && covered);
            let on = inside && !covered;
            self.wanted[v] = on;
            if on {
                let target = self.target_at_boundary[slot];
                let source = self.source_at_boundary[slot];
                for c in 0..MEMBRANE_CHANNELS {
                    self.values[c * n + v] = f64::from(target[c] - source[c]);
                }
            }
        }
        stats.switches = factor.set_constrained(&self.wanted)?;
        stats.constrained = factor.constrained_count();
        if stats.constrained == 0 {
            self.membrane.fill([0.0; 3]);
            return Ok(stats);
        }
        factor.solve_dirichlet(&mut self.values, MEMBRANE_CHANNELS);
        for (v, m) in self.membrane.iter_mut().enumerate() {
            *m = [0, 1, 2].map(|c| self.values[c * n + v] as f32);
        }
        Ok(stats)
    }

    /// Glue (see [`Glue`]): refines the last [`solve`](Self::solve)'s membrane so that the
    /// glued vertices continue the patch's composite beneath them. Switches nothing.
    pub fn solve_glue(&mut self, glue: &mut Glue) -> GlueStats {
        let factor = &mut self.factor;
        let (target, source) = (&self.target_at_boundary, &self.source_at_boundary);
        // Exactly the value the solve gave each constrained slot.
        let initial = |slot: usize| [0, 1, 2].map(|c| f64::from(target[slot][c] - source[slot][c]));
        let stats = glue.solve(factor, &mut self.values, initial, source);
        if stats.iterations > 0 {
            let n = self.wanted.len();
            for (v, m) in self.membrane.iter_mut().enumerate() {
                *m = [0, 1, 2].map(|c| self.values[c * n + v] as f32);
            }
        }
        stats
    }

    /// The source's boundary data at the rest boundary, one RGB value per boundary slot.
    pub fn source_at_boundary(&self) -> &[[f32; 3]] {
        &self.source_at_boundary
    }

    /// The canvas's boundary data in the last solve, one RGB value per boundary slot.
    pub fn target_at_boundary(&self) -> &[[f32; 3]] {
        &self.target_at_boundary
    }

    /// The membrane of the last solve, one RGB offset per vertex.
    pub fn membrane(&self) -> &[[f32; 3]] {
        &self.membrane
    }

    /// The kept factor.
    pub fn factor(&self) -> &PenaltyFactor {
        &self.factor
    }

    pub fn boundary_vertices(&self) -> &[u32] {
        self.sampler.boundary_vertices()
    }

    /// How the boundary data is sampled.
    pub fn boundary_data(&self) -> BoundaryData {
        self.sampler.kind()
    }
}

fn rgb(c: [f32; 4]) -> [f32; 3] {
    [c[0], c[1], c[2]]
}
