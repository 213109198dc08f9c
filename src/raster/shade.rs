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
use super::setup::{RowMaps, TriangleSetup};
use super::triangles::NO_TRIANGLE;
use super::PixelRect;
use crate::pixels::{FloatImage, Texel};
use crate::simd::{Kernel, LevelSource, Path, Wide};

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
    /// Whether every texel of `texels` [`is_full`](Self::is_full).
    #[inline(always)]
    fn all_full(texels: &[Self]) -> bool {
        texels.iter().all(|c| c.is_full())
    }
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
    fn all_full(texels: &[Self]) -> bool {
        // Eight at a time as one word where there are eight (the eight-lane chunks).
        match texels.first_chunk::<8>() {
            Some(eight) if texels.len() == 8 => u64::from_ne_bytes(*eight) == u64::MAX,
            _ => texels.iter().all(|&c| c == u8::MAX),
        }
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
/// Sources loaded from 8-bit files are sampled from their 8-bit texels, and onto an 8-bit
/// canvas the interior goes eight pixels at a time where the CPU allows ([`Wide`]).
pub(crate) fn shade_and_composite<T: Texel, C: CoverageTexel>(
    input: &ShadeInput<C>,
    rows: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
) -> (usize, usize) {
    let path = Path::current();
    path.run(Shade {
        input,
        rows,
        canvas,
        canvas_width,
        wide: Wide::detect(path),
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
    wide: Option<Wide>,
}

/// The eight-lane shader and the source as it reads it, where both apply.
type Fast<'a> = Option<(Wide, LevelSource<'a>)>;

impl<T: Texel, C: CoverageTexel> Kernel for Shade<'_, '_, T, C> {
    type Output = (usize, usize);

    #[inline(always)]
    fn call(self) -> (usize, usize) {
        let Shade {
            input,
            rows,
            canvas,
            canvas_width,
            wide,
        } = self;
        let source = input.source;
        // The eight lanes write 8-bit levels only (an empty slice tells the canvas's kind).
        let wide = wide.filter(|_| T::as_levels_mut(&mut []).is_some());
        match source.eight_bit_view() {
            Some((texels, _)) => {
                let sampler = Sampler::with_texels(source, texels);
                let fast = wide.zip(sampler.levels());
                walk_rows(input, &sampler, fast, rows, (canvas, canvas_width))
            }
            None => walk_rows(input, &Sampler::new(source), None, rows, (canvas, canvas_width)),
        }
    }
}

#[inline(always)]
fn walk_rows<S: SourceTexel, T: Texel, C: CoverageTexel>(
    input: &ShadeInput<C>,
    sampler: &Sampler<S>,
    fast: Fast,
    rows: PixelRect,
    (canvas, canvas_width): (&mut [[T; 4]], usize),
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
        let cover_row = (y - input.coverage_origin.1) as usize * input.coverage_stride;
        let canvas_row = (y - rows.y0) as usize * canvas_width;
        let span = Span {
            x0: rows.x0,
            y,
            coverage: &input.coverage[cover_row + cover_first..cover_row + cover_last],
        };
        let row = &mut canvas[canvas_row + rows.x0 as usize..canvas_row + rows.x1 as usize];
        let ids = &input.ids[ids_row + first..ids_row + last];
        let (row_hits, row_written) = shade_row(input, sampler, fast, ids, &span, row);
        hits += row_hits;
        written += row_written;
    }
    (hits, written)
}

/// Shades one row (`span`, its triangle `ids`, its `pixels`): eight pixels at a time
/// where all eight are inside triangles and fully covered and `fast` applies, runs of equal
/// triangle id otherwise (at most eight long with `fast`, so the eight lanes come back
/// after the fringe). Gives the pixels whose centre a triangle owns and those written.
#[inline(always)]
fn shade_row<S: SourceTexel, T: Texel, C: CoverageTexel>(
    input: &ShadeInput<C>,
    sampler: &Sampler<S>,
    fast: Fast,
    ids: &[u32],
    span: &Span<C>,
    pixels: &mut [[T; 4]],
) -> (usize, usize) {
    let (mut hits, mut written, mut start) = (0, 0, 0);
    while start < ids.len() {
        // Outside the silhouette and every triangle (most of a bounding box): nothing to do.
        let outside = ids[start..].iter().zip(&span.coverage[start..]);
        let outside = outside.take_while(|&(&id, c)| id == NO_TRIANGLE && !c.is_covered());
        start += outside.count();
        if start == ids.len() {
            break;
        }
        let end = ids.len().min(start + 8);
        let x0 = span.x0 + start as i32;
        let lanes = Span {
            x0,
            y: span.y,
            coverage: &span.coverage[start..end],
        };
        let eight = end - start == 8
            && C::all_full(lanes.coverage)
            && ids[start..end].iter().all(|&id| id != NO_TRIANGLE);
        if let (Some(fast), true) = (fast, eight) {
            if let Some(out) = T::as_levels_mut(&mut pixels[start..end]) {
                written += shade_eight(input, fast, sampler, &lanes, &ids[start..end], out);
                hits += 8;
                start = end;
                continue;
            }
        }
        let id = ids[start];
        let limit = if fast.is_some() { end } else { ids.len() };
        let end = start + ids[start..limit].iter().take_while(|&&other| other == id).count();
        let run = Span {
            x0,
            y: span.y,
            coverage: &span.coverage[start..end],
        };
        let pixels = &mut pixels[start..end];
        written += if id == NO_TRIANGLE {
            shade_fringe(input, sampler, &run, pixels)
        } else {
            hits += end - start;
            shade_span(&input.setups[id as usize], sampler, &run, pixels)
        };
        start = end;
    }
    (hits, written)
}

/// Eight pixels inside triangles (`ids`) and fully covered, through the eight-lane shader;
/// the lanes whose sample is not opaque through the plain code. Returns the pixels written.
#[inline(always)]
fn shade_eight<S: SourceTexel, C: CoverageTexel>(
    input: &ShadeInput<C>,
    (wide, source): (Wide, LevelSource),
    sampler: &Sampler<S>,
    span: &Span<C>,
    ids: &[u32],
    out: &mut [[u8; 4]],
) -> usize {
    let setups = input.setups;
    let lane_ids: [u32; 8] = std::array::from_fn(|lane| ids[lane]);
    let maps = |id: u32| setups[id as usize].span.along_row(span.y).affine();
    // A patch moved by whole pixels: the eight samples are eight texels of one source row.
    let shift = setups[lane_ids[0] as usize].span.shift;
    let same = |shift| lane_ids.iter().all(|&id| setups[id as usize].span.shift == shift);
    let texels = shift.filter(|_| same(shift)).and_then(|[sx, sy]| {
        let (x, y) = (span.x0.checked_sub(sx)?, span.y.checked_sub(sy)?);
        source.run_start(x, y, 8)
    });
    let (levels, opaque) = match texels {
        Some(first) => wide.shade_texels(&source, first, span.x0, lane_ids, maps),
        None => wide.shade_opaque(&source, span.x0, lane_ids, maps),
    };
    if opaque == u8::MAX {
        out.copy_from_slice(&levels);
        return 8;
    }
    let mut written = 0;
    for (lane, (pixel, &texel)) in out.iter_mut().zip(span.coverage).enumerate() {
        if opaque >> lane & 1 == 1 {
            *pixel = levels[lane];
            written += 1;
        } else {
            let maps = setups[ids[lane] as usize].span.along_row(span.y);
            let x = span.x0 + lane as i32;
            written += shade_at(&maps, sampler, x, texel, pixel);
        }
    }
    written
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
        written += shade_at(&maps, sampler, x, texel, pixel);
    }
    written
}

