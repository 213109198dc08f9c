//! `lapclone test [PATH …]`: golden-frame tests of scene files. Takes scene files and folders
//! (searched recursively for `*.rhai`), renders only the frames each checks (the scene's
//! `golden(#{ frames })`, `--frames`, or first, middle and last) on `--jobs` threads, and
//! compares them with `goldens/<stem>/frame_NNNN.png` beside the scene through
//! [`lapclone::golden`]. Gives one line (or JSON object) per frame and a summary, pending
//! `frame_NNNN.new.png` files for new and changed frames (never with `CI` set), failure
//! pictures and `index.html` under `--out`, optional JUnit XML, and exit code 0 (passed,
//! warnings allowed), 1 (a frame failed or was missing) or 2 (usage, or a scene that does not
//! load). `--accept`, `--reject` and `--review` handle pending files (`test_pending.rs`);
//! printing and reports are in `test_report.rs`.

use lapclone::util::ShowPath;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use lapclone::golden::{compare, encode_rgba_png, triptych, GoldenError, GoldenFrame, Thresholds};
use lapclone::output::{frame_digits, frame_file_name};
use lapclone::pixels::Canvas;
use lapclone::render::Renderer;

use super::render::{default_jobs, positioned};
use super::test_args::{
    check_golden_dirs, check_own_file, find_scenes, golden_dir, is_ci, overrides, pending_path,
    remove_if_present, write_file, FramePaths, FrameResult, Outcome, Pictures, SceneFailure,
    SceneResult, Status, TestArgs,
};
use super::test_report;
use super::UsageError;

/// Everything a worker needs, shared by all scenes.
struct Job<'a> {
    args: &'a TestArgs,
    ci: bool,
}

pub fn run(args: TestArgs) -> anyhow::Result<()> {
    let jobs = super::jobs(args.jobs, default_jobs())?;
    let paths = if args.paths.is_empty() {
        vec![PathBuf::from(".")]
    } else {
        args.paths.clone()
    };
    args.check_out()?;
    if args.accept || args.reject || args.review {
        return super::test_pending::run(&args, &paths);
    }
    if let Some(root) = args.goldens.as_deref().filter(|r| !r.is_dir()) {
        // A file (or a FIFO, a device) in its place is no missing folder.
        if root.exists() {
            let message = format!(
                "--goldens {}: it is not a folder; name a folder",
                root.shown()
            );
            return Err(UsageError(message).into());
        }
        if !args.update {
            return Err(UsageError(format!(
                "--goldens {}: no such folder (create the goldens with --update)",
                root.shown()
            ))
            .into());
        }
    }
    // lapclone never creates a missing parent of a path it is given.
    if let Some(junit) = &args.junit {
        super::refuse_stdout_dash("--junit", junit)?;
    }
    for path in args.junit.iter().chain(&args.out).chain(&args.goldens) {
        lapclone::output::check_output_folder(path)?;
    }
    if let Some(junit) = &args.junit {
        lapclone::util::check_destination(junit)
            .map_err(|e| UsageError(format!("--junit {}: {e}", junit.shown())))?;
        test_report::refuse_replacing_other_than_junit(junit)?;
    }
    let scenes = find_scenes(&paths, &args.out_dir())?;
    if scenes.is_empty() {
        return Err(
            UsageError(format!("no scene files (*.rhai) found in {}", list(&paths))).into(),
        );
    }
    check_golden_dirs(&scenes, args.goldens.as_deref())?;
    let roots = scenes
        .iter()
        .map(|scene| super::test_args::goldens_root(scene, args.goldens.as_deref()));
    super::test_args::check_out_beside_goldens(&args, roots)?;
    check_all(&args, &scenes, jobs.min(scenes.len()))
}

fn list(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.shown().to_string()).collect();
    names.join(", ")
}

