//! `lapclone track`: takes footage (a `%04d` plate pattern or a video), points on its first
//! frame and tracking settings, and writes the track CSV (atomically), warning on stderr for
//! each run of frames where a point was lost.

use lapclone::util::ShowPath;
use std::io::Write;
use std::path::PathBuf;

use super::render::progress_bar;
use anyhow::Context;
use lapclone::glam::DVec2;
use lapclone::pixels::{Footage, FootageError, FootageReader, FootageSource};
use lapclone::track::{
    pair_motion, read_ahead, Estimate, PointTracker, TrackOptions, TrackedFrame,
};

use super::render::{frame_range, FrameRange};
use super::UsageError;

/// Most points one run follows.
const MAX_POINTS: usize = 16;

#[derive(clap::Args, Debug)]
pub struct TrackArgs {
    /// Footage: numbered images (`plates/frame_%04d.png`) or a video (.mp4, .mov, .webm, .mkv).
    pub footage: PathBuf,
    /// A point to follow, X,Y in pixels on the first frame of the range (repeat for two:
    /// the CSV then also has the pair's rotation and scale).
    #[arg(long = "point", value_name = "X,Y", required = true, value_parser = super::point,
          allow_hyphen_values = true)]
    pub points: Vec<[f64; 2]>,
    /// Side of the square matched around each point, in pixels.
    #[arg(long, value_name = "PX", default_value_t = TrackOptions::default().size,
          allow_hyphen_values = true)]
    pub size: u32,
    /// How far a point may move from one frame to the next, in pixels.
    #[arg(long, value_name = "PX", default_value_t = TrackOptions::default().search,
          allow_hyphen_values = true)]
    pub search: u32,
    /// Frames to track, A..B (numbered as `render` numbers them, from 1); default: all.
    #[arg(long, value_name = "A..B", value_parser = frame_range)]
    pub frames: Option<FrameRange>,
    /// The file number of frame 1 of a pattern (default: the lowest number with a file).
    #[arg(long, value_name = "N", allow_hyphen_values = true,
          value_parser = clap::value_parser!(u64).range(..=lapclone::limits::MAX_START_NUMBER))]
    pub start: Option<u64>,
    /// The rate a video is decoded at, frames per second (as the scene's `fps`).
    #[arg(long, default_value_t = 24.0, value_parser = super::finite_f64,
          allow_hyphen_values = true)]
    pub fps: f64,
    /// The track CSV to write (`-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: TrackArgs) -> anyhow::Result<()> {
    check_arguments(&args)?;
    // `track` has no setting that holds a last frame: its messages suggest none.
    let footage = Footage::open(&args.footage, args.start, false, "")
        .with_context(|| format!("opening {}", args.footage.shown()))?;
    let to_stdout = args.output.as_os_str() == "-";
    if !to_stdout {
        lapclone::output::refuse_footage_input(&args.output, &footage)?;
    }
    let reader = FootageReader::new(footage, args.fps);
    let available = available_frames(&reader, args.fps, args.frames)?;
    let range = match (args.frames, available) {
        (Some(range), Some(available)) if range.last > available => {
            return Err(UsageError(format!(
                "--frames {}..{}: the footage has {available} frames",
                range.first, range.last
            ))
            .into())
        }
        (Some(range), _) => range,
        (None, available) => FrameRange {
            first: 1,
            last: available.unwrap_or(lapclone::limits::MAX_FRAMES),
        },
    };
    let points: Vec<DVec2> = args.points.iter().map(|p| DVec2::from_array(*p)).collect();
    let to_end = args.frames.is_none();
    let frames = track_frames(&reader, range, &points, options(&args), args.fps, to_end)?;
    let range = FrameRange {
        last: frames.last().map_or(range.last, |f| f.frame),
        ..range
    };
    warn_lost(&frames);
    let into = if to_stdout {
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        lapclone::track::write_csv(&mut out, &frames)
            .and_then(|()| out.flush())
            .context("writing the track to standard output")?;
        "standard output".to_string()
    } else {
        lapclone::util::write_atomic_with(&args.output, |file| {
            let mut out = std::io::BufWriter::new(file);
            lapclone::track::write_csv(&mut out, &frames)?;
            out.flush()
        })
        .with_context(|| format!("writing {}", args.output.shown()))?;
        args.output.shown().to_string()
    };
    eprint_line!(
        "tracked {} point{} through frames {}..{} into {into}",
        points.len(),
        if points.len() == 1 { "" } else { "s" },
        range.first,
        range.last,
    );
    Ok(())
}

fn options(args: &TrackArgs) -> TrackOptions {
    TrackOptions {
        size: args.size,
        search: args.search,
    }
}

