//! The shading sampler: takes the source [`FloatImage`] and gives bilinear samples as SIMD
//! [`Vec4`]s for the raster's inner loop — branch-free clamped taps, one slice, no per-call
//! setup. The hot path ([`Sampler::sample_texel_space`]) takes f32 positions and clamped
//! taps; it differs from [`FloatImage::sample_bilinear`] only by the f32
//! rounding of the position (tested to 1e-5 per channel). The f64 path, kept for tests, is
//! bit-identical to it.
//!
//! Texels come in two kinds ([`SourceTexel`]): the image's `f32` pixels, or — for an 8-bit
//! source, the usual case — its [`eight_bit_texels`](FloatImage::eight_bit_texels), a quarter
//! of the bytes, which is what the shading loop waits on. An 8-bit sample blends the integer
//! levels `k` and divides by 255 once at the end: at texel centres that is exactly the image's
//! `k / 255`, elsewhere it differs from the `f32` blend by an ulp or so (tested).

use glam::Vec4;

use crate::pixels::FloatImage;
use crate::simd::{texel_taps, LevelSource};

/// A texel type the sampler reads.
pub(crate) trait SourceTexel: Copy {
    /// The texels as 8-bit levels, if they are.
    fn as_levels(texels: &[Self]) -> Option<&[[u8; 4]]>;

    /// The texel's channels in the blend's units.
    fn blend_units(self) -> Vec4;
    /// A blend of texels in channel values.
    fn finish(blend: Vec4) -> Vec4;
}

impl SourceTexel for [f32; 4] {
    #[inline(always)]
    fn as_levels(_: &[Self]) -> Option<&[[u8; 4]]> {
        None
    }

    #[inline(always)]
    fn blend_units(self) -> Vec4 {
        Vec4::from_array(self)
    }

    #[inline(always)]
    fn finish(blend: Vec4) -> Vec4 {
        blend
    }
}

impl SourceTexel for [u8; 4] {
    #[inline(always)]
    fn as_levels(texels: &[Self]) -> Option<&[[u8; 4]]> {
        Some(texels)
    }

    #[inline(always)]
    fn blend_units(self) -> Vec4 {
        Vec4::from_array(self.map(f32::from))
    }

    #[inline(always)]
    fn finish(blend: Vec4) -> Vec4 {
        blend / 255.0
    }
}

/// A borrowed view of the source, set up once per draw.
pub(crate) struct Sampler<'a, S = [f32; 4]> {
    pixels: &'a [S],
    width: usize,
    last_x: usize,
    last_y: usize,
    last_x_f32: f32,
    last_y_f32: f32,
    /// Both bounds below 2^31, as [`texel_taps`] needs (images are far smaller).
    taps_fit_i32: bool,
}

impl<'a> Sampler<'a> {
    pub fn new(source: &'a FloatImage) -> Sampler<'a> {
        Sampler::with_texels(source, source.pixels())
    }

    /// The f64 reference path (tests: bit-identical to the image sampler).
    #[cfg(test)]
    /// Bilinear sample at `(x, y)` (centres at i + ½, clamped to edge, NaN → pixel 0).
    #[inline(always)]
    pub fn sample(&self, x: f64, y: f64) -> Vec4 {
        let (x0, x1, tx) = taps(x, self.last_x);
        let (y0, y1, ty) = taps(y, self.last_y);
        let (row0, row1) = (y0 * self.width, y1 * self.width);
        let texel = |i: usize| Vec4::from_array(self.pixels[i]);
        let top = texel(row0 + x0).lerp(texel(row0 + x1), tx);
        let bottom = texel(row1 + x0).lerp(texel(row1 + x1), tx);
        top.lerp(bottom, ty)
    }
}

impl<'a, S: SourceTexel> Sampler<'a, S> {
    /// A sampler of `source` reading `texels` (its pixels in one of the texel kinds).
    pub fn with_texels(source: &FloatImage, texels: &'a [S]) -> Sampler<'a, S> {
        assert_eq!(
            texels.len(),
            source.width() as usize * source.height() as usize,
            "one texel per pixel"
        );
        Sampler {
            pixels: texels,
            width: source.width() as usize,
            last_x: source.width().saturating_sub(1) as usize,
            last_y: source.height().saturating_sub(1) as usize,
            last_x_f32: last_as_f32(source.width()),
            last_y_f32: last_as_f32(source.height()),
            taps_fit_i32: source.width().max(source.height()) <= 1 << 31,
        }
    }

    /// The source as the eight-lane shader reads it, if its texels are 8-bit levels and its
    /// indices fit the lanes (see [`LevelSource::new`]).
    pub fn levels(&self) -> Option<LevelSource<'a>> {
        let texels = S::as_levels(self.pixels)?;
        let last = [self.last_x_f32, self.last_y_f32];
        LevelSource::new(texels, self.width, last).filter(|_| self.taps_fit_i32)
    }

