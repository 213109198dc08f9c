//! `lapclone-bench track`: takes synthetic footage it makes (a photograph moved along a known
//! path) and gives the tracker's speed and accuracy beside the references: one point
//! through N frames of 1920×1080 PNG, reading ahead on every core as `lapclone track` does,
//! against decoding those frames alone the same way (and on one thread, for scale), against an OpenCV loop (`imread` + `calcOpticalFlowPyrLK` per frame,
//! through python3 and cv2), and the RMS error of both on the 100-frame 320×240 JPEG
//! sequences the tests use. OpenCV's figures are skipped, with the reason, where cv2 is
//! missing.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use lapclone::glam::DVec2;
use lapclone::pixels::{Footage, FootageReader};
use lapclone::track::{read_ahead, PointTracker, TrackOptions};
use lapclone::FloatImage;

#[path = "../../../tests/common/track_footage.rs"]
mod track_footage;
use track_footage::{frame, jpeg, Motion, Noise};

#[derive(clap::Args, Debug)]
pub struct TrackBenchArgs {
    /// Frames of 1920×1080 footage.
    #[arg(long, default_value_t = 240)]
    pub frames: u32,
    /// Timed rounds (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// The Python interpreter that has cv2 (OpenCV) and numpy.
    #[arg(long, default_value = "python3")]
    pub python: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

const HD: (u32, u32) = (1920, 1080);
const SMALL: (u32, u32) = (320, 240);
const HD_POINT: DVec2 = DVec2::new(1004.0, 522.0);
const SMALL_POINT: DVec2 = DVec2::new(150.0, 112.0);

/// OpenCV's loop: pixel centres are at whole coordinates there, at +0.5 here.
const OPENCV_LOOP: &str = r#"
import sys, time
import cv2, numpy as np
pattern, n, x, y = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)
start = time.perf_counter()
prev = cv2.cvtColor(cv2.imread(pattern % 1), cv2.COLOR_BGR2GRAY)
pts = np.array([[[x - 0.5, y - 0.5]]], np.float32)
out = [(x, y)]
for i in range(2, n + 1):
    cur = cv2.cvtColor(cv2.imread(pattern % i), cv2.COLOR_BGR2GRAY)
    pts, st, err = cv2.calcOpticalFlowPyrLK(prev, cur, pts, None, winSize=(31, 31), maxLevel=3, criteria=criteria)
    out.append((float(pts[0, 0, 0]) + 0.5, float(pts[0, 0, 1]) + 0.5))
    prev = cur
print(time.perf_counter() - start)
for p in out:
    print(p[0], p[1])
"#;