/// Every frame of `range` tracked, in order, with the pair's motion for two points. With
/// `to_end` (no `--frames`), a video that ends before `range` (its length is only
/// estimated, or unknown) ends the track there.
fn track_frames(
    reader: &FootageReader,
    range: FrameRange,
    points: &[DVec2],
    options: TrackOptions,
    fps: f64,
    to_end: bool,
) -> anyhow::Result<Vec<TrackedFrame>> {
    let progress = progress_bar(range.last - range.first + 1);
    let mut tracker: Option<PointTracker> = None;
    let mut frames: Vec<TrackedFrame> = Vec::new();
    let threads = lapclone::util::available_cores();
    let indices = range.first - 1..=range.last - 1;
    let read = read_ahead(reader.footage(), fps, indices, threads, |index, frame| {
        let number = index + 1;
        let estimates = match tracker.as_mut() {
            Some(t) => t.next(frame).with_context(|| format!("frame {number}"))?,
            None => {
                let (t, first) = PointTracker::start(frame, points, options)
                    .map_err(|e| UsageError(format!("--point: {e}")))?;
                tracker = Some(t);
                first
            }
        };
        let mut next = tracked(number, estimates, points);
        if let (Some(first), Some(previous)) = (frames.first(), frames.last()) {
            if let ([a0, b0, ..], [a, b, ..]) = (&first.points[..], &next.points[..]) {
                // A lost point sits where it was last seen: the pair's motion holds too,
                // rather than be measured against that stale position.
                let held = previous.pair.unwrap_or((0.0, 1.0));
                next.pair = Some(match a.lost.is_some() || b.lost.is_some() {
                    true => held,
                    false => pair_motion(a0.at, b0.at, a.at, b.at, held.0),
                });
            }
        }
        frames.push(next);
        progress.inc(1);
        Ok::<(), anyhow::Error>(())
    });
    progress.finish_and_clear();
    let Err(error) = read else {
        return Ok(frames);
    };
    match error.downcast_ref::<FootageError>() {
        Some(FootageError::VideoTooShort { available, .. }) if *available > 0 => {
            if to_end {
                return Ok(frames);
            }
            Err(UsageError(format!(
                "--frames {}..{}: the video has {available} frames at --fps {fps}",
                range.first, range.last
            ))
            .into())
        }
        _ => Err(error),
    }
}

fn tracked(frame: u64, points: Vec<Estimate>, starts: &[DVec2]) -> TrackedFrame {
    TrackedFrame {
        frame,
        points,
        pair: (starts.len() > 1).then_some((0.0, 1.0)),
    }
}

fn check_arguments(args: &TrackArgs) -> anyhow::Result<()> {
    if args.points.len() > MAX_POINTS {
        return Err(UsageError(format!("at most {MAX_POINTS} --point options")).into());
    }
    if args.fps <= 0.0 || args.fps > 1000.0 {
        return Err(UsageError(format!("--fps {} must be in (0, 1000]", args.fps)).into());
    }
    if let Err(error) = options(args).check() {
        return Err(UsageError(format!("--{error}")).into());
    }
    if args.output.as_os_str() == "-" {
        return super::check_stdout_for_data();
    }
    if args.output.is_dir() {
        return Err(UsageError(format!("-o {} is a folder", args.output.shown())).into());
    }
    Ok(lapclone::output::check_output_folder(&args.output)?)
}

/// How many frames the footage has: the unbroken run of plates from the start (a gap
/// before later plates, or something other than a file in the run, is an error rather than
/// a silent end), or a video's frames at `fps` (`None`: its container states no length).
fn available_frames(
    reader: &FootageReader,
    fps: f64,
    wanted: Option<FrameRange>,
) -> anyhow::Result<Option<u64>> {
    let limit = lapclone::limits::MAX_FRAMES;
    match &reader.footage().source {
        FootageSource::Sequence { pattern, start } => {
            let count = (0..=limit)
                .find(|i| !pattern.path(start + i).is_file())
                .unwrap_or(limit);
            let missing = pattern.path(start + count);
            if wanted.is_some_and(|r| r.last <= count) {
                return Ok(Some(count));
            }
            if let Some(what) =
                lapclone::util::not_a_file(&missing).filter(|w| *w != "does not exist")
            {
                anyhow::bail!("frame {} ({}) {what}", count + 1, missing.shown());
            }
            if let Some(last) = pattern.highest_number().filter(|n| *n > start + count) {
                return Err(UsageError(format!(
                    "frame {} ({}) is missing, but plates up to number {last} follow: fill the \
                     gap, or give --frames 1..{count}",
                    count + 1,
                    missing.shown()
                ))
                .into());
            }
            Ok(Some(count))
        }
        FootageSource::Video(_) => match reader.footage().check_covers(limit, fps) {
            Err(FootageError::VideoTooShort { available, .. }) => Ok(Some(available)),
            Err(other) => Err(other.into()),
            Ok(()) => Ok(None),
        },
    }
}

/// One warning per run of frames in which a point was lost.
fn warn_lost(frames: &[TrackedFrame]) {
    let count = frames.first().map_or(0, |f| f.points.len());
    for point in 0..count {
        let mut run: Option<(u64, u64, &'static str, f64)> = None;
        let flush = |run: &mut Option<(u64, u64, &'static str, f64)>| {
            if let Some((a, b, why, worst)) = run.take() {
                let span = if a == b {
                    format!("frame {a}")
                } else {
                    format!("frames {a}–{b}")
                };
                eprint_line!(
                    "lapclone: warning: point {} lost at {span} ({why}; confidence down to {worst:.2}); its last sure position is kept there",
                    point + 1
                );
            }
        };
        for frame in frames {
            let e = &frame.points[point];
            match (e.lost, run.as_mut()) {
                (Some(_), Some(r)) => {
                    r.1 = frame.frame;
                    r.3 = r.3.min(e.confidence);
                }
                (Some(why), None) => {
                    run = Some((frame.frame, frame.frame, why.describe(), e.confidence))
                }
                (None, _) => flush(&mut run),
            }
        }
        flush(&mut run);
    }
}
