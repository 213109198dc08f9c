//! Lucas–Kanade alignment of a square template (translation only, inverse compositional):
//! takes a template cut from one frame's pyramid level and a level of another frame, and
//! gives the sub-pixel position where the template fits, plus the normalised
//! cross-correlation there (the match's confidence) and the template's contrast (how much
//! texture it has to lock on to).

use glam::DVec2;

use super::pyramid::Level;

/// Iterations per level before giving up on convergence.
const MAX_ITERATIONS: usize = 30;
/// A step shorter than this (pixels at the level) ends the iterations.
const STEP_DONE: f64 = 1e-3;

/// A square of grey values around a point with its gradients and their Hessian (fixed for
/// every iteration: the inverse-compositional form never recomputes them).
#[derive(Clone)]
pub(super) struct Template {
    half: i32,
    values: Vec<f32>,
    gx: Vec<f32>,
    gy: Vec<f32>,
    /// The inverse of Σ ∇T ∇Tᵀ, or `None` when it is singular (no texture).
    inverse: Option<[f64; 3]>,
    /// The inverse of the similarity warp's 4 × 4 Hessian, or `None` when singular.
    similarity_inverse: Option<[[f64; 4]; 4]>,
    /// Standard deviation of the values.
    pub(super) contrast: f64,
}

impl Template {
    /// The `(2 half + 1)²` template centred on `centre` (level coordinates).
    pub(super) fn cut(level: &Level, centre: DVec2, half: i32) -> Template {
        let side = (2 * half + 1) as usize;
        let mut values = Vec::with_capacity(side * side);
        let mut gx = Vec::with_capacity(side * side);
        let mut gy = Vec::with_capacity(side * side);
        let (mut sxx, mut sxy, mut syy) = (0.0f64, 0.0f64, 0.0f64);
        for j in -half..=half {
            for i in -half..=half {
                let p = centre + DVec2::new(f64::from(i), f64::from(j));
                values.push(level.sample(p));
                let dx = 0.5 * (level.sample(p + DVec2::X) - level.sample(p - DVec2::X));
                let dy = 0.5 * (level.sample(p + DVec2::Y) - level.sample(p - DVec2::Y));
                gx.push(dx);
                gy.push(dy);
                sxx += f64::from(dx * dx);
                sxy += f64::from(dx * dy);
                syy += f64::from(dy * dy);
            }
        }
        let det = sxx * syy - sxy * sxy;
        // Relative to the trace²: a determinant this small means one direction (or none) has
        // texture, and the step along the other would be noise.
        let inverse = (det > 1e-9 * (sxx + syy).powi(2) && det > 0.0)
            .then(|| [syy / det, -sxy / det, sxx / det]);
        let contrast = std_dev(&values);
        let mut template = Template {
            half,
            values,
            gx,
            gy,
            inverse,
            similarity_inverse: None,
            contrast,
        };
        template.similarity_inverse = template.similarity_hessian().and_then(invert4);
        template
    }

    /// The similarity warp's steepest-descent row at pixel `k`, offset `(i, j)`.
    fn steepest(&self, k: usize, i: i32, j: i32) -> [f64; 4] {
        let (x, y) = (f64::from(i), f64::from(j));
        let (gx, gy) = (f64::from(self.gx[k]), f64::from(self.gy[k]));
        [gx, gy, gx * x + gy * y, gy * x - gx * y]
    }

    fn similarity_hessian(&self) -> Option<[[f64; 4]; 4]> {
        self.inverse?;
        let mut h = [[0.0; 4]; 4];
        let mut k = 0;
        for j in -self.half..=self.half {
            for i in -self.half..=self.half {
                let s = self.steepest(k, i, j);
                for (row, sr) in h.iter_mut().zip(s) {
                    for (cell, sc) in row.iter_mut().zip(s) {
                        *cell += sr * sc;
                    }
                }
                k += 1;
            }
        }
        Some(h)
    }

