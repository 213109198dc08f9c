//! Gaussian falloff weights: takes the frame's handles (their grab points and rates, from
//! [`prepare_handles`](DeformRig::prepare_handles)) and gives `g_h = exp(−rate_h |x − p0_h|²)`
//! of each handle at every triangle centroid and every vertex, which the triangle angles and
//! the vertex depths multiply by. The weights are kept between frames and recomputed only for
//! a handle whose grab point or rate changed: an interactive drag moves p1 and keeps p0, so
//! its frames evaluate no exponential. A kept weight is the value a fresh evaluation gives,
//! bit for bit (same inputs, same expression).

use glam::DVec2;

use super::rig::DeformRig;
use super::Handle;

/// One handle slot's weights and the grab point and rate they were computed for.
#[derive(Debug, Default)]
pub(crate) struct HandleFalloff {
    /// `(p0, rate)` as bits; `None`: nothing computed yet.
    key: Option<([u64; 2], u64)>,
    /// Weight at each triangle centroid.
    pub triangles: Vec<f64>,
    /// Weight at each vertex.
    pub vertices: Vec<f64>,
}

/// `exp(−rate |x − from|²)`: the one expression both the fresh and the kept weights come from.
#[inline]
pub(crate) fn gaussian(rate: f64, x: DVec2, from: DVec2) -> f64 {
    (-rate * x.distance_squared(from)).exp()
}

impl DeformRig {
    /// Brings `self.falloff[h]` up to date for each of `handles` (slots grow only).
    pub(crate) fn update_falloff(&mut self, handles: &[Handle]) {
        if self.falloff.len() < handles.len() {
            self.falloff
                .resize_with(handles.len(), HandleFalloff::default);
        }
        for ((h, frame), slot) in handles.iter().zip(&self.frames).zip(&mut self.falloff) {
            let key = Some((h.from.to_array().map(f64::to_bits), frame.rate.to_bits()));
            if slot.key == key {
                continue;
            }
            slot.key = key;
            slot.triangles.clear();
            slot.triangles.extend(
                self.centroids
                    .iter()
                    .map(|&c| gaussian(frame.rate, c, h.from)),
            );
            slot.vertices.clear();
            slot.vertices
                .extend(self.rest.iter().map(|&p| gaussian(frame.rate, p, h.from)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{mesh_mask, synth, MeshOptions};
    use crate::solve::LaplacianKind;

    /// After every update, each slot in use holds exactly the fresh weights of its handle.
    #[test]
    fn kept_weights_are_the_fresh_ones_after_any_sequence_of_handles() {
        let mask = synth::disc(40, 40, 17.0);
        let mesh = mesh_mask(&mask, &MeshOptions::default()).unwrap().mesh;
        let mut rig = DeformRig::new(&mesh, LaplacianKind::Combinatorial).unwrap();
        let a = DVec2::new(15.0, 18.0);
        let b = DVec2::new(25.0, 21.0);
        let drag = |from: DVec2, to: DVec2, radius: f64| Handle::drag(from, to, radius);
        // p1 moves (weights kept), p0 moves, the radius changes, a handle is added, the
        // handles swap slots, one is dropped and comes back.
        let frames = [
            vec![drag(a, b, 10.0)],
            vec![drag(a, b + DVec2::X, 10.0)],
            vec![drag(a + DVec2::Y, b, 10.0)],
            vec![drag(a + DVec2::Y, b, 12.0)],
            vec![drag(a + DVec2::Y, b, 12.0), drag(b, a, 6.0)],
            vec![drag(b, a, 6.0), drag(a + DVec2::Y, b, 12.0)],
            vec![drag(b, a, 6.0)],
            vec![drag(b, a, 6.0), drag(a + DVec2::Y, b, 12.0)],
        ];
        for (k, handles) in frames.iter().enumerate() {
            rig.prepare_handles(handles).unwrap();
            rig.update_falloff(handles);
            for (slot, (h, frame)) in rig.falloff.iter().zip(handles.iter().zip(&rig.frames)) {
                let fresh = |points: &[DVec2]| -> Vec<u64> {
                    points
                        .iter()
                        .map(|&x| gaussian(frame.rate, x, h.from).to_bits())
                        .collect()
                };
                let bits = |w: &[f64]| -> Vec<u64> { w.iter().map(|v| v.to_bits()).collect() };
                assert_eq!(bits(&slot.triangles), fresh(&rig.centroids), "frame {k}");
                assert_eq!(bits(&slot.vertices), fresh(&rig.rest), "frame {k}");
            }
        }
    }
}
