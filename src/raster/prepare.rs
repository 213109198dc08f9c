//! The work before a draw's bands: takes a placed patch and a function that gives its
//! membrane, and fills the raster scratch's per-triangle setups and silhouette strips.
//!
//! The membrane need not be known when this starts. The calling thread solves it while a
//! helper thread fills the silhouette's strips and the setups' geometry (everything but the
//! membrane maps, see [`TriangleSetup::geometry`]); neither reads the membrane. So a frame's
//! membrane solve (and whatever else the caller puts before it) overlaps the raster's serial
//! part instead of preceding it.
//!
//! Work goes out in pieces (strips first, then chunks of setups) to whichever thread asks
//! next, so a helper that the scheduler starts late only takes what is left. A chunk whose
//! geometry is done before the membrane is known waits for it in a fixed array, and gets its
//! membrane maps from the first thread that asks once it is. The split changes no value: each
//! setup depends on its triangle alone (geometry then membrane gives the bits of one pass),
//! and the strips are laid out by
//! [`Silhouette::layout`](super::coverage::Silhouette::layout) whatever the thread count.

use std::sync::Mutex;

use super::bands::NO_ROWS;
use super::coverage::{rest_loop_orientation, SilhouetteInput, Strip};
use super::helper;
use super::setup::{LocalFrame, SnappedVertex, TriangleSetup};
use super::triangles::centre_rows;
use super::{Patch, PixelRect, RasterError, RasterScratch};
use crate::util::{lock, SpinWait};

/// Large draws hand out their triangle setups in chunks of at least this many triangles...
const SETUP_CHUNK: usize = 1024;

/// ... and in at most this many chunks, so that the chunks waiting for the membrane fit a
/// fixed array (no allocation per frame).
const MAX_SETUP_CHUNKS: usize = 16;

/// Fills `scratch`'s setups and (with `anti_alias`) silhouette strips for `patch` over
/// `work`, with the membrane that `solve` gives; gives that membrane. `patch.membrane` is
/// not read. With `threads` ≥ 2 and enough work, `solve` runs on this thread while a
/// helper thread starts on the membrane-free work.
pub(crate) fn prepare<'m, E: From<RasterError>>(
    patch: &Patch,
    work: PixelRect,
    anti_alias: bool,
    threads: usize,
    scratch: &mut RasterScratch,
    solve: impl FnOnce() -> Result<&'m [[f32; 3]], E>,
) -> Result<&'m [[f32; 3]], E> {
    let snapped = &mut scratch.snapped;
    snapped.clear();
    snapped.extend(patch.placed.iter().map(|&p| SnappedVertex::new(p)));
    let triangles = patch.triangles.len();
    scratch.setups.resize(triangles, TriangleSetup::default());
    scratch.frames.resize(triangles, LocalFrame::default());
    scratch.centre_rows.resize(triangles, NO_ROWS);
    let loop_orientation = rest_loop_orientation(patch);
    let strips: &mut [Strip] = if anti_alias {
        scratch.silhouette.layout(work)
    } else {
        &mut []
    };
    match anti_alias && loop_orientation != 0.0 {
        true => scratch.folds.build(patch, loop_orientation),
        false => scratch.folds.clear(),
    }
    let context = Context {
        patch,
        snapped: &scratch.snapped,
        silhouette: SilhouetteInput {
            patch,
            loop_orientation,
            folds: &scratch.folds,
        },
    };
    let chunk = SETUP_CHUNK.max(triangles.div_ceil(MAX_SETUP_CHUNKS));
    let pieces = strips.len() + triangles.div_ceil(chunk);
    let jobs = strips.iter_mut().map(Job::Strip).chain(
        (scratch.setups.chunks_mut(chunk))
            .zip(scratch.frames.chunks_mut(chunk))
            .zip(scratch.centre_rows.chunks_mut(chunk))
            .enumerate()
            .map(move |(k, ((setups, frames), rows))| {
                Job::Geometry(SetupChunk {
                    first: k * chunk,
                    setups,
                    frames,
                    rows,
                })
            }),
    );
    if threads < 2 || pieces < 2 {
        let membrane = solved(patch, solve)?;
        for job in jobs {
            // invariant: with the membrane known, no chunk is left waiting for it.
            let left = context.run(job, Some(membrane));
            debug_assert!(left.is_none());
        }
        return Ok(membrane);
    }
    let queue = Mutex::new(Queue {
        jobs,
        waiting: Default::default(),
        membrane: MembraneState::Solving,
    });
    let ((), membrane) = helper::join(
        || context.work(&queue),
        || {
            // Whatever happens to the solve, the helper must stop waiting for it.
            let mut abandon = Abandon(&queue);
            let membrane = solved(patch, solve);
            abandon.publish(membrane.as_ref().ok().copied());
            context.work(&queue);
            membrane
        },
    );
    membrane
}

