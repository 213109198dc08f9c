//! Shading and compositing: takes the per-pixel triangle ids and coverage over the work
//! rectangle and gives the composited canvas pixels: source sampled bilinearly at the rest
//! position, plus the interpolated membrane, clamped to [0, 1], source alpha kept, composited
//! source-over with alpha = coverage · source alpha.
//!
//! Edge pixels with coverage but no triangle at their centre extrapolate the affine maps of
//! the triangle of the nearest hit pixel within two pixels (ties broken by a fixed scan
//! order), so the anti-aliased fringe continues the patch's colours instead of guessing.

use glam::Vec4;

use super::sampler::Sampler;
use super::setup::TriangleSetup;
use super::triangles::NO_TRIANGLE;
use super::PixelRect;
use crate::pixels::{FloatImage, Texel};

/// Neighbour offsets within radius 2, nearest first (fixed order for determinism).
const NEIGHBOURS: [(i32, i32); 24] = [
    (0, -1),
    (-1, 0),
    (1, 0),
    (0, 1),
    (-1, -1),
    (1, -1),
    (-1, 1),
    (1, 1),
    (0, -2),
    (-2, 0),
    (2, 0),
    (0, 2),
    (-1, -2),
    (1, -2),
    (-2, -1),
    (2, -1),
    (-2, 1),
    (2, 1),
    (-1, 2),
    (1, 2),
    (-2, -2),
    (2, -2),
    (-2, 2),
    (2, 2),
];

/// Everything shading reads, bundled to keep signatures short.
pub(crate) struct ShadeInput<'a> {
    pub setups: &'a [TriangleSetup],
    pub ids: &'a [u32],
    pub coverage: &'a [f32],
    pub work: PixelRect,
    pub source: &'a FloatImage,
}

/// Composites the patch over `canvas` (row-major, `canvas_width` wide) inside `target`
/// (the work rectangle clipped to the canvas). Returns the number of pixels written.
///
/// Each row is walked in runs of equal triangle id, so a run reads its triangle's setup
/// once; only the fringe (coverage without a triangle at the centre) looks at neighbours.
pub(crate) fn shade_and_composite<T: StoreTexel>(
    input: &ShadeInput,
    target: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
) -> usize {
    let work = input.work;
    let work_width = work.width();
    let (first, last) = (
        (target.x0 - work.x0) as usize,
        (target.x1 - work.x0) as usize,
    );
    let sampler = Sampler::new(input.source);
    let mut written = 0;
    for y in target.y0..target.y1 {
        let work_row = (y - work.y0) as usize * work_width;
        let ids = &input.ids[work_row + first..work_row + last];
        let coverage = &input.coverage[work_row + first..work_row + last];
        let canvas_row = y as usize * canvas_width;
        let row = &mut canvas[canvas_row + target.x0 as usize..canvas_row + target.x1 as usize];
        let mut start = 0;
        while start < ids.len() {
            let id = ids[start];
            let end = start
                + ids[start..]
                    .iter()
                    .take_while(|&&other| other == id)
                    .count();
            let x0 = target.x0 + start as i32;
            let span = Span {
                x0,
                y,
                coverage: &coverage[start..end],
            };
            written += if id == NO_TRIANGLE {
                shade_fringe(input, &span, &mut row[start..end])
            } else {
                let setup = &input.setups[id as usize];
                shade_span(setup, &sampler, &span, &mut row[start..end])
            };
            start = end;
        }
    }
    written
}

/// A run of pixels of one row starting at canvas column `x0`, with their coverage.
struct Span<'a> {
    x0: i32,
    y: i32,
    coverage: &'a [f32],
}

/// Shades a run of pixels whose centres all lie in `setup`'s triangle. The affine maps are
/// evaluated exactly (f64) at the run's first centre, then stepped in f32 along the run
/// (`value = first + step · t`, no accumulated rounding): over a run of a few dozen pixels
/// the source position moves by far less than 1/1000 px, invisible after 8- or 16-bit
/// rounding. Interior pixels (full coverage, opaque source) skip the blend.
#[inline(always)]
fn shade_span<T: StoreTexel>(
    setup: &TriangleSetup,
    sampler: &Sampler,
    span: &Span,
    pixels: &mut [[T; 4]],
) -> usize {
    let (cx, cy) = (f64::from(span.x0) + 0.5, f64::from(span.y) + 0.5);
    let (rx, ry) = (setup.rest_x, setup.rest_y);
    let u_first = (rx[0] + rx[1] * cx + rx[2] * cy) as f32;
    let v_first = (ry[0] + ry[1] * cx + ry[2] * cy) as f32;
    let (u_step, v_step) = (rx[1] as f32, ry[1] as f32);
    let channel = |k: usize| {
        let m = &setup.membrane_affine;
        Vec4::new(m[0][k], m[1][k], m[2][k], 0.0)
    };
    let m_step = channel(1);
    let m_first = channel(0) + m_step * cx as f32 + channel(2) * cy as f32;
    let mut written = 0;
    let mut t = 0.0f32;
    for (&coverage, pixel) in span.coverage.iter().zip(pixels.iter_mut()) {
        if coverage > 0.0 {
            let sample = sampler.sample_f32(u_first + u_step * t, v_first + v_step * t);
            // The membrane's alpha lane is 0, so an opaque sample clamps to alpha 1 here.
            let mut colour = (sample + m_first + m_step * t).clamp(Vec4::ZERO, Vec4::ONE);
            written += if coverage >= 1.0 && sample.w >= 1.0 {
                *pixel = T::store_unit(colour);
                1
            } else {
                colour.w = sample.w;
                usize::from(composite(pixel, colour.to_array(), coverage))
            };
        }
        t += 1.0;
    }
    written
}