/// One pixel of a triangle's row at column `x`, if covered; whether it was written.
#[inline(always)]
fn shade_at<S: SourceTexel, T: Texel, C: CoverageTexel>(
    maps: &RowMaps,
    sampler: &Sampler<S>,
    x: i32,
    texel: C,
    pixel: &mut [T; 4],
) -> usize {
    if !texel.is_covered() {
        return 0;
    }
    let (u, v, membrane) = maps.at(x);
    let sample = sampler.sample_texel_space(u, v);
    usize::from(shade_pixel(pixel, sample, membrane, texel))
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

#[cfg(test)]
mod tests {
    use glam::DVec2;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngSeed, TestRunner};

    use super::*;
    use crate::pixels::PixelFormat;
    use crate::raster::triangles::rasterise_triangles;

    /// A small deterministic generator, so one proptest seed drives a whole scene.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
        fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
        fn byte(&mut self) -> u8 {
            self.next() as u8
        }
    }

    /// The shading of one pixel written out as plainly as possible: every map evaluated in
    /// full at the pixel, each tap clamped and truncated by scalar comparisons and casts,
    /// each channel quantised by its own cast.
    fn reference_pixel(input: &ShadeInput<u8>, x: i32, y: i32, pixel: &mut [u8; 4]) {
        let source = input.source;
        let (w, h) = (source.width() as usize, source.height() as usize);
        let coverage = input.coverage[y as usize * input.coverage_stride + x as usize];
        if coverage == 0 {
            return;
        }
        let Some(triangle) = owning_triangle(input, x, y) else {
            return;
        };
        let span = &input.setups[triangle as usize].span;
        let dx = (x - span.membrane.origin[0]) as f32;
        let dy = (y - span.membrane.origin[1]) as f32;
        let at = |m: &[f32; 3]| m[0] + m[1] * dx + m[2] * dy;
        let [m0, mx, my] = span.membrane.maps;
        let membrane = m0 + mx * dx + my * dy;
        let tap = |p: f32, last: usize| {
            let low = if p > 0.0 { p } else { 0.0 };
            let u = if low < last as f32 { low } else { last as f32 };
            let i = u as i64 as usize;
            (i, (i + 1).min(last), u - i as f32)
        };
        let (x0, x1, tx) = tap(at(&span.texel_x), w - 1);
        let (y0, y1, ty) = tap(at(&span.texel_y), h - 1);
        let texel = |i: usize| match source.eight_bit_view() {
            Some((levels, _)) => Vec4::from_array(levels[i].map(f32::from)),
            None => Vec4::from_array(source.pixels()[i]),
        };
        let lerp = |a: Vec4, b: Vec4, t: f32| a + (b - a) * t;
        let top = lerp(texel(y0 * w + x0), texel(y0 * w + x1), tx);
        let bottom = lerp(texel(y1 * w + x0), texel(y1 * w + x1), tx);
        let blend = lerp(top, bottom, ty);
        let sample = match source.eight_bit_view() {
            Some(_) => blend / 255.0,
            None => blend,
        };
        let mut colour = (sample + membrane).clamp(Vec4::ZERO, Vec4::ONE);
        let quantise = |c: [f32; 4]| c.map(|v| (v * 255.0 + 0.5) as u8);
        if coverage == u8::MAX && sample.w >= 1.0 {
            *pixel = quantise(colour.to_array());
            return;
        }
        colour.w = sample.w;
        let alpha = coverage.unit().min(1.0) * colour.w;
        if alpha <= 0.0 {
            return;
        }
        if alpha >= 1.0 {
            *pixel = quantise(colour.to_array());
            return;
        }
        let premultiplied = [colour.x * alpha, colour.y * alpha, colour.z * alpha];
        let under = pixel.map(Texel::to_unit);
        *pixel = quantise(crate::pixels::canvas_composite_over(premultiplied, alpha, under));
    }

    /// Random sources (8-bit levels or floats, opaque or not), random triangles (any
    /// orientation, partly off the source and the canvas), random membranes, coverage and
    /// canvases: the shading loop writes exactly the reference's bytes, on the dispatched and
    /// the portable instruction sets.
    #[test]
    fn shading_matches_the_scalar_reference() {
        let config = Config {
            rng_seed: RngSeed::Fixed(0x5ade),
            cases: 300,
            ..Config::default()
        };
        // Pixels the reference changed, over all cases: the test must shade something.
        let changed = std::cell::Cell::new(0usize);
        // Stretches the eight lanes must have taken (on a CPU with them).
        let stretches = std::cell::Cell::new(0usize);
        // Those of them in patches moved by whole pixels (the lanes' direct texel reads).
        let shifted = std::cell::Cell::new(0usize);
        TestRunner::new(config)
            .run(&any::<u64>(), |seed| {
                let mut rng = Rng(seed | 1);
                // Half the cases are wide and mostly covered, so the eight-lane path runs
                // (across triangle edges too); the rest stress the fringe and coverage.
                let interior = rng.next() % 2 == 0;
                let (shift, w, h) = random_shift(&mut rng, interior);
                let opaque = rng.next() % 2 == 0;
                let source = random_source(&mut rng, w, h, opaque);
                let rect = PixelRect {
                    x0: 0,
                    y0: 0,
                    x1: if interior { 43 } else { 13 },
                    y1: 11,
                };
                let setups = random_setups(&mut rng, rect, interior, shift);
                let mut ids = vec![0; rect.area()];
                let mut bins = Default::default();
                rasterise_triangles(&setups, rect, false, (&mut ids, &mut []), &mut bins);
                let coverage = random_coverage(&mut rng, rect, interior);
                if opaque && source.eight_bit_view().is_some() {
                    let eights = eight_lane_stretches(&ids, &coverage, rect);
                    stretches.set(stretches.get() + eights);
                    if shift.is_some() {
                        shifted.set(shifted.get() + eights);
                    }
                }
                let canvas = random_canvas(&mut rng, rect);
                let input = ShadeInput {
                    setups: &setups,
                    ids: &ids,
                    ids_rect: rect,
                    coverage: &coverage,
                    coverage_stride: rect.width(),
                    coverage_origin: (0, 0),
                    source: &source,
                };
                let expected = reference_shading(&input, rect, &canvas);
                let differ = expected.iter().zip(&canvas).filter(|(a, b)| a != b).count();
                changed.set(changed.get() + differ);
                for path in [Path::Vector, Path::Portable] {
                    let shaded = shade_on(path, &input, rect, &canvas);
                    prop_assert_eq!(&shaded, &expected, "{:?}", path);
                }
                Ok(())
            })
            .unwrap();
        assert!(changed.get() > 3_000, "{} pixels shaded", changed.get());
        assert!(stretches.get() > 200, "{} eight-lane stretches", stretches.get());
        assert!(shifted.get() > 50, "{} shifted eight-lane stretches", shifted.get());
    }

    /// For a third of the `interior` cases, a whole-pixel move of every triangle (each vertex
    /// up to the placement grid's rounding off) over a source wide enough for the lanes'
    /// direct texel reads; then the source's size.
    fn random_shift(rng: &mut Rng, interior: bool) -> (Option<DVec2>, u64, u64) {
        let shift = (interior && rng.next() % 3 == 0).then(|| {
            let mut whole = || (rng.next() % 9) as f64 - 4.0;
            DVec2::new(whole(), whole())
        });
        let (w, h) = match shift {
            Some(_) => (16 + rng.next() % 40, 4 + rng.next() % 12),
            None => (2 + rng.next() % 9, 2 + rng.next() % 7),
        };
        (shift, w, h)
    }

    /// `canvas` (covering `rect`) shaded by the loop on `path`'s instruction set.
    fn shade_on(path: Path, input: &ShadeInput<u8>, rect: PixelRect, canvas: &[[u8; 4]]) -> Vec<[u8; 4]> {
        let mut shaded = canvas.to_vec();
        path.run(Shade {
            input,
            rows: rect,
            canvas: &mut shaded,
            canvas_width: rect.width(),
            wide: Wide::detect(path),
        });
        shaded
    }

    /// `canvas` (covering `rect`) shaded pixel by pixel by the scalar reference.
    fn reference_shading(input: &ShadeInput<u8>, rect: PixelRect, canvas: &[[u8; 4]]) -> Vec<[u8; 4]> {
        let mut expected = canvas.to_vec();
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                let pixel = &mut expected[y as usize * rect.width() + x as usize];
                reference_pixel(input, x, y, pixel);
            }
        }
        expected
    }

    /// A random canvas over `rect`, a third of its pixels translucent.
    fn random_canvas(rng: &mut Rng, rect: PixelRect) -> Vec<[u8; 4]> {
        (0..rect.area())
            .map(|_| {
                let a = if rng.next() % 3 == 0 { rng.byte() } else { 255 };
                [rng.byte(), rng.byte(), rng.byte(), a]
            })
            .collect()
    }

    /// A `w`×`h` source of random levels (alpha 255 when `opaque`), in 8 or 16 bits.
    fn random_source(rng: &mut Rng, w: u64, h: u64, opaque: bool) -> FloatImage {
        let levels: Vec<[u8; 4]> = (0..w * h)
            .map(|_| {
                let a = if opaque { 255 } else { rng.byte() };
                [rng.byte(), rng.byte(), rng.byte(), a]
            })
            .collect();
        let (w, h) = (w as u32, h as u32);
        match rng.next() % 3 {
            0 => FloatImage::from_fn(w, h, PixelFormat::RGBA16, |i, j| {
                levels[(j * w + i) as usize].map(|v| f32::from(v) / 255.0 * 0.999)
            }),
            _ => FloatImage::from_levels(w, h, levels.clone(), PixelFormat::RGBA8),
        }
        .unwrap()
    }

    /// One to six random triangles around `rect` with random rest points and membranes; with
    /// `interior`, the first covers all of `rect` under the others; with `shift`, every rest
    /// point is its placed point moved by those whole pixels (up to the placement grid).
    fn random_setups(
        rng: &mut Rng,
        rect: PixelRect,
        interior: bool,
        shift: Option<DVec2>,
    ) -> Vec<TriangleSetup> {
        let right = f64::from(rect.x1) + 2.0;
        (0..1 + rng.next() % 6)
            .map(|k| {
                let mut placed =
                    [0; 3].map(|_| DVec2::new(rng.range(-2.0, right), rng.range(-2.0, 15.0)));
                if interior && k == 0 {
                    placed = [[-9.0, -9.0], [99.0, -9.0], [-9.0, 40.0]].map(DVec2::from);
                }
                let mut point = |lo: f64, hi: f64| DVec2::new(rng.range(lo, hi), rng.range(lo, hi));
                let mut rest = [point(-3.0, 12.0), point(-3.0, 12.0), point(-3.0, 12.0)];
                if let Some(s) = shift {
                    let mut off = || f64::from(rng.next() as u8 % 3) - 1.0;
                    let grid = 1.0 / 131_072.0;
                    rest = placed.map(|p| p - s + DVec2::new(off(), off()) * grid);
                }
                let mut m = || rng.range(-0.7, 0.7) as f32;
                let membrane = [[m(), m(), m()], [m(), m(), m()], [m(), m(), m()]];
                TriangleSetup::new(placed, rest, membrane, [0.0; 3])
            })
            .collect()
    }

    /// Coverage over `rect`: mostly full with `interior` (long covered rows), else a mix of
    /// empty, partial and full pixels that stresses the fringe.
    fn random_coverage(rng: &mut Rng, rect: PixelRect, interior: bool) -> Vec<u8> {
        (0..rect.area())
            .map(|_| match (interior, rng.next() % 16) {
                (_, 0) => 0,
                (true, 1) | (false, 1..=4) => rng.byte(),
                (true, _) | (false, 5..=11) => u8::MAX,
                (false, _) => 0,
            })
            .collect()
    }

    /// Stretches of 16 pixels in a row, all inside triangles and fully covered: the row walk
    /// steps at most 8 pixels at a time, so it starts eight lanes in each.
    fn eight_lane_stretches(ids: &[u32], coverage: &[u8], rect: PixelRect) -> usize {
        let fits: Vec<bool> = ids
            .iter()
            .zip(coverage)
            .map(|(&id, &c)| id != NO_TRIANGLE && c == u8::MAX)
            .collect();
        fits.chunks(rect.width())
            .flat_map(|row| row.split(|&f| !f))
            .map(|run| run.len() / 16)
            .sum()
    }
}
