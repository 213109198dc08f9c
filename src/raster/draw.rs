//! Drawing one patch: takes a [`Patch`], options and a [`RasterScratch`] and composites the
//! patch over a [`Canvas`]. Per frame: per-triangle setup and silhouette coverage once (in
//! pieces that two threads share, for large patches), then per row band (threaded likewise)
//! exact coverage with depth test and shading — all inside the patch's bounding box.
//! Feathered patches draw in one piece.

use std::sync::{Mutex, OnceLock};

use super::bands::{Bands, APRON};
use super::coverage::Silhouette;
use super::feather::apply_feather;
use super::helper;
use super::prepare::prepare;
use super::record::record_and_composite;
use super::replay::SpanGeometry;
use super::scratch::BandScratch;
use super::setup::{TriangleSetup, MAX_COORDINATE};
use super::shade::{
    shade_and_composite, CoverageTexel, NoRecorder, Recorder, ShadeInput, StoreTexel,
};
use super::shade_simd::Kernel;
use super::triangles::{rasterise_triangles, NO_TRIANGLE};
use super::{Patch, PixelRect, RasterError, RasterScratch};
use crate::pixels::{Canvas, CanvasPixels, Depth};
use crate::util::lock;

/// How to draw a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterOptions {
    /// Width in px of the coverage ramp inside the silhouette (0: none).
    pub feather: f32,
    /// Anti-alias the silhouette (tiny-skia coverage); off: pixel-centre coverage only.
    pub anti_alias: bool,
    /// Threads drawing one large patch (0: one per core). Any count gives the same pixels.
    pub threads: usize,
    /// Replay the previous draw when the patch only moved by whole pixels (see
    /// `raster/replay.rs`). Only for a scratch that stays with one patch whose
    /// source and mesh are not modified in place between draws.
    pub replay: bool,
    /// Shade with the CPU's SIMD kernel when it has one (AVX2 on x86_64, 8-bit canvases).
    /// It gives the same bytes as the scalar path, which `false` forces (tests compare them).
    pub simd: bool,
}

