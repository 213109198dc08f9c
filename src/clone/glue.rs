//! Glue where a patch overlaps itself: takes the placed patch (rest and placed positions,
//! triangles, per-vertex depth), its source and the boundary vertices not hidden under its own
//! front layer, and gives the *glued* vertices — front-layer boundary vertices lying over a
//! lower layer of the same patch (`raster::boundary_layers`) — and then the membrane in which each of
//! them continues the patch's own composite beneath it instead of the target pixel there,
//! which the lower layer covers.
//!
//! A glued vertex `v` over the point `q` of the lower triangle `(a, b, c)` (weights `w`) is
//! constrained to `f(v) = s(q) + Σ wₖ f(k) − s(v)`: the lower layer's source plus membrane at
//! `q`, minus `v`'s own source, so the front layer's edge shows what is beneath. `s(v)` is the
//! membrane's own boundary datum of `v` (a hat average or a vertex sample, as configured) and
//! `s(q)` is taken the same way along `v`'s placed boundary edges, carried into the source by
//! the lower triangle's affine map. The constraint couples `v` to three vertices far away in
//! the mesh, so the exact penalty (`α (f(v) − Σ wₖ f(k))²`) would add fill outside the factor's
//! pattern. Instead the factor is kept, with `v` constrained as before, and only its Dirichlet
//! value moves: a fixed-point iteration from today's value (target − source), each step one
//! back-substitution of the change in the glued values alone, until no glued value changes by
//! more than [`GLUE_TOLERANCE`] (or after [`MAX_GLUE_ITERATIONS`] steps). The step maps glued
//! values through the harmonic measure of the glued set seen from the lower triangles'
//! corners, which is below 1 while any boundary vertex keeps its target value, so the
//! iteration contracts. Nothing is switched: a fold that moves only changes values.

use glam::DVec2;


use super::{BoundaryData, HAT_SAMPLE_SPACING};
use crate::mesh::Mesh;
use crate::pixels::FloatImage;
use crate::raster::Beneath;
use crate::solve::PenaltyFactor;

/// The iteration stops once no glued Dirichlet value changes by more than this (colour units
/// in [0, 1]: a 4000th of an 8-bit level, a 15th of a 16-bit one).
pub const GLUE_TOLERANCE: f64 = 1e-6;

/// Number of colour channels the membrane carries (alpha is never cloned).
pub const MEMBRANE_CHANNELS: usize = 3;

/// Back-substitutions one glue solve may add at most; a contraction as weak as 0.8 per step
/// still reaches [`GLUE_TOLERANCE`] from a full-range start within this many.
pub const MAX_GLUE_ITERATIONS: usize = 64;

/// What a glue solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GlueStats {
    /// Constrained boundary vertices whose value continues the patch beneath them.
    pub glued: usize,
    /// Back-substitutions added to the membrane solve.
    pub iterations: usize,
}

/// One glued vertex: where it lies over the lower layer and the source value there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GluedVertex {
    pub beneath: Beneath,
    /// `s(q)`: the source beneath, sampled as the vertex's own boundary datum is.
    pub source_beneath: [f32; 3],
}

/// The placed frame the glue is found in.
#[derive(Clone, Copy)]
pub struct GlueFrame<'a> {
    pub rest: &'a [DVec2],
    pub placed: &'a [DVec2],
    pub triangles: &'a [[u32; 3]],
    pub depth: &'a [f32],
}

/// The glued vertices of the last frame and the buffers of their query and solve.
pub struct Glue {
    kind: BoundaryData,
    /// Per boundary slot: its neighbours along its loop (`u32::MAX` where there is none).
    neighbours: Vec<[u32; 2]>,
    glued: Vec<GluedVertex>,
    /// Per glued vertex: its Dirichlet value in the last solve.
    current: Vec<[f64; 3]>,
    /// The change of the glued values, n×3 column-major, zero elsewhere.
    correction: Vec<f64>,
}

impl Glue {
    /// The boundary neighbours of `boundary` (slot order) in `mesh`'s loops.
    pub fn new(mesh: &Mesh, boundary: &[u32], kind: BoundaryData) -> Self {
        let mut slot_of = vec![u32::MAX; mesh.vertex_count()];
        for (slot, &v) in boundary.iter().enumerate() {
            slot_of[v as usize] = slot as u32;
        }
        let mut neighbours = vec![[u32::MAX; 2]; boundary.len()];
        for boundary_loop in &mesh.loops {
            let vertices = &boundary_loop.vertices;
            for (i, &from) in vertices.iter().enumerate() {
                let to = vertices[(i + 1) % vertices.len()];
                for (end, other) in [(from, to), (to, from)] {
                    if let Some(slot) = neighbours.get_mut(slot_of[end as usize] as usize) {
                        if let Some(free) = slot.iter_mut().find(|s| **s == u32::MAX) {
                            *free = other;
                        }
                    }
                }
            }
        }
        Self {
            kind,
            neighbours,
            glued: Vec::new(),
            current: Vec::new(),
            correction: Vec::new(),
        }
    }

    /// No glue (a rigid clone, or no depth).
    pub fn clear(&mut self) {
        self.glued.clear();
    }

    /// The glued candidates of the last [`find`](Self::find) (constrained or not).
    pub fn glued(&self) -> &[GluedVertex] {
        &self.glued
    }

