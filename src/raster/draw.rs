//! Drawing one patch: takes a [`Patch`] with its solved membrane, options and a
//! [`RasterScratch`] and composites the patch over a [`Canvas`] inside the patch's bounding
//! box: per-triangle setup and silhouette coverage, exact pixel-centre ownership with the
//! depth test, then shading row by row; on one thread, or with `RasterOptions::threads` on
//! several (the same pixels).

use std::sync::{Mutex, OnceLock};

use super::bands::Bands;
use super::coverage::Silhouette;
use super::feather::apply_feather;
use super::prepare::{prepare, prepare_setups, prepare_silhouette};
use super::setup::{TriangleSetup, MAX_COORDINATE};
use super::shade::{shade_and_composite, CoverageTexel, ShadeInput};
use super::triangles::{bands, rasterise_triangles, Band, TriangleBins, NO_TRIANGLE};
use super::workers::{self, MAX_RASTER_THREADS};
use super::{Patch, PixelRect, RasterError, RasterScratch};
use crate::pixels::{Canvas, CanvasPixels, Texel};

/// How to draw a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterOptions {
    /// Width in px of the coverage ramp inside the silhouette (0: none).
    pub feather: f32,
    /// Anti-alias the silhouette (tiny-skia coverage); off: pixel-centre coverage only.
    pub anti_alias: bool,
    /// Threads that draw (the caller's, and the raster's worker pool, one thread per core,
    /// started on the first draw that asks for more than one); the pixels are the same for
    /// any count. 1 by default: a scene render's other cores encode frames. At most
    /// [`MAX_RASTER_THREADS`], and one per 64 rows of the patch, share a draw.
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
    if !crate::limits::feather_in_range(f64::from(options.feather)) {
        return Err(RasterError::Feather(options.feather));
    }
    let Some(work) = work_rect(patch, canvas, options.feather) else {
        return Ok(RasterStats::default());
    };
    if work.area() as u64 > crate::limits::MAX_RASTER_PIXELS {
        let (width, height) = (work.width(), work.height());
        return Err(RasterError::WorkTooLarge { width, height });
    }
    let frame = Frame {
        patch,
        work,
        target: work.intersect(&canvas.bounds()),
        width: canvas.width() as usize,
        threads: options.threads,
    };
    let overlap = options.anti_alias && options.feather == 0.0;
    let overlap = overlap && frame.helpers(frame.target) > 0;
    let (centre_hits, written) = match (canvas.pixels_mut(), overlap) {
        (CanvasPixels::Eight(p), true) => frame.draw_overlapped(scratch, p),
        (CanvasPixels::Sixteen(p), true) => frame.draw_overlapped(scratch, p),
        (pixels, false) => {
            prepare(patch, work, options.anti_alias, scratch);
            let buffers = (&mut scratch.ids, &mut scratch.depths);
            frame.rasterise(&scratch.setups, buffers, &mut scratch.bins);
            match pixels {
                CanvasPixels::Eight(p) => frame.shade(options, scratch, p),
                CanvasPixels::Sixteen(p) => frame.shade(options, scratch, p),
            }
        }
    };
    Ok(RasterStats {
        work,
        centre_hits,
        written,
    })
}

