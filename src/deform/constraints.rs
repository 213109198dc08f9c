//! Constraint set and targets: takes the frame's handles and pins and gives which vertices are
//! constrained (`wanted`) and their target displacements (`target`), in the precedence order
//! far field < pins < handle core < handle vertex (rules in [`deform`](super)); then switches
//! the factor to that set (rank-1 updates) and adds the penalty terms `α (c − p)` to the
//! right-hand side.

use super::rig::DeformRig;
use super::{DeformError, Handle, Pin};
use crate::solve::SwitchStats;
use glam::DVec2;

impl DeformRig {
    /// Fills `wanted`, `pinned` and `target` for this frame. `prepare_handles` ran first.
    pub(crate) fn choose_constraints(
        &mut self,
        handles: &[Handle],
        pins: &[Pin],
    ) -> Result<(), DeformError> {
        if let Some(index) = pins.iter().position(|p| !p.0.is_finite()) {
            return Err(DeformError::InvalidPin { index });
        }
        for (v, p) in self.rest.iter().enumerate() {
            let far = handles
                .iter()
                .zip(&self.frames)
                .all(|(h, f)| p.distance_squared(h.from) > f.far_d2);
            self.wanted[v] = far;
            self.pinned[v] = false;
            self.target[v] = DVec2::ZERO;
        }
        for pin in pins {
            let v = self.nearest_vertex(pin.0);
            self.wanted[v] = true;
            self.pinned[v] = true;
            self.target[v] = DVec2::ZERO;
        }
        for (i, h) in handles.iter().enumerate() {
            let f = self.frames[i];
            if f.core_d2 > 0.0 {
                self.constrain_core(h, f.vertex, f.theta, f.core_d2);
            }
        }
        for (h, f) in handles.iter().zip(&self.frames) {
            self.wanted[f.vertex] = true;
            self.pinned[f.vertex] = false;
            self.target[f.vertex] = h.to - h.from;
        }
        Ok(())
    }

    /// Core vertices move rigidly with the handle vertex: target `p_h + (p1 − p0) + R(p_v − p_h)`.
    fn constrain_core(&mut self, h: &Handle, vertex: usize, theta: f64, core_d2: f64) {
        let anchor = self.rest[vertex];
        let moved_anchor = anchor + (h.to - h.from);
        let rotation = glam::DVec2::from_angle(theta);
        for (v, p) in self.rest.iter().enumerate() {
            if p.distance_squared(h.from) <= core_d2 {
                self.wanted[v] = true;
                self.pinned[v] = false;
                self.target[v] = moved_anchor + rotation.rotate(*p - anchor) - *p;
            }
        }
    }

    /// Switches the factor to `wanted` and adds `α · target` at constrained rows of `rhs`.
    pub(crate) fn apply_constraints(&mut self) -> Result<SwitchStats, DeformError> {
        let stats = self.factor.set_constrained(&self.wanted)?;
        let alpha = self.factor.alpha();
        let n = self.rest.len();
        let (xs, ys) = self.rhs.split_at_mut(n);
        for v in 0..n {
            if self.wanted[v] {
                xs[v] += alpha * self.target[v].x;
                ys[v] += alpha * self.target[v].y;
            }
        }
        Ok(stats)
    }
}
