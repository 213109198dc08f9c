//! Deform stage: takes a rest [`Mesh`](crate::mesh::Mesh) and, per frame, drag [`Handle`]s and
//! [`Pin`]s in the rest frame, and gives deformed positions (still in rest-frame pixel units)
//! and a per-vertex depth ([`Deformed`]). This is the paper's §III (Yu et al. 2004 Poisson
//! deformation): per-triangle gradients of the rest coordinates are rotated, and x and y are
//! recovered by two Poisson solves on a penalised Laplacian factored once per mesh.
//!
//! Work is split as everywhere in lapclone: [`DeformRig::new`] ([`rig`]) does the once-per-mesh
//! work — per-triangle edge weights ([`weights`]), the Laplacian assembled from them, the rest
//! centroid, and a [`PenaltyFactor`](crate::solve::PenaltyFactor) of its own (not the cloning
//! one). [`DeformRig::deform`] ([`step`]) does the per-frame work in fixed stages: rotation
//! angles ([`rotation`]), the divergence right-hand side ([`divergence`]), the constraint set
//! and targets ([`constraints`], switched by rank-1 updates), one two-column solve, and the
//! depth ([`depth`]). Once warm, a frame allocates nothing.
//!
//! # Rules (decided here; every test and caller relies on them)
//! * **Rotation.** Handle h has pivot `o` (its own `pivot`, else the area-weighted rest
//!   centroid of the whole mesh) and angle `θ_h = atan2((p0−o) × (p1−o), (p0−o)·(p1−o))`, the
//!   signed angle turning o→p0 onto o→p1 (0 when either vector is zero), or
//!   `rotation_deg.to_radians()` when given. A positive angle turns +x towards +y, which on
//!   screen (y down) is clockwise. Falloff `g_h(d) = exp(−d² / (2σ²))`, `σ = r / 2` (so
//!   `g = e⁻² ≈ 0.135` on the handle's circle). Triangle t rotates by `θ_t = Σ_h θ_h g_h(d_t)`,
//!   `d_t` = rest distance from p0 to t's centroid; `R_t` is the rotation by `θ_t`.
//! * **Divergence, consistent with the factored Laplacian.** Each triangle t owns a share
//!   `w^t_ij` of the weight of each of its edges ([`weights`]): cotangent — ½ cot of the angle
//!   opposite ij in t (0 for a degenerate triangle, and 0 in every triangle when the edge's
//!   total is negative, which is exactly the solver's clamp); combinatorial — 1 / (number of
//!   triangles on the edge). The Laplacian is assembled from these shares, so
//!   `L = Σ_t L_t` exactly, and the right-hand side is
//!   `b_i = Σ_t Σ_{j∈t, j≠i} w^t_ij R_t (p_i − p_j)`, which for cotangent shares is the paper's
//!   `½ Σ e_j · w_j`. With every `R_t = I`, `b = L p`.
//! * **Solve for the displacement.** We solve `(L + P + εI) u = b − L p + P (c − p)` for
//!   `u = x − p`, where `b − L p = Σ w^t_ij (R_t − I)(p_i − p_j)` is formed per triangle (with
//!   `cos θ − 1 = −2 sin²(θ/2)` to keep small angles accurate). Identity is then exact, not
//!   merely within the penalty error: no rotation and constraints at rest give `u = 0`
//!   bit-for-bit, and the ε regularisation pulls an unconstrained piece towards rest instead
//!   of towards the origin.
//! * **Constraints** (penalty α of the factor; a constrained vertex misses its target by at
//!   most ≈ `l_vv · range / α ≈ 1e-7 · range`). In increasing precedence (a later rule
//!   overrides an earlier one at the same vertex):
//!   1. *Far field:* a vertex where every handle's falloff is below
//!      [`DeformOptions::far_cutoff`] (default 1e-3, i.e. farther than ≈ 1.86 r from every
//!      p0) stays at rest. With no handle every vertex is far field.
//!   2. *Pins:* the vertex nearest each [`Pin`] stays at rest.
//!   3. *Handle core:* vertices within `core_fraction · r` of p0 (default 0, i.e. none) move
//!      rigidly with the handle vertex: target `p_h + (p1 − p0) + R_{θ_h}(p_v − p_h)`. A core spreads the
//!      translation over a disc instead of one vertex, allowing longer drags without
//!      inverting triangles around the handle vertex.
//!   4. *Handle vertex:* the vertex `p_h` nearest p0 (lowest index on ties) moves by the drag
//!      vector: target `p_h + (p1 − p0)`, which is p1 exactly when p0 lies on the vertex. (A
//!      target of p1 itself would make a handle with p1 = p0 move its vertex, breaking
//!      identity, and would make the mesh jump when a drag starts.) Between handles the later
//!      one in the slice wins.
//!
//!   The constrained set is switched with
//!   [`PenaltyFactor::set_constrained`](crate::solve::PenaltyFactor::set_constrained) (rank-1
//!   updates/downdates; the deform stage never asks for a refactor, though the solver's own
//!   guards may take one — reported in [`DeformStats::refactored`]); targets only enter the
//!   right-hand side. With no handle, no solve is run at all and the positions are the rest
//!   positions (unless [`DeformOptions::solve_without_handles`]).
//! * **Depth.** `depth_v = Σ_h depth_h g_h(|p_v − p0_h|)`, `depth_h` = the handle's `depth`
//!   or 1 (a dragged region comes in front); vertices held by an explicit pin get 0. Larger
//!   is nearer the viewer.
//! * **Inversion.** A triangle counts as inverted when its deformed signed area is `≤ 0`
//!   (rest triangles have positive area).

