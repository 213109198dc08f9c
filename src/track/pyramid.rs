//! Grey pyramids of a window of a frame: takes a frame, a centre and a radius and gives the
//! Rec. 709 luma of the pixels around the centre at full size and halved `levels − 1` times
//! (2 × 2 means), sampled bilinearly in pixel coordinates (pixel (i, j) covers [i, i + 1] ×
//! [j, j + 1] at its level). Only the window is converted, cut to the frame grown by a
//! coarsest pixel, so a tracked point costs the same on a 4K plate as on a thumbnail; when
//! the windows of a frame's points would together hold more than the frame, the frame is
//! converted once and they share it ([`FramePyramid`]), so memory is bounded by the frame.

use std::sync::Arc;

use glam::DVec2;

use crate::pixels::FloatImage;

/// Rec. 709 luma weights, as the `monochrome` clone mode uses.
const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// One level: a window of grey values, `origin` in this level's pixels. The values may be
/// a window into a larger grid shared with other points' windows (see
/// [`FramePyramid`]): `stride` is that grid's row length and `offset` the index of the
/// window's first pixel in it. A window samples the same whether it owns its values or
/// shares them: both hold the same exact means, and sampling clamps at the window's edge.
pub(super) struct Level {
    origin: [i64; 2],
    width: usize,
    height: usize,
    stride: usize,
    offset: usize,
    values: Arc<[f32]>,
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
        let row0 = self.offset + j * self.stride;
        let row1 = self.offset + j1 * self.stride;
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
            let top = &self.values[self.offset + (j0 + r) * self.stride + i0..][..=side];
            let bottom = &self.values[self.offset + (j0 + r + 1) * self.stride + i0..][..=side];
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
                let k = self.offset + j * self.stride + i;
                let top = self.values[k] * (1.0 - fx) + self.values[k + 1] * fx;
                let below = &self.values[k + self.stride..];
                let bottom = below[0] * (1.0 - fx) + below[1] * fx;
                out.push(top * (1.0 - fy) + bottom * fy);
            }
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
    /// so every level's pixels are exact means of the level below, and cut to the frame
    /// grown by one coarsest pixel ([`window`]), so its size is bounded by the frame's
    /// whatever the radius.
    pub(super) fn around(frame: &FloatImage, centre: DVec2, radius: f64, levels: usize) -> Self {
        let size = (frame.width(), frame.height());
        Pyramid::build(frame, window(size, centre, radius, levels), levels)
    }

    /// The pyramid of the window `[x0, y0, x1, y1]` (aligned to the coarsest level's grid).
    fn build(frame: &FloatImage, [x0, y0, x1, y1]: [i64; 4], levels: usize) -> Self {
        let (width, height) = ((x1 - x0) as usize, (y1 - y0) as usize);
        let mut grid = Grid {
            origin: [x0, y0],
            width,
            height,
            values: grey_window(frame, [x0, y0], width, height),
        };
        let mut out = Vec::with_capacity(levels);
        for _ in 1..levels {
            let next = grid.halved();
            out.push(std::mem::replace(&mut grid, next).into_level());
        }
        out.push(grid.into_level());
        Pyramid { levels: out }
    }
}

/// The pyramid of a whole frame grown by one coarsest pixel on every side, whose values the
/// windows of many points share: a frame's full-range windows come from it when they would
/// together hold more pixels than it does, so the memory a track takes is bounded by its
/// frame's size, not by the points times the search range.
pub(super) struct FramePyramid {
    whole: Pyramid,
    size: (u32, u32),
}

impl FramePyramid {
    pub(super) fn new(frame: &FloatImage, levels: usize) -> Self {
        let size = (frame.width(), frame.height());
        FramePyramid {
            whole: Pyramid::build(frame, bounds(size, levels), levels),
            size,
        }
    }

    /// What [`Pyramid::around`] gives for this frame, its values shared with this pyramid
    /// (the same exact means: both are aligned to the same grid).
    pub(super) fn around(&self, centre: DVec2, radius: f64) -> Pyramid {
        let levels = self.whole.levels.len();
        let [x0, y0, x1, y1] = window(self.size, centre, radius, levels);
        let levels = (self.whole.levels.iter().enumerate()).map(|(level, whole)| {
            // Exact: the window is aligned to the coarsest level's grid.
            let scale = 1i64 << level;
            let origin = [x0 / scale, y0 / scale];
            let dx = (origin[0] - whole.origin[0]) as usize;
            let dy = (origin[1] - whole.origin[1]) as usize;
            Level {
                origin,
                width: ((x1 - x0) / scale) as usize,
                height: ((y1 - y0) / scale) as usize,
                stride: whole.stride,
                offset: whole.offset + dy * whole.stride + dx,
                values: whole.values.clone(),
            }
        });
        Pyramid {
            levels: levels.collect(),
        }
    }

    /// Full-size pixels a frame's shared pyramid holds.
    pub(super) fn area(size: (u32, u32), levels: usize) -> u64 {
        area(bounds(size, levels))
    }
}

/// Full-size pixels the pyramid [`Pyramid::around`] makes holds.
pub(super) fn window_area(size: (u32, u32), centre: DVec2, radius: f64, levels: usize) -> u64 {
    area(window(size, centre, radius, levels))
}