/// The solve's membrane, checked against the patch.
fn solved<'m, E: From<RasterError>>(
    patch: &Patch,
    solve: impl FnOnce() -> Result<&'m [[f32; 3]], E>,
) -> Result<&'m [[f32; 3]], E> {
    let membrane = solve()?;
    patch.validate_membrane(membrane)?;
    Ok(membrane)
}

/// Setups of triangles `first..first + setups.len()`, their frames and centre rows.
struct SetupChunk<'s> {
    first: usize,
    setups: &'s mut [TriangleSetup],
    frames: &'s mut [LocalFrame],
    /// What the bands bin (see [`triangle_rows`]).
    rows: &'s mut [(i64, i64)],
}

/// One piece of the work before the bands.
enum Job<'s> {
    Strip(&'s mut Strip),
    /// A chunk's geometry, and its membrane maps if the membrane is known by then.
    Geometry(SetupChunk<'s>),
}

enum MembraneState<'m> {
    Solving,
    Solved(&'m [[f32; 3]]),
    /// The solve failed or panicked: the draw is off.
    Failed,
}

/// What the threads take their work from.
struct Queue<'s, 'm, I> {
    jobs: I,
    /// Chunks whose geometry is done, waiting for the membrane.
    waiting: [Option<SetupChunk<'s>>; MAX_SETUP_CHUNKS],
    membrane: MembraneState<'m>,
}

/// What a thread does next.
enum Next<'s, 'm> {
    Job(Job<'s>, Option<&'m [[f32; 3]]>),
    Membrane(SetupChunk<'s>, &'m [[f32; 3]]),
    Wait,
    Stop,
}

impl<'s, 'm, I: Iterator<Item = Job<'s>>> Queue<'s, 'm, I> {
    fn next(&mut self) -> Next<'s, 'm> {
        let membrane = match self.membrane {
            MembraneState::Solving => None,
            MembraneState::Solved(membrane) => Some(membrane),
            MembraneState::Failed => return Next::Stop,
        };
        if let Some(job) = self.jobs.next() {
            return Next::Job(job, membrane);
        }
        match membrane {
            None => Next::Wait,
            Some(membrane) => match self.waiting.iter_mut().find_map(Option::take) {
                Some(chunk) => Next::Membrane(chunk, membrane),
                None => Next::Stop,
            },
        }
    }

    fn park(&mut self, chunk: SetupChunk<'s>) {
        let slot = self.waiting.iter_mut().find(|slot| slot.is_none());
        // invariant: there are at most MAX_SETUP_CHUNKS chunks, each parked at most once.
        *slot.expect("a free slot per chunk") = Some(chunk);
    }
}

/// Publishes the solve's outcome to the queue; on drop (a panicking solve) declares it
/// failed, so the helper stops waiting.
struct Abandon<'q, 's, 'm, I>(&'q Mutex<Queue<'s, 'm, I>>);

impl<'m, I> Abandon<'_, '_, 'm, I> {
    fn publish(&mut self, membrane: Option<&'m [[f32; 3]]>) {
        lock(self.0).membrane = membrane.map_or(MembraneState::Failed, MembraneState::Solved);
    }
}

impl<I> Drop for Abandon<'_, '_, '_, I> {
    fn drop(&mut self) {
        let mut queue = lock(self.0);
        if matches!(queue.membrane, MembraneState::Solving) {
            queue.membrane = MembraneState::Failed;
        }
    }
}

/// What every job reads.
struct Context<'a> {
    patch: &'a Patch<'a>,
    snapped: &'a [SnappedVertex],
    silhouette: SilhouetteInput<'a>,
}

