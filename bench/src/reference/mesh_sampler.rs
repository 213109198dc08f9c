//! Reads a per-vertex mesh function back at pixel centres, so a mesh membrane can be
//! compared pixel by pixel with the pixel-grid reference. It takes a [`Mesh`] in pixel
//! coordinates and a [`GridMask`] and gives, once per mesh, the triangle and barycentric
//! weights of every mask pixel centre ([`MeshSampler::new`]); then, per membrane, the linear
//! interpolation of per-vertex values at those centres ([`MeshSampler::interpolate`]).
//!
//! This is the membrane the renderer draws at identity placement (linear inside triangles,
//! pixel-centre sampling), computed here in `f64` without the raster's 8/16-bit canvas, its
//! anti-aliased silhouette blending or its clamping, so PSNR measures the membrane alone.
//!
//! Centres inside (or on the edge of) a triangle are *covered*: they take that triangle's
//! barycentric interpolation, the first triangle in mesh order winning on shared edges
//! (the interpolant is continuous there, so the choice does not change the value). A mask
//! pixel whose centre lies in no triangle is *uncovered*; like the raster, it is given the
//! value of the nearest triangle's affine function extrapolated to the centre (searched
//! within [`EXTRAPOLATION_REACH_PX`]); farther than that it gets 0 (the counts say so).

use glam::DVec2;

use super::GridMask;
use lapclone::mesh::Mesh;

/// How far (px) from a triangle an uncovered centre may be and still extrapolate from it.
pub const EXTRAPOLATION_REACH_PX: f64 = 2.0;

/// Relative barycentric slack under which a centre on an edge counts as inside.
const EDGE_SLACK: f64 = 1e-12;

/// One sampled pixel: its row-major index, three vertices and their weights.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Tap {
    pixel: u32,
    vertices: [u32; 3],
    weights: [f64; 3],
}

/// Barycentric taps of every mask pixel centre of one mesh (see the module doc).
#[derive(Clone, Debug)]
pub struct MeshSampler {
    width: usize,
    height: usize,
    vertex_count: usize,
    taps: Vec<Tap>,
    covered: Vec<bool>,
    uncovered: usize,
    unreached: usize,
}

impl MeshSampler {
    /// Locates every mask pixel centre in the mesh (once per mesh).
    pub fn new(mesh: &Mesh, mask: GridMask<'_>) -> Self {
        let (width, height) = (mask.width(), mask.height());
        let mut tap_of_pixel: Vec<Option<Tap>> = vec![None; mask.pixel_count()];
        let mut covered = vec![false; mask.pixel_count()];
        for t in &mesh.triangles {
            let corners = t.map(|v| mesh.positions[v as usize]);
            for p in centres_near(&corners, 0.0, width, height) {
                if !mask.is_inside(p) || covered[p] {
                    continue;
                }
                let weights = barycentric(&corners, centre_of(p, width));
                if weights.iter().all(|&w| w >= -EDGE_SLACK) {
                    covered[p] = true;
                    tap_of_pixel[p] = Some(tap(p, *t, weights));
                }
            }
        }
        let unreached = extrapolate_uncovered(mesh, mask, &covered, &mut tap_of_pixel);
        let uncovered = (0..mask.pixel_count())
            .filter(|&p| mask.is_inside(p) && !covered[p])
            .count();
        Self {
            width,
            height,
            vertex_count: mesh.vertex_count(),
            taps: tap_of_pixel.into_iter().flatten().collect(),
            covered,
            uncovered,
            unreached,
        }
    }

    /// `covered[p]`: mask pixel `p`'s centre lies in a triangle (false outside the mask).
    pub fn covered(&self) -> &[bool] {
        &self.covered
    }

    /// Mask pixels whose centre lies in no triangle.
    pub fn uncovered_count(&self) -> usize {
        self.uncovered
    }

    /// Uncovered mask pixels farther than [`EXTRAPOLATION_REACH_PX`] from every triangle
    /// (they read 0).
    pub fn unreached_count(&self) -> usize {
        self.unreached
    }

    /// Interpolates per-vertex `values` (`vertex × channels`, interleaved) at the mask pixel
    /// centres into `out` (`width × height × channels`, interleaved). Pixels outside the mask
    /// (and unreached ones) get 0. Allocates nothing.
    ///
    /// # Panics
    /// If `values` or `out` has the wrong length (a caller bug, not an input error).
    pub fn interpolate<T: Copy + Into<f64>>(&self, values: &[T], channels: usize, out: &mut [f64]) {
        assert_eq!(values.len(), self.vertex_count * channels, "values length");
        assert_eq!(out.len(), self.width * self.height * channels, "out length");
        out.fill(0.0);
        for tap in &self.taps {
            let o = tap.pixel as usize * channels;
            for c in 0..channels {
                out[o + c] = (0..3)
                    .map(|k| {
                        tap.weights[k] * values[tap.vertices[k] as usize * channels + c].into()
                    })
                    .sum();
            }
        }
    }
}

fn tap(pixel: usize, vertices: [u32; 3], weights: [f64; 3]) -> Tap {
    Tap {
        pixel: pixel as u32,
        vertices,
        weights,
    }
}