impl Default for RasterOptions {
    fn default() -> Self {
        RasterOptions {
            feather: 0.0,
            anti_alias: true,
            threads: 0,
            replay: false,
            simd: true,
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
    /// Whether the draw replayed the previous one moved by whole pixels (see
    /// [`RasterOptions::replay`]).
    pub replayed: bool,
}

/// Composites `patch` over `canvas`. Allocates nothing once `scratch` has grown (apart from
/// the worker threads of a large patch).
pub fn draw_patch(
    canvas: &mut Canvas,
    patch: &Patch,
    options: &RasterOptions,
    scratch: &mut RasterScratch,
) -> Result<RasterStats, RasterError> {
    draw_patch_solving(canvas, patch, options, scratch, |_| Ok(patch.membrane))
}

/// [`draw_patch`] for a patch whose membrane is not known yet: `solve` gives it, reading the
/// canvas before anything is drawn (`patch.membrane` is not read). On a large patch `solve`
/// runs on this thread while a helper thread starts the raster's membrane-free work (see
/// `raster/prepare.rs`), so the draw finishes sooner than a solve followed by
/// [`draw_patch`] — with the same bytes. `solve` runs exactly once, also when nothing is
/// drawn; its error ends the draw with the canvas untouched.
pub fn draw_patch_solving<'m, E: From<RasterError>>(
    canvas: &mut Canvas,
    patch: &Patch,
    options: &RasterOptions,
    scratch: &mut RasterScratch,
    solve: impl FnOnce(&Canvas) -> Result<&'m [[f32; 3]], E>,
) -> Result<RasterStats, E> {
    let checked = patch.validate_geometry().and_then(|()| {
        match options.feather.is_finite() && options.feather >= 0.0 {
            true => Ok(work_rect(patch, canvas, options.feather)),
            false => Err(RasterError::Feather(options.feather)),
        }
    });
    let Some(work) = checked? else {
        let membrane = solve(canvas)?;
        patch.validate_membrane(membrane)?;
        return Ok(RasterStats::default());
    };
    if let Some(shift) = replay_shift(canvas, patch, options, work, scratch) {
        return replay(canvas, patch, options, work, shift, scratch, solve);
    }
    let canvas_bounds = canvas_rect(canvas);
    let target = work.intersect(&canvas_bounds);
    let replayable = options.replay && patch.depth.is_none() && options.feather == 0.0;
    if replayable && target == work && scratch.replay.wants_record(patch, options.anti_alias, work)
    {
        return record_and_composite(canvas, patch, options, work, scratch, solve);
    }
    let threads = worker_threads(options.threads, work.area(), usize::MAX);
    let membrane = prepare(patch, work, options.anti_alias, threads, scratch, || {
        solve(canvas)
    })?;
    let patch = &Patch { membrane, ..*patch };
    let frame = Frame {
        patch,
        work,
        target,
        anti_alias: options.anti_alias,
        threads,
        use_depth: patch.depth.is_some(),
        kernel: if options.simd {
            Kernel::detect()
        } else {
            Kernel::Scalar
        },
    };
    let canvas_width = canvas.width() as usize;
    let mut none = NoRecorder;
    let (centre_hits, written) = match canvas.pixels_mut() {
        CanvasPixels::Eight(p) => draw_frame(&frame, options, scratch, p, canvas_width, &mut none),
        CanvasPixels::Sixteen(p) => {
            draw_frame(&frame, options, scratch, p, canvas_width, &mut none)
        }
    };
    if replayable {
        scratch.replay.remember(patch, options.anti_alias);
    }
    Ok(RasterStats {
        work,
        centre_hits,
        written,
        replayed: false,
    })
}

/// The whole-pixel shift by which the scratch's record replays as `patch` (see
/// [`replay`](super::replay)); `None` when a fresh draw is needed. Reads no membrane.
fn replay_shift(
    canvas: &Canvas,
    patch: &Patch,
    options: &RasterOptions,
    work: PixelRect,
    scratch: &RasterScratch,
) -> Option<(i32, i32)> {
    if !options.replay || patch.depth.is_some() || options.feather != 0.0 {
        return None;
    }
    scratch
        .replay
        .shift_for(patch, options.anti_alias, canvas_rect(canvas), work)
}

/// Replays the scratch's record shifted by `shift` with the membrane `solve` gives (see
/// [`Replay::draw_solving`](super::replay::Replay::draw_solving)).
pub(super) fn replay<'m, E: From<RasterError>>(
    canvas: &mut Canvas,
    patch: &Patch,
    options: &RasterOptions,
    work: PixelRect,
    shift: (i32, i32),
    scratch: &mut RasterScratch,
    solve: impl FnOnce(&Canvas) -> Result<&'m [[f32; 3]], E>,
) -> Result<RasterStats, E> {
    let solve = |canvas: &Canvas| -> Result<&'m [[f32; 3]], E> {
        let membrane = solve(canvas)?;
        patch.validate_membrane(membrane)?;
        Ok(membrane)
    };
    let geometry = SpanGeometry {
        placed: patch.placed,
        triangles: patch.triangles,
    };
    let threads = worker_threads(options.threads, work.area(), 2);
    let (replay, workers) = (&scratch.replay, &mut scratch.replay_spans);
    let (centre_hits, written) = match canvas.depth() {
        Depth::Eight => {
            replay.draw_solving(shift, geometry, threads, workers, canvas, eight_bit, solve)
        }
        Depth::Sixteen => replay.draw_solving(
            shift,
            geometry,
            threads,
            workers,
            canvas,
            sixteen_bit,
            solve,
        ),
    }?;
    scratch.replay.remember(patch, options.anti_alias);
    Ok(RasterStats {
        work,
        centre_hits,
        written,
        replayed: true,
    })
}

fn eight_bit(canvas: &mut Canvas) -> &mut [[u8; 4]] {
    match canvas.pixels_mut() {
        CanvasPixels::Eight(pixels) => pixels,
        // invariant: called only for a canvas whose depth is eight bits.
        CanvasPixels::Sixteen(_) => unreachable!("an 8-bit canvas"),
    }
}

fn sixteen_bit(canvas: &mut Canvas) -> &mut [[u16; 4]] {
    match canvas.pixels_mut() {
        CanvasPixels::Sixteen(pixels) => pixels,
        // invariant: called only for a canvas whose depth is sixteen bits.
        CanvasPixels::Eight(_) => unreachable!("a 16-bit canvas"),
    }
}