impl Context<'_> {
    /// Takes and runs jobs until none is left (or the solve failed).
    fn work<'s, 'm, I: Iterator<Item = Job<'s>>>(&self, queue: &Mutex<Queue<'s, 'm, I>>) {
        let mut wait = SpinWait::default();
        loop {
            let next = lock(queue).next();
            match next {
                Next::Job(job, membrane) => {
                    // If the membrane came meanwhile, this thread takes the chunk back
                    // itself: it asks again before it can stop.
                    if let Some(chunk) = self.run(job, membrane) {
                        lock(queue).park(chunk);
                    }
                }
                Next::Membrane(chunk, membrane) => self.add_membrane(chunk, membrane),
                Next::Wait => wait.pause(),
                Next::Stop => return,
            }
        }
    }

    /// Runs one job; gives back a chunk whose membrane maps still wait for the membrane.
    fn run<'s>(&self, job: Job<'s>, membrane: Option<&[[f32; 3]]>) -> Option<SetupChunk<'s>> {
        match (job, membrane) {
            (Job::Strip(strip), _) => strip.fill(self.silhouette),
            (Job::Geometry(chunk), Some(membrane)) => self.build_setups(chunk, membrane),
            (Job::Geometry(mut chunk), None) => {
                self.build_geometry(&mut chunk);
                return Some(chunk);
            }
        }
        None
    }

    /// A chunk's whole setups: the membrane is known.
    fn build_setups(&self, chunk: SetupChunk, membrane: &[[f32; 3]]) {
        let patch = self.patch;
        let triangles = &patch.triangles[chunk.first..];
        let setups = chunk.setups.iter_mut().zip(chunk.rows.iter_mut());
        for ((setup, rows), tri) in setups.zip(triangles) {
            let [a, b, c] = tri.map(|v| v as usize);
            *setup = TriangleSetup::from_snapped(
                [patch.placed[a], patch.placed[b], patch.placed[c]],
                [self.snapped[a], self.snapped[b], self.snapped[c]],
                [patch.rest[a], patch.rest[b], patch.rest[c]],
                [membrane[a], membrane[b], membrane[c]],
                depth_of(patch, [a, b, c]),
            );
            *rows = triangle_rows(setup);
        }
    }

    /// A chunk's setups without the membrane maps, and the frames that add them later.
    fn build_geometry(&self, chunk: &mut SetupChunk) {
        let patch = self.patch;
        let triangles = &patch.triangles[chunk.first..];
        let setups = chunk.setups.iter_mut().zip(chunk.frames.iter_mut());
        for (((setup, frame), rows), tri) in setups.zip(chunk.rows.iter_mut()).zip(triangles) {
            let [a, b, c] = tri.map(|v| v as usize);
            (*setup, *frame) = TriangleSetup::geometry(
                [patch.placed[a], patch.placed[b], patch.placed[c]],
                [self.snapped[a], self.snapped[b], self.snapped[c]],
                [patch.rest[a], patch.rest[b], patch.rest[c]],
                depth_of(patch, [a, b, c]),
            );
            *rows = triangle_rows(setup);
        }
    }

    /// The membrane maps of a chunk from [`build_geometry`](Self::build_geometry).
    fn add_membrane(&self, chunk: SetupChunk, membrane: &[[f32; 3]]) {
        let triangles = &self.patch.triangles[chunk.first..];
        let setups = chunk.setups.iter_mut().zip(chunk.frames.iter());
        for ((setup, frame), tri) in setups.zip(triangles) {
            let [a, b, c] = tri.map(|v| v as usize);
            setup.set_membrane(frame, [membrane[a], membrane[b], membrane[c]]);
        }
    }
}

/// The canvas rows whose pixel centres the triangle may own ([`centre_rows`]), or none
/// when it is not drawn. Kept beside the setups while they are hot in this thread's cache,
/// so the bands bin a compact array instead of reading every setup again.
fn triangle_rows(setup: &TriangleSetup) -> (i64, i64) {
    if setup.drawable {
        centre_rows(setup)
    } else {
        NO_ROWS
    }
}

fn depth_of(patch: &Patch, [a, b, c]: [usize; 3]) -> [f32; 3] {
    patch.depth.map_or([0.0; 3], |d| [d[a], d[b], d[c]])
}

#[cfg(test)]
mod tests {
    use super::super::folds::FoldOutline;
    use super::*;
    use crate::pixels::{FloatImage, PixelFormat};
    use glam::DVec2;

    struct Ribbon {
        rest: Vec<DVec2>,
        placed: Vec<DVec2>,
        triangles: Vec<[u32; 3]>,
        membrane: Vec<[f32; 3]>,
        depth: Vec<f32>,
    }

