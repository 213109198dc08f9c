//! Shading and compositing: takes the per-pixel triangle ids and coverage over the work
//! rectangle and gives the composited canvas pixels: source sampled bilinearly at the rest
//! position, plus the interpolated membrane, clamped to [0, 1], source alpha kept, composited
//! source-over with alpha = coverage · source alpha.
//!
//! Edge pixels with coverage but no triangle at their centre extrapolate the affine maps of
//! the triangle of the nearest hit pixel within two pixels (ties broken by a fixed scan
//! order), so the anti-aliased fringe continues the patch's colours instead of guessing.

use glam::Vec4;

use super::sampler::{Sampler, SourceTexel};
use super::setup::TriangleSetup;
#[cfg(target_arch = "x86_64")]
use super::shade_simd::shade_run_rgba8;
use super::shade_simd::Kernel;
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

/// A coverage texel: 8-bit (the tiny-skia mask) or f32 (after feathering).
pub(crate) trait CoverageTexel: Copy {
    fn unit(self) -> f32;
    /// `unit() > 0`, without the conversion.
    fn is_covered(self) -> bool;
    /// `unit() >= 1`, without the conversion.
    fn is_full(self) -> bool;
    /// The texels as bytes when they are 8-bit (the SIMD kernel's input).
    fn as_bytes(texels: &[Self]) -> Option<&[u8]>;
}

impl CoverageTexel for u8 {
    #[inline(always)]
    fn unit(self) -> f32 {
        f32::from(self) * (1.0 / 255.0)
    }
    #[inline(always)]
    fn is_covered(self) -> bool {
        self > 0
    }
    #[inline(always)]
    fn is_full(self) -> bool {
        self == u8::MAX
    }
    #[inline(always)]
    fn as_bytes(texels: &[u8]) -> Option<&[u8]> {
        Some(texels)
    }
}

impl CoverageTexel for f32 {
    #[inline(always)]
    fn unit(self) -> f32 {
        self
    }
    #[inline(always)]
    fn is_covered(self) -> bool {
        self > 0.0
    }
    #[inline(always)]
    fn is_full(self) -> bool {
        self >= 1.0
    }
    #[inline(always)]
    fn as_bytes(_: &[f32]) -> Option<&[u8]> {
        None
    }
}

/// Everything shading reads, bundled to keep signatures short.
pub(crate) struct ShadeInput<'a, C> {
    pub setups: &'a [TriangleSetup],
    /// Triangle ids over `ids_rect` (row-major, `ids_rect.width()` wide).
    pub ids: &'a [u32],
    pub ids_rect: PixelRect,
    /// Coverage, row-major with `coverage_stride`, its element 0 at canvas pixel
    /// `coverage_origin`; it covers every pixel shaded.
    pub coverage: &'a [C],
    pub coverage_stride: usize,
    pub coverage_origin: (i32, i32),
    pub source: &'a FloatImage,
    /// The span kernel (SIMD or scalar; same bytes either way).
    pub kernel: Kernel,
}

/// Composites the patch over `canvas` inside `rows` (a rectangle of the canvas inside
/// `ids_rect`). `canvas` holds the canvas rows from `rows.y0` on, `canvas_width` wide.
/// Returns the number of pixels whose centre a triangle owns, and the number written.
///
/// Each row is walked in runs of equal triangle id, so a run reads its triangle's setup
/// once; only the fringe (coverage without a triangle at the centre) looks at neighbours.
pub(crate) fn shade_and_composite<T: StoreTexel, C: CoverageTexel, R: Recorder<C>>(
    input: &ShadeInput<C>,
    rows: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
    recorder: &mut R,
) -> (usize, usize) {
    #[cfg(target_arch = "x86_64")]
    if input.kernel == Kernel::Avx2 {
        // SAFETY: `Kernel::Avx2` is only ever detected on CPUs with AVX2.
        return unsafe { shade_rows_avx2(input, rows, canvas, canvas_width, recorder) };
    }
    shade_rows(input, rows, canvas, canvas_width, recorder)
}