    /// Refines position `start` and shape `m` (the template's offset d appears at
    /// `p + [[m0, −m1], [m1, m0]] d`: a turn and a scale) until the template fits `level`;
    /// `None` without texture, on divergence, or when the shape leaves ¼–4× scale.
    pub(super) fn align_similarity(
        &self,
        level: &Level,
        start: DVec2,
        m: [f64; 2],
    ) -> Option<(DVec2, [f64; 2])> {
        let inverse = self.similarity_inverse?;
        let (mut p, mut m) = (start, m);
        for _ in 0..MAX_ITERATIONS {
            let mut b = [0.0f64; 4];
            let mut k = 0;
            for j in -self.half..=self.half {
                for i in -self.half..=self.half {
                    let error = f64::from(level.sample(p + warp(m, i, j)) - self.values[k]);
                    let s = self.steepest(k, i, j);
                    for (br, sr) in b.iter_mut().zip(s) {
                        *br += sr * error;
                    }
                    k += 1;
                }
            }
            let d: [f64; 4] = std::array::from_fn(|r| (0..4).map(|c| inverse[r][c] * b[c]).sum());
            if d.iter().any(|v| !v.is_finite()) {
                return None;
            }
            // Compose with the inverse of the step: M ← M (I + A)⁻¹, p ← p − M t.
            let (a, bb) = (1.0 + d[2], d[3]);
            let det = a * a + bb * bb;
            let inv = [a / det, -bb / det];
            m = [m[0] * inv[0] - m[1] * inv[1], m[0] * inv[1] + m[1] * inv[0]];
            p -= DVec2::new(m[0] * d[0] - m[1] * d[1], m[1] * d[0] + m[0] * d[1]);
            let scale = (m[0] * m[0] + m[1] * m[1]).sqrt();
            if !(0.25..=4.0).contains(&scale) {
                return None;
            }
            let step = d[0].hypot(d[1]) + f64::from(self.half) * d[2].hypot(d[3]);
            if step < STEP_DONE {
                break;
            }
        }
        Some((p, m))
    }

    /// [`correlation`](Self::correlation) with the template warped by shape `m`.
    pub(super) fn correlation_warped(&self, level: &Level, p: DVec2, m: [f64; 2]) -> f64 {
        let mut seen = Vec::with_capacity(self.values.len());
        for j in -self.half..=self.half {
            for i in -self.half..=self.half {
                seen.push(level.sample(p + warp(m, i, j)));
            }
        }
        ncc(&self.values, &seen)
    }

    /// Refines `start` (level coordinates) until the template fits `level` there; `None`
    /// when the template has no texture or the iterations diverge.
    pub(super) fn align(&self, level: &Level, start: DVec2) -> Option<DVec2> {
        let [a, b, c] = self.inverse?;
        let mut p = start;
        for _ in 0..MAX_ITERATIONS {
            let (mut bx, mut by) = (0.0f64, 0.0f64);
            let mut k = 0;
            for j in -self.half..=self.half {
                for i in -self.half..=self.half {
                    let q = p + DVec2::new(f64::from(i), f64::from(j));
                    let error = level.sample(q) - self.values[k];
                    bx += f64::from(self.gx[k] * error);
                    by += f64::from(self.gy[k] * error);
                    k += 1;
                }
            }
            let step = DVec2::new(a * bx + b * by, b * bx + c * by);
            if !step.is_finite() {
                return None;
            }
            p -= step;
            if step.length() < STEP_DONE {
                break;
            }
        }
        Some(p)
    }

    /// Normalised cross-correlation of the template with `level` at `p`, in [−1, 1]; 0 when
    /// either side is flat (nothing to correlate).
    pub(super) fn correlation(&self, level: &Level, p: DVec2) -> f64 {
        self.correlation_warped(level, p, [1.0, 0.0])
    }
}

/// Offset `(i, j)` under shape `m`.
#[inline]
fn warp(m: [f64; 2], i: i32, j: i32) -> DVec2 {
    let (x, y) = (f64::from(i), f64::from(j));
    DVec2::new(m[0] * x - m[1] * y, m[1] * x + m[0] * y)
}

