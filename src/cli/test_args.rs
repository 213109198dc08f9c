//! What the `lapclone test` files share: takes the command line and gives the parsed
//! `TestArgs`, the per-frame and per-scene results, where goldens and pending frames live,
//! the scene search and the atomic file writes.

use lapclone::util::ShowPath;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use lapclone::golden::{Comparison, Mismatch, Thresholds, Verdict};

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
    #[arg(long, value_name = "T", value_parser = non_negative, allow_hyphen_values = true)]
    pub fail: Option<f64>,
    /// Percentage of pixels allowed to fail [default: 0].
    #[arg(long, value_name = "P", value_parser = percent, allow_hyphen_values = true)]
    pub fail_percent: Option<f64>,
    /// Any channel differing by more than T fails the frame, whatever the percentage.
    #[arg(long, value_name = "T", value_parser = non_negative, allow_hyphen_values = true)]
    pub hard_fail: Option<f64>,
    /// A pixel warns when a channel differs by more than T [default: 0].
    #[arg(long, value_name = "T", value_parser = non_negative, allow_hyphen_values = true)]
    pub warn: Option<f64>,
    /// Percentage of pixels allowed to warn [default: 0].
    #[arg(long, value_name = "P", value_parser = percent, allow_hyphen_values = true)]
    pub warn_percent: Option<f64>,
    /// The frame fails when its SSIM (0–1) is below S.
    #[arg(long, value_name = "S", value_parser = unit_interval, allow_hyphen_values = true)]
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
            frames.extend(range.first..=range.last.min(range.first.saturating_add(100_000)));
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

    /// A usage error when `--out` names something that is not a folder: the pictures
    /// would fail to write only after every scene had run.
    pub fn check_out(&self) -> Result<(), UsageError> {
        match &self.out {
            Some(dir) if dir.exists() && !dir.is_dir() => Err(UsageError(format!(
                "--out {}: not a folder (failure pictures and index.html go in a folder)",
                dir.shown()
            ))),
            _ => Ok(()),
        }
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

/// Each scene's goldens folder must be its own and inside the goldens root: a scene named
/// `...rhai` (stem `..`) would keep them in the folder above, and two scenes of one name
/// under `--goldens` would overwrite each other's.
pub fn check_golden_dirs(scenes: &[PathBuf], root: Option<&Path>) -> anyhow::Result<()> {
    let mut seen: std::collections::HashMap<PathBuf, &Path> = Default::default();
    for scene in scenes {
        let stem = scene.file_stem().unwrap_or_default();
        if stem.is_empty() || stem == "." || stem == ".." {
            return Err(UsageError(format!(
                "{}: a scene's name must make a folder name for its goldens; rename it",
                scene.shown()
            ))
            .into());
        }
        let dir = golden_dir(scene, root);
        if let Some(other) = seen.insert(dir.clone(), scene) {
            return Err(UsageError(format!(
                "{} and {} would share the goldens in {}: give them separate --goldens runs \
                 or different names",
                other.shown(),
                scene.shown(),
                dir.shown()
            ))
            .into());
        }
    }
    Ok(())
}

/// A usage error when the report folder (`--out`, else `lapclone-test-out`) is, or lies inside,
/// one of the `goldens` folders: its pictures would mix with the goldens (and be committed
/// with them).
pub fn check_out_beside_goldens(
    args: &TestArgs,
    goldens: impl IntoIterator<Item = PathBuf>,
) -> Result<(), UsageError> {
    let out = args.out_dir();
    let inside = absolute(&out);
    for folder in goldens {
        if inside.starts_with(absolute(&folder)) {
            let named = match args.out {
                Some(_) => format!("--out {}", out.shown()),
                None => format!(
                    "the report folder {} (name another with --out)",
                    out.shown()
                ),
            };
            return Err(UsageError(format!(
                "{named}: it lies in the goldens folder {}; the report's pictures would mix with the goldens",
                folder.shown()
            )));
        }
    }
    Ok(())
}

/// The folder holding `scene`'s goldens folder (`<scene's folder>/goldens`, or `root`).
pub fn goldens_root(scene: &Path, root: Option<&Path>) -> PathBuf {
    let dir = golden_dir(scene, root);
    dir.parent().unwrap_or(Path::new("")).to_path_buf()
}

/// `path` with links resolved as far as it exists, the rest joined on (for comparing
/// folders that may not exist yet).
fn absolute(path: &Path) -> PathBuf {
    let path = if path.as_os_str().is_empty() {
        Path::new(".")
    } else {
        path
    };
    if let Ok(real) = path.canonicalize() {
        return real;
    }
    match (path.parent(), path.file_name()) {
        (Some(parent), Some(name)) => absolute(parent).join(name),
        _ => path.to_path_buf(),
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

/// Scene files under `paths`, sorted, each once.
pub fn find_scenes(paths: &[PathBuf], out: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut scenes = Vec::new();
    for path in paths {
        if path.is_dir() {
            walk(path, out, &mut scenes)?;
        } else if path.is_file() {
            scenes.push(path.strip_prefix(".").unwrap_or(path).to_path_buf());
        } else {
            return Err(UsageError(format!("{}: no such file or folder", path.shown())).into());
        }
    }
    scenes.sort();
    scenes.dedup();
    Ok(scenes)
}

fn walk(dir: &Path, out: &Path, scenes: &mut Vec<PathBuf>) -> anyhow::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.shown()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if path.is_dir() {
            // A linked folder is not followed (as ripgrep does not): a link back up the tree
            // would find every scene again, or forever.
            let skipped = name.starts_with('.')
                || ["scripts", "goldens", "target"].contains(&name.as_ref())
                || is_link(&path)
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

/// Whether `path` itself is a symbolic link.
pub fn is_link(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink())
}

fn same_path(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
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

/// Writes `bytes` atomically, creating the folder first.
pub fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    check_own_file(path)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.shown()))?;
    }
    lapclone::util::write_atomic(path, bytes).with_context(|| format!("writing {}", path.shown()))
}

pub fn remove_if_present(path: &Path) -> anyhow::Result<()> {
    check_own_file(path)?;
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("removing {}", path.shown()))
        }
        _ => Ok(()),
    }
}

/// A file `lapclone test` keeps (a golden, a pending frame, a failure picture) must be a
/// regular file when it exists: it is never written through a link (which could lead to a
/// scene or an asset), into a FIFO (which would wait) or over a folder, and nothing else is
/// ever removed in its place. Missing is fine.
pub fn check_own_file(path: &Path) -> anyhow::Result<()> {
    let meta = match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.shown())),
        Ok(meta) => meta,
    };
    let what = match meta.file_type() {
        t if t.is_file() => return Ok(()),
        t if t.is_symlink() => "is a symbolic link",
        _ => lapclone::util::not_a_file(path).unwrap_or("is not a regular file"),
    };
    anyhow::bail!(
        "{} {what}: lapclone test reads, writes and removes only regular files there; move it away",
        path.shown()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A range at the top of the numbers is kept, not wrapped into an empty list that
    /// checked nothing and passed.
    #[test]
    fn frame_lists_keep_every_range_they_are_given() {
        assert_eq!(frame_list("3..4,1,3").unwrap(), FrameList(vec![1, 3, 4]));
        let top = u64::MAX - 5;
        let list = frame_list(&format!("{top}..{}", u64::MAX)).unwrap();
        assert_eq!(list.0, (top..=u64::MAX).collect::<Vec<_>>());
        assert!(frame_list("0").is_err());
    }
}
