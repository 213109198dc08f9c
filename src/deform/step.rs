//! The per-frame deformation: takes handles and pins and gives deformed positions and depth
//! in a reused [`Deformed`], running rotation → divergence → constraints (rank-1 switches) →
//! one two-column solve → depth (rules in [`deform`](super)). No allocation once warm.

use super::rig::DeformRig;
use super::{DeformError, DeformStats, Deformed, Handle, Pin};
use glam::DVec2;

impl DeformRig {
    /// Deforms the rest mesh by `handles` and `pins` into `out` (resized to n on first use).
    /// On error `out` is left unchanged.
    pub fn deform(
        &mut self,
        handles: &[Handle],
        pins: &[Pin],
        out: &mut Deformed,
    ) -> Result<DeformStats, DeformError> {
        self.prepare_handles(handles)?;
        self.update_falloff(handles);
        self.choose_constraints(handles, pins)?;
        let n = self.rest.len();
        out.positions.resize(n, DVec2::ZERO);
        out.depth.resize(n, 0.0);
        let mut stats = DeformStats::default();
        if handles.is_empty() && !self.options.solve_without_handles {
            out.positions.copy_from_slice(&self.rest);
        } else {
            self.triangle_angles();
            self.divergence_rhs();
            let switched = self.apply_constraints()?;
            stats.updates = switched.updates;
            stats.downdates = switched.downdates;
            stats.refactored = switched.refactored;
            stats.solved = true;
            self.factor.solve_in_place(&mut self.rhs, 2);
            let (xs, ys) = self.rhs.split_at(n);
            for (v, out_p) in out.positions.iter_mut().enumerate() {
                *out_p = self.rest[v] + DVec2::new(xs[v], ys[v]);
            }
        }
        stats.constrained = self.factor.constrained_count();
        self.vertex_depth(handles.len(), &mut out.depth);
        Ok(stats)
    }
}
