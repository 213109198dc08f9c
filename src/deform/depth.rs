//! Per-vertex depth: takes the frame's handles and the pinned flags and gives
//! `depth_v = Σ_h depth_h g_h(|p_v − p0_h|)` (larger is nearer the viewer; default
//! `depth_h = 1`), 0 at vertices held by an explicit pin (rules in [`deform`](super)).

use super::rig::DeformRig;

impl DeformRig {
    /// Writes the depth of every vertex into `depth` (length n), for the `handles` count of
    /// handles whose frames and falloff weights are up to date.
    pub(crate) fn vertex_depth(&self, handles: usize, depth: &mut [f32]) {
        let slots = self.frames.iter().zip(&self.falloff).take(handles);
        for (v, out) in depth.iter_mut().enumerate() {
            *out = if self.pinned[v] {
                0.0
            } else {
                slots
                    .clone()
                    .map(|(f, falloff)| f64::from(f.depth) * falloff.vertices[v])
                    .sum::<f64>() as f32
            };
        }
    }
}
