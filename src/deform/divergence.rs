//! Divergence right-hand side: takes the per-triangle angles θ_t and gives, in the rig's
//! column-major n×2 buffer, `b − L p = Σ_t Σ_{j∈t} w^t_ij (R_t − I)(p_i − p_j)` — the paper's
//! `½ Σ e_j · w_j` of the rotated gradient fields minus that of the rest fields (rules in
//! [`deform`](super)). Exactly zero where θ_t = 0.

use super::rig::DeformRig;
use glam::DVec2;

/// `(cos θ − 1, sin θ)`, with `cos θ − 1 = −2 sin²(θ/2)` so small angles keep their digits.
pub fn rotation_minus_identity(theta: f64) -> (f64, f64) {
    let half = (0.5 * theta).sin();
    (-2.0 * half * half, theta.sin())
}

/// `(R_θ − I) q` from [`rotation_minus_identity`]'s pair.
#[inline]
pub fn apply_rotation_minus_identity((cos_minus_one, sin): (f64, f64), q: DVec2) -> DVec2 {
    DVec2::new(
        cos_minus_one * q.x - sin * q.y,
        sin * q.x + cos_minus_one * q.y,
    )
}

impl DeformRig {
    /// Overwrites `self.rhs` with the rotation part of the right-hand side.
    pub(crate) fn divergence_rhs(&mut self) {
        let n = self.rest.len();
        self.rhs.iter_mut().for_each(|v| *v = 0.0);
        let (xs, ys) = self.rhs.split_at_mut(n);
        for ((tri, terms), &theta) in self.triangles.iter().zip(&self.edge_terms).zip(&self.theta) {
            if theta == 0.0 {
                continue;
            }
            let rotation = rotation_minus_identity(theta);
            for k in 0..3 {
                let e = apply_rotation_minus_identity(rotation, terms[k]);
                let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
                xs[a] += e.x;
                ys[a] += e.y;
                xs[b] -= e.x;
                ys[b] -= e.y;
            }
        }
    }
}