fn centre_of(p: usize, width: usize) -> DVec2 {
    DVec2::new((p % width) as f64 + 0.5, (p / width) as f64 + 0.5)
}

/// Row-major indices of the pixels whose centre lies in the triangle's bounding box grown by
/// `margin`, clipped to the image.
fn centres_near(
    corners: &[DVec2; 3],
    margin: f64,
    width: usize,
    height: usize,
) -> impl Iterator<Item = usize> {
    let min = corners[0].min(corners[1]).min(corners[2]) - DVec2::splat(margin);
    let max = corners[0].max(corners[1]).max(corners[2]) + DVec2::splat(margin);
    // Centre i + 0.5 ∈ [min, max] ⇔ i ∈ [min − 0.5, max − 0.5].
    let range = |lo: f64, hi: f64, size: usize| {
        let first = (lo - 0.5).ceil().max(0.0) as usize;
        let last = ((hi - 0.5).floor() + 1.0).clamp(0.0, size as f64) as usize;
        first..last.max(first)
    };
    let xs = range(min.x, max.x, width);
    let ys = range(min.y, max.y, height);
    ys.flat_map(move |y| xs.clone().map(move |x| y * width + x))
}

/// Barycentric coordinates of `x` in the triangle (any orientation; degenerate → NaNs,
/// which every comparison rejects).
fn barycentric(c: &[DVec2; 3], x: DVec2) -> [f64; 3] {
    let area = (c[1] - c[0]).perp_dot(c[2] - c[0]);
    let w1 = (x - c[0]).perp_dot(c[2] - c[0]) / area;
    let w2 = (c[1] - c[0]).perp_dot(x - c[0]) / area;
    [1.0 - w1 - w2, w1, w2]
}

/// Distance from `x` to the closed triangle (0 inside).
fn distance_to_triangle(c: &[DVec2; 3], x: DVec2, weights: &[f64; 3]) -> f64 {
    if weights.iter().all(|&w| w >= 0.0) {
        return 0.0;
    }
    (0..3)
        .map(|k| distance_to_segment(c[k], c[(k + 1) % 3], x))
        .fold(f64::INFINITY, f64::min)
}

fn distance_to_segment(a: DVec2, b: DVec2, x: DVec2) -> f64 {
    let ab = b - a;
    let t = ((x - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    if t.is_finite() {
        (a + ab * t - x).length()
    } else {
        (a - x).length()
    }
}

/// Gives every uncovered mask pixel the extrapolated weights of its nearest triangle within
/// reach (ties: first in mesh order). Returns how many found none.
fn extrapolate_uncovered(
    mesh: &Mesh,
    mask: GridMask<'_>,
    covered: &[bool],
    tap_of_pixel: &mut [Option<Tap>],
) -> usize {
    let (width, height) = (mask.width(), mask.height());
    let mut best = vec![f64::INFINITY; mask.pixel_count()];
    for t in &mesh.triangles {
        let corners = t.map(|v| mesh.positions[v as usize]);
        for p in centres_near(&corners, EXTRAPOLATION_REACH_PX, width, height) {
            if !mask.is_inside(p) || covered[p] {
                continue;
            }
            let x = centre_of(p, width);
            let weights = barycentric(&corners, x);
            if !weights.iter().all(|w| w.is_finite()) {
                continue;
            }
            let distance = distance_to_triangle(&corners, x, &weights);
            if distance <= EXTRAPOLATION_REACH_PX && distance < best[p] {
                best[p] = distance;
                tap_of_pixel[p] = Some(tap(p, *t, weights));
            }
        }
    }
    (0..mask.pixel_count())
        .filter(|&p| mask.is_inside(p) && !covered[p] && best[p].is_infinite())
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lapclone::mesh::{mesh_mask, BitMask, MeshOptions};

    #[test]
    fn linear_function_is_reproduced_at_every_covered_centre() {
        let (w, h) = (40, 30);
        let inside: Vec<bool> = (0..w * h)
            .map(|p| {
                let (x, y) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
                (x - 20.0).powi(2) / 300.0 + (y - 15.0).powi(2) / 120.0 < 1.0
            })
            .collect();
        let bits = BitMask::from_fn(w, h, |x, y| inside[y * w + x]);
        let mesh = mesh_mask(&bits, &MeshOptions::default()).unwrap().mesh;
        let mask = GridMask::new(w, h, &inside).unwrap();
        let sampler = MeshSampler::new(&mesh, mask);
        let f = |p: DVec2| 0.3 * p.x - 0.7 * p.y + 2.0;
        let values: Vec<f64> = mesh.positions.iter().map(|&p| f(p)).collect();
        let mut out = vec![0.0; w * h];
        sampler.interpolate(&values, 1, &mut out);
        assert_eq!(sampler.unreached_count(), 0);
        for p in (0..w * h).filter(|&p| inside[p]) {
            // Extrapolating an affine map is exact too, so every mask pixel matches.
            assert!((out[p] - f(centre_of(p, w))).abs() < 1e-9, "pixel {p}");
        }
    }
}