fn area([x0, y0, x1, y1]: [i64; 4]) -> u64 {
    (x1 - x0) as u64 * (y1 - y0) as u64
}

/// The frame grown by one coarsest pixel on every side, aligned to the coarsest grid:
/// beyond it every level repeats its edge pixels, as a window cut there does.
fn bounds((width, height): (u32, u32), levels: usize) -> [i64; 4] {
    let step = 1i64 << (levels - 1);
    let align_up = |v: u32| (i64::from(v) + step - 1).div_euclid(step) * step;
    [-step, -step, align_up(width) + step, align_up(height) + step]
}

/// The square of half-side `radius` around `centre`, aligned outwards to the coarsest
/// level's grid and cut to the frame's [`bounds`] (at least one coarsest pixel wide and
/// high): `[x0, y0, x1, y1]`.
fn window(size: (u32, u32), centre: DVec2, radius: f64, levels: usize) -> [i64; 4] {
    let step = 1i64 << (levels - 1);
    let [bx0, by0, bx1, by1] = bounds(size, levels);
    let align_down = |v: f64| (v.floor() as i64).div_euclid(step) * step;
    let x0 = align_down(centre.x - radius).clamp(bx0, bx1 - step);
    let y0 = align_down(centre.y - radius).clamp(by0, by1 - step);
    let x1 = (align_down(centre.x + radius) + step).clamp(x0 + step, bx1);
    let y1 = (align_down(centre.y + radius) + step).clamp(y0 + step, by1);
    [x0, y0, x1, y1]
}

/// A level's values while its pyramid is built.
struct Grid {
    origin: [i64; 2],
    width: usize,
    height: usize,
    values: Vec<f32>,
}

impl Grid {
    /// The level above, by 2 × 2 means (the width and height are even).
    fn halved(&self) -> Grid {
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
        Grid {
            origin: [self.origin[0] / 2, self.origin[1] / 2],
            width,
            height,
            values,
        }
    }

    fn into_level(self) -> Level {
        Level {
            origin: self.origin,
            width: self.width,
            height: self.height,
            stride: self.width,
            offset: 0,
            values: self.values.into(),
        }
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

    fn texture(width: u32, height: u32) -> FloatImage {
        FloatImage::from_fn(width, height, PixelFormat::RGBA8, |i, j| {
            let v = ((i * 7 + j * 13) % 31) as f32 / 31.0;
            [v, 1.0 - v, v * v, 1.0]
        })
        .unwrap()
    }

    /// However far a point may move, its window holds no more than the frame grown by one
    /// coarsest pixel a side: a 255-px template searching 1,024 px (a 10,304-px window,
    /// 424 MB a level) on a 64 × 48 frame stays a few kilobytes.
    #[test]
    fn a_window_never_outgrows_its_frame() {
        let frame = texture(64, 48);
        for (centre, radius, levels) in [
            (DVec2::new(30.0, 20.0), 5152.0, 6),
            (DVec2::new(0.0, 48.0), 1e7, 1),
            (DVec2::new(-500.0, 9e3), 40.0, 3),
        ] {
            let pyramid = Pyramid::around(&frame, centre, radius, levels);
            let bound = FramePyramid::area((64, 48), levels);
            let level = &pyramid.levels[0];
            assert!(level.width > 0 && level.height > 0);
            assert!((level.width * level.height) as u64 <= bound, "{centre} {radius}");
            let expected = window_area((64, 48), centre, radius, levels);
            assert_eq!((level.width * level.height) as u64, expected);
        }
    }

    /// A window of the frame's shared pyramid samples exactly as the window's own pyramid,
    /// at every level, inside it, across its edges and beyond the frame.
    #[test]
    fn shared_windows_sample_as_their_own() {
        let frame = texture(90, 70);
        let levels = 3;
        let shared = FramePyramid::new(&frame, levels);
        let mut own_out = Vec::new();
        let mut shared_out = Vec::new();
        for (centre, radius) in [
            (DVec2::new(45.0, 35.0), 12.0),
            (DVec2::new(3.2, 66.7), 20.0),
            (DVec2::new(88.0, 1.0), 300.0),
        ] {
            let own = Pyramid::around(&frame, centre, radius, levels);
            let view = shared.around(centre, radius);
            for (level, (a, b)) in own.levels.iter().zip(&view.levels).enumerate() {
                let c = centre / f64::from(1u32 << level);
                let points = [c, c + DVec2::new(7.3, -4.6), c + DVec2::new(-60.0, 45.5)];
                for p in points {
                    assert_eq!(a.sample(p).to_bits(), b.sample(p).to_bits(), "{p}");
                    a.sample_grid(p, 5, &mut own_out);
                    b.sample_grid(p, 5, &mut shared_out);
                    assert_eq!(own_out, shared_out, "{p}");
                    a.sample_warped(p, [0.9, 0.3], 5, &mut own_out);
                    b.sample_warped(p, [0.9, 0.3], 5, &mut shared_out);
                    assert_eq!(own_out, shared_out, "{p}");
                }
            }
        }
    }
}