/// [`shade_rows`] compiled for AVX2, so the SIMD run kernel inlines into the row walk (a
/// call and the kernel's set-up per run cost as much as a short run's pixels). The scalar
/// parts do the same IEEE operations either way (Rust never fuses a multiply and an add).
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn shade_rows_avx2<T: StoreTexel, C: CoverageTexel, R: Recorder<C>>(
    input: &ShadeInput<C>,
    rows: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
    recorder: &mut R,
) -> (usize, usize) {
    shade_rows(input, rows, canvas, canvas_width, recorder)
}

/// The row walk with the source's cheapest texels: its 8-bit view when it has one.
#[inline(always)]
fn shade_rows<T: StoreTexel, C: CoverageTexel, R: Recorder<C>>(
    input: &ShadeInput<C>,
    rows: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
    recorder: &mut R,
) -> (usize, usize) {
    let source = input.source;
    match source.eight_bit_view() {
        Some((texels, opaque)) => {
            let sampler = Sampler::with_texels(source, texels).known_opaque(opaque);
            walk_rows(input, &sampler, rows, canvas, canvas_width, recorder)
        }
        None => {
            let sampler = Sampler::new(source);
            walk_rows(input, &sampler, rows, canvas, canvas_width, recorder)
        }
    }
}

#[inline(always)]
fn walk_rows<S: SourceTexel, T: StoreTexel, C: CoverageTexel, R: Recorder<C>>(
    input: &ShadeInput<C>,
    sampler: &Sampler<S>,
    rows: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
    recorder: &mut R,
) -> (usize, usize) {
    let ids_rect = input.ids_rect;
    let ids_width = ids_rect.width();
    let (first, last) = (
        (rows.x0 - ids_rect.x0) as usize,
        (rows.x1 - ids_rect.x0) as usize,
    );
    let (cover_first, cover_last) = (
        (rows.x0 - input.coverage_origin.0) as usize,
        (rows.x1 - input.coverage_origin.0) as usize,
    );
    // The SIMD kernel indexes texels with i32 lanes: sources beyond 2³¹ texels (far above
    // `limits`, but a library caller may build one) take the scalar path.
    let small_source = input.source.pixels().len() <= i32::MAX as usize;
    let kernel = if !small_source {
        Kernel::Scalar
    } else {
        input.kernel
    };
    let (mut hits, mut written) = (0, 0);
    for y in rows.y0..rows.y1 {
        let ids_row = (y - ids_rect.y0) as usize * ids_width;
        let ids = &input.ids[ids_row + first..ids_row + last];
        let cover_row = (y - input.coverage_origin.1) as usize * input.coverage_stride;
        let coverage = &input.coverage[cover_row + cover_first..cover_row + cover_last];
        let canvas_row = (y - rows.y0) as usize * canvas_width;
        let row = &mut canvas[canvas_row + rows.x0 as usize..canvas_row + rows.x1 as usize];
        let mut start = 0;
        while start < ids.len() {
            let id = ids[start];
            let end = start + run_length(&ids[start..], id);
            let x0 = rows.x0 + start as i32;
            let span = Span {
                x0,
                y,
                coverage: &coverage[start..end],
            };
            recorder.run(x0, y, end - start, id);
            let pixels = &mut row[start..end];
            written += if id == NO_TRIANGLE {
                shade_fringe(input, sampler, &span, pixels, recorder)
            } else {
                hits += end - start;
                let setup = &input.setups[id as usize];
                match simd_run(kernel, setup, sampler, &span, pixels, recorder) {
                    Some(written) => written,
                    None => shade_span(setup, sampler, &span, pixels, recorder),
                }
            };
            start = end;
        }
    }
    (hits, written)
}