    /// [`sample`](Self::sample) with `f32` coordinates and tap arithmetic (the shading hot
    /// path; differs from the f64 taps only by the f32 rounding of the position).
    #[inline(always)]
    #[cfg(test)]
    pub fn sample_f32(&self, x: f32, y: f32) -> Vec4 {
        self.sample_texel_space(x - 0.5, y - 0.5)
    }

    /// `sample_f32` at `(x + ½, y + ½)`: positions in texel space,
    /// where texel (i, j)'s centre is at (i, j) (the shading loop folds the ½ into its maps).
    #[inline(always)]
    pub fn sample_texel_space(&self, x: f32, y: f32) -> Vec4 {
        let ((x0, x1, tx), (y0, y1, ty)) = if self.taps_fit_i32 {
            // Both axes in one go: the same comparisons and truncation (see `texel_taps`).
            let ([i, j], [tx, ty]) = texel_taps([x, y], [self.last_x_f32, self.last_y_f32]);
            let (i, j) = (i as usize, j as usize);
            (
                (i, i + usize::from(i < self.last_x), tx),
                (j, j + usize::from(j < self.last_y), ty),
            )
        } else {
            (
                taps_shifted(x, self.last_x, self.last_x_f32),
                taps_shifted(y, self.last_y, self.last_y_f32),
            )
        };
        let (row0, row1) = (y0 * self.width, y1 * self.width);
        // The taps are ≤ last_x < width and ≤ last_y < height (see `taps_shifted`).
        let texel = |i: usize| self.pixels[i].blend_units();
        // a + (b − a)·t: one multiply fewer than glam's `lerp` (a·(1 − t) + b·t); differs
        // from the f64 reference only in the last bits.
        let lerp = |a: Vec4, b: Vec4, t: f32| a + (b - a) * t;
        let top = lerp(texel(row0 + x0), texel(row0 + x1), tx);
        let bottom = lerp(texel(row1 + x0), texel(row1 + x1), tx);
        S::finish(lerp(top, bottom, ty))
    }
}

/// `size − 1` rounded down to an f32, so clamped positions never truncate past the last
/// pixel (only matters above 2^24 px).
fn last_as_f32(size: u32) -> f32 {
    let last = size.saturating_sub(1);
    let rounded = last as f32;
    if rounded as u64 > u64::from(last) {
        // The next f32 towards zero (positive, normal): one ulp down.
        f32::from_bits(rounded.to_bits() - 1)
    } else {
        rounded
    }
}

/// f32 taps of a texel-space coordinate: clamped into the centres' range (NaN goes to 0),
/// then truncated without the saturating cast's range checks. Both taps are ≤ `last`:
/// u ≤ `last_f32` ≤ last.
#[inline(always)]
fn taps_shifted(shifted: f32, last: usize, last_f32: f32) -> (usize, usize, f32) {
    // Plain comparisons compile to maxss/minss (NaN → 0 by the first), unlike f32::max/min.
    let low = if shifted > 0.0 { shifted } else { 0.0 };
    let u = if low < last_f32 { low } else { last_f32 };
    // u is finite and in [0, last] ⊂ [0, 2^32) after the clamp (±∞ and NaN included), so
    // the cast truncates exactly.
    let whole = u as i64;
    // The signed conversion back is one instruction; an unsigned 64-bit one is a branchy
    // sequence on x86_64. Same value either way (0 ≤ whole < 2^32).
    let fraction = u - whole as f32;
    let i = whole as usize;
    (i, i + usize::from(i < last), fraction)
}

#[cfg(test)]
/// Same arithmetic as the pixels module's bilinear taps (so results agree bit for bit).
#[inline(always)]
fn taps(coordinate: f64, last: usize) -> (usize, usize, f32) {
    let u = (coordinate - 0.5).max(0.0).min(last as f64);
    // Through i64: u ∈ [0, last] fits, and the saturating f64 → u64 cast costs far more.
    let i = u as i64 as usize;
    (i, (i + 1).min(last), (u - i as f64) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixels::PixelFormat;

    #[test]
    fn f32_last_never_rounds_past_the_last_pixel() {
        for size in [
            1u32,
            2,
            480,
            (1 << 24) + 1,
            (1 << 24) + 3,
            (1 << 25) + 7,
            u32::MAX,
        ] {
            let last = last_as_f32(size);
            assert!(last as u64 <= u64::from(size - 1), "{size}: {last}");
            assert!(
                last as u64 + 4 >= u64::from(size - 1) || size > 1 << 24,
                "{size}"
            );
        }
        assert_eq!(last_as_f32(480), 479.0);
    }

    #[test]
    fn agrees_bit_for_bit_with_the_image_sampler() {
        let image = FloatImage::from_fn(7, 5, PixelFormat::RGBA8, |i, j| {
            let v = (i * 31 + j * 17) as f32 / 250.0;
            [v, 1.0 - v, (v * 3.0).fract(), 0.5 + v / 4.0]
        })
        .unwrap();
        let sampler = Sampler::new(&image);
        let coordinates = [
            -3.0,
            0.0,
            0.25,
            0.5,
            1.37,
            2.5,
            4.999,
            5.0,
            6.5,
            7.2,
            40.0,
            f64::NAN,
        ];
        for &x in &coordinates {
            for &y in &coordinates {
                let fast = sampler.sample(x, y).to_array();
                let reference = image.sample_bilinear(x, y);
                assert_eq!(
                    fast.map(f32::to_bits),
                    reference.map(f32::to_bits),
                    "{x} {y}"
                );
                // f32 taps: same up to the f32 rounding of the position (tiny here).
                let single = sampler.sample_f32(x as f32, y as f32).to_array();
                for (s, r) in single.iter().zip(reference) {
                    assert!(
                        (s - r).abs() <= 1e-5,
                        "{x} {y}: {single:?} vs {reference:?}"
                    );
                }
            }
        }
    }

    /// 8-bit texels give the f32 texels' samples: exactly at texel centres, to a few ulps
    /// elsewhere (the blend runs on levels and divides once).
    #[test]
    fn eight_bit_texels_sample_like_the_f32_pixels() {
        let image = FloatImage::from_fn(9, 6, PixelFormat::RGBA8, |i, j| {
            let k = |m: u32| ((i * m + j * 59 + m) % 256) as f32 / 255.0;
            [k(37), k(101), k(7), k(211)]
        })
        .unwrap();
        let texels = image.eight_bit_texels().expect("levels k / 255");
        let (levels, floats) = (Sampler::with_texels(&image, texels), Sampler::new(&image));
        for j in -2..9 {
            for i in -2..12 {
                let (x, y) = (i as f32, j as f32);
                let (a, b) = (
                    levels.sample_texel_space(x, y),
                    floats.sample_texel_space(x, y),
                );
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits)
                );
                for (dx, dy) in [(0.25, 0.5), (0.5, 0.125), (0.9, 0.37), (0.013, 0.77)] {
                    let a = levels.sample_texel_space(x + dx, y + dy);
                    let b = floats.sample_texel_space(x + dx, y + dy);
                    let error = (a - b).abs().max_element();
                    assert!(error <= 4.0 * f32::EPSILON, "{x}+{dx} {y}+{dy}: {a} vs {b}");
                }
            }
        }
    }
}
