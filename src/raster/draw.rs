//! Drawing one patch: takes a [`Patch`] with its solved membrane, options and a
//! [`RasterScratch`] and composites the patch over a [`Canvas`], in one sequential pass
//! inside the patch's bounding box: per-triangle setup and silhouette coverage, exact
//! pixel-centre ownership with the depth test, then shading row by row.

use std::sync::Mutex;

use super::feather::apply_feather;
use super::prepare::prepare;
use super::setup::MAX_COORDINATE;
use super::shade::{shade_and_composite, CoverageTexel, ShadeInput};
use super::triangles::{rasterise_triangles, NO_TRIANGLE};
use super::{Patch, PixelRect, RasterError, RasterScratch};
use crate::pixels::{Canvas, CanvasPixels, Texel};

/// How to draw a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterOptions {
    /// Width in px of the coverage ramp inside the silhouette (0: none).
    pub feather: f32,
    /// Anti-alias the silhouette (tiny-skia coverage); off: pixel-centre coverage only.
    pub anti_alias: bool,
    /// Threads that shade (row ranges, the caller's thread and scoped ones); the pixels are
    /// the same for any count. 1 by default: a scene render's other cores encode frames.
    pub threads: usize,
}

impl Default for RasterOptions {
    fn default() -> Self {
        RasterOptions {
            feather: 0.0,
            anti_alias: true,
            threads: 1,
        }
    }
}

/// What a draw touched.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Pixels examined (the patch's bounding box with margins, clipped near the canvas).
    pub work: PixelRect,
    /// Work pixels whose centre lies in a placed triangle.
    pub centre_hits: usize,
    /// Canvas pixels written.
    pub written: usize,
}

/// Composites `patch` over `canvas`. Allocates nothing once `scratch` has grown. On an
/// error the canvas is untouched.
pub fn draw_patch(
    canvas: &mut Canvas,
    patch: &Patch,
    options: &RasterOptions,
    scratch: &mut RasterScratch,
) -> Result<RasterStats, RasterError> {
    patch.validate()?;
    if !(options.feather.is_finite() && options.feather >= 0.0) {
        return Err(RasterError::Feather(options.feather));
    }
    let Some(work) = work_rect(patch, canvas, options.feather) else {
        return Ok(RasterStats::default());
    };
    prepare(patch, work, options.anti_alias, scratch);
    let use_depth = patch.depth.is_some();
    scratch.ids.resize(work.area(), 0);
    if use_depth {
        scratch.depths.resize(work.area(), 0.0);
    }
    let all = 0..scratch.setups.len() as u32;
    let (ids, depths) = (&mut scratch.ids, &mut scratch.depths);
    rasterise_triangles(&scratch.setups, all, work, use_depth, ids, depths);
    let frame = Frame {
        patch,
        work,
        target: work.intersect(&canvas.bounds()),
        width: canvas.width() as usize,
        threads: options.threads,
    };
    let (centre_hits, written) = match canvas.pixels_mut() {
        CanvasPixels::Eight(p) => frame.shade(options, scratch, p),
        CanvasPixels::Sixteen(p) => frame.shade(options, scratch, p),
    };
    Ok(RasterStats {
        work,
        centre_hits,
        written,
    })
}

/// Fewer rows than this per thread are shaded on the caller's thread alone.
const MIN_ROWS_PER_THREAD: usize = 64;

/// Rows per band the shading threads take in turn (see `Frame::in_parts`).
const ROWS_PER_BAND: usize = 40;

/// One draw's rectangles and canvas width.
struct Frame<'a> {
    patch: &'a Patch<'a>,
    work: PixelRect,
    /// The work rectangle clipped to the canvas: the pixels that can be written.
    target: PixelRect,
    /// The canvas width in pixels.
    width: usize,
    /// Threads to shade on.
    threads: usize,
}

