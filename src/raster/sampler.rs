//! The shading sampler: takes the source [`FloatImage`] and gives bilinear samples as SIMD
//! [`Vec4`]s for the raster's inner loop — branch-free clamped taps, one slice, no per-call
//! setup. The hot path ([`Sampler::sample_f32`]) takes f32 positions and unchecked
//! (proven in-range) taps; it differs from [`FloatImage::sample_bilinear`] only by the f32
//! rounding of the position (tested to 1e-5 per channel). The f64 path, kept for tests, is
//! bit-identical to it.

use glam::Vec4;

use crate::pixels::FloatImage;

/// A borrowed view of the source, set up once per draw.
pub(crate) struct Sampler<'a> {
    pub(super) pixels: &'a [[f32; 4]],
    pub(super) width: usize,
    pub(super) last_x: usize,
    pub(super) last_y: usize,
    pub(super) last_x_f32: f32,
    pub(super) last_y_f32: f32,
}

impl<'a> Sampler<'a> {
    pub fn new(source: &'a FloatImage) -> Sampler<'a> {
        Sampler {
            pixels: source.pixels(),
            width: source.width() as usize,
            last_x: source.width().saturating_sub(1) as usize,
            last_y: source.height().saturating_sub(1) as usize,
            last_x_f32: last_as_f32(source.width()),
            last_y_f32: last_as_f32(source.height()),
        }
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

    /// [`sample`](Self::sample) with `f32` coordinates and tap arithmetic (the shading hot
    /// path; differs from the f64 taps only by the f32 rounding of the position).
    #[inline(always)]
    #[cfg(test)]
    pub fn sample_f32(&self, x: f32, y: f32) -> Vec4 {
        self.sample_texel_space(x - 0.5, y - 0.5)
    }

    /// [`sample_f32`](Self::sample_f32) at `(x + ½, y + ½)`: positions in texel space,
    /// where texel (i, j)'s centre is at (i, j) (the shading loop folds the ½ into its maps).
    #[inline(always)]
    pub fn sample_texel_space(&self, x: f32, y: f32) -> Vec4 {
        let (x0, x1, tx) = taps_shifted(x, self.last_x, self.last_x_f32);
        let (y0, y1, ty) = taps_shifted(y, self.last_y, self.last_y_f32);
        let (row0, row1) = (y0 * self.width, y1 * self.width);
        // SAFETY: the taps are ≤ last_x < width and ≤ last_y < height (see `taps_f32`), and
        // `pixels` holds width · height ≥ 1 texels (a FloatImage is never empty).
        let texel = |i: usize| Vec4::from_array(unsafe { *self.pixels.get_unchecked(i) });
        // a + (b − a)·t: one multiply fewer than glam's `lerp` (a·(1 − t) + b·t); differs
        // from the f64 reference only in the last bits.
        let lerp = |a: Vec4, b: Vec4, t: f32| a + (b - a) * t;
        let top = lerp(texel(row0 + x0), texel(row0 + x1), tx);
        let bottom = lerp(texel(row1 + x0), texel(row1 + x1), tx);
        lerp(top, bottom, ty)
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
    // SAFETY: u is finite and in [0, last] ⊂ [0, 2^32) after the clamp (±∞ and NaN included),
    // so it is representable in i64.
    let whole = unsafe { u.to_int_unchecked::<i64>() };
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
}
