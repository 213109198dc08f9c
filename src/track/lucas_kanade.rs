//! Lucas–Kanade alignment of a square template (translation only, inverse compositional):
//! takes a template cut from one frame's pyramid level and a level of another frame, and
//! gives the sub-pixel position where the template fits, plus the normalised
//! cross-correlation there (the match's confidence) and the template's contrast (how much
//! texture it has to lock on to).

use glam::DVec2;

use super::pyramid::Level;

/// Iterations per level before giving up on convergence.
const MAX_ITERATIONS: usize = 30;

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
    /// What [`align_similarity`](Self::align_similarity) needs, once
    /// [`prepare_similarity`](Self::prepare_similarity) made it (only the templates that are
    /// turned and scaled pay for it).
    similarity: Option<Similarity>,
    /// Standard deviation of the values.
    pub(super) contrast: f64,
}

/// The similarity warp's steepest-descent rows, and the inverse of their 4 × 4 Hessian
/// (`None` when singular).
#[derive(Clone)]
struct Similarity {
    steepest: Vec<[f32; 4]>,
    inverse: Option<[[f64; 4]; 4]>,
}

impl Template {
    /// The `(2 half + 1)²` template centred on `centre` (level coordinates).
    pub(super) fn cut(level: &Level, centre: DVec2, half: i32) -> Template {
        let side = (2 * half + 1) as usize;
        // One grid a pixel wider on every side gives the values and their central
        // differences (the neighbours share the centre's fraction).
        let wide = side + 2;
        let mut grid = Vec::with_capacity(wide * wide);
        level.sample_grid(centre, half + 1, &mut grid);
        let mut values = Vec::with_capacity(side * side);
        let mut gx = Vec::with_capacity(side * side);
        let mut gy = Vec::with_capacity(side * side);
        let (mut sxx, mut sxy, mut syy) = (0.0f64, 0.0f64, 0.0f64);
        for r in 1..=side {
            for c in 1..=side {
                let k = r * wide + c;
                values.push(grid[k]);
                let dx = 0.5 * (grid[k + 1] - grid[k - 1]);
                let dy = 0.5 * (grid[k + wide] - grid[k - wide]);
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
        Template {
            half,
            values,
            gx,
            gy,
            inverse,
            similarity: None,
            contrast,
        }
    }

    /// Makes what [`align_similarity`](Self::align_similarity) needs: the similarity warp's
    /// steepest-descent row at every pixel and the inverse of their Hessian.
    pub(super) fn prepare_similarity(&mut self) {
        let mut steepest = Vec::with_capacity(self.values.len());
        let mut h = [[0.0f64; 4]; 4];
        let mut k = 0;
        for j in -self.half..=self.half {
            for i in -self.half..=self.half {
                let (x, y) = (i as f32, j as f32);
                let (gx, gy) = (self.gx[k], self.gy[k]);
                let s = [gx, gy, gx * x + gy * y, gy * x - gx * y];
                for (row, sr) in h.iter_mut().zip(s) {
                    for (cell, sc) in row.iter_mut().zip(s) {
                        *cell += f64::from(sr) * f64::from(sc);
                    }
                }
                steepest.push(s);
                k += 1;
            }
        }
        let inverse = self.inverse.and_then(|_| invert4(h));
        self.similarity = Some(Similarity { steepest, inverse });
    }

    /// Refines position `start` and shape `m` (the template's offset d appears at
    /// `p + [[m0, −m1], [m1, m0]] d`: a turn and a scale) until the template fits `level`,
    /// stopping when a step moves the template's corners less than `done` pixels; `None`
    /// without texture (or before [`prepare_similarity`](Self::prepare_similarity)), on
    /// divergence, or when the shape leaves ¼–4× scale.
    pub(super) fn align_similarity(
        &self,
        level: &Level,
        start: DVec2,
        m: [f64; 2],
        done: f64,
    ) -> Option<(DVec2, [f64; 2])> {
        let similarity = self.similarity.as_ref()?;
        let inverse = similarity.inverse?;
        let (mut p, mut m) = (start, m);
        let mut seen = Vec::with_capacity(self.values.len());
        let mut previous: Option<[f64; 4]> = None;
        for _ in 0..MAX_ITERATIONS {
            level.sample_warped(p, m, self.half, &mut seen);
            let b = self.similarity_errors(&similarity.steepest, &seen);
            let mut d: [f64; 4] =
                std::array::from_fn(|r| (0..4).map(|c| inverse[r][c] * b[c]).sum());
            if d.iter().any(|v| !v.is_finite()) {
                return None;
            }
            // The step in pixels: the translation, and the turn and scale at the corners.
            let h = f64::from(self.half);
            let moved = [d[0], d[1], h * d[2], h * d[3]];
            let step = d[0].hypot(d[1]) + h * d[2].hypot(d[3]);
            let factor = match previous {
                Some(last) if step >= done => speed_up(&last, &moved),
                _ => 1.0,
            };
            previous = (factor == 1.0).then_some(moved);
            d = d.map(|v| v * factor);
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
            if step < done {
                break;
            }
        }
        Some((p, m))
    }

    /// `Σ steepest · (seen − values)`, summed a row at a time in f32 and the rows in f64.
    fn similarity_errors(&self, steepest: &[[f32; 4]], seen: &[f32]) -> [f64; 4] {
        let side = (2 * self.half + 1) as usize;
        let mut b = [0.0f64; 4];
        let rows = seen.chunks_exact(side).zip(self.values.chunks_exact(side));
        for ((seen, values), steepest) in rows.zip(steepest.chunks_exact(side)) {
            let mut row = [0.0f32; 4];
            for ((&s, &v), st) in seen.iter().zip(values).zip(steepest) {
                let error = s - v;
                for (r, st) in row.iter_mut().zip(st) {
                    *r += st * error;
                }
            }
            for (br, r) in b.iter_mut().zip(row) {
                *br += f64::from(r);
            }
        }
        b
    }

    /// [`correlation`](Self::correlation) with the template warped by shape `m`.
    pub(super) fn correlation_warped(&self, level: &Level, p: DVec2, m: [f64; 2]) -> f64 {
        if m == [1.0, 0.0] {
            return self.correlation(level, p);
        }
        let mut seen = Vec::with_capacity(self.values.len());
        level.sample_warped(p, m, self.half, &mut seen);
        ncc(&self.values, &seen)
    }

    /// Refines `start` (level coordinates) until the template fits `level` there, stopping
    /// when a step is shorter than `done` pixels; `None` when the template has no texture or
    /// the iterations diverge.
    pub(super) fn align(&self, level: &Level, start: DVec2, done: f64) -> Option<DVec2> {
        let [a, b, c] = self.inverse?;
        let mut p = start;
        let mut seen = Vec::with_capacity(self.values.len());
        let mut previous = None;
        for _ in 0..MAX_ITERATIONS {
            level.sample_grid(p, self.half, &mut seen);
            let (bx, by) = weighted_errors(&self.gx, &self.gy, &seen, &self.values);
            let step = DVec2::new(a * bx + b * by, b * bx + c * by);
            if !step.is_finite() {
                return None;
            }
            if step.length() < done {
                p -= step;
                break;
            }
            let factor = previous.map_or(1.0, |last: DVec2| {
                speed_up(&[last.x, last.y], &[step.x, step.y])
            });
            previous = (factor == 1.0).then_some(step);
            p -= step * factor;
        }
        Some(p)
    }

    /// Normalised cross-correlation of the template with `level` at `p`, in [−1, 1]; 0 when
    /// either side is flat (nothing to correlate).
    pub(super) fn correlation(&self, level: &Level, p: DVec2) -> f64 {
        let mut seen = Vec::with_capacity(self.values.len());
        level.sample_grid(p, self.half, &mut seen);
        ncc(&self.values, &seen)
    }
}

/// How much to lengthen `step` when it repeats `last` shrunk by a steady ratio r: the
/// iterations converge linearly where the template's gradients carry noise the frame's do
/// not share (the Hessian is too large by that noise), so the remaining steps would add up
/// to `step · r / (1 − r)`; taking them at once lands near the same fixed point, which the
/// next iterations then confirm. Only small steps in the same direction are lengthened, by at
/// most 10×; anything else is taken as it is.
fn speed_up(last: &[f64], step: &[f64]) -> f64 {
    let dot: f64 = last.iter().zip(step).map(|(a, b)| a * b).sum();
    let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    let (l, s) = (norm(last), norm(step));
    let r = s / l;
    if s < 0.5 && dot > 0.95 * l * s && (0.3..=0.9).contains(&r) {
        1.0 / (1.0 - r)
    } else {
        1.0
    }
}

/// `(Σ gx (seen − values), Σ gy (seen − values))`, summed in eight f32 lanes (which
/// vectorise) and the lanes in f64.
fn weighted_errors(gx: &[f32], gy: &[f32], seen: &[f32], values: &[f32]) -> (f64, f64) {
    const LANES: usize = 8;
    let (mut ax, mut ay) = ([0.0f32; LANES], [0.0f32; LANES]);
    let chunks = gx
        .chunks_exact(LANES)
        .zip(gy.chunks_exact(LANES))
        .zip(seen.chunks_exact(LANES).zip(values.chunks_exact(LANES)));
    for ((gx, gy), (seen, values)) in chunks {
        for l in 0..LANES {
            let error = seen[l] - values[l];
            ax[l] += gx[l] * error;
            ay[l] += gy[l] * error;
        }
    }
    let (mut bx, mut by) = (0.0f64, 0.0f64);
    for l in 0..LANES {
        bx += f64::from(ax[l]);
        by += f64::from(ay[l]);
    }
    let tail = values.len() / LANES * LANES;
    for k in tail..values.len() {
        let error = seen[k] - values[k];
        bx += f64::from(gx[k] * error);
        by += f64::from(gy[k] * error);
    }
    (bx, by)
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
        let found = template.align(&b.levels[0], centre, 1e-3).unwrap();
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
        let mut template = Template::cut(&a.levels[0], centre, 10);
        template.prepare_similarity();
        let start = centre + DVec2::new(0.4, -0.3);
        let (found, m) = template
            .align_similarity(&b.levels[0], start, [1.0, 0.0], 1e-3)
            .unwrap();
        assert!(found.distance(centre) < 0.05, "{found}");
        let (scale, angle) = (m[0].hypot(m[1]), m[1].atan2(m[0]));
        assert!((scale - grow).abs() < 0.005, "{scale}");
        assert!((angle - turn).abs() < 0.005, "{angle}");
    }
}