/// Fewer rows than this per thread are shaded on the caller's thread alone.
const MIN_ROWS_PER_THREAD: usize = 64;

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
    /// Fills `ids` (and `depths`, with depth) over the work rectangle from `setups`.
    fn rasterise(&self, setups: &[TriangleSetup], buffers: IdBuffers, bins: &mut TriangleBins) {
        let use_depth = self.sized((&mut *buffers.0, &mut *buffers.1));
        rasterise_triangles(setups, self.work, use_depth, (buffers.0, buffers.1), bins);
    }

    /// Sizes `ids` (and `depths`, with depth) to the work rectangle; whether with depth.
    fn sized(&self, (ids, depths): IdBuffers) -> bool {
        let use_depth = self.patch.depth.is_some();
        ids.resize(self.work.area(), 0);
        if use_depth {
            depths.resize(self.work.area(), 0.0);
        }
        use_depth
    }

    /// The anti-aliased, unfeathered draw on the raster's workers, in two parts. First the
    /// caller sets up the triangles and bins them by row band while a free worker fills the
    /// silhouette, and both draw the bands' ids (the three depend only on the patch); then
    /// the workers shade [`Bands`]. A part no worker took in time runs on the caller's
    /// thread (see [`workers`](super::workers)), so nothing waits for a busy core.
    fn draw_overlapped<T: Texel + Send>(
        &self,
        scratch: &mut RasterScratch,
        canvas: &mut [[T; 4]],
    ) -> (usize, usize) {
        workers::on_pool(|| {
            self.prepare_shared(scratch);
            let drawn = (&scratch.setups[..], &scratch.ids[..], &scratch.silhouette);
            self.in_parts(self.target, canvas, |part, canvas| {
                self.shade_strips(drawn, part, canvas)
            })
        })
    }

    /// The first part of [`draw_overlapped`](Self::draw_overlapped): the caller sets up and
    /// bins the triangles and draws id bands; the silhouette's part fills it, then draws id
    /// bands too if the bins are ready by then.
    fn prepare_shared(&self, scratch: &mut RasterScratch) {
        let use_depth = self.sized((&mut scratch.ids, &mut scratch.depths));
        let RasterScratch {
            setups,
            snapped,
            ids,
            depths,
            silhouette,
            folds,
            bins,
            ..
        } = scratch;
        let (patch, work) = (self.patch, self.work);
        let id_bands = &Mutex::new(bands(work, ids, depths, use_depth));
        let binned: &OnceLock<(&[TriangleSetup], &TriangleBins)> = &OnceLock::new();
        workers::both(
            move || {
                prepare_setups(patch, snapped, setups);
                bins.fill(setups, work);
                let (setups, bins) = binned.get_or_init(|| (setups, bins));
                draw_bands(setups, bins, id_bands);
            },
            move || {
                prepare_silhouette(patch, work, folds, silhouette);
                if let Some((setups, bins)) = binned.get() {
                    draw_bands(setups, bins, id_bands);
                }
            },
        );
    }

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
        let drawn = (&scratch.setups[..], &scratch.ids[..], &scratch.silhouette);
        self.in_parts(self.target, canvas, |part, canvas| {
            self.shade_strips(drawn, part, canvas)
        })
    }

    /// Shades the canvas rows `part` (`canvas` from its first row on): each strip of the
    /// silhouette the rows it holds, from its own mask, whatever the bands.
    fn shade_strips<T: Texel>(
        &self,
        (setups, ids, silhouette): (&[TriangleSetup], &[u32], &Silhouette),
        part: PixelRect,
        canvas: &mut [[T; 4]],
    ) -> (usize, usize) {
        let mut totals = (0, 0);
        for strip in silhouette.strips() {
            let rows = part.intersect(&strip.rect());
            if !rows.is_empty() {
                let canvas = &mut canvas[(rows.y0 - part.y0) as usize * self.width..];
                let input = self.input((setups, ids), strip.coverage());
                let (h, w) = shade_and_composite(&input, rows, canvas, self.width);
                totals = (totals.0 + h, totals.1 + w);
            }
        }
        totals
    }

    fn input<'a, C>(
        &'a self,
        (setups, ids): (&'a [TriangleSetup], &'a [u32]),
        (coverage, coverage_stride, coverage_origin): (&'a [C], usize, (i32, i32)),
    ) -> ShadeInput<'a, C> {
        ShadeInput {
            setups,
            ids,
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
        let input = self.input((&scratch.setups, &scratch.ids), coverage);
        self.in_parts(rows, canvas, |part, canvas| {
            shade_and_composite(&input, part, canvas, self.width)
        })
    }

    /// Runs `shade` over `rows` of the canvas as up to `threads` copies on the raster's
    /// workers, which take [`Bands`] in turn; `shade` gets a band and the canvas from its
    /// first row on, and gives (centre hits, pixels written), summed here.
    fn in_parts<T: Texel + Send>(
        &self,
        rows: PixelRect,
        canvas: &mut [[T; 4]],
        shade: impl Fn(PixelRect, &mut [[T; 4]]) -> (usize, usize) + Sync,
    ) -> (usize, usize) {
        let canvas_rows = &mut canvas[rows.y0.max(0) as usize * self.width..];
        let helpers = self.helpers(rows);
        if helpers == 0 {
            return shade(rows, canvas_rows);
        }
        let bands = Bands::new(rows, self.width, canvas_rows);
        workers::on_pool(|| workers::copies(helpers + 1, &|| bands.shade(&shade)))
    }

    /// Threads besides the caller's to shade `rows` on.
    fn helpers(&self, rows: PixelRect) -> usize {
        let threads = self.threads.min(MAX_RASTER_THREADS);
        threads.min(rows.height() / MIN_ROWS_PER_THREAD).max(1) - 1
    }
}

/// The per-pixel ids and depths of the work rectangle.
type IdBuffers<'a> = (&'a mut Vec<u32>, &'a mut Vec<f32>);

/// Draws the triangles of the bands left in `left` until none is.
fn draw_bands<'a>(
    setups: &[TriangleSetup],
    bins: &TriangleBins,
    left: &Mutex<impl Iterator<Item = Band<'a>>>,
) {
    // A poisoned lock means the other thread panicked, which its join reports.
    while let Some(band) = left.lock().ok().and_then(|mut left| left.next()) {
        bins.rasterise(setups, band);
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