/// What every band of one draw shares.
pub(super) struct Frame<'a> {
    pub(super) patch: &'a Patch<'a>,
    pub(super) work: PixelRect,
    /// The work rectangle clipped to the canvas: the pixels that can be written.
    pub(super) target: PixelRect,
    /// Whether the silhouette strips hold the coverage (else pixel centres decide).
    pub(super) anti_alias: bool,
    /// Threads drawing the frame (1 for a recording).
    pub(super) threads: usize,
    pub(super) use_depth: bool,
    pub(super) kernel: Kernel,
}

/// Draws over the canvas pixels; gives (centre hits, pixels written).
pub(super) fn draw_frame<T: StoreTexel + Send, R: Recorder<u8>>(
    frame: &Frame,
    options: &RasterOptions,
    scratch: &mut RasterScratch,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
    recorder: &mut R,
) -> (usize, usize) {
    if options.feather > 0.0 {
        return draw_feathered(frame, options.feather, scratch, canvas, canvas_width);
    }
    let target = frame.target;
    scratch.bands.build(
        &scratch.centre_rows,
        (target.y0, target.y1),
        target.width(),
        scratch.band_pixels,
    );
    let threads = frame.threads.min(scratch.bands.count()).max(1);
    if scratch.workers.len() < threads {
        scratch.workers.resize_with(threads, BandScratch::default);
    }
    let shared = BandInput {
        frame,
        setups: &scratch.setups,
        bands: &scratch.bands,
        silhouette: frame.anti_alias.then_some(&scratch.silhouette),
    };
    let band_rows = scratch.bands.height() as usize * canvas_width;
    let rows = &mut canvas[target.y0 as usize * canvas_width..target.y1 as usize * canvas_width];
    let mut jobs = rows.chunks_mut(band_rows).enumerate();
    let workers = &mut scratch.workers[..threads];
    if threads == 1 {
        let worker = &mut workers[0];
        return jobs.fold((0, 0), |(hits, written), (band, rows)| {
            let (h, w) = draw_band(&shared, band, rows, canvas_width, worker, recorder);
            (hits + h, written + w)
        });
    }
    let queue = Mutex::new(&mut jobs);
    let mut totals = [(0usize, 0usize); MAX_THREADS];
    let take_bands = |worker: &mut BandScratch, total: &mut (usize, usize)| loop {
        let job = lock(&queue).next();
        let Some((band, rows)) = job else { break };
        let (h, w) = draw_band(&shared, band, rows, canvas_width, worker, &mut NoRecorder);
        *total = (total.0 + h, total.1 + w);
    };
    // This thread is one of the workers and its helper thread another; more (on machines
    // with more cores) are spawned.
    let ((own, others), (own_total, other_totals)) =
        (workers.split_at_mut(1), totals.split_at_mut(1));
    let ((helped, spawned), (helped_total, spawned_totals)) =
        (others.split_at_mut(1), other_totals.split_at_mut(1));
    let take_bands = &take_bands;
    helper::join(
        || take_bands(&mut helped[0], &mut helped_total[0]),
        || {
            std::thread::scope(|scope| {
                for (worker, total) in spawned.iter_mut().zip(spawned_totals) {
                    scope.spawn(move || take_bands(worker, total));
                }
                take_bands(&mut own[0], &mut own_total[0]);
            })
        },
    );
    totals.iter().fold((0, 0), |(h, w), t| (h + t.0, w + t.1))
}

/// At most this many threads draw one patch.
const MAX_THREADS: usize = 8;

/// Below this many target pixels a second thread costs more than it saves.
const THREADED_AREA: usize = 64 * 1024;

/// Threads for one draw: `requested` (0: one per core), at most one per band.
pub(super) fn worker_threads(requested: usize, area: usize, bands: usize) -> usize {
    static CORES: OnceLock<usize> = OnceLock::new();
    let cores = *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let wanted = if requested == 0 { cores } else { requested };
    if area < THREADED_AREA {
        return 1;
    }
    wanted.clamp(1, MAX_THREADS).min(bands.max(1))
}

/// What a band worker reads.
struct BandInput<'a> {
    frame: &'a Frame<'a>,
    setups: &'a [TriangleSetup],
    bands: &'a Bands,
    silhouette: Option<&'a Silhouette>,
}