pub fn run(args: TrackBenchArgs) -> anyhow::Result<()> {
    let dir = tempfile_dir()?;
    let result = measure(&args, &dir);
    let _ = std::fs::remove_dir_all(&dir);
    let report = result?;
    // The table form is the same JSON: a handful of figures reads well either way.
    let _ = args.json;
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

fn tempfile_dir() -> anyhow::Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("lapclone-bench-track-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

fn measure(args: &TrackBenchArgs, dir: &Path) -> anyhow::Result<serde_json::Value> {
    let hd = dir.join("hd");
    std::fs::create_dir_all(&hd)?;
    eprintln!("making {} frames of 1920×1080 PNG footage", args.frames);
    write_hd(&hd, args.frames)?;
    let pattern = hd.join("f_%04d.png");
    let threads = lapclone::util::available_cores();
    let (mut sequential, mut decode, mut track) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..args.runs.max(1) {
        sequential.push(time_decode(&pattern, args.frames, 1)?);
        decode.push(time_decode(&pattern, args.frames, threads)?);
        track.push(time_track(&pattern, args.frames, HD_POINT, threads)?.0);
    }
    let sequential_s = median(&mut sequential);
    let (decode_s, track_s) = (median(&mut decode), median(&mut track));
    let cv = probe(&args.python);
    let opencv_s = match &cv {
        Ok(()) => {
            let mut times = Vec::new();
            for _ in 0..args.runs.max(1) {
                times.push(opencv(&args.python, &pattern, args.frames, HD_POINT)?.0);
            }
            Some(median(&mut times))
        }
        Err(_) => None,
    };
    let accuracy = [
        ("translation", Motion::translation()),
        ("similarity", Motion::similarity()),
    ]
    .into_iter()
    .map(|(name, motion)| accuracy(dir, name, &motion, &args.python, cv.is_ok()))
    .collect::<anyhow::Result<serde_json::Map<_, _>>>()?;
    Ok(serde_json::json!({
        "frames": args.frames,
        "threads": threads,
        "decode_one_thread_s": sequential_s,
        "decode_s": decode_s,
        "track_s": track_s,
        "track_over_decode": track_s / decode_s,
        "opencv_s": opencv_s,
        "track_over_opencv": opencv_s.map(|o| track_s / o),
        "opencv_skipped": cv.err(),
        "accuracy": accuracy,
    }))
}

fn write_hd(dir: &Path, frames: u32) -> anyhow::Result<()> {
    let coffee =
        FloatImage::load(Path::new("assets/coffee.png")).context("run from the repository root")?;
    // Enlarged 3.5× so the 1920×1080 frame stays inside the photograph as it moves.
    let photo = FloatImage::from_fn(2100, 1400, coffee.format(), |i, j| {
        coffee.sample_bilinear((f64::from(i) + 0.5) / 3.5, (f64::from(j) + 0.5) / 3.5)
    })?;
    let motion = Motion::translation();
    let mut noise = Noise::new(7);
    for k in 0..frames {
        let image = frame(&photo, HD, &motion, k, 2.0, &mut noise);
        image.save(dir.join(format!("f_{:04}.png", k + 1)))?;
    }
    Ok(())
}

fn reader(pattern: &Path) -> anyhow::Result<FootageReader> {
    Ok(FootageReader::new(
        Footage::open(pattern, Some(1), false, "hold")?,
        24.0,
    ))
}

fn time_decode(pattern: &Path, frames: u32, threads: usize) -> anyhow::Result<f64> {
    let start = Instant::now();
    let footage = reader(pattern)?.footage().clone();
    read_ahead(
        &footage,
        24.0,
        0..=u64::from(frames) - 1,
        threads,
        |_, frame| {
            std::hint::black_box(frame);
            Ok::<(), anyhow::Error>(())
        },
    )?;
    Ok(start.elapsed().as_secs_f64())
}

/// Seconds, and the tracked path, reading ahead on `threads` as `lapclone track` does.
fn time_track(
    pattern: &Path,
    frames: u32,
    point: DVec2,
    threads: usize,
) -> anyhow::Result<(f64, Vec<DVec2>)> {
    let start = Instant::now();
    let footage = reader(pattern)?.footage().clone();
    let mut tracker: Option<PointTracker> = None;
    let mut path = Vec::new();
    read_ahead(
        &footage,
        24.0,
        0..=u64::from(frames) - 1,
        threads,
        |_, frame| {
            let estimates = match tracker.as_mut() {
                Some(t) => t.next(frame)?,
                None => {
                    let (t, first) = PointTracker::start(frame, &[point], TrackOptions::default())?;
                    tracker = Some(t);
                    first
                }
            };
            path.push(estimates[0].at);
            Ok::<(), anyhow::Error>(())
        },
    )?;
    Ok((start.elapsed().as_secs_f64(), path))
}

fn probe(python: &Path) -> Result<(), String> {
    super::child_run::probe(python, &["-c", "import cv2, numpy"])
        .map_err(|why| format!("OpenCV not available ({why}); install opencv-python-headless"))
}

/// OpenCV's loop time (inside Python, without its start-up) and path.
fn opencv(
    python: &Path,
    pattern: &Path,
    frames: u32,
    point: DVec2,
) -> anyhow::Result<(f64, Vec<DVec2>)> {
    let output = Command::new(python)
        .args(["-c", OPENCV_LOOP])
        .arg(pattern)
        .arg(frames.to_string())
        .arg(point.x.to_string())
        .arg(point.y.to_string())
        .output()?;
    anyhow::ensure!(
        output.status.success(),
        "OpenCV loop failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = String::from_utf8(output.stdout)?;
    let mut lines = text.lines();
    let seconds: f64 = lines.next().context("no time")?.trim().parse()?;
    let path = lines
        .map(|l| {
            let mut v = l.split_whitespace().map(|x| x.parse::<f64>());
            Ok(DVec2::new(v.next().context("x")??, v.next().context("y")??))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok((seconds, path))
}

/// RMS error of lapclone (and OpenCV) on the tests' 100-frame 320×240 JPEG sequence.
fn accuracy(
    dir: &Path,
    name: &str,
    motion: &Motion,
    python: &Path,
    with_opencv: bool,
) -> anyhow::Result<(String, serde_json::Value)> {
    let folder = dir.join(name);
    std::fs::create_dir_all(&folder)?;
    let photo = FloatImage::load(Path::new("assets/chelsea.png"))?;
    let mut noise = Noise::new(41);
    let frames = 100;
    for k in 0..frames {
        let image = frame(&photo, SMALL, motion, k, 2.0, &mut noise);
        std::fs::write(folder.join(format!("f_{:04}.jpg", k + 1)), jpeg(&image, 90))?;
    }
    let pattern = folder.join("f_%04d.jpg");
    let rms = |path: &[DVec2]| {
        let sum: f64 = path
            .iter()
            .enumerate()
            .map(|(k, p)| p.distance_squared(motion.truth(SMALL, k as u32, SMALL_POINT)))
            .sum();
        (sum / path.len() as f64).sqrt()
    };
    let ours = rms(&time_track(&pattern, frames, SMALL_POINT, 1)?.1);
    let theirs = if with_opencv {
        Some(rms(&opencv(python, &pattern, frames, SMALL_POINT)?.1))
    } else {
        None
    };
    Ok((
        name.to_string(),
        serde_json::json!({ "lapclone_rms_px": ours, "opencv_rms_px": theirs }),
    ))
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}
