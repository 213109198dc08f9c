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

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use anyhow::Context as _;
use lapclone::golden::{
    compare, encode_rgba_png, triptych, Comparison, GoldenError, GoldenFrame, Mismatch, Thresholds,
    Verdict,
};
use lapclone::output::{frame_digits, frame_file_name};
use lapclone::pixels::Canvas;
use lapclone::render::Renderer;

use super::render::{default_jobs, positioned};
use super::test_report::{self, Reporter};
use super::UsageError;

const AFTER_HELP: &str = "\
Goldens live beside each scene in goldens/<scene stem>/frame_NNNN.png (numbered as
`lapclone render` numbers frames, from 1), at the scene's bit depth.

A pixel fails when any channel differs by more than --fail (8-bit units: one level of an
8-bit channel is 1); a frame fails when more than --fail-percent of its pixels fail, when any
channel differs by more than --hard-fail, or when its SSIM is below --min-ssim. --warn and
--warn-percent do the same for warnings. A scene sets its own frames and thresholds with
golden(#{ frames: [1, 12, 48], fail: 2, fail_percent: 0.1 }); flags override it.

A new frame (no golden) or a failing one writes frame_NNNN.new.png beside its golden, and its
actual frame, difference image and expected | difference | actual triptych under --out, with
an index.html. While CI is set nothing is written unless asked for: no golden or pending file
except by --update or --accept, and pictures only with an explicit --out.

Exit codes: 0 all passed (warnings allowed), 1 a frame failed or had no golden, 2 usage error
or a scene that does not load.

Examples:
  lapclone test scenes/ --update        write every golden
  lapclone test                         check every scene under the current folder
  lapclone test --review                accept / reject / skip each pending frame
  lapclone test --junit report.xml      also write JUnit XML for CI";

#[derive(clap::Args, Debug)]
#[command(after_help = AFTER_HELP)]
#[command(group(clap::ArgGroup::new("mode").args(["accept", "reject", "review", "update"]).multiple(false)))]
pub struct TestArgs {
    /// Scene files or folders (searched recursively for *.rhai; folders named `scripts`,
    /// `goldens` or `target` and hidden ones are skipped). Default: the current folder.
    pub paths: Vec<PathBuf>,
    /// Frames to check in every scene, e.g. 1,12,48 or 1..5 (numbered from 1).
    #[arg(long, value_parser = frame_list)]
    pub frames: Option<FrameList>,
    /// Root of the goldens instead of `goldens/` beside each scene: `DIR/<stem>/frame_NNNN.png`.
    #[arg(long, value_name = "DIR")]
    pub goldens: Option<PathBuf>,
    /// A pixel fails when a channel differs by more than T (8-bit units) [default: 1].
    #[arg(long, value_name = "T", value_parser = non_negative)]
    pub fail: Option<f64>,
    /// Percentage of pixels allowed to fail [default: 0].
    #[arg(long, value_name = "P", value_parser = percent)]
    pub fail_percent: Option<f64>,
    /// Any channel differing by more than T fails the frame, whatever the percentage.
    #[arg(long, value_name = "T", value_parser = non_negative)]
    pub hard_fail: Option<f64>,
    /// A pixel warns when a channel differs by more than T [default: 0].
    #[arg(long, value_name = "T", value_parser = non_negative)]
    pub warn: Option<f64>,
    /// Percentage of pixels allowed to warn [default: 0].
    #[arg(long, value_name = "P", value_parser = percent)]
    pub warn_percent: Option<f64>,
    /// The frame fails when its SSIM (0–1) is below S.
    #[arg(long, value_name = "S", value_parser = unit_interval)]
    pub min_ssim: Option<f64>,
    /// One JSON object per frame on stdout instead of text lines.
    #[arg(long)]
    pub json: bool,
    /// Folder for failure pictures and index.html [default: lapclone-test-out; with CI set,
    /// none unless given].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Promote every pending frame_NNNN.new.png (under the paths given) to its golden.
    #[arg(long)]
    pub accept: bool,
    /// Delete every pending frame_NNNN.new.png (under the paths given).
    #[arg(long)]
    pub reject: bool,
    /// Go through pending frames one by one: accept, reject or skip.
    #[arg(long)]
    pub review: bool,
    /// Render and overwrite every checked golden (also with CI set).
    #[arg(long)]
    pub update: bool,
    /// Also write JUnit XML (one test case per scene and frame) to FILE.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Scenes checked at once (default: available cores).
    #[arg(long, allow_hyphen_values = true)]
    pub jobs: Option<usize>,
}

/// Frame numbers from 1, sorted, without repeats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameList(pub Vec<u64>);

/// `1,12,48`, `1..5` or a mix.
pub fn frame_list(text: &str) -> Result<FrameList, String> {
    let mut frames = Vec::new();
    for part in text.split(',') {
        let part = part.trim();
        if part.contains("..") {
            let range = super::render::frame_range(part)?;
            frames.extend(range.first..=range.last.min(range.first + 100_000));
        } else {
            match part.parse::<u64>() {
                Ok(n) if n >= 1 => frames.push(n),
                _ => return Err(format!("`{part}` is not a frame number (from 1)")),
            }
        }
    }
    frames.sort_unstable();
    frames.dedup();
    Ok(FrameList(frames))
}

fn non_negative(text: &str) -> Result<f64, String> {
    let value = super::finite_f64(text)?;
    if value < 0.0 {
        return Err(format!("`{text}` must be ≥ 0"));
    }
    Ok(value)
}

fn percent(text: &str) -> Result<f64, String> {
    let value = non_negative(text)?;
    if value > 100.0 {
        return Err(format!("`{text}` must be a percentage in 0..=100"));
    }
    Ok(value)
}

fn unit_interval(text: &str) -> Result<f64, String> {
    let value = super::finite_f64(text)?;
    if !(0.0..=1.0).contains(&value) {
        return Err(format!("`{text}` must be in 0..=1"));
    }
    Ok(value)
}

/// The report folder when `--out` is not given.
const DEFAULT_OUT: &str = "lapclone-test-out";

impl TestArgs {
    /// The `--out` folder, or its default; scene search skips it.
    pub fn out_dir(&self) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| PathBuf::from(DEFAULT_OUT))
    }

    /// Where failure pictures and `index.html` go: none on CI unless `--out` was given, so a
    /// CI run writes nothing it was not asked for.
    pub fn report_dir(&self) -> Option<PathBuf> {
        match &self.out {
            Some(dir) => Some(dir.clone()),
            None => (!is_ci()).then(|| PathBuf::from(DEFAULT_OUT)),
        }
    }
}

