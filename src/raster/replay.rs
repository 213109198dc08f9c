//! Replaying a draw for a patch moved by whole pixels: takes the record of an earlier draw
//! (pixel runs, source samples and coverage, in shading order) and a patch whose placed
//! vertices are the recorded ones shifted by an integer vector, and composites it with this
//! frame's membrane — no rasterising, no silhouette fill, no source sampling. This is the
//! interactive drag of an undeformed patch (and any layer that holds still).
//!
//! A replay gives the same bytes as a fresh draw: triangle ownership, the silhouette mask
//! and the span maps of [`setup`](super::setup) depend only on differences between placed
//! positions, which an exact integer shift leaves unchanged; the membrane is evaluated by
//! the same formulas, run by run. It is used only when neither the recorded nor the shifted
//! work rectangle is clipped by the canvas (clipping changes where runs start), without
//! depth, without feather, and for the same mesh and source.
//!
//! When to record: a fresh draw records when it is the scratch's first draw or when the
//! patch moved by whole pixels since the previous draw (so a continuously, fractionally
//! moving patch never pays for recording).

use std::sync::Mutex;

use glam::{DVec2, Vec4};

use super::helper;
use super::setup::MembraneSpan;
use super::shade::{shade_pixel, Recorder, StoreTexel};
use super::triangles::NO_TRIANGLE;
use super::{Patch, PixelRect};
use crate::pixels::Canvas;
use crate::util::{lock, SpinWait};

/// Largest shift replayed (px): far below the fixed-point range, so shifted coordinates stay
/// exact.
const MAX_SHIFT: f64 = (1u64 << 20) as f64;

/// Largest recorded area (px): the record holds 17 bytes per covered pixel.
const MAX_RECORDED_AREA: usize = 4 << 20;

/// Recorded pixels from which a second thread (this thread's [`helper`]) replays half the
/// rows. It is handed its half before the membrane solve, so any wake-up hides behind it;
/// when a thread was spawned after the solve, 16K pixels measured slower than one thread.
const THREADED_PIXELS: usize = 8 * 1024;

/// What identifies the patch a record belongs to (addresses and sizes of the mesh and
/// source slices the draw read; the scratch belongs to one patch).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct ReplayKey {
    rest: (usize, usize),
    triangles: (usize, usize),
    source: (usize, u32, u32),
    anti_alias: bool,
}

impl ReplayKey {
    fn of(patch: &Patch, anti_alias: bool) -> ReplayKey {
        ReplayKey {
            rest: (patch.rest.as_ptr() as usize, patch.rest.len()),
            triangles: (patch.triangles.as_ptr() as usize, patch.triangles.len()),
            source: (
                patch.source.pixels().as_ptr() as usize,
                patch.source.width(),
                patch.source.height(),
            ),
            anti_alias,
        }
    }
}

/// One run of the record: `len` pixels from `(x0, y)`, owned by the triangle with record
/// number `id` or, for [`NO_TRIANGLE`], fringe pixels each with its own owner.
#[derive(Clone, Copy, Debug)]
struct RecordedRun {
    x0: i32,
    y: i32,
    len: u32,
    id: u32,
    /// Fringe runs: how many of their pixels were drawn (and recorded).
    fringe_pixels: u32,
    /// Record numbers given before this run: the triangles of all earlier runs have smaller
    /// numbers, and every triangle first met from here on a number at least this.
    numbered_before: u32,
    /// Where the run's data starts in the record's `coverage`, `samples` and `fringe`, so
    /// a replay can start at any run (two threads each take half the rows).
    data: [u32; 3],
}