/// How many ids from the start equal `id`. Eight at a time with a branch-free test (it
/// vectorises), since the interior runs of a coarse mesh are hundreds of pixels long.
#[inline]
fn run_length(ids: &[u32], id: u32) -> usize {
    let mut chunks = ids.chunks_exact(8);
    let mut length = 0;
    for chunk in &mut chunks {
        if chunk.iter().fold(0, |differ, &other| differ | (other ^ id)) != 0 {
            break;
        }
        length += 8;
    }
    length
        + ids[length..]
            .iter()
            .take_while(|&&other| other == id)
            .count()
}

/// A run of pixels of one row starting at canvas column `x0`, with their coverage.
struct Span<'a, C> {
    x0: i32,
    y: i32,
    coverage: &'a [C],
}

/// Shades a run of pixels whose centres all lie in `setup`'s triangle. The single-precision
/// maps are evaluated at every pixel centre relative to the triangle's own origin (small
/// exact offsets), the same formula the fringe, the replay and the SIMD kernel
/// ([`shade_simd`](super::shade_simd)) use, so every path gives the same bytes.
/// Interior pixels (full coverage, opaque source) skip the blend.
#[inline(always)]
fn shade_span<S: SourceTexel, T: StoreTexel, C: CoverageTexel, R: Recorder<C>>(
    setup: &TriangleSetup,
    sampler: &Sampler<S>,
    span: &Span<C>,
    pixels: &mut [[T; 4]],
    recorder: &mut R,
) -> usize {
    let mut written = 0;
    for (x, (&texel, pixel)) in (span.x0..).zip(span.coverage.iter().zip(pixels.iter_mut())) {
        if texel.is_covered() {
            let (u, v, membrane) = setup.span.at_pixel(x, span.y);
            let sample = sampler.sample_texel_space(u, v);
            recorder.pixel(Some(sample), texel);
            written += usize::from(shade_pixel(pixel, sample, membrane, texel));
        } else {
            recorder.pixel(None, texel);
        }
    }
    written
}

/// Runs shorter than this take the scalar path even with a SIMD kernel: the kernel's per-run
/// set-up (maps as vectors, eight tap positions) outweighs its per-pixel gain on 1–2 pixel
/// runs, which meshes with a 1 px boundary are full of. Measured on `bench render` (A/B,
/// three rounds): raster mean 4.89–5.07 → 4.59–4.82 ms, callgrind −4.3 % in the band draw;
/// 4 and 5 were no better. Both paths write the same bytes.
const SIMD_MIN_RUN: usize = 3;

/// The run shaded by the SIMD kernel when there is one for this CPU and these texel types
/// (8-bit canvas and coverage); `None`: the caller shades it the scalar way.
#[inline(always)]
fn simd_run<S: SourceTexel, T: StoreTexel, C: CoverageTexel, R: Recorder<C>>(
    kernel: Kernel,
    setup: &TriangleSetup,
    sampler: &Sampler<S>,
    span: &Span<C>,
    pixels: &mut [[T; 4]],
    recorder: &mut R,
) -> Option<usize> {
    #[cfg(target_arch = "x86_64")]
    if kernel != Kernel::Scalar && span.coverage.len() >= SIMD_MIN_RUN {
        if let (Some(coverage), Some(pixels)) = (C::as_bytes(span.coverage), T::as_rgba8(pixels)) {
            let at = (span.x0, span.y);
            let mut sink = RecorderSink {
                recorder,
                coverage: span.coverage,
                next: 0,
            };
            return Some(shade_run_rgba8(
                kernel,
                &setup.span,
                sampler,
                at,
                coverage,
                pixels,
                &mut sink,
            ));
        }
    }
    let _ = (kernel, setup, sampler, span, pixels, recorder);
    None
}

