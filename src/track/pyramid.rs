//! Grey pyramids of a window of a frame: takes a frame, a centre and a radius and gives the
//! Rec. 709 luma of the pixels around the centre at full size and halved `levels − 1` times
//! (2 × 2 means), sampled bilinearly in pixel coordinates (pixel (i, j) covers [i, i + 1] ×
//! [j, j + 1] at its level). Only the window is converted, never the whole frame, so a
//! tracked point costs the same on a 4K plate as on a thumbnail.

use glam::DVec2;

use crate::pixels::FloatImage;

/// Rec. 709 luma weights, as the `monochrome` clone mode uses.
const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// One level: a rectangle of grey values, `origin` in this level's pixels.
pub(super) struct Level {
    origin: [i64; 2],
    width: usize,
    height: usize,
    values: Vec<f32>,
}

impl Level {
    /// Bilinear sample at `p` (this level's pixel coordinates), edges replicated.
    #[inline]
    pub(super) fn sample(&self, p: DVec2) -> f32 {
        let u = (p.x - 0.5 - self.origin[0] as f64).clamp(0.0, (self.width - 1) as f64);
        let v = (p.y - 0.5 - self.origin[1] as f64).clamp(0.0, (self.height - 1) as f64);
        // Clamped to at least 0, so truncating is flooring (without a libm call per sample).
        let (i, j) = (u as usize, v as usize);
        let (fx, fy) = ((u - i as f64) as f32, (v - j as f64) as f32);
        let i1 = (i + 1).min(self.width - 1);
        let j1 = (j + 1).min(self.height - 1);
        let row0 = j * self.width;
        let row1 = j1 * self.width;
        let top = self.values[row0 + i] * (1.0 - fx) + self.values[row0 + i1] * fx;
        let bottom = self.values[row1 + i] * (1.0 - fx) + self.values[row1 + i1] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Bilinear samples at `p + (i, j)` for `i, j` in `−half..=half`, row-major into `out`
    /// (cleared first). Every sample shares `p`'s fraction, so one pair of weights serves the
    /// whole grid and rows are read as runs; a grid reaching the level's edge is sampled
    /// point by point, edges replicated, as [`sample`](Self::sample) does.
    pub(super) fn sample_grid(&self, p: DVec2, half: i32, out: &mut Vec<f32>) {
        out.clear();
        let side = (2 * half + 1) as usize;
        let u = p.x - 0.5 - self.origin[0] as f64 - f64::from(half);
        let v = p.y - 0.5 - self.origin[1] as f64 - f64::from(half);
        // Every sample's right and lower neighbours inside (false for NaN too).
        let inside = u >= 0.0
            && v >= 0.0
            && u + (side as f64) < self.width as f64
            && v + (side as f64) < self.height as f64;
        if !inside {
            for j in -half..=half {
                for i in -half..=half {
                    out.push(self.sample(p + DVec2::new(f64::from(i), f64::from(j))));
                }
            }
            return;
        }
        let (i0, j0) = (u as usize, v as usize);
        let (fx, fy) = ((u - i0 as f64) as f32, (v - j0 as f64) as f32);
        for r in 0..side {
            let top = &self.values[(j0 + r) * self.width + i0..][..=side];
            let bottom = &self.values[(j0 + r + 1) * self.width + i0..][..=side];
            let pairs = top[..side].iter().zip(&top[1..]);
            out.extend(
                pairs
                    .zip(bottom[..side].iter().zip(&bottom[1..]))
                    .map(|((&a, &b), (&c, &d))| {
                        let top = a * (1.0 - fx) + b * fx;
                        let bottom = c * (1.0 - fx) + d * fx;
                        top * (1.0 - fy) + bottom * fy
                    }),
            );
        }
    }

    /// Bilinear samples at `p + M (i, j)` for `i, j` in `−half..=half`, row-major into `out`
    /// (cleared first), where `M = [[m0, −m1], [m1, m0]]` turns and scales. A grid whose
    /// corners and their neighbours are inside the level is read without clamping (in
    /// level-window coordinates, so `f32` keeps a hundred-thousandth of a pixel); otherwise
    /// point by point as [`sample`](Self::sample) does.
    pub(super) fn sample_warped(&self, p: DVec2, m: [f64; 2], half: i32, out: &mut Vec<f32>) {
        out.clear();
        let extent = (m[0].abs() + m[1].abs()) * f64::from(half);
        let u = p.x - 0.5 - self.origin[0] as f64;
        let v = p.y - 0.5 - self.origin[1] as f64;
        // A thousandth of a pixel to spare for the f32 rounding below.
        let inside = u - extent >= 0.0
            && v - extent >= 0.0
            && u + extent + 1.001 < self.width as f64
            && v + extent + 1.001 < self.height as f64;
        if !inside {
            for j in -half..=half {
                for i in -half..=half {
                    let (x, y) = (f64::from(i), f64::from(j));
                    let q = DVec2::new(m[0] * x - m[1] * y, m[1] * x + m[0] * y);
                    out.push(self.sample(p + q));
                }
            }
            return;
        }
        let (m0, m1) = (m[0] as f32, m[1] as f32);
        let (u, v) = (u as f32, v as f32);
        for j in -half..=half {
            let y = j as f32;
            let (row_x, row_y) = (u - m1 * y, v + m0 * y);
            for i in -half..=half {
                let x = i as f32;
                let (x0, y0) = (row_x + m0 * x, row_y + m1 * x);
                // Inside by the test above: truncating is flooring, and i + 1, j + 1 exist.
                let (i, j) = (x0 as usize, y0 as usize);
                let (fx, fy) = (x0 - i as f32, y0 - j as f32);
                let k = j * self.width + i;
                let top = self.values[k] * (1.0 - fx) + self.values[k + 1] * fx;
                let below = &self.values[k + self.width..];
                let bottom = below[0] * (1.0 - fx) + below[1] * fx;
                out.push(top * (1.0 - fy) + bottom * fy);
            }
        }
    }

    /// The level below, halved by 2 × 2 means (the width and height are even).
    fn halved(&self) -> Level {
        let (width, height) = (self.width / 2, self.height / 2);
        let mut values = Vec::with_capacity(width * height);
        for j in 0..height {
            let (a, b) = (2 * j * self.width, (2 * j + 1) * self.width);
            for i in 0..width {
                let sum = self.values[a + 2 * i]
                    + self.values[a + 2 * i + 1]
                    + self.values[b + 2 * i]
                    + self.values[b + 2 * i + 1];
                values.push(sum * 0.25);
            }
        }
        Level {
            origin: [self.origin[0] / 2, self.origin[1] / 2],
            width,
            height,
            values,
        }
    }
}

/// The luma of the `width × height` pixels from `origin`, pixels beyond the frame repeating
/// its edge. An 8-bit frame is read from its texels (the same `f32` products as from its
/// `f32` values, so the same bits) without making its `f32` buffer.
fn grey_window(frame: &FloatImage, origin: [i64; 2], width: usize, height: usize) -> Vec<f32> {
    let (fw, fh) = (i64::from(frame.width()), i64::from(frame.height()));
    // Column of each window x, clamped into the frame: one lookup per pixel in the rows.
    let columns: Vec<usize> = (0..width as i64)
        .map(|x| (origin[0] + x).clamp(0, fw - 1) as usize)
        .collect();
    let mut values = Vec::with_capacity(width * height);
    let row_of = |y: i64| (origin[1] + y).clamp(0, fh - 1) as usize * fw as usize;
    // Whole rows of the window inside the frame are read as runs (which vectorise).
    let run = (origin[0] >= 0 && origin[0] + width as i64 <= fw).then(|| origin[0] as usize);
    if let Some(texels) = frame.stored_texels() {
        // The same products as `LUMA[c] * (k / 255)` on the f32 values, so the same bits.
        let luma = |[r, g, b, _]: [u8; 4]| {
            LUMA[0] * (f32::from(r) / 255.0)
                + LUMA[1] * (f32::from(g) / 255.0)
                + LUMA[2] * (f32::from(b) / 255.0)
        };
        for y in 0..height as i64 {
            let row = &texels[row_of(y)..][..fw as usize];
            match run {
                Some(x0) => values.extend(row[x0..x0 + width].iter().map(|&t| luma(t))),
                None => values.extend(columns.iter().map(|&i| luma(row[i]))),
            }
        }
    } else {
        let pixels = frame.pixels();
        for y in 0..height as i64 {
            let row = &pixels[row_of(y)..][..fw as usize];
            values.extend(columns.iter().map(|&i| {
                let [r, g, b, _] = row[i];
                LUMA[0] * r + LUMA[1] * g + LUMA[2] * b
            }));
        }
    }
    values
}

/// Levels 0 (full size) to `levels − 1`.
pub(super) struct Pyramid {
    pub(super) levels: Vec<Level>,
}

impl Pyramid {
    /// The pyramid of the square of half-side `radius` around `centre` in `frame`; pixels
    /// beyond the frame repeat its edge. The window is aligned to the coarsest level's grid
    /// so every level's pixels are exact means of the level below.
    pub(super) fn around(frame: &FloatImage, centre: DVec2, radius: f64, levels: usize) -> Self {
        let step = 1i64 << (levels - 1);
        let align_down = |v: f64| (v.floor() as i64).div_euclid(step) * step;
        let x0 = align_down(centre.x - radius);
        let y0 = align_down(centre.y - radius);
        let x1 = align_down(centre.x + radius) + step;
        let y1 = align_down(centre.y + radius) + step;
        let (width, height) = ((x1 - x0) as usize, (y1 - y0) as usize);
        let values = grey_window(frame, [x0, y0], width, height);
        let mut out = vec![Level {
            origin: [x0, y0],
            width,
            height,
            values,
        }];
        for _ in 1..levels {
            // invariant: the loop runs only while levels remain, after the first was pushed.
            let next = out.last().expect("level 0 pushed").halved();
            out.push(next);
        }
        Pyramid { levels: out }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixels::PixelFormat;

    #[test]
    fn levels_halve_and_samples_interpolate() {
        let frame = FloatImage::from_fn(64, 48, PixelFormat::RGBA8, |i, _| {
            let v = i as f32 / 64.0;
            [v, v, v, 1.0]
        })
        .unwrap();
        let pyramid = Pyramid::around(&frame, DVec2::new(30.0, 20.0), 10.0, 3);
        assert_eq!(pyramid.levels.len(), 3);
        // Luma of a grey ramp is the ramp; pixel i's centre is at i + 0.5.
        let level0 = &pyramid.levels[0];
        assert!((level0.sample(DVec2::new(30.5, 20.5)) - 30.0 / 64.0).abs() < 1e-5);
        assert!((level0.sample(DVec2::new(31.0, 20.5)) - 30.5 / 64.0).abs() < 1e-5);
        // Level 1 pixel 15 is the mean of level-0 pixels 30 and 31.
        let level1 = &pyramid.levels[1];
        assert!((level1.sample(DVec2::new(15.5, 10.5)) - 30.5 / 64.0).abs() < 1e-5);
    }

    /// The grid samplers give what sampling point by point gives, inside the window and
    /// where the grid runs over its edge.
    #[test]
    fn grids_are_their_points() {
        let frame = FloatImage::from_fn(80, 60, PixelFormat::RGBA8, |i, j| {
            let v = ((i * 7 + j * 13) % 31) as f32 / 31.0;
            [v, 1.0 - v, v * v, 1.0]
        })
        .unwrap();
        let level = &Pyramid::around(&frame, DVec2::new(40.0, 30.0), 25.0, 1).levels[0];
        let half = 4;
        let m = [1.03 * 0.2f64.cos(), 1.03 * 0.2f64.sin()];
        let mut out = Vec::new();
        for p in [DVec2::new(40.3, 29.8), DVec2::new(17.6, 8.1), DVec2::new(63.2, 51.9)] {
            level.sample_grid(p, half, &mut out);
            let mut k = 0;
            for j in -half..=half {
                for i in -half..=half {
                    let q = p + DVec2::new(f64::from(i), f64::from(j));
                    assert!((out[k] - level.sample(q)).abs() < 1e-6, "{p} {i} {j}");
                    k += 1;
                }
            }
            level.sample_warped(p, m, half, &mut out);
            let mut k = 0;
            for j in -half..=half {
                for i in -half..=half {
                    let (x, y) = (f64::from(i), f64::from(j));
                    let q = p + DVec2::new(m[0] * x - m[1] * y, m[1] * x + m[0] * y);
                    assert!((out[k] - level.sample(q)).abs() < 1e-4, "{p} {i} {j}");
                    k += 1;
                }
            }
        }
    }
}
