//! Bilinear sampling: takes a row-major RGBA buffer (any [`Texel`] type, or any pixel type
//! with a function giving its channels) and a point in pixel
//! coordinates and gives the interpolated straight RGBA colour in [0, 1].
//!
//! Pixel-centre convention: pixel (i, j) is exact at (i + 0.5, j + 0.5); outside the centres'
//! hull the edge pixels are repeated (clamp to edge).

use glam::Vec4;

use super::Texel;

/// Samples `pixels` (`width` × `height`, row-major) at `(x, y)`.
///
/// The buffer must hold `width * height` pixels and both sizes must be non-zero (every
/// image type of this crate guarantees it). Non-finite coordinates sample pixel (0, 0).
#[inline(always)]
pub fn sample_bilinear_rgba<T: Texel>(
    pixels: &[[T; 4]],
    width: u32,
    height: u32,
    x: f64,
    y: f64,
) -> [f32; 4] {
    sample_bilinear_by(pixels, width, height, x, y, |p| {
        Vec4::from_array(p.map(Texel::to_unit))
    })
}

/// [`sample_bilinear_rgba`] over any pixel type, `value` giving a pixel's channels in [0, 1].
#[inline(always)]
pub(crate) fn sample_bilinear_by<P>(
    pixels: &[P],
    width: u32,
    height: u32,
    x: f64,
    y: f64,
    value: impl Fn(&P) -> Vec4,
) -> [f32; 4] {
    let (x0, x1, tx) = axis_taps(x, width);
    let (y0, y1, ty) = axis_taps(y, height);
    let w = width as usize;
    let row0 = &pixels[y0 * w..y0 * w + w];
    let row1 = &pixels[y1 * w..y1 * w + w];
    // glam's Vec4 is SIMD (SSE2 / NEON): one lerp handles all four channels.
    let top = value(&row0[x0]).lerp(value(&row0[x1]), tx);
    let bottom = value(&row1[x0]).lerp(value(&row1[x1]), tx);
    top.lerp(bottom, ty).to_array()
}

/// The two neighbouring pixel indices along one axis and the weight of the second one.
/// Branch-free: the position is clamped into the centres' range (NaN goes to 0), and the
/// second tap is clamped to the last pixel, where its weight is 0 anyway.
#[inline(always)]
fn axis_taps(coordinate: f64, size: u32) -> (usize, usize, f32) {
    let last = size.saturating_sub(1) as usize;
    // `f64::max` returns the non-NaN operand, so NaN samples pixel 0 like a far-left point.
    let u = (coordinate - 0.5).max(0.0).min(last as f64);
    // u ≥ 0 here, so truncation is floor (and avoids a libm call without SSE4.1).
    // Through i64: u ∈ [0, last] fits, and the saturating f64 → u64 cast costs far more.
    let i = u as i64 as usize;
    (i, (i + 1).min(last), (u - i as f64) as f32)
}