/// The record of one draw, and the placement of the last draw.
#[derive(Default)]
pub(crate) struct Replay {
    key: ReplayKey,
    /// Placed positions of the recorded draw (empty: nothing recorded).
    recorded: Vec<DVec2>,
    work: PixelRect,
    runs: Vec<RecordedRun>,
    /// Per pixel of triangle runs (covered or not) and per covered fringe pixel.
    coverage: Vec<u8>,
    /// Per covered pixel, in order.
    samples: Vec<Vec4>,
    /// Per covered fringe pixel: column and the record number of its owning triangle.
    fringe: Vec<(i32, u32)>,
    /// The triangles the record meets, by record number: numbered in order of first use,
    /// so a replay walking the runs in row order reads its membrane maps nearly
    /// sequentially. (By mesh index, the maps of a 20K-triangle mesh are 1.3 MB read at
    /// random: on the seam-quality spiral the lookups were most of a replay's time.)
    triangles: Vec<u32>,
    /// Per mesh triangle: its record number, or [`NO_TRIANGLE`] (grow-only).
    record_number: Vec<u32>,
    /// Placed positions of the last draw through this scratch.
    last: Vec<DVec2>,
    last_key: ReplayKey,
}

impl Replay {
    /// The whole-pixel shift from the recorded draw to `patch`, when it can be replayed
    /// onto a canvas of `canvas` pixels.
    pub fn shift_for(
        &self,
        patch: &Patch,
        anti_alias: bool,
        canvas: PixelRect,
        work: PixelRect,
    ) -> Option<(i32, i32)> {
        if self.recorded.is_empty() || self.key != ReplayKey::of(patch, anti_alias) {
            return None;
        }
        let (dx, dy) = whole_pixel_shift(&self.recorded, patch.placed)?;
        let moved = PixelRect {
            x0: self.work.x0 + dx,
            y0: self.work.y0 + dy,
            x1: self.work.x1 + dx,
            y1: self.work.y1 + dy,
        };
        (moved == work && moved.intersect(&canvas) == moved).then_some((dx, dy))
    }

    /// Whether a fresh draw of `patch` into `work` (unclipped, inside the canvas) should
    /// be recorded.
    pub fn wants_record(&self, patch: &Patch, anti_alias: bool, work: PixelRect) -> bool {
        let first_draw = self.last.is_empty();
        let same_patch = self.last_key == ReplayKey::of(patch, anti_alias);
        work.area() <= MAX_RECORDED_AREA
            && (first_draw || (same_patch && whole_pixel_shift(&self.last, patch.placed).is_some()))
    }

    /// Notes the placement of a draw (recorded or not).
    pub fn remember(&mut self, patch: &Patch, anti_alias: bool) {
        self.last.clear();
        self.last.extend_from_slice(patch.placed);
        self.last_key = ReplayKey::of(patch, anti_alias);
    }