/// A [`Recorder`] seen by the SIMD kernel: it reports byte coverage, which is the run's own
/// coverage texels (the kernel runs only when they are bytes), so each report takes the next
/// texel of the run instead of converting.
#[cfg(target_arch = "x86_64")]
struct RecorderSink<'a, C, R> {
    recorder: &'a mut R,
    coverage: &'a [C],
    next: usize,
}

#[cfg(target_arch = "x86_64")]
impl<C: CoverageTexel, R: Recorder<C>> super::shade_simd::SampleSink for RecorderSink<'_, C, R> {
    const ACTIVE: bool = R::ACTIVE;

    #[inline(always)]
    fn pixel(&mut self, sample: Option<Vec4>, _coverage: u8) {
        // invariant: the kernel reports each pixel of the run once, in order.
        let texel = self.coverage[self.next];
        self.next += 1;
        self.recorder.pixel(sample, texel);
    }
}

/// Source sample plus membrane, composited with the pixel's coverage; whether it changed.
#[inline(always)]
pub(crate) fn shade_pixel<T: StoreTexel, C: CoverageTexel>(
    pixel: &mut [T; 4],
    sample: Vec4,
    membrane: Vec4,
    coverage: C,
) -> bool {
    // The membrane's alpha lane is 0, so an opaque sample clamps to alpha 1 here.
    let mut colour = (sample + membrane).clamp(Vec4::ZERO, Vec4::ONE);
    if coverage.is_full() && sample.w >= 1.0 {
        *pixel = T::store_unit(colour);
        true
    } else {
        colour.w = sample.w;
        composite(pixel, colour.to_array(), coverage.unit())
    }
}

/// Shades a run of pixels whose centres miss every triangle (the anti-aliased fringe): each
/// extrapolates the maps of its owning triangle (see [`owning_triangle`]).
fn shade_fringe<S: SourceTexel, T: StoreTexel, C: CoverageTexel, R: Recorder<C>>(
    input: &ShadeInput<C>,
    sampler: &Sampler<S>,
    span: &Span<C>,
    pixels: &mut [[T; 4]],
    recorder: &mut R,
) -> usize {
    let mut written = 0;
    let len = span.coverage.len().min(pixels.len());
    let bytes = C::as_bytes(&span.coverage[..len]);
    let mut k = 0;
    while k < len {
        // Most pixels of a run without a triangle lie outside the silhouette altogether
        // (the work rectangle's corners): skip their zero coverage bytes in blocks.
        if let Some(bytes) = bytes {
            k += zero_prefix(&bytes[k..]);
            if k == len {
                break;
            }
        }
        let texel = span.coverage[k];
        let x = span.x0 + k as i32;
        k += 1;
        if !texel.is_covered() {
            continue;
        }
        let Some(triangle) = owning_triangle(input, x, span.y) else {
            continue;
        };
        let (u, v, membrane) = input.setups[triangle as usize].span.at_pixel(x, span.y);
        let sample = sampler.sample_texel_space(u, v);
        recorder.fringe(x, triangle, sample, texel);
        written += usize::from(shade_pixel(&mut pixels[k - 1], sample, membrane, texel));
    }
    written
}

/// How many bytes from the start are zero; sixteen at a time with a branch-free test.
#[inline]
fn zero_prefix(bytes: &[u8]) -> usize {
    let mut length = 0;
    for chunk in bytes.chunks_exact(16) {
        if chunk.iter().fold(0, |any, &b| any | b) != 0 {
            break;
        }
        length += 16;
    }
    length + bytes[length..].iter().take_while(|&&b| b == 0).count()
}

/// Watches shading (for [`replay`](super::replay)): runs, the source sample and coverage
/// of every covered pixel, in shading order. [`NoRecorder`] compiles to nothing.
pub(crate) trait Recorder<C> {
    /// Whether anything is recorded (a recording draw runs on one thread, in band order).
    const ACTIVE: bool = true;
    /// A run of `len` pixels from `(x0, y)` owned by triangle `id`.
    fn run(&mut self, x0: i32, y: i32, len: usize, id: u32);
    /// The next pixel of the current triangle run, with its sample when covered.
    fn pixel(&mut self, sample: Option<Vec4>, coverage: C);
    /// A covered fringe pixel at column `x` of the current row, extrapolating `owner`.
    fn fringe(&mut self, x: i32, owner: u32, sample: Vec4, coverage: C);
}