impl Frame<'_> {
    /// Shades the target rectangle with the coverage the options ask for; gives (centre
    /// hits, pixels written).
    fn shade<T: Texel + Send>(
        &self,
        options: &RasterOptions,
        scratch: &mut RasterScratch,
        canvas: &mut [[T; 4]],
    ) -> (usize, usize) {
        let hit = |&id: &u32| id != NO_TRIANGLE;
        if options.feather > 0.0 {
            let mut coverage = std::mem::take(&mut scratch.feathered);
            coverage.clear();
            match options.anti_alias {
                true => {
                    let work = self.work;
                    for y in work.y0..work.y1 {
                        let row = scratch.silhouette.row(y, work.x0, work.x1);
                        coverage.extend(row.iter().map(|&m| m.unit()));
                    }
                }
                false => coverage.extend(scratch.ids.iter().map(|id| f32::from(u8::from(hit(id))))),
            }
            scratch.distance.resize(self.work.area(), 0.0);
            let (distance, row) = (&mut scratch.distance, &mut scratch.distance_row);
            apply_feather(
                &scratch.ids,
                self.work.width(),
                options.feather,
                distance,
                row,
                &mut coverage,
            );
            let totals = self.shade_target(scratch, &coverage, canvas);
            scratch.feathered = coverage;
            return totals;
        }
        if !options.anti_alias {
            let mut coverage = std::mem::take(&mut scratch.centres);
            coverage.clear();
            coverage.extend(scratch.ids.iter().map(|id| u8::from(hit(id)) * u8::MAX));
            let totals = self.shade_target(scratch, &coverage, canvas);
            scratch.centres = coverage;
            return totals;
        }
        // Each strip of the silhouette shades the target rows it holds from its own mask;
        // threads split the target's rows, whatever the strips.
        let scratch = &*scratch;
        self.in_parts(self.target, canvas, |part, canvas| {
            let mut totals = (0, 0);
            for strip in scratch.silhouette.strips() {
                let rows = part.intersect(&strip.rect());
                if !rows.is_empty() {
                    let canvas = &mut canvas[(rows.y0 - part.y0) as usize * self.width..];
                    let input = self.input(scratch, strip.coverage());
                    let (h, w) = shade_and_composite(&input, rows, canvas, self.width);
                    totals = (totals.0 + h, totals.1 + w);
                }
            }
            totals
        })
    }

    fn input<'a, C>(
        &'a self,
        scratch: &'a RasterScratch,
        (coverage, coverage_stride, coverage_origin): (&'a [C], usize, (i32, i32)),
    ) -> ShadeInput<'a, C> {
        ShadeInput {
            setups: &scratch.setups,
            ids: &scratch.ids,
            ids_rect: self.work,
            coverage,
            coverage_stride,
            coverage_origin,
            source: self.patch.source,
        }
    }

    /// Shades the whole target with `coverage` laid out like the work rectangle.
    fn shade_target<T: Texel + Send, C: CoverageTexel + Sync>(
        &self,
        scratch: &RasterScratch,
        coverage: &[C],
        canvas: &mut [[T; 4]],
    ) -> (usize, usize) {
        let origin = (self.work.x0, self.work.y0);
        let layout = (coverage, self.work.width(), origin);
        self.shade_rows(scratch, layout, self.target, canvas)
    }

    /// Shades `rows` (inside the target) with `coverage` (texels, row stride, the canvas
    /// pixel of texel 0).
    fn shade_rows<T: Texel + Send, C: CoverageTexel + Sync>(
        &self,
        scratch: &RasterScratch,
        coverage: (&[C], usize, (i32, i32)),
        rows: PixelRect,
        canvas: &mut [[T; 4]],
    ) -> (usize, usize) {
        let input = self.input(scratch, coverage);
        self.in_parts(rows, canvas, |part, canvas| {
            shade_and_composite(&input, part, canvas, self.width)
        })
    }

    /// Runs `shade` over `rows` of the canvas in bands of [`ROWS_PER_BAND`] rows, which the
    /// caller's thread and up to `threads − 1` scoped ones take in turn until none is left;
    /// `shade` gets a band and the canvas from that band's first row on, and gives (centre
    /// hits, pixels written), summed here. Rows shade independently, so the pixels are the
    /// same for any split. Bands are taken rather than halves given out because a helper
    /// starts 50–60 µs late (its spawn) and may share its core: the caller does not wait
    /// for a fixed half that started late.
    fn in_parts<T: Texel + Send>(
        &self,
        rows: PixelRect,
        canvas: &mut [[T; 4]],
        shade: impl Fn(PixelRect, &mut [[T; 4]]) -> (usize, usize) + Sync,
    ) -> (usize, usize) {
        let mut canvas_rows = &mut canvas[rows.y0.max(0) as usize * self.width..];
        let height = rows.height();
        let helpers = self.threads.min(height / MIN_ROWS_PER_THREAD).max(1) - 1;
        if helpers == 0 {
            return shade(rows, canvas_rows);
        }
        let mut bands = Vec::with_capacity(height.div_ceil(ROWS_PER_BAND));
        let mut y0 = rows.y0;
        while y0 < rows.y1 {
            let y1 = (y0 + ROWS_PER_BAND as i32).min(rows.y1);
            let len = ((y1 - y0) as usize * self.width).min(canvas_rows.len());
            let (band, rest) = std::mem::take(&mut canvas_rows).split_at_mut(len);
            canvas_rows = rest;
            bands.push((PixelRect { y0, y1, ..rows }, band));
            y0 = y1;
        }
        let bands = Mutex::new(bands.into_iter());
        let take_bands = || {
            let mut sum = (0, 0);
            // A poisoned lock means another thread panicked, which the join below reports.
            while let Some((band_rows, band)) = bands.lock().ok().and_then(|mut b| b.next()) {
                let (h, w) = shade(band_rows, band);
                sum = (sum.0 + h, sum.1 + w);
            }
            sum
        };
        std::thread::scope(|scope| {
            let spawned: Vec<_> = (0..helpers).map(|_| scope.spawn(take_bands)).collect();
            let mine = take_bands();
            spawned.into_iter().fold(mine, |(h, w), handle| {
                // invariant: shading does not panic on validated input; a panic is a bug
                // to surface, not to hide.
                let (h2, w2) = handle.join().expect("a shading thread");
                (h + h2, w + w2)
            })
        })
    }
}

/// The placed bounding box grown by the AA band and the feather width, intersected with the
/// canvas grown by the feather width (so distances near the canvas edge see the silhouette
/// just outside it). `None` when nothing can reach the canvas.
fn work_rect(patch: &Patch, canvas: &Canvas, feather: f32) -> Option<PixelRect> {
    let mut min = glam::DVec2::splat(f64::INFINITY);
    let mut max = glam::DVec2::splat(f64::NEG_INFINITY);
    for tri in patch.triangles {
        for &v in tri {
            let p = patch.placed[v as usize];
            min = min.min(p);
            max = max.max(p);
        }
    }
    if !(min.x <= max.x && min.y <= max.y) {
        return None;
    }
    let clamp = |v: f64| v.clamp(-MAX_COORDINATE, MAX_COORDINATE) as i32;
    let margin = feather.ceil() as i32 + 2;
    let placed = PixelRect {
        x0: clamp(min.x.floor()) - 1,
        y0: clamp(min.y.floor()) - 1,
        x1: clamp(max.x.ceil()) + 1,
        y1: clamp(max.y.ceil()) + 1,
    };
    let work = placed.intersect(&canvas.bounds().grow(margin));
    (!work.is_empty() && !placed.intersect(&canvas.bounds()).is_empty()).then_some(work)
}