    /// Clears the record and starts recording a draw of `patch` over `work`.
    pub fn start(&mut self, patch: &Patch, anti_alias: bool, work: PixelRect) -> Recording<'_> {
        self.key = ReplayKey::of(patch, anti_alias);
        self.recorded.clear();
        self.recorded.extend_from_slice(patch.placed);
        self.work = work;
        self.runs.clear();
        self.coverage.clear();
        self.samples.clear();
        // A draw records at most one coverage byte and one sample per work pixel. Reserving
        // that bound up front saves a fresh scratch's first draw the copies of growing (its
        // untouched pages cost nothing).
        self.coverage.reserve(work.area());
        self.samples.reserve(work.area());
        self.fringe.clear();
        self.triangles.clear();
        self.record_number.clear();
        self.record_number
            .resize(patch.triangles.len(), NO_TRIANGLE);
        Recording { replay: self }
    }

    /// Composites the record shifted by `shift` with the membrane that `solve` gives for the
    /// shifted `geometry` (on this thread, reading the canvas first), on up to `threads`
    /// threads. Gives (centre hits, pixels written), as a fresh draw would.
    ///
    /// A large record is cut into two halves of whole rows. This thread's helper thread gets
    /// the lower half before the solve, so its wake-up hides behind it, and starts once the
    /// membrane is known; each thread computes the membrane maps of the triangles its runs
    /// meet ([`LazySpans`]). Any thread count gives the same bytes: each pixel is written by
    /// one run with the maps of a fresh draw.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_solving<'m, T: StoreTexel + Send, E>(
        &self,
        shift: (i32, i32),
        geometry: SpanGeometry,
        threads: usize,
        workers: &mut [LazySpans; 2],
        canvas: &mut Canvas,
        pixels: impl FnOnce(&mut Canvas) -> &mut [[T; 4]],
        solve: impl FnOnce(&Canvas) -> Result<&'m [[f32; 3]], E>,
    ) -> Result<(usize, usize), E> {
        let canvas_width = canvas.width() as usize;
        let split = (threads >= 2 && self.samples.len() >= THREADED_PIXELS)
            .then(|| self.row_split())
            .flatten();
        let [upper_spans, lower_spans] = workers;
        let every = 0..self.triangles.len() as u32;
        let Some(k) = split else {
            let membrane = solve(canvas)?;
            let maps = SpanSource::new(geometry, &self.triangles, every, membrane, upper_spans);
            return Ok(self.draw_runs(&self.runs, shift, 0, maps, pixels(canvas), canvas_width));
        };
        let (top_runs, bottom_runs) = self.runs.split_at(k);
        let first_row = (bottom_runs[0].y + shift.1) as usize;
        // The top half meets exactly the numbers below `first_new`; the bottom half all
        // from it on, and a few below (triangles crossing the split row).
        let first_new = bottom_runs[0].numbered_before;
        let (upper, lower) = (0..first_new, first_new..every.end);
        let handoff = Mutex::new(Handoff::Waiting);
        let (lower, upper) = helper::join(
            || {
                let (bottom, membrane) = wait_for(&handoff)?;
                let maps = SpanSource::new(geometry, &self.triangles, lower, membrane, lower_spans);
                Some(self.draw_runs(bottom_runs, shift, first_row, maps, bottom, canvas_width))
            },
            || {
                // Whatever happens to the solve, the lower half must stop waiting for it.
                let cancel = CancelOnDrop(&handoff);
                let membrane = solve(canvas)?;
                let (top, bottom) = pixels(canvas).split_at_mut(first_row * canvas_width);
                *lock(&handoff) = Handoff::Go((bottom, membrane));
                drop(cancel);
                let maps = SpanSource::new(geometry, &self.triangles, upper, membrane, upper_spans);
                Ok(self.draw_runs(top_runs, shift, 0, maps, top, canvas_width))
            },
        );
        let (upper, lower) = (upper?, lower.unwrap_or_default());
        Ok((upper.0 + lower.0, upper.1 + lower.1))
    }

    /// A run index near the middle where a new row starts (runs are in row order), or
    /// `None` when there is none.
    fn row_split(&self) -> Option<usize> {
        let half = self.runs.len() / 2;
        (half.max(1)..self.runs.len()).find(|&k| self.runs[k].y != self.runs[k - 1].y)
    }

    /// Replays `runs` (consecutive runs of the record) into `canvas`, which starts at canvas
    /// row `first_row`.
    fn draw_runs<T: StoreTexel>(
        &self,
        runs: &[RecordedRun],
        (dx, dy): (i32, i32),
        first_row: usize,
        mut maps: SpanSource,
        canvas: &mut [[T; 4]],
        canvas_width: usize,
    ) -> (usize, usize) {
        let (mut hits, mut written) = (0, 0);
        let Some(first) = runs.first() else {
            return (0, 0);
        };
        let [c, s, f] = first.data.map(|at| at as usize);
        let (mut coverage, mut samples, mut fringe) = (
            self.coverage[c..].iter(),
            self.samples[s..].iter(),
            self.fringe[f..].iter(),
        );
        for run in runs {
            let (x0, y) = (run.x0 + dx, run.y + dy);
            let start = (y as usize - first_row) * canvas_width + x0 as usize;
            let pixels = &mut canvas[start..start + run.len as usize];
            if run.id == NO_TRIANGLE {
                for _ in 0..run.fringe_pixels {
                    let (Some(&(x, owner)), Some(&cover), Some(&sample)) =
                        (fringe.next(), coverage.next(), samples.next())
                    else {
                        break;
                    };
                    let membrane = maps.of(owner).at_pixel(x + dx, y);
                    let pixel = &mut pixels[(x - run.x0) as usize];
                    written += usize::from(shade_pixel(pixel, sample, membrane, cover));
                }
                continue;
            }
            hits += run.len as usize;
            let mut membrane = maps.of(run.id).along_row(x0, y);
            for (pixel, &cover) in pixels.iter_mut().zip(coverage.by_ref()) {
                if cover > 0 {
                    let Some(&sample) = samples.next() else { break };
                    written += usize::from(shade_pixel(pixel, sample, membrane.value(), cover));
                }
                membrane.advance();
            }
        }
        (hits, written)
    }
}