/// The inverse of a symmetric 4 × 4 matrix (Gauss–Jordan with partial pivoting).
fn invert4(mut a: [[f64; 4]; 4]) -> Option<[[f64; 4]; 4]> {
    let mut inv = [[0.0; 4]; 4];
    for (r, row) in inv.iter_mut().enumerate() {
        row[r] = 1.0;
    }
    let scale = (0..4).map(|r| a[r][r].abs()).fold(0.0, f64::max);
    for c in 0..4 {
        let pivot = (c..4).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[pivot][c].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(c, pivot);
        inv.swap(c, pivot);
        let d = a[c][c];
        a[c] = a[c].map(|v| v / d);
        inv[c] = inv[c].map(|v| v / d);
        let (pivot_row, pivot_inv) = (a[c], inv[c]);
        for (r, (row, inv_row)) in a.iter_mut().zip(inv.iter_mut()).enumerate() {
            if r != c {
                let f = row[c];
                for (v, p) in row.iter_mut().zip(pivot_row) {
                    *v -= f * p;
                }
                for (v, p) in inv_row.iter_mut().zip(pivot_inv) {
                    *v -= f * p;
                }
            }
        }
    }
    Some(inv)
}

fn mean(values: &[f32]) -> f64 {
    values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64
}

fn std_dev(values: &[f32]) -> f64 {
    let m = mean(values);
    let var = values
        .iter()
        .map(|&v| (f64::from(v) - m).powi(2))
        .sum::<f64>()
        / values.len() as f64;
    var.sqrt()
}

/// Normalised cross-correlation of two equally long value lists.
fn ncc(a: &[f32], b: &[f32]) -> f64 {
    let (ma, mb) = (mean(a), mean(b));
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (&x, &y) in a.iter().zip(b) {
        let (x, y) = (f64::from(x) - ma, f64::from(y) - mb);
        ab += x * y;
        aa += x * x;
        bb += y * y;
    }
    // A flat side (all values within float noise) correlates with nothing.
    let floor = 1e-10 * a.len() as f64;
    if aa <= floor || bb <= floor {
        return 0.0;
    }
    ab / (aa * bb).sqrt()
}

#[cfg(test)]
mod tests {
    use super::super::pyramid::Pyramid;
    use super::*;
    use crate::pixels::{FloatImage, PixelFormat};

    /// A smooth, textured grey image shifted by `shift`.
    fn blobs(shift: DVec2) -> FloatImage {
        FloatImage::from_fn(96, 96, PixelFormat::RGBA8, |i, j| {
            let (x, y) = (f64::from(i) + 0.5 - shift.x, f64::from(j) + 0.5 - shift.y);
            let v = 0.5 + 0.2 * (x * 0.31).sin() * (y * 0.23).cos() + 0.1 * ((x + y) * 0.17).sin();
            let v = v as f32;
            [v, v, v, 1.0]
        })
        .unwrap()
    }

    #[test]
    fn aligns_a_sub_pixel_shift() {
        let centre = DVec2::new(48.0, 48.0);
        let shift = DVec2::new(1.37, -0.62);
        let a = Pyramid::around(&blobs(DVec2::ZERO), centre, 30.0, 1);
        let b = Pyramid::around(&blobs(shift), centre, 30.0, 1);
        let template = Template::cut(&a.levels[0], centre, 7);
        let found = template.align(&b.levels[0], centre).unwrap();
        assert!((found - (centre + shift)).length() < 0.02, "{found}");
        assert!(template.correlation(&b.levels[0], found) > 0.999);
    }

    #[test]
    fn aligns_a_turn_and_a_scale() {
        // b shows a turned by 4° and grown by 5 % about the centre.
        let centre = DVec2::new(48.0, 48.0);
        let a = Pyramid::around(&blobs(DVec2::ZERO), centre, 40.0, 1);
        let (turn, grow) = (4f64.to_radians(), 1.05);
        let turned = FloatImage::from_fn(96, 96, PixelFormat::RGBA8, |i, j| {
            let p = DVec2::new(f64::from(i) + 0.5, f64::from(j) + 0.5) - centre;
            let q = centre + DVec2::from_angle(-turn).rotate(p) / grow;
            let v = a.levels[0].sample(q);
            [v, v, v, 1.0]
        })
        .unwrap();
        let b = Pyramid::around(&turned, centre, 40.0, 1);
        let template = Template::cut(&a.levels[0], centre, 10);
        let start = centre + DVec2::new(0.4, -0.3);
        let (found, m) = template.align_similarity(&b.levels[0], start, [1.0, 0.0]).unwrap();
        assert!(found.distance(centre) < 0.05, "{found}");
        let (scale, angle) = (m[0].hypot(m[1]), m[1].atan2(m[0]));
        assert!((scale - grow).abs() < 0.005, "{scale}");
        assert!((angle - turn).abs() < 0.005, "{angle}");
    }
}