    /// A ribbon of `columns` × 2 triangles with a membrane and depth that vary per vertex.
    fn ribbon(columns: u32) -> Ribbon {
        let rest: Vec<DVec2> = (0..=columns)
            .flat_map(|k| [0.0, 1.0].map(|y| DVec2::new(f64::from(k), y)))
            .collect();
        let placed = rest
            .iter()
            .map(|p| DVec2::new(p.x * 1.7 + 0.3 * p.y + 5.1, p.y * 9.3 + 0.01 * p.x * p.x))
            .collect();
        let triangles = (0..columns)
            .flat_map(|k| {
                [
                    [2 * k, 2 * k + 2, 2 * k + 1],
                    [2 * k + 1, 2 * k + 2, 2 * k + 3],
                ]
            })
            .collect();
        let membrane = rest
            .iter()
            .map(|p| [(p.x * 0.013).sin() as f32, p.y as f32 * 0.2, -0.1])
            .collect();
        let depth = rest.iter().map(|p| (p.x * 0.37).cos() as f32).collect();
        Ribbon {
            rest,
            placed,
            triangles,
            membrane,
            depth,
        }
    }

    /// Chunks whose geometry ran before the membrane was known wait for it, and get the
    /// same bits as setups built in one pass once it comes.
    #[test]
    fn chunks_done_before_the_membrane_match_one_pass() {
        let Ribbon {
            rest,
            placed,
            triangles,
            membrane,
            depth,
        } = ribbon(2_000);
        let source = FloatImage::from_fn(4, 4, PixelFormat::RGBA8, |_, _| [0.5; 4]).unwrap();
        let patch = Patch {
            rest: &rest,
            placed: &placed,
            triangles: &triangles,
            membrane: &membrane,
            depth: Some(&depth),
            loops: &[],
            source: &source,
        };
        let snapped: Vec<SnappedVertex> = placed.iter().map(|&p| SnappedVertex::new(p)).collect();
        let context = Context {
            patch: &patch,
            snapped: &snapped,
            silhouette: SilhouetteInput {
                patch: &patch,
                loop_orientation: 0.0,
                folds: &FoldOutline::default(),
            },
        };
        let mut setups = vec![TriangleSetup::default(); triangles.len()];
        let mut frames = vec![LocalFrame::default(); triangles.len()];
        let mut rows = vec![NO_ROWS; triangles.len()];
        let chunk = 1024;
        let jobs = setups
            .chunks_mut(chunk)
            .zip(frames.chunks_mut(chunk))
            .zip(rows.chunks_mut(chunk))
            .enumerate()
            .map(|(k, ((setups, frames), rows))| {
                Job::Geometry(SetupChunk {
                    first: k * chunk,
                    setups,
                    frames,
                    rows,
                })
            });
        let mut queue = Queue {
            jobs,
            waiting: Default::default(),
            membrane: MembraneState::Solving,
        };
        let mut parked = 0;
        loop {
            match queue.next() {
                Next::Job(job, known) => {
                    assert!(known.is_none());
                    let chunk = context.run(job, known).expect("a chunk without membrane");
                    queue.park(chunk);
                    parked += 1;
                }
                Next::Wait => break,
                _ => panic!("only jobs, then a wait, while the membrane is solved"),
            }
        }
        assert_eq!(parked, triangles.len().div_ceil(chunk));
        queue.membrane = MembraneState::Solved(&membrane);
        let mut finished = 0;
        loop {
            match queue.next() {
                Next::Membrane(chunk, m) => {
                    context.add_membrane(chunk, m);
                    finished += 1;
                }
                Next::Stop => break,
                _ => panic!("only waiting chunks, then a stop, once the membrane is known"),
            }
        }
        assert_eq!(finished, parked);
        for (t, (setup, tri)) in setups.iter().zip(&triangles).enumerate() {
            let [a, b, c] = tri.map(|v| v as usize);
            let one_pass = TriangleSetup::new(
                [placed[a], placed[b], placed[c]],
                [rest[a], rest[b], rest[c]],
                [membrane[a], membrane[b], membrane[c]],
                [depth[a], depth[b], depth[c]],
            );
            assert_eq!(
                format!("{setup:?}"),
                format!("{one_pass:?}"),
                "triangle {t}"
            );
        }
    }

    /// A failed solve stops every thread: nothing is left waiting for a membrane.
    #[test]
    fn a_failed_solve_stops_the_queue() {
        let mut queue = Queue {
            jobs: std::iter::empty::<Job>(),
            waiting: Default::default(),
            membrane: MembraneState::Solving,
        };
        assert!(matches!(queue.next(), Next::Wait));
        let queue = Mutex::new(queue);
        drop(Abandon(&queue));
        assert!(matches!(lock(&queue).next(), Next::Stop));
    }
}