fn check_all(args: &TestArgs, scenes: &[PathBuf], jobs: usize) -> anyhow::Result<()> {
    let started = Instant::now();
    let job = Job { args, ci: is_ci() };
    let mut results: Vec<Option<SceneResult>> = (0..scenes.len()).map(|_| None).collect();
    let next = AtomicUsize::new(0);
    let (sender, receiver) = mpsc::channel();
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            let sender = sender.clone();
            let (job, next) = (&job, &next);
            scope.spawn(move || loop {
                let index = next.fetch_add(1, Ordering::Relaxed);
                let Some(scene) = scenes.get(index) else {
                    break;
                };
                if sender.send((index, check_scene(job, scene))).is_err() {
                    break;
                }
            });
        }
        drop(sender);
        // Print in scene order as soon as each scene and all before it are done.
        let mut printed = 0;
        for (index, result) in receiver {
            results[index] = Some(result);
            while let Some(Some(result)) = results.get(printed) {
                test_report::print_scene(result, args.json);
                printed += 1;
            }
        }
    });
    let results: Vec<SceneResult> = results.into_iter().flatten().collect();
    test_report::finish(args, &results, started.elapsed().as_secs_f64())
}

/// Loads, renders and compares one scene; never panics on bad input.
fn check_scene(job: &Job, scene: &Path) -> SceneResult {
    let started = Instant::now();
    let mut result = SceneResult {
        scene: scene.to_path_buf(),
        frames: Vec::new(),
        failure: None,
        thresholds: Thresholds::default(),
        seconds: 0.0,
    };
    let (loaded, mut renderer) = match load(scene) {
        Ok(pair) => pair,
        Err(error) => {
            result.failure = Some(SceneFailure {
                message: super::describe(&error),
                loads: false,
            });
            return result;
        }
    };
    super::scene_open::print_warnings(&loaded, &renderer);
    let settings = loaded.scene.golden.clone().unwrap_or_default();
    result.thresholds = overrides(job.args, settings.apply(Thresholds::default()));
    let total = renderer.frame_count();
    let frames = match choose_frames(job.args, settings.frames.as_deref(), total) {
        Ok(frames) => frames,
        Err(message) => {
            result.failure = Some(SceneFailure {
                message: format!("{}: {message}", scene.shown()),
                loads: false,
            });
            return result;
        }
    };
    check_frames(job, scene, &loaded, &mut renderer, frames, &mut result);
    result.seconds = started.elapsed().as_secs_f64();
    result
}

/// Renders and compares `frames` (numbers from 1) into `result`; a render error ends the
/// scene's checks.
fn check_frames(
    job: &Job,
    scene: &Path,
    loaded: &lapclone::script::LoadedScene,
    renderer: &mut Renderer,
    frames: Vec<u64>,
    result: &mut SceneResult,
) {
    let total = renderer.frame_count();
    let dir = golden_dir(scene, job.args.goldens.as_deref());
    let digits = frame_digits(total);
    let format = renderer.output_format();
    for number in frames {
        let frame_started = Instant::now();
        let canvas = match renderer.render_frame(number - 1) {
            Ok(canvas) => canvas,
            Err(error) => {
                let error = positioned(loaded, error);
                result.failure = Some(SceneFailure {
                    message: format!("frame {number}: {}", super::describe(&error)),
                    loads: true,
                });
                break;
            }
        };
        let golden = dir.join(frame_file_name(number, digits));
        let paths = FramePaths {
            pending: pending_path(&golden),
            golden,
        };
        let mut frame = check_frame(
            job,
            scene,
            number,
            paths,
            canvas,
            format,
            &result.thresholds,
        );
        frame.seconds = frame_started.elapsed().as_secs_f64();
        result.frames.push(frame);
    }
}

fn load(scene: &Path) -> anyhow::Result<(lapclone::script::LoadedScene, Renderer)> {
    lapclone::open_scene(scene).map_err(|e| anyhow::anyhow!("{e}"))
}

/// `--frames`, else the scene's own, else first, middle and last; all within the scene.
fn choose_frames(args: &TestArgs, own: Option<&[u64]>, total: u64) -> Result<Vec<u64>, String> {
    let (frames, origin) = match (&args.frames, own) {
        (Some(frames), _) => (frames.0.clone(), "--frames"),
        (None, Some(frames)) => (frames.to_vec(), "golden(#{ frames })"),
        (None, None) => {
            let mut frames = vec![1, 1 + (total - 1) / 2, total];
            frames.dedup();
            return Ok(frames);
        }
    };
    match frames.iter().find(|&&n| n > total) {
        Some(n) => Err(format!(
            "{origin}: frame {n} is past the end (the scene has {total} frames)"
        )),
        None => Ok(frames),
    }
}

