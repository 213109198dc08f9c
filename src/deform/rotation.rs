//! Rotation angles: takes the handles of one frame and gives each handle's angle θ_h, falloff
//! rate and nearest vertex, then every triangle's angle `θ_t = Σ_h θ_h g_h(d_t)` (rules in
//! [`deform`](super)).

use super::rig::{DeformRig, HandleFrame};
use super::{falloff_rate, DeformError, Handle};
use glam::DVec2;

/// Signed angle turning `a` onto `b` (0 when either is zero).
pub fn signed_angle(a: DVec2, b: DVec2) -> f64 {
    a.perp_dot(b).atan2(a.dot(b))
}

/// Rejects non-finite coordinates, non-positive radii and non-finite overrides.
pub fn validate_handle(index: usize, h: &Handle) -> Result<(), DeformError> {
    let bad = |reason: &str| {
        Err(DeformError::InvalidHandle {
            index,
            reason: reason.to_string(),
        })
    };
    if !(h.from.is_finite() && h.to.is_finite()) {
        return bad("from/to must be finite");
    }
    if !(h.radius.is_finite() && h.radius > 0.0) {
        return bad("radius must be finite and positive");
    }
    if h.pivot.is_some_and(|p| !p.is_finite()) {
        return bad("pivot must be finite");
    }
    if h.rotation_deg.is_some_and(|r| !r.is_finite()) {
        return bad("rotation must be finite");
    }
    if h.depth.is_some_and(|d| !d.is_finite()) {
        return bad("depth must be finite");
    }
    Ok(())
}

impl DeformRig {
    /// Validates the handles and fills `self.frames` (reused; grows only with the count).
    pub(crate) fn prepare_handles(&mut self, handles: &[Handle]) -> Result<(), DeformError> {
        for (i, h) in handles.iter().enumerate() {
            validate_handle(i, h)?;
        }
        // ln(1/cutoff) turns g < cutoff into d² > 2σ² ln(1/cutoff).
        let far_log = -self.options.far_cutoff.ln();
        self.frames.clear();
        for h in handles {
            let pivot = h.pivot.unwrap_or(self.rest_centroid);
            let theta = match h.rotation_deg {
                Some(deg) => deg.to_radians(),
                None => signed_angle(h.from - pivot, h.to - pivot),
            };
            let rate = falloff_rate(h.radius);
            let core = self.options.core_fraction * h.radius;
            self.frames.push(HandleFrame {
                vertex: self.nearest_vertex(h.from),
                theta,
                rate,
                far_d2: far_log / rate,
                core_d2: core * core,
                depth: h.depth.unwrap_or(1.0),
            });
        }
        Ok(())
    }

    /// `self.theta[t] = Σ_h θ_h exp(−rate_h |c_t − p0_h|²)`, the exponentials from
    /// [`update_falloff`](DeformRig::update_falloff).
    pub(crate) fn triangle_angles(&mut self) {
        self.theta.iter_mut().for_each(|a| *a = 0.0);
        for (frame, falloff) in self.frames.iter().zip(&self.falloff) {
            if frame.theta == 0.0 {
                continue;
            }
            for (angle, weight) in self.theta.iter_mut().zip(&falloff.triangles) {
                *angle += frame.theta * weight;
            }
        }
    }
}
