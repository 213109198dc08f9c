//! Per-vertex depth: takes the frame's handles and the pinned flags and gives
//! `depth_v = Σ_h depth_h g_h(|p_v − p0_h|)` (larger is nearer the viewer; default
//! `depth_h = 1`), 0 at vertices held by an explicit pin (rules in [`deform`](super)).

use super::rig::DeformRig;
use super::Handle;

impl DeformRig {
    /// Writes the depth of every vertex into `depth` (length n).
    pub(crate) fn vertex_depth(&self, handles: &[Handle], depth: &mut [f32]) {
        for (v, (p, out)) in self.rest.iter().zip(depth.iter_mut()).enumerate() {
            *out = if self.pinned[v] {
                0.0
            } else {
                handles
                    .iter()
                    .zip(&self.frames)
                    .map(|(h, f)| f64::from(f.depth) * (-f.rate * p.distance_squared(h.from)).exp())
                    .sum::<f64>() as f32
            };
        }
    }
}