/// Shades a run of pixels whose centres miss every triangle (the anti-aliased fringe).
fn shade_fringe<T: Texel>(input: &ShadeInput, span: &Span, pixels: &mut [[T; 4]]) -> usize {
    let cy = f64::from(span.y) + 0.5;
    let mut written = 0;
    for (k, (&coverage, pixel)) in span.coverage.iter().zip(pixels.iter_mut()).enumerate() {
        if coverage <= 0.0 {
            continue;
        }
        let x = span.x0 + k as i32;
        let Some(triangle) = owning_triangle(input, x, span.y) else {
            continue;
        };
        let cx = f64::from(x) + 0.5;
        let colour = patch_colour(&input.setups[triangle as usize], input.source, cx, cy);
        written += usize::from(composite(pixel, colour, coverage));
    }
    written
}

/// Canvas texels with a fast store for the interior path (8-bit on x86_64: SSE2 packs).
pub(crate) trait StoreTexel: Texel {
    /// `from_unit` of each channel of a colour already clamped to [0, 1].
    fn store_unit(colour: Vec4) -> [Self; 4];
}

impl StoreTexel for u8 {
    /// SSE2: one truncating conversion and two saturating packs — exactly `from_unit` per
    /// channel for values in [0, 1] (the packs saturate nothing; NaN was clamped to 0 by
    /// SSE max/min, and even a NaN would only give a wrong byte, never UB).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn store_unit(colour: Vec4) -> [u8; 4] {
        use std::arch::x86_64::{
            __m128, _mm_cvtsi128_si32, _mm_cvttps_epi32, _mm_packs_epi32, _mm_packus_epi16,
        };
        let scaled: __m128 = (colour * 255.0 + 0.5).into();
        // SAFETY: SSE2 is part of the x86_64 baseline, so these intrinsics are available.
        let packed = unsafe {
            let words = _mm_cvttps_epi32(scaled);
            let halves = _mm_packs_epi32(words, words);
            _mm_cvtsi128_si32(_mm_packus_epi16(halves, halves))
        };
        packed.to_le_bytes()
    }

    #[cfg(not(target_arch = "x86_64"))]
    #[inline(always)]
    fn store_unit(colour: Vec4) -> [u8; 4] {
        // Elsewhere a NaN channel may survive the clamp (NEON max/min propagate NaN), so keep
        // the saturating cast.
        colour.to_array().map(u8::from_unit)
    }
}

impl StoreTexel for u16 {
    #[inline(always)]
    fn store_unit(colour: Vec4) -> [u16; 4] {
        // The saturating cast: a NaN channel may survive the clamp on some SIMD backends.
        colour.to_array().map(u16::from_unit)
    }
}

/// Source-over of a straight colour with `coverage`; whether the pixel changed.
#[inline(always)]
fn composite<T: Texel>(pixel: &mut [T; 4], colour: [f32; 4], coverage: f32) -> bool {
    let alpha = coverage.min(1.0) * colour[3];
    if alpha <= 0.0 {
        return false;
    }
    if alpha >= 1.0 {
        *pixel = colour.map(T::from_unit);
        return true;
    }
    let premultiplied = [colour[0] * alpha, colour[1] * alpha, colour[2] * alpha];
    let under = pixel.map(Texel::to_unit);
    let out = crate::pixels::canvas_composite_over(premultiplied, alpha, under);
    *pixel = out.map(T::from_unit);
    true
}

#[inline(always)]
fn patch_colour(setup: &TriangleSetup, source: &FloatImage, x: f64, y: f64) -> [f32; 4] {
    let values = setup.interpolate(x, y);
    let sample = source.sample_bilinear(values.rest.x, values.rest.y);
    [
        (sample[0] + values.membrane[0]).clamp(0.0, 1.0),
        (sample[1] + values.membrane[1]).clamp(0.0, 1.0),
        (sample[2] + values.membrane[2]).clamp(0.0, 1.0),
        sample[3],
    ]
}

/// The triangle at the pixel's centre, or the nearest hit neighbour's.
#[inline]
fn owning_triangle(input: &ShadeInput, x: i32, y: i32) -> Option<u32> {
    let work = input.work;
    let width = work.width();
    let id = input.ids[(y - work.y0) as usize * width + (x - work.x0) as usize];
    if id != NO_TRIANGLE {
        return Some(id);
    }
    NEIGHBOURS.iter().find_map(|&(dx, dy)| {
        let (nx, ny) = (x + dx, y + dy);
        if nx < work.x0 || ny < work.y0 || nx >= work.x1 || ny >= work.y1 {
            return None;
        }
        let id = input.ids[(ny - work.y0) as usize * width + (nx - work.x0) as usize];
        (id != NO_TRIANGLE).then_some(id)
    })
}