/// Whether the environment says this is a CI run (`CI` set, and not to `false` or `0`).
pub fn is_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// Where one frame's golden and pending files live.
#[derive(Clone, Debug)]
pub struct FramePaths {
    pub golden: PathBuf,
    pub pending: PathBuf,
}

/// The pending file of a golden: `frame_NNNN.png` → `frame_NNNN.new.png`.
pub fn pending_path(golden: &Path) -> PathBuf {
    golden.with_extension("new.png")
}

/// The folder holding a scene's goldens.
pub fn golden_dir(scene: &Path, root: Option<&Path>) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default();
    match root {
        Some(root) => root.join(stem),
        None => scene
            .parent()
            .unwrap_or(Path::new(""))
            .join("goldens")
            .join(stem),
    }
}

/// What happened to one frame.
#[derive(Debug)]
pub enum Outcome {
    Compared(Comparison),
    Mismatch(Mismatch),
    /// No golden file; whether its folder existed.
    Missing {
        folder: bool,
    },
    /// The golden exists but cannot be read.
    Unreadable(String),
    /// `--update` wrote the golden.
    Updated,
}

/// The status word and whether it counts as a failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Pass,
    Warn,
    Fail,
    New,
    Updated,
}

impl Outcome {
    pub fn status(&self) -> Status {
        match self {
            Outcome::Compared(c) => match c.verdict {
                Verdict::Pass => Status::Pass,
                Verdict::Warn => Status::Warn,
                Verdict::Fail => Status::Fail,
            },
            Outcome::Mismatch(_) | Outcome::Unreadable(_) => Status::Fail,
            Outcome::Missing { .. } => Status::New,
            Outcome::Updated => Status::Updated,
        }
    }
}

/// One checked frame and the files written for it.
#[derive(Debug)]
pub struct FrameResult {
    pub frame: u64,
    pub paths: FramePaths,
    pub outcome: Outcome,
    /// The pending file, if one was written.
    pub pending_written: Option<PathBuf>,
    /// Failure pictures under `--out`: actual, difference (if there is a golden), triptych.
    pub pictures: Option<Pictures>,
    pub seconds: f64,
}

#[derive(Debug, Clone)]
pub struct Pictures {
    pub actual: PathBuf,
    pub difference: Option<PathBuf>,
    pub triptych: PathBuf,
}

/// A scene that could not be loaded (exit 2) or rendered (a failure).
#[derive(Debug)]
pub struct SceneFailure {
    pub message: String,
    pub loads: bool,
}

#[derive(Debug)]
pub struct SceneResult {
    pub scene: PathBuf,
    pub frames: Vec<FrameResult>,
    pub failure: Option<SceneFailure>,
    pub thresholds: Thresholds,
    pub seconds: f64,
}

/// Everything a worker needs, shared by all scenes.
struct Job<'a> {
    args: &'a TestArgs,
    ci: bool,
}