/// Rasterises one band's triangles over the band and its apron, then shades the band's
/// rows (`canvas_rows`: those canvas rows, whole). Gives (centre hits, pixels written).
fn draw_band<T: StoreTexel, R: Recorder<u8>>(
    input: &BandInput,
    band: usize,
    canvas_rows: &mut [[T; 4]],
    canvas_width: usize,
    scratch: &mut BandScratch,
    recorder: &mut R,
) -> (usize, usize) {
    let frame = input.frame;
    let (work, target) = (frame.work, frame.target);
    let (y0, y1) = input.bands.rows(band);
    let ids_rect = PixelRect {
        y0: (y0 - APRON).max(work.y0),
        y1: (y1 + APRON).min(work.y1),
        ..work
    };
    scratch.prepare(ids_rect.area(), frame.use_depth);
    let triangles = input.bands.triangles(band).iter().copied();
    rasterise_triangles(
        input.setups,
        triangles,
        ids_rect,
        frame.use_depth,
        &mut scratch.ids,
        &mut scratch.depths,
    );
    let rows = PixelRect { y0, y1, ..target };
    let shade = |coverage, stride, origin| ShadeInput {
        setups: input.setups,
        ids: &scratch.ids,
        ids_rect,
        coverage,
        coverage_stride: stride,
        coverage_origin: origin,
        source: frame.patch.source,
        kernel: frame.kernel,
    };
    let Some(silhouette) = input.silhouette else {
        let hit = |&id: &u32| if id == NO_TRIANGLE { 0 } else { u8::MAX };
        let mut coverage = std::mem::take(&mut scratch.coverage);
        coverage.clear();
        coverage.extend(scratch.ids.iter().map(hit));
        let origin = (ids_rect.x0, ids_rect.y0);
        let input = shade(&coverage, ids_rect.width(), origin);
        let totals = shade_and_composite(&input, rows, canvas_rows, canvas_width, recorder);
        scratch.coverage = coverage;
        return totals;
    };
    // A band may straddle a border between strips: each part reads its own strip's mask.
    let mut totals = (0, 0);
    for strip in silhouette.strips() {
        let part = rows.intersect(&strip.rect());
        if part.is_empty() {
            continue;
        }
        let (coverage, stride, origin) = strip.coverage();
        let canvas_part = &mut canvas_rows[(part.y0 - y0) as usize * canvas_width..];
        let input = shade(coverage, stride, origin);
        let (h, w) = shade_and_composite(&input, part, canvas_part, canvas_width, recorder);
        totals = (totals.0 + h, totals.1 + w);
    }
    totals
}

/// The feathered draw, in one piece: the feather's distance transform needs the ids of the
/// whole work rectangle at once.
fn draw_feathered<T: StoreTexel>(
    frame: &Frame,
    feather: f32,
    scratch: &mut RasterScratch,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
) -> (usize, usize) {
    let (work, target) = (frame.work, frame.target);
    if scratch.workers.is_empty() {
        scratch.workers.push(BandScratch::default());
    }
    let worker = &mut scratch.workers[0];
    worker.prepare(work.area(), frame.use_depth);
    let all = 0..scratch.setups.len() as u32;
    rasterise_triangles(
        &scratch.setups,
        all,
        work,
        frame.use_depth,
        &mut worker.ids,
        &mut worker.depths,
    );
    let width = work.width();
    let coverage = &mut scratch.coverage;
    coverage.clear();
    match frame.anti_alias {
        true => {
            for y in work.y0..work.y1 {
                let row = scratch.silhouette.row(y, work.x0, work.x1);
                coverage.extend(row.iter().map(|&m| m.unit()));
            }
        }
        false => coverage.extend(
            worker
                .ids
                .iter()
                .map(|&id| if id == NO_TRIANGLE { 0.0 } else { 1.0 }),
        ),
    }
    scratch.distance.resize(work.area(), 0.0);
    apply_feather(
        &worker.ids,
        width,
        feather,
        &mut scratch.distance,
        &mut scratch.distance_row,
        coverage,
    );
    let shade = ShadeInput {
        setups: &scratch.setups,
        ids: &worker.ids,
        ids_rect: work,
        coverage: coverage.as_slice(),
        coverage_stride: width,
        coverage_origin: (work.x0, work.y0),
        source: frame.patch.source,
        kernel: frame.kernel,
    };
    let rows = &mut canvas[target.y0 as usize * canvas_width..];
    shade_and_composite(&shade, target, rows, canvas_width, &mut NoRecorder)
}