    /// Takes the boundary vertices found over a lower layer of the patch in `frame`
    /// (`raster::boundary_layers`' answer) and samples `source` beneath them.
    pub fn find(&mut self, frame: GlueFrame, found: &[Beneath], source: &FloatImage) {
        self.glued.clear();
        for &beneath in found {
            let source_beneath = self.sample_beneath(frame, &beneath, source);
            self.glued.push(GluedVertex {
                beneath,
                source_beneath,
            });
        }
    }

    /// `s(q)`: the source under the lower triangle's affine map (placed → rest), at the
    /// vertex or averaged with its hat along its placed boundary edges (trapezoid rule with
    /// the boundary data's spacing, as [`BoundarySampler`](super::BoundarySampler) does).
    fn sample_beneath(&self, frame: GlueFrame, hit: &Beneath, source: &FloatImage) -> [f32; 3] {
        let corners = hit.triangle.map(|k| frame.placed[k as usize]);
        let rest = hit.triangle.map(|k| frame.rest[k as usize]);
        let to_rest = |p: DVec2| {
            let w = barycentric(corners, p);
            rest[0] * w[0] + rest[1] * w[1] + rest[2] * w[2]
        };
        let sample = |p: DVec2| {
            let r = to_rest(p);
            let c = source.sample_bilinear(r.x, r.y);
            [c[0], c[1], c[2]].map(f64::from)
        };
        let v = hit.vertex as usize;
        let own = frame.placed[v];
        let neighbours = self.neighbours[hit.slot as usize];
        if self.kind == BoundaryData::Vertex || neighbours.contains(&u32::MAX) {
            return sample(own).map(|c| c as f32);
        }
        let (mut sum, mut mass) = ([0.0f64; 3], 0.0);
        for u in neighbours.map(|u| u as usize) {
            let length = (frame.rest[u] - frame.rest[v]).length();
            let intervals = (length / HAT_SAMPLE_SPACING - 1e-9).ceil().max(1.0);
            let step = length / intervals;
            let mut add = |p: DVec2, weight: f64| {
                for (s, c) in sum.iter_mut().zip(sample(p)) {
                    *s += weight * c;
                }
            };
            add(own, 0.5 * step);
            for j in 1..intervals as u32 {
                let t = f64::from(j) / intervals;
                add(own.lerp(frame.placed[u], t), (1.0 - t) * step);
            }
            mass += 0.5 * length;
        }
        if mass > 0.0 {
            sum.map(|s| (s / mass) as f32)
        } else {
            sample(own).map(|c| c as f32)
        }
    }

    /// Moves the glued vertices' Dirichlet values to the composite beneath them until they
    /// hold to [`GLUE_TOLERANCE`] (see the module doc). On entry `values` (n×3
    /// column-major) is the membrane solved with `initial[slot]` at every constrained
    /// boundary slot; on exit it is the glued membrane. `own[slot]` is `s(v)`.
    pub fn solve(
        &mut self,
        factor: &mut PenaltyFactor,
        values: &mut [f64],
        initial: impl Fn(usize) -> [f64; 3],
        own: &[[f32; 3]],
    ) -> GlueStats {
        let n = factor.n();
        self.glued
            .retain(|g| factor.is_constrained(g.beneath.vertex as usize));
        let mut stats = GlueStats {
            glued: self.glued.len(),
            iterations: 0,
        };
        if self.glued.is_empty() {
            return stats;
        }
        self.current.clear();
        self.current
            .extend(self.glued.iter().map(|g| initial(g.beneath.slot as usize)));
        self.correction.clear();
        self.correction.resize(n * MEMBRANE_CHANNELS, 0.0);
        while self.next_correction(values, own, n) > GLUE_TOLERANCE
            && stats.iterations < MAX_GLUE_ITERATIONS
        {
            factor.solve_dirichlet(&mut self.correction, MEMBRANE_CHANNELS);
            for (value, change) in values.iter_mut().zip(&mut self.correction) {
                *value += *change;
                *change = 0.0;
            }
            stats.iterations += 1;
        }
        stats
    }

    /// Writes each glued vertex's change of Dirichlet value into `correction` (which is zero
    /// elsewhere) and into `current`; gives the largest change.
    fn next_correction(&mut self, values: &[f64], own: &[[f32; 3]], n: usize) -> f64 {
        let mut largest = 0.0f64;
        for (g, current) in self.glued.iter().zip(&mut self.current) {
            let [a, b, c] = g.beneath.triangle.map(|k| k as usize);
            let w = g.beneath.weights;
            let v = g.beneath.vertex as usize;
            for ch in 0..MEMBRANE_CHANNELS {
                let column = &values[ch * n..(ch + 1) * n];
                let beneath = w[0] * column[a] + w[1] * column[b] + w[2] * column[c];
                let wanted = f64::from(g.source_beneath[ch]) + beneath
                    - f64::from(own[g.beneath.slot as usize][ch]);
                let change = wanted - current[ch];
                current[ch] = wanted;
                self.correction[ch * n + v] = change;
                largest = largest.max(change.abs());
            }
        }
        largest
    }
}

/// Barycentric weights of `p` in the triangle `corners` (any point, any orientation; the
/// corners of a triangle found by the query span a positive area).
fn barycentric(corners: [DVec2; 3], p: DVec2) -> [f64; 3] {
    let [a, b, c] = corners;
    let area = (b - a).perp_dot(c - a);
    [
        (c - b).perp_dot(p - b) / area,
        (a - c).perp_dot(p - c) / area,
        (b - a).perp_dot(p - a) / area,
    ]
}