/// Compares (or, with `--update`, writes) one rendered frame.
fn check_frame(
    job: &Job,
    scene: &Path,
    number: u64,
    paths: FramePaths,
    canvas: &Canvas,
    format: lapclone::pixels::PixelFormat,
    thresholds: &Thresholds,
) -> FrameResult {
    let mut result = FrameResult {
        frame: number,
        outcome: Outcome::Updated,
        pending_written: None,
        pictures: None,
        seconds: 0.0,
        paths,
    };
    let written = (|| -> anyhow::Result<()> {
        if job.args.update {
            write_file(&result.paths.golden, &canvas.encode_png(format)?)?;
            remove_if_present(&result.paths.pending)?;
            result.outcome = Outcome::Updated;
            return Ok(());
        }
        let actual = GoldenFrame::from_canvas(canvas, format)?;
        let (outcome, expected) = judge(&result.paths.golden, &actual, thresholds);
        result.outcome = outcome;
        let failing = matches!(result.outcome.status(), Status::Fail | Status::New);
        if !failing {
            if !job.ci {
                remove_if_present(&result.paths.pending)?;
            }
            return Ok(());
        }
        let png = canvas.encode_png(format)?;
        if !job.ci {
            write_file(&result.paths.pending, &png)?;
            result.pending_written = Some(result.paths.pending.clone());
        }
        if let Some(root) = job.args.report_dir() {
            let pictures = write_pictures(
                &root,
                scene,
                number,
                &png,
                expected.as_ref(),
                &actual,
                thresholds,
            )?;
            result.pictures = Some(pictures);
        }
        Ok(())
    })();
    if let Err(error) = written {
        result.outcome = Outcome::Unreadable(format!("writing files: {}", super::describe(&error)));
    }
    result
}

/// The outcome of comparing with the golden file, and the golden when it could be read.
fn judge(
    golden: &Path,
    actual: &GoldenFrame,
    thresholds: &Thresholds,
) -> (Outcome, Option<GoldenFrame>) {
    if let Err(error) = check_own_file(golden) {
        return (Outcome::Unreadable(super::describe(&error)), None);
    }
    if !golden.is_file() {
        let folder = golden.parent().is_some_and(Path::is_dir);
        return (Outcome::Missing { folder }, None);
    }
    let expected = match GoldenFrame::load(golden) {
        Ok(expected) => expected,
        Err(error @ (GoldenError::Read { .. } | GoldenError::Decode { .. })) => {
            return (Outcome::Unreadable(error.to_string()), None)
        }
        Err(error) => return (Outcome::Unreadable(error.to_string()), None),
    };
    let outcome = match compare(&expected, actual, thresholds) {
        Ok(comparison) => Outcome::Compared(comparison),
        Err(mismatch) => Outcome::Mismatch(mismatch),
    };
    (outcome, Some(expected))
}

/// Writes the actual frame, the difference image and the triptych under `--out`.
fn write_pictures(
    root: &Path,
    scene: &Path,
    number: u64,
    png: &[u8],
    expected: Option<&GoldenFrame>,
    actual: &GoldenFrame,
    thresholds: &Thresholds,
) -> anyhow::Result<Pictures> {
    let dir = root.join(test_report::scene_slug(scene));
    let stem = format!("frame_{number:04}");
    let pictures = Pictures {
        actual: dir.join(format!("{stem}.actual.png")),
        difference: expected.map(|_| dir.join(format!("{stem}.diff.png"))),
        triptych: dir.join(format!("{stem}.triptych.png")),
    };
    write_file(&pictures.actual, png)?;
    if let (Some(expected), Some(path)) = (expected, &pictures.difference) {
        let difference = lapclone::golden::difference_image(expected, actual, thresholds);
        write_file(path, &encode_rgba_png(&difference))?;
    }
    let sheet = triptych(expected, actual, thresholds);
    write_file(&pictures.triptych, &encode_rgba_png(&sheet))?;
    Ok(pictures)
}