pub mod constraints;
pub mod depth;
pub mod divergence;
pub(crate) mod falloff;
pub mod inversion;
pub mod rig;
pub mod rotation;
pub mod step;
pub mod weights;

pub use rig::DeformRig;

use crate::solve::SolveError;
use glam::DVec2;

/// A drag from `from` (p0, rest frame) to `to` (p1) with falloff radius `radius` (pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Handle {
    /// Rest point (source coordinates) that is dragged.
    pub from: DVec2,
    /// Where `from` goes, in rest coordinates.
    pub to: DVec2,
    /// Falloff radius in pixels (> 0).
    pub radius: f64,
    /// Rotation centre o; `None`: the rest centroid of the mesh.
    pub pivot: Option<DVec2>,
    /// Replaces the angle θ_h derived from o, p0, p1 (degrees, + turns +x towards +y).
    pub rotation_deg: Option<f64>,
    /// Depth of the dragged region (default 1: in front of the undragged patch at 0).
    pub depth: Option<f32>,
}

impl Handle {
    /// A plain drag: default pivot, derived angle, default depth.
    pub fn drag(from: DVec2, to: DVec2, radius: f64) -> Self {
        Self {
            from,
            to,
            radius,
            pivot: None,
            rotation_deg: None,
            depth: None,
        }
    }
}

/// Holds the mesh vertex nearest this rest-frame point at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pin(pub DVec2);

/// Rig settings; see the rules in the module doc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeformOptions {
    /// Falloff below which a vertex counts as far field and is held at rest.
    pub far_cutoff: f64,
    /// Radius of the rigid handle core as a fraction of the handle radius (0: vertex only).
    pub core_fraction: f64,
    /// Run the solve even when there is no handle (all vertices then are far field); used to
    /// check that the solve path itself reproduces the rest mesh.
    pub solve_without_handles: bool,
    /// Penalty settings of the deformation's own factor.
    pub penalty: crate::solve::PenaltyOptions,
}

impl Default for DeformOptions {
    fn default() -> Self {
        Self {
            far_cutoff: 1e-3,
            core_fraction: 0.0,
            solve_without_handles: false,
            penalty: crate::solve::PenaltyOptions::default(),
        }
    }
}

/// One frame's result, reused across frames (no allocation once warm).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Deformed {
    /// Deformed vertex positions in rest-frame pixel units.
    pub positions: Vec<DVec2>,
    /// Per-vertex depth, larger is nearer the viewer.
    pub depth: Vec<f32>,
}

/// What one [`DeformRig::deform`] call did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DeformStats {
    /// Whether the two Poisson solves ran (false: positions were copied from rest).
    pub solved: bool,
    /// Constrained vertices after this frame.
    pub constrained: usize,
    /// Constraints switched on (rank-1 updates) this frame.
    pub updates: usize,
    /// Constraints switched off (rank-1 downdates) this frame.
    pub downdates: usize,
    /// Whether a solver guard rebuilt the factor (never requested by the deform stage).
    pub refactored: bool,
}

impl DeformStats {
    /// Constraint switches this frame (updates + downdates).
    pub fn switches(&self) -> usize {
        self.updates + self.downdates
    }
}

/// Everything that can go wrong in the deform stage.
#[derive(Debug, thiserror::Error)]
pub enum DeformError {
    /// The mesh has no vertices.
    #[error("cannot deform an empty mesh")]
    EmptyMesh,
    /// The mesh breaks an invariant the rig needs.
    #[error("mesh is not valid for deformation: {0}")]
    InvalidMesh(String),
    /// A handle is unusable (not finite, radius not positive).
    #[error("handle {index}: {reason}")]
    InvalidHandle {
        /// Position of the handle in the slice given.
        index: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// A pin has a non-finite coordinate.
    #[error("pin {index}: coordinates must be finite")]
    InvalidPin {
        /// Position of the pin in the slice given.
        index: usize,
    },
    /// The [`DeformOptions`] are out of range.
    #[error("invalid deform options: {0}")]
    InvalidOptions(String),
    /// The deformation's solver failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// The rest frame's falloff `g(d²) = exp(−d² / (2σ²))` with `σ = r / 2`, as `1 / (2σ²)`.
pub(crate) fn falloff_rate(radius: f64) -> f64 {
    let sigma = 0.5 * radius;
    1.0 / (2.0 * sigma * sigma)
}