/// The shifted patch's placed positions and triangles, which the membrane maps are made of.
#[derive(Clone, Copy)]
pub(crate) struct SpanGeometry<'a> {
    pub placed: &'a [DVec2],
    pub triangles: &'a [[u32; 3]],
}

/// One thread's membrane maps of a replay, by record number: those of the numbers its rows
/// are known to meet computed up front in one sequential pass, any other the first time a
/// run needs it (a half of the rows meets about half of the triangles). Grow-only; kept in
/// the scratch.
#[derive(Default)]
pub(crate) struct LazySpans {
    spans: Vec<MembraneSpan>,
    /// Per record number: the replay whose map `spans` holds.
    computed_in: Vec<u32>,
    replay: u32,
}

/// The maps of one replay: the geometry and membrane, the record's triangles, and a
/// thread's [`LazySpans`].
struct SpanSource<'a> {
    geometry: SpanGeometry<'a>,
    /// Mesh triangle of each record number.
    triangles: &'a [u32],
    membrane: &'a [[f32; 3]],
    lazy: &'a mut LazySpans,
}

impl<'a> SpanSource<'a> {
    /// The maps of `triangles` (mesh triangle per record number), those numbered in `eager`
    /// computed now.
    fn new(
        geometry: SpanGeometry<'a>,
        triangles: &'a [u32],
        eager: std::ops::Range<u32>,
        membrane: &'a [[f32; 3]],
        lazy: &'a mut LazySpans,
    ) -> SpanSource<'a> {
        let count = triangles.len();
        lazy.spans.resize(count, MembraneSpan::default());
        lazy.computed_in.resize(count, 0);
        lazy.replay = lazy.replay.wrapping_add(1);
        if lazy.replay == 0 {
            // Every 2³² replays: no stale mark may equal the new number.
            lazy.computed_in.fill(0);
            lazy.replay = 1;
        }
        let mut source = SpanSource {
            geometry,
            triangles,
            membrane,
            lazy,
        };
        for n in eager.start as usize..(eager.end as usize).min(count) {
            source.compute(n);
        }
        source
    }

    /// The membrane maps of the triangle with record number `n` (exactly
    /// `MembraneSpan::of_triangle`).
    #[inline(always)]
    fn of(&mut self, n: u32) -> MembraneSpan {
        let n = n as usize;
        if self.lazy.computed_in[n] != self.lazy.replay {
            self.compute(n);
        }
        self.lazy.spans[n]
    }

    #[inline(never)]
    fn compute(&mut self, n: usize) {
        let t = self.triangles[n] as usize;
        let [a, b, c] = self.geometry.triangles[t].map(|v| v as usize);
        let (placed, membrane) = (self.geometry.placed, self.membrane);
        self.lazy.spans[n] = MembraneSpan::of_triangle(
            [placed[a], placed[b], placed[c]],
            [membrane[a], membrane[b], membrane[c]],
        );
        self.lazy.computed_in[n] = self.lazy.replay;
    }
}

/// The lower half's canvas rows and the membrane.
type LowerHalf<'c, 'm, T> = (&'c mut [[T; 4]], &'m [[f32; 3]]);

