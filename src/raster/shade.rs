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
use super::triangles::NO_TRIANGLE;
use super::PixelRect;
use crate::pixels::{FloatImage, Texel};
use crate::simd::{Kernel, Path};

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
}

/// Composites the patch over `canvas` inside `rows` (a rectangle of the canvas inside
/// `ids_rect`). `canvas` holds the canvas rows from `rows.y0` on, `canvas_width` wide.
/// Returns the number of pixels whose centre a triangle owns, and the number written.
///
/// Each row is walked in runs of equal triangle id, so a run reads its triangle's setup
/// once; only the fringe (coverage without a triangle at the centre) looks at neighbours.
/// Sources loaded from 8-bit files are sampled from their 8-bit texels.
pub(crate) fn shade_and_composite<T: Texel, C: CoverageTexel>(
    input: &ShadeInput<C>,
    rows: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
) -> (usize, usize) {
    Path::current().run(Shade {
        input,
        rows,
        canvas,
        canvas_width,
    })
}

/// [`shade_and_composite`]'s arguments, as a kernel compiled for the CPU's best
/// instruction set: the loops are separate IEEE operations in a fixed order, so any
/// instruction set gives the same bits (see [`crate::simd`]).
struct Shade<'a, 'c, T, C> {
    input: &'a ShadeInput<'a, C>,
    rows: PixelRect,
    canvas: &'c mut [[T; 4]],
    canvas_width: usize,
}

impl<T: Texel, C: CoverageTexel> Kernel for Shade<'_, '_, T, C> {
    type Output = (usize, usize);

    #[inline(always)]
    fn call(self) -> (usize, usize) {
        let Shade {
            input,
            rows,
            canvas,
            canvas_width,
        } = self;
        let source = input.source;
        match source.eight_bit_view() {
            Some((texels, _)) => {
                let sampler = Sampler::with_texels(source, texels);
                walk_rows(input, &sampler, rows, canvas, canvas_width)
            }
            None => walk_rows(input, &Sampler::new(source), rows, canvas, canvas_width),
        }
    }
}

#[inline(always)]
fn walk_rows<S: SourceTexel, T: Texel, C: CoverageTexel>(
    input: &ShadeInput<C>,
    sampler: &Sampler<S>,
    rows: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
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
            let end = start
                + ids[start..]
                    .iter()
                    .take_while(|&&other| other == id)
                    .count();
            let span = Span {
                x0: rows.x0 + start as i32,
                y,
                coverage: &coverage[start..end],
            };
            let pixels = &mut row[start..end];
            written += if id == NO_TRIANGLE {
                shade_fringe(input, sampler, &span, pixels)
            } else {
                hits += end - start;
                shade_span(&input.setups[id as usize], sampler, &span, pixels)
            };
            start = end;
        }
    }
    (hits, written)
}

/// A run of pixels of one row starting at canvas column `x0`, with their coverage.
struct Span<'a, C> {
    x0: i32,
    y: i32,
    coverage: &'a [C],
}

/// Shades a run of pixels whose centres all lie in `setup`'s triangle. The single-precision
/// maps are evaluated at every pixel centre relative to the triangle's own origin (small
/// exact offsets), the same formula the fringe uses, with the row's terms taken once.
#[inline(always)]
fn shade_span<S: SourceTexel, T: Texel, C: CoverageTexel>(
    setup: &TriangleSetup,
    sampler: &Sampler<S>,
    span: &Span<C>,
    pixels: &mut [[T; 4]],
) -> usize {
    let maps = setup.span.along_row(span.y);
    let mut written = 0;
    for (x, (&texel, pixel)) in (span.x0..).zip(span.coverage.iter().zip(pixels.iter_mut())) {
        if texel.is_covered() {
            let (u, v, membrane) = maps.at(x);
            let sample = sampler.sample_texel_space(u, v);
            written += usize::from(shade_pixel(pixel, sample, membrane, texel));
        }
    }
    written
}

/// Source sample plus membrane, composited with the pixel's coverage; whether it changed.
#[inline(always)]
fn shade_pixel<T: Texel, C: CoverageTexel>(
    pixel: &mut [T; 4],
    sample: Vec4,
    membrane: Vec4,
    coverage: C,
) -> bool {
    // The membrane's alpha lane is 0, so an opaque sample clamps to alpha 1 here.
    let mut colour = (sample + membrane).clamp(Vec4::ZERO, Vec4::ONE);
    if coverage.is_full() && sample.w >= 1.0 {
        *pixel = T::from_unit4(colour.to_array());
        true
    } else {
        colour.w = sample.w;
        composite(pixel, colour.to_array(), coverage.unit())
    }
}

/// Shades a run of pixels whose centres miss every triangle (the anti-aliased fringe): each
/// extrapolates the maps of its owning triangle (see [`owning_triangle`]).
#[inline(always)]
fn shade_fringe<S: SourceTexel, T: Texel, C: CoverageTexel>(
    input: &ShadeInput<C>,
    sampler: &Sampler<S>,
    span: &Span<C>,
    pixels: &mut [[T; 4]],
) -> usize {
    let mut written = 0;
    for (x, (&texel, pixel)) in (span.x0..).zip(span.coverage.iter().zip(pixels.iter_mut())) {
        if !texel.is_covered() {
            continue;
        }
        let Some(triangle) = owning_triangle(input, x, span.y) else {
            continue;
        };
        let (u, v, membrane) = input.setups[triangle as usize].span.at_pixel(x, span.y);
        let sample = sampler.sample_texel_space(u, v);
        written += usize::from(shade_pixel(pixel, sample, membrane, texel));
    }
    written
}

/// Source-over of a straight colour with `coverage`; whether the pixel changed.
#[inline(always)]
fn composite<T: Texel>(pixel: &mut [T; 4], colour: [f32; 4], coverage: f32) -> bool {
    let alpha = coverage.min(1.0) * colour[3];
    if alpha <= 0.0 {
        return false;
    }
    if alpha >= 1.0 {
        *pixel = T::from_unit4(colour);
        return true;
    }
    let premultiplied = [colour[0] * alpha, colour[1] * alpha, colour[2] * alpha];
    let under = pixel.map(Texel::to_unit);
    let out = crate::pixels::canvas_composite_over(premultiplied, alpha, under);
    *pixel = T::from_unit4(out);
    true
}

/// The triangle at the pixel's centre, or the nearest hit neighbour's.
#[inline(always)]
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
