//! Gaussian falloff weights: takes the frame's handles (their grab points and rates, from
//! `DeformRig::prepare_handles`) and gives `g_h = exp(−rate_h |x − p0_h|²)`
//! of each handle at every triangle centroid and every vertex, which the triangle angles and
//! the vertex depths multiply by. The weights are kept between frames and recomputed only for
//! a handle whose grab point or rate changed: an interactive drag moves p1 and keeps p0, so
//! its frames evaluate no exponential. A kept weight is the value a fresh evaluation gives,
//! bit for bit (same inputs, same expression).

use glam::DVec2;

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

impl HandleFalloff {
    /// Recomputes the weights of a handle grabbed at `from` with `rate` at `centroids` and
    /// `vertices`, unless they were computed for exactly these.
    pub(crate) fn refresh(
        &mut self,
        from: DVec2,
        rate: f64,
        centroids: &[DVec2],
        vertices: &[DVec2],
    ) {
        let key = Some((from.to_array().map(f64::to_bits), rate.to_bits()));
        if self.key == key {
            return;
        }
        self.key = key;
        self.triangles.clear();
        self.triangles
            .extend(centroids.iter().map(|&c| gaussian(rate, c, from)));
        self.vertices.clear();
        self.vertices
            .extend(vertices.iter().map(|&p| gaussian(rate, p, from)));
    }
}