/// What the lower half of a two-thread replay is waiting for.
enum Handoff<'c, 'm, T> {
    Waiting,
    Go(LowerHalf<'c, 'm, T>),
    /// The solve failed or panicked.
    Cancelled,
}

/// Waits for the hand-off; `None` when it is cancelled. Spins (the wait is about one solve),
/// yielding the core after a while.
fn wait_for<'c, 'm, T>(handoff: &Mutex<Handoff<'c, 'm, T>>) -> Option<LowerHalf<'c, 'm, T>> {
    let mut wait = SpinWait::default();
    loop {
        match std::mem::replace(&mut *lock(handoff), Handoff::Waiting) {
            Handoff::Go(lower) => return Some(lower),
            Handoff::Cancelled => return None,
            Handoff::Waiting => wait.pause(),
        }
    }
}

/// Cancels a hand-off still waiting when dropped (an error or panic in the solve).
struct CancelOnDrop<'h, 'c, 'm, T>(&'h Mutex<Handoff<'c, 'm, T>>);

impl<T> Drop for CancelOnDrop<'_, '_, '_, T> {
    fn drop(&mut self) {
        let mut handoff = lock(self.0);
        if matches!(*handoff, Handoff::Waiting) {
            *handoff = Handoff::Cancelled;
        }
    }
}

/// Records a draw into a [`Replay`].
pub(crate) struct Recording<'a> {
    replay: &'a mut Replay,
}

impl Recording<'_> {
    /// The record number of mesh triangle `t`, numbering it if it is new.
    fn number(&mut self, t: u32) -> u32 {
        let replay = &mut *self.replay;
        let Some(slot) = replay.record_number.get_mut(t as usize) else {
            return NO_TRIANGLE;
        };
        if *slot == NO_TRIANGLE {
            // At most one number per mesh triangle, and a mesh has fewer than u32::MAX.
            *slot = replay.triangles.len() as u32;
            replay.triangles.push(t);
        }
        *slot
    }
}

impl Recorder<u8> for Recording<'_> {
    fn run(&mut self, x0: i32, y: i32, len: usize, id: u32) {
        let len = u32::try_from(len).unwrap_or(u32::MAX);
        let numbered_before = self.replay.triangles.len() as u32;
        let id = if id == NO_TRIANGLE {
            id
        } else {
            self.number(id)
        };
        let replay = &mut *self.replay;
        // The record holds at most MAX_RECORDED_AREA pixels, so offsets fit u32.
        let at = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
        let data = [
            at(replay.coverage.len()),
            at(replay.samples.len()),
            at(replay.fringe.len()),
        ];
        replay.runs.push(RecordedRun {
            x0,
            y,
            len,
            id,
            fringe_pixels: 0,
            numbered_before,
            data,
        });
    }

    fn pixel(&mut self, sample: Option<Vec4>, coverage: u8) {
        self.replay.coverage.push(coverage);
        self.replay.samples.extend(sample);
    }

    fn fringe(&mut self, x: i32, owner: u32, sample: Vec4, coverage: u8) {
        let owner = self.number(owner);
        if let Some(run) = self.replay.runs.last_mut() {
            run.fringe_pixels += 1;
        }
        self.replay.fringe.push((x, owner));
        self.replay.coverage.push(coverage);
        self.replay.samples.push(sample);
    }
}