pub(crate) struct NoRecorder;

impl<C> Recorder<C> for NoRecorder {
    const ACTIVE: bool = false;
    #[inline(always)]
    fn run(&mut self, _: i32, _: i32, _: usize, _: u32) {}
    #[inline(always)]
    fn pixel(&mut self, _: Option<Vec4>, _: C) {}
    #[inline(always)]
    fn fringe(&mut self, _: i32, _: u32, _: Vec4, _: C) {}
}

/// Canvas texels with a fast store for the interior path (8-bit on x86_64: SSE2 packs).
pub(crate) trait StoreTexel: Texel {
    /// `from_unit` of each channel of a colour already clamped to [0, 1].
    fn store_unit(colour: Vec4) -> [Self; 4];
    /// The pixels as 8-bit RGBA when they are (the SIMD kernel's output).
    fn as_rgba8(pixels: &mut [[Self; 4]]) -> Option<&mut [[u8; 4]]>;
}

impl StoreTexel for u8 {
    #[inline(always)]
    fn as_rgba8(pixels: &mut [[u8; 4]]) -> Option<&mut [[u8; 4]]> {
        Some(pixels)
    }

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
    fn as_rgba8(_: &mut [[u16; 4]]) -> Option<&mut [[u8; 4]]> {
        None
    }

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

/// The triangle at the pixel's centre, or the nearest hit neighbour's.
#[inline]
fn owning_triangle<C>(input: &ShadeInput<C>, x: i32, y: i32) -> Option<u32> {
    let rect = input.ids_rect;
    let width = rect.width();
    let id = input.ids[(y - rect.y0) as usize * width + (x - rect.x0) as usize];
    if id != NO_TRIANGLE {
        return Some(id);
    }
    NEIGHBOURS.iter().find_map(|&(dx, dy)| {
        let (nx, ny) = (x + dx, y + dy);
        if nx < rect.x0 || ny < rect.y0 || nx >= rect.x1 || ny >= rect.y1 {
            return None;
        }
        let id = input.ids[(ny - rect.y0) as usize * width + (nx - rect.x0) as usize];
        (id != NO_TRIANGLE).then_some(id)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_length_counts_the_leading_equal_ids() {
        // Runs of every length from 0 to 40 at every offset of a 48-id row, against the
        // one-at-a-time count.
        for run in 0..=40usize {
            for tail in [0u32, 1, 7, 8, 9] {
                let mut ids = vec![5u32; run];
                ids.extend((0..tail).map(|k| 6 + k % 2));
                let expected = ids.iter().take_while(|&&id| id == 5).count();
                assert_eq!(run_length(&ids, 5), expected, "run {run}, tail {tail}");
                assert_eq!(run_length(&ids, 9), 0);
            }
        }
        assert_eq!(run_length(&[], 3), 0);
    }

    #[test]
    fn zero_prefix_counts_the_leading_zero_bytes() {
        // A non-zero byte at every position of rows up to 50 bytes long, one or two of them.
        for len in 0..=50usize {
            for hit in 0..=len {
                for value in [1u8, 128, 255] {
                    let mut bytes = vec![0u8; len];
                    if hit < len {
                        bytes[hit] = value;
                    }
                    assert_eq!(zero_prefix(&bytes), hit, "len {len}, hit {hit}");
                    if hit + 17 < len {
                        bytes[hit + 17] = 3;
                        assert_eq!(zero_prefix(&bytes), hit);
                    }
                }
            }
        }
    }
}