pub fn run(args: TestArgs) -> anyhow::Result<()> {
    if args.jobs == Some(0) {
        return Err(UsageError("--jobs must be at least 1".into()).into());
    }
    let paths = if args.paths.is_empty() {
        vec![PathBuf::from(".")]
    } else {
        args.paths.clone()
    };
    if args.accept || args.reject || args.review {
        return super::test_pending::run(&args, &paths);
    }
    if let Some(root) = args.goldens.as_deref().filter(|r| !r.is_dir()) {
        if !args.update {
            return Err(UsageError(format!(
                "--goldens {}: no such folder (create the goldens with --update)",
                root.display()
            ))
            .into());
        }
    }
    let scenes = find_scenes(&paths, &args.out_dir())?;
    if scenes.is_empty() {
        return Err(
            UsageError(format!("no scene files (*.rhai) found in {}", list(&paths))).into(),
        );
    }
    check_all(&args, &scenes)
}

fn list(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    names.join(", ")
}

fn check_all(args: &TestArgs, scenes: &[PathBuf]) -> anyhow::Result<()> {
    let started = Instant::now();
    let job = Job { args, ci: is_ci() };
    let jobs = args.jobs.unwrap_or_else(default_jobs).min(scenes.len());
    let mut reporter = Reporter::new(args.json);
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
                reporter.scene(result);
                printed += 1;
            }
        }
    });
    let results: Vec<SceneResult> = results.into_iter().flatten().collect();
    test_report::finish(args, &results, started.elapsed().as_secs_f64(), &reporter)
}

/// Scene files under `paths`, sorted, each once.
pub fn find_scenes(paths: &[PathBuf], out: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut scenes = Vec::new();
    for path in paths {
        if path.is_dir() {
            walk(path, out, &mut scenes)?;
        } else if path.is_file() {
            scenes.push(path.strip_prefix(".").unwrap_or(path).to_path_buf());
        } else {
            return Err(UsageError(format!("{}: no such file or folder", path.display())).into());
        }
    }
    scenes.sort();
    scenes.dedup();
    Ok(scenes)
}

fn walk(dir: &Path, out: &Path, scenes: &mut Vec<PathBuf>) -> anyhow::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if path.is_dir() {
            let skipped = name.starts_with('.')
                || ["scripts", "goldens", "target"].contains(&name.as_ref())
                || same_path(&path, out);
            if !skipped {
                walk(&path, out, scenes)?;
            }
        } else if name.ends_with(".rhai") {
            scenes.push(path.strip_prefix(".").unwrap_or(&path).to_path_buf());
        }
    }
    Ok(())
}

fn same_path(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
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
    let settings = loaded.scene.golden.clone().unwrap_or_default();
    result.thresholds = overrides(job.args, settings.apply(Thresholds::default()));
    let total = renderer.frame_count();
    let frames = match choose_frames(job.args, settings.frames.as_deref(), total) {
        Ok(frames) => frames,
        Err(message) => {
            result.failure = Some(SceneFailure {
                message: format!("{}: {message}", scene.display()),
                loads: false,
            });
            return result;
        }
    };
    let dir = golden_dir(scene, job.args.goldens.as_deref());
    let digits = frame_digits(total);
    let format = renderer.output_format();
    for number in frames {
        let frame_started = Instant::now();
        let canvas = match renderer.render_frame(number - 1) {
            Ok(canvas) => canvas,
            Err(error) => {
                let error = positioned(&loaded, error);
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
    result.seconds = started.elapsed().as_secs_f64();
    result
}

fn load(scene: &Path) -> anyhow::Result<(lapclone::script::LoadedScene, Renderer)> {
    use lapclone::script::{load_scene, validate_scene};
    let loaded = load_scene(scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    validate_scene(&loaded).map_err(|e| anyhow::anyhow!("{e}"))?;
    let renderer = Renderer::new(loaded.scene.clone()).map_err(|e| positioned(&loaded, e))?;
    Ok((loaded, renderer))
}

/// Flags win over the scene's settings.
pub fn overrides(args: &TestArgs, base: Thresholds) -> Thresholds {
    Thresholds {
        fail: args.fail.unwrap_or(base.fail),
        fail_percent: args.fail_percent.unwrap_or(base.fail_percent),
        hard_fail: args.hard_fail.unwrap_or(base.hard_fail),
        warn: args.warn.unwrap_or(base.warn),
        warn_percent: args.warn_percent.unwrap_or(base.warn_percent),
        min_ssim: args.min_ssim.or(base.min_ssim),
    }
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

/// Writes `bytes` atomically, creating the folder first.
pub fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    lapclone::util::write_atomic(path, bytes).with_context(|| format!("writing {}", path.display()))
}

pub fn remove_if_present(path: &Path) -> anyhow::Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("removing {}", path.display()))
        }
        _ => Ok(()),
    }
}