/// `(dx, dy)` when every `now[i]` is exactly `before[i] + (dx, dy)` with whole dx, dy.
fn whole_pixel_shift(before: &[DVec2], now: &[DVec2]) -> Option<(i32, i32)> {
    let (first_before, first_now) = (before.first()?, now.first()?);
    // The nearest whole shift; the exact test below decides whether it is the move.
    let shift = (*first_now - *first_before).round();
    let in_range = shift.abs().max_element() <= MAX_SHIFT; // false for NaN
    if before.len() != now.len() || !in_range {
        return None;
    }
    let exact = before.iter().zip(now).all(|(b, n)| *b + shift == *n);
    exact.then_some((shift.x as i32, shift.y as i32))
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use crate::mesh::{BoundaryLoop, LoopKind};
    use crate::pixels::{Canvas, FloatImage, PixelFormat};
    use crate::raster::{draw_patch, Patch, RasterOptions, RasterScratch};

    /// A rotated, scaled `cells`² grid whose triangles give runs long enough for the SIMD
    /// kernel, over a source of exact 8-bit levels (`translucent`: alpha below 1 in places).
    fn record(simd: bool, translucent: bool) -> RasterScratch {
        let cells = 6u32;
        let side = cells + 1;
        let rest: Vec<DVec2> = (0..side * side)
            .map(|k| DVec2::new((k % side) as f64 * 9.0 + 2.0, (k / side) as f64 * 8.0 + 3.0))
            .collect();
        let mut triangles = vec![];
        for j in 0..cells {
            for i in 0..cells {
                let v = j * side + i;
                triangles.push([v, v + 1, v + side + 1]);
                triangles.push([v, v + side + 1, v + side]);
            }
        }
        let ring = (0..cells)
            .chain((0..cells).map(|j| j * side + cells))
            .chain((0..cells).map(|i| cells * side + cells - i))
            .chain((0..cells).map(|j| (cells - j) * side))
            .collect();
        let loops = [BoundaryLoop {
            kind: LoopKind::Outer,
            piece: 0,
            vertices: ring,
        }];
        let placed: Vec<DVec2> = rest
            .iter()
            .map(|p| DVec2::new(1.3 * p.x - 0.4 * p.y + 30.3, 0.4 * p.x + 1.3 * p.y + 7.6))
            .collect();
        let membrane: Vec<[f32; 3]> = rest
            .iter()
            .map(|p| [(p.x * 0.004) as f32, -0.03, (p.y * 0.003) as f32])
            .collect();
        let source = FloatImage::from_fn(60, 56, PixelFormat::RGBA8, |i, j| {
            let level = |m: u32| ((i * m + j * 37 + m) % 256) as f32 / 255.0;
            let alpha = if translucent && (i + j) % 5 == 0 {
                0.4
            } else {
                1.0
            };
            [level(13), level(29), level(71), alpha]
        })
        .unwrap();
        assert!(source.eight_bit_texels().is_some(), "exact 8-bit levels");
        let patch = Patch {
            rest: &rest,
            placed: &placed,
            triangles: &triangles,
            membrane: &membrane,
            depth: None,
            loops: &loops,
            source: &source,
        };
        let mut canvas = Canvas::from_image(
            &FloatImage::from_fn(140, 150, PixelFormat::RGBA8, |_, _| [0.3, 0.5, 0.7, 1.0])
                .unwrap(),
        );
        let options = RasterOptions {
            replay: true,
            simd,
            ..RasterOptions::default()
        };
        let mut scratch = RasterScratch::new();
        draw_patch(&mut canvas, &patch, &options, &mut scratch).unwrap();
        scratch
    }

    #[test]
    fn a_record_made_by_the_simd_kernel_is_the_scalar_record_bit_for_bit() {
        for translucent in [false, true] {
            let (simd, scalar) = (record(true, translucent), record(false, translucent));
            let (simd, scalar) = (&simd.replay, &scalar.replay);
            assert!(!scalar.samples.is_empty(), "the draw recorded");
            assert!(
                scalar.runs.iter().filter(|r| r.len >= 8).count() > 10,
                "runs long enough for the kernel"
            );
            assert_eq!(format!("{:?}", simd.runs), format!("{:?}", scalar.runs));
            assert_eq!(simd.coverage, scalar.coverage);
            assert_eq!(simd.fringe, scalar.fringe);
            assert_eq!(simd.triangles, scalar.triangles);
            let bits = |samples: &[glam::Vec4]| -> Vec<[u32; 4]> {
                samples
                    .iter()
                    .map(|s| s.to_array().map(f32::to_bits))
                    .collect()
            };
            assert_eq!(
                bits(&simd.samples),
                bits(&scalar.samples),
                "translucent {translucent}"
            );
        }
    }
}