fn canvas_rect(canvas: &Canvas) -> PixelRect {
    PixelRect {
        x0: 0,
        y0: 0,
        x1: canvas.width().min(i32::MAX as u32) as i32,
        y1: canvas.height().min(i32::MAX as u32) as i32,
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
    let work = placed.intersect(&canvas_rect(canvas).grow(margin));
    (!work.is_empty() && !placed.intersect(&canvas_rect(canvas)).is_empty()).then_some(work)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{BoundaryLoop, LoopKind};
    use crate::pixels::{FloatImage, PixelFormat};
    use glam::DVec2;

    /// A wavy ring of thin triangles: long silhouettes cross every band border, so fringe
    /// pixels there look up neighbours in the apron.
    fn ring(segments: u32) -> (Vec<DVec2>, Vec<[u32; 3]>, Vec<BoundaryLoop>) {
        let mut positions = Vec::new();
        for k in 0..segments {
            let angle = std::f64::consts::TAU * f64::from(k) / f64::from(segments);
            let direction = DVec2::new(angle.cos(), angle.sin());
            let wobble = 6.0 * (angle * 7.0).sin();
            positions.push(DVec2::new(150.0, 140.0) + direction * (100.0 + wobble));
            positions.push(DVec2::new(150.0, 140.0) + direction * (123.3 + wobble));
        }
        let mut triangles = Vec::new();
        for k in 0..segments {
            let (inner, outer) = (2 * k, 2 * k + 1);
            let (next_inner, next_outer) =
                ((2 * k + 2) % (2 * segments), (2 * k + 3) % (2 * segments));
            triangles.push([inner, outer, next_inner]);
            triangles.push([outer, next_outer, next_inner]);
        }
        let outer_loop = (0..segments).map(|k| 2 * k + 1).collect();
        let inner_loop = (0..segments).rev().map(|k| 2 * k).collect();
        let loops = vec![
            BoundaryLoop {
                kind: LoopKind::Outer,
                piece: 0,
                vertices: outer_loop,
            },
            BoundaryLoop {
                kind: LoopKind::Hole,
                piece: 0,
                vertices: inner_loop,
            },
        ];
        (positions, triangles, loops)
    }

    #[test]
    fn band_height_changes_no_pixel() {
        let (rest, triangles, loops) = ring(97);
        let placed: Vec<DVec2> = rest
            .iter()
            .map(|p| *p * 1.3 + DVec2::new(7.3, 4.1))
            .collect();
        let source = FloatImage::from_fn(300, 300, PixelFormat::RGBA8, |i, j| {
            [(i % 17) as f32 / 16.0, (j % 13) as f32 / 12.0, 0.5, 1.0]
        })
        .unwrap();
        let membrane: Vec<[f32; 3]> = rest
            .iter()
            .map(|p| [(p.x * 1e-3) as f32, 0.0, -0.05])
            .collect();
        let patch = Patch {
            rest: &rest,
            placed: &placed,
            triangles: &triangles,
            membrane: &membrane,
            depth: None,
            loops: &loops,
            source: &source,
        };
        let draw = |band_pixels: usize| {
            let background =
                FloatImage::from_fn(420, 400, PixelFormat::RGBA8, |_, _| [0.2; 4]).unwrap();
            let mut canvas = Canvas::from_image(&background);
            let mut scratch = RasterScratch::new();
            scratch.band_pixels = band_pixels;
            let options = RasterOptions {
                threads: 1,
                ..RasterOptions::default()
            };
            let stats = draw_patch(&mut canvas, &patch, &options, &mut scratch).unwrap();
            (canvas.to_float_image(PixelFormat::RGBA8), stats)
        };
        // One band for the whole patch versus 8-row bands.
        let (whole, whole_stats) = draw(usize::MAX);
        let (banded, banded_stats) = draw(1);
        assert_eq!(whole_stats, banded_stats);
        let fringe = whole
            .pixels()
            .iter()
            .zip(banded.pixels())
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(fringe, 0, "pixels differ between band heights");
    }
}
