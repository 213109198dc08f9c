//! `lapclone-bench opencv`: the whole-process budgets of issue 32, measured on the release
//! `lapclone` binary against OpenCV (through `python3` and `cv2`) and ffmpeg. Takes the
//! binary (by default the one beside `lapclone-bench`), the scripts under `benches/` and a
//! work folder; gives per figure the median of per-round ratios beside its target, and per
//! command its wall times and peak resident set, as a table or one JSON document.
//!
//! - `png`: `lapclone render benches/scenes/hd_move.rhai` (1920×1080, 48 frames) to PNG files
//!   ÷ `benches/opencv/hd_move.py` (the same motion with warpAffine, seamlessClone, imwrite).
//! - `mp4`: the same scene to MP4 ÷ to PNG files.
//! - `clone`: `lapclone clone` of a 12.5-megapixel patch into a 6000×5000 target (images from
//!   `benches/make_big_images.py`) ÷ OpenCV's seamlessClone call alone on the same images
//!   (`benches/opencv/clone_big.py` prints it), and the clone process's peak resident set.
//!
//! Commands run in rounds, each command once per round in a fixed order (A, B, A, B, …), so a
//! ratio pairs runs made under the same load; the figure is the median of the rounds' ratios.
//! A figure whose tool is missing (`cv2` not importable, no `ffmpeg` on PATH) is skipped with
//! the reason, not failed.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

use anyhow::Context;

use super::child_run::{self, Invocation, Measured};

/// One of the command's figure groups.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// hd_move to PNG files against the OpenCV loop.
    Png,
    /// hd_move to MP4 against the same scene to PNG files.
    Mp4,
    /// The 6000×5000 clone against seamlessClone, and its peak memory.
    Clone,
}

#[derive(clap::Args, Debug)]
pub struct OpencvBenchArgs {
    /// Measured rounds (each runs every command once); default 5, 3 under --quick.
    #[arg(long)]
    pub runs: Option<usize>,
    /// Three rounds instead of five.
    #[arg(long)]
    pub quick: bool,
    /// Unmeasured rounds first (caches, Python's imports).
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    /// Which figures to measure.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = vec![Case::Png, Case::Mp4, Case::Clone])]
    pub cases: Vec<Case>,
    /// The `lapclone` binary (default: the one beside this program, i.e. target/release/lapclone).
    #[arg(long)]
    pub lapclone: Option<PathBuf>,
    /// The Python interpreter that has cv2 (OpenCV) and numpy.
    #[arg(long, default_value = "python3")]
    pub python: PathBuf,
    /// Folder for outputs and the large test images, kept afterwards (the images are reused
    /// when present); default a temporary folder, removed afterwards.
    #[arg(long)]
    pub work: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Issue 32's budgets: (figure, unit, at most).
pub const TARGETS: [(&str, &str, f64); 4] = [
    (PNG_VS_OPENCV, "×", 0.10),
    (MP4_VS_PNG, "×", 1.5),
    (CLONE_VS_SEAMLESS, "×", 0.08),
    (CLONE_PEAK, "MB", 1000.0),
];
pub const PNG_VS_OPENCV: &str = "png_vs_opencv";
pub const MP4_VS_PNG: &str = "mp4_vs_png";
pub const CLONE_VS_SEAMLESS: &str = "clone_vs_seamless_clone";
/// The clone's peak resident set in MB of 10⁶ bytes, so 1000 is the "1.0 GB".
pub const CLONE_PEAK: &str = "clone_peak_rss_mb";

const SCENE: &str = "benches/scenes/hd_move.rhai";
/// The centre of the 6000×5000 target, where clone_big.py puts the patch too.
const BIG_AT: &str = "3000,2500";

/// One figure against its target: `measured` or, when a tool is missing, `skipped`.
#[derive(serde::Serialize, Debug)]
pub struct Figure {
    pub measured: Option<f64>,
    pub bound: &'static str,
    pub target: f64,
    pub unit: &'static str,
    /// The figure of each round (a ratio, or a peak); `measured` is their median (the peak:
    /// their maximum).
    pub per_round: Vec<f64>,
    pub skipped: Option<String>,
}

/// One command's runs.
#[derive(serde::Serialize, Debug)]
pub struct CommandTimes {
    pub command: String,
    pub wall_s: Vec<f64>,
    pub median_s: f64,
    pub min_s: f64,
    pub max_s: f64,
    /// The largest peak resident set over its runs, MB (10⁶ bytes).
    pub peak_rss_mb: Option<f64>,
}

/// `/proc/loadavg`'s 1, 5 and 15-minute figures (null where there is none).
#[derive(serde::Serialize, Debug)]
pub struct LoadAverage {
    pub before: Option<[f64; 3]>,
    pub after: Option<[f64; 3]>,
}

#[derive(serde::Serialize, Debug)]
pub struct Report {
    pub runs: usize,
    pub warmup: usize,
    pub lapclone: String,
    /// `/proc/loadavg`'s 1, 5 and 15-minute figures before and after (other work on the
    /// machine moves wall times).
    pub load_average: LoadAverage,
    pub warnings: Vec<String>,
    pub figures: BTreeMap<&'static str, Figure>,
    pub commands: BTreeMap<&'static str, CommandTimes>,
}

/// Where things are and how often to run them.
struct Setup {
    root: PathBuf,
    lapclone: PathBuf,
    python: PathBuf,
    work: PathBuf,
    runs: usize,
    warmup: usize,
}

pub fn run(args: OpencvBenchArgs) -> anyhow::Result<()> {
    let runs = args.runs.unwrap_or(if args.quick { 3 } else { 5 });
    if runs == 0 || args.cases.is_empty() {
        return Err(super::UsageError("--runs and --cases must not be empty or 0".into()).into());
    }
    let explicit_binary = args.lapclone.is_some();
    let lapclone = match args.lapclone {
        Some(path) => path,
        None => beside_this_program("lapclone")?,
    };
    if !lapclone.is_file() {
        anyhow::bail!(
            "no lapclone binary at {}: build it with `cargo build --release` (or pass --lapclone)",
            lapclone.display()
        );
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let root = std::fs::canonicalize(&root).unwrap_or(root);
    let mut warnings = Vec::new();
    if !explicit_binary {
        warnings.extend(stale_binary(&lapclone, &root));
    }
    let work = WorkFolder::new(args.work)?;
    let setup = Setup {
        root,
        lapclone: std::fs::canonicalize(&lapclone).unwrap_or(lapclone),
        python: args.python,
        work: work.path.clone(),
        runs,
        warmup: args.warmup,
    };
    let mut report = Report {
        runs,
        warmup: args.warmup,
        lapclone: setup.lapclone.display().to_string(),
        load_average: LoadAverage {
            before: load_average(),
            after: None,
        },
        warnings,
        figures: BTreeMap::new(),
        commands: BTreeMap::new(),
    };
    let cv = child_run::probe(&setup.python, &["-c", "import cv2, numpy"])
        .map_err(|why| format!("OpenCV not available ({why}); install opencv-python"));
    hd_move_figures(&setup, &args.cases, &cv, &mut report)?;
    if args.cases.contains(&Case::Clone) {
        clone_figures(&setup, &cv, &mut report)?;
    }
    report.load_average.after = load_average();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report);
    }
    Ok(())
}

/// `name` in the folder of the running program (target/release for a release build).
pub(crate) fn beside_this_program(name: &str) -> anyhow::Result<PathBuf> {
    let me = std::env::current_exe().context("cannot locate lapclone-bench itself")?;
    let folder = me.parent().context("lapclone-bench has no parent folder")?;
    Ok(folder.join(format!("{name}{}", std::env::consts::EXE_SUFFIX)))
}

/// A warning when a file under `src/` is newer than the binary: the figures would then be
/// of code that is no longer the tree's. (Manifests are left out: cargo may find nothing to
/// rebuild after their change, and the warning would then never go away.)
pub(crate) fn stale_binary(binary: &Path, root: &Path) -> Option<String> {
    let built = std::fs::metadata(binary).and_then(|m| m.modified()).ok()?;
    let mut newest = None;
    newest_file(&root.join("src"), &mut newest);
    let (changed, path) = newest?;
    (changed > built).then(|| {
        format!(
            "{} is older than {}: rebuild it with `cargo build --release` to measure the current code",
            binary.display(),
            path.display()
        )
    })
}

fn newest_file(path: &Path, newest: &mut Option<(std::time::SystemTime, PathBuf)>) {
    let Ok(meta) = std::fs::metadata(path) else {
        return;
    };
    if meta.is_dir() {
        for entry in std::fs::read_dir(path).into_iter().flatten().flatten() {
            newest_file(&entry.path(), newest);
        }
    } else if let Ok(changed) = meta.modified() {
        if newest.as_ref().is_none_or(|(t, _)| changed > *t) {
            *newest = Some((changed, path.to_path_buf()));
        }
    }
}

/// The run's folder: given (kept) or temporary (removed when dropped).
struct WorkFolder {
    path: PathBuf,
    remove: bool,
}

impl WorkFolder {
    fn new(given: Option<PathBuf>) -> anyhow::Result<Self> {
        let (path, remove) = match given {
            Some(path) => (path, false),
            None => (
                std::env::temp_dir().join(format!("lapclone-bench-opencv-{}", std::process::id())),
                true,
            ),
        };
        std::fs::create_dir_all(path.join("logs"))
            .with_context(|| format!("cannot create {}", path.display()))?;
        let path = std::fs::canonicalize(&path)?;
        Ok(Self { path, remove })
    }
}

impl Drop for WorkFolder {
    fn drop(&mut self) {
        if self.remove {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut fields = text.split_whitespace().map(|f| f.parse::<f64>().ok());
    Some([fields.next()??, fields.next()??, fields.next()??])
}

fn invocation(
    setup: &Setup,
    name: &'static str,
    program: &Path,
    args: impl IntoIterator<Item = OsString>,
) -> Invocation {
    Invocation {
        name,
        program: program.to_path_buf(),
        args: args.into_iter().collect(),
        cwd: setup.root.clone(),
    }
}

/// hd_move to PNG files, to MP4, and the OpenCV loop, each writing into the work folder.
fn hd_move_commands(setup: &Setup) -> [Invocation; 3] {
    let work = |name: &str| setup.work.join(name).into_os_string();
    let render = |output: OsString| ["render".into(), SCENE.into(), "-o".into(), output];
    let mut png_args = render(work("hd_move_png")).to_vec();
    png_args.push("--force".into());
    [
        invocation(setup, "lapclone_png", &setup.lapclone, png_args),
        invocation(
            setup,
            "lapclone_mp4",
            &setup.lapclone,
            render(work("hd_move.mp4")),
        ),
        invocation(
            setup,
            "opencv_loop",
            &setup.python,
            ["benches/opencv/hd_move.py".into(), work("hd_move_opencv")],
        ),
    ]
}

/// The PNG and MP4 figures of hd_move: one set of rounds over the commands they need.
fn hd_move_figures(
    setup: &Setup,
    cases: &[Case],
    cv: &Result<(), String>,
    report: &mut Report,
) -> anyhow::Result<()> {
    let want_png = cases.contains(&Case::Png);
    let want_mp4 = cases.contains(&Case::Mp4);
    if !want_png && !want_mp4 {
        return Ok(());
    }
    let ffmpeg = child_run::probe(Path::new("ffmpeg"), &["-hide_banner", "-version"])
        .map_err(|why| format!("ffmpeg not found on PATH ({why}); install it"));
    let [png, video, loop_cv] = hd_move_commands(setup);
    let mut order = vec![png];
    if want_png && cv.is_ok() {
        order.push(loop_cv);
    }
    if want_mp4 && ffmpeg.is_ok() {
        order.push(video);
    }
    // The PNG render alone compares with nothing: no rounds then.
    let runs = if order.len() > 1 {
        rounds(setup, &order)?
    } else {
        BTreeMap::new()
    };
    if want_png {
        let figure = ratio_figure(PNG_VS_OPENCV, cv, &runs, "lapclone_png", "opencv_loop");
        report.figures.insert(PNG_VS_OPENCV, figure);
    }
    if want_mp4 {
        let figure = ratio_figure(MP4_VS_PNG, &ffmpeg, &runs, "lapclone_mp4", "lapclone_png");
        report.figures.insert(MP4_VS_PNG, figure);
    }
    record_commands(&order, &runs, report);
    Ok(())
}

/// Figure `name`: the median of round-by-round wall time `a ÷ b`, or skipped for `tool`'s
/// reason.
fn ratio_figure(
    name: &str,
    tool: &Result<(), String>,
    runs: &BTreeMap<&'static str, Vec<Measured>>,
    a: &str,
    b: &str,
) -> Figure {
    match (tool, runs.get(a), runs.get(b)) {
        (Err(why), ..) => skipped(name, why),
        (Ok(()), Some(a), Some(b)) => measured(name, ratios(&walls(a), &walls(b)), median),
        _ => skipped(name, "not run"),
    }
}

/// `lapclone clone` of the large images, and clone_big.py on the same folder.
fn clone_commands(setup: &Setup, big: &Path) -> [Invocation; 2] {
    let file = |name: &str| big.join(name).into_os_string();
    let args = [
        "clone".into(),
        "--source".into(),
        file("source.png"),
        "--mask".into(),
        file("mask.png"),
        "--target".into(),
        file("target.png"),
        "--at".into(),
        BIG_AT.into(),
        "-o".into(),
        file("lapclone_out.png"),
    ];
    let script = [
        "benches/opencv/clone_big.py".into(),
        big.as_os_str().to_owned(),
    ];
    [
        invocation(setup, "lapclone_clone", &setup.lapclone, args),
        invocation(setup, "opencv_clone", &setup.python, script),
    ]
}

/// The large clone against seamlessClone, and its peak memory.
fn clone_figures(
    setup: &Setup,
    cv: &Result<(), String>,
    report: &mut Report,
) -> anyhow::Result<()> {
    if let Err(why) = cv {
        for name in [CLONE_VS_SEAMLESS, CLONE_PEAK] {
            report.figures.insert(name, skipped(name, why));
        }
        return Ok(());
    }
    let order = clone_commands(setup, &big_images(setup)?);
    let runs = rounds(setup, &order)?;
    let clones = &runs["lapclone_clone"];
    let call = runs["opencv_clone"]
        .iter()
        .map(|m| seamless_clone_seconds(&m.stdout))
        .collect::<anyhow::Result<Vec<f64>>>()?;
    let ratio = measured(CLONE_VS_SEAMLESS, ratios(&walls(clones), &call), median);
    report.figures.insert(CLONE_VS_SEAMLESS, ratio);
    report.figures.insert(CLONE_PEAK, peak_figure(clones));
    record_commands(&order, &runs, report);
    let what = "cv2.seamlessClone(…) alone, as clone_big.py prints it";
    report
        .commands
        .insert("seamless_clone_call", times(what.into(), call, None));
    Ok(())
}

/// The largest peak resident set of `runs`, MB.
fn peak_figure(runs: &[Measured]) -> Figure {
    let peaks: Vec<f64> = runs
        .iter()
        .filter_map(|m| m.peak_rss_bytes)
        .map(|bytes| bytes as f64 / 1e6)
        .collect();
    if peaks.is_empty() {
        return skipped(CLONE_PEAK, "this platform reports no peak memory");
    }
    measured(CLONE_PEAK, peaks, |v| {
        v.iter().copied().fold(f64::MIN, f64::max)
    })
}

/// The 6000×5000 target, its source and mask in `work/big`, made by make_big_images.py
/// unless all three are already there.
fn big_images(setup: &Setup) -> anyhow::Result<PathBuf> {
    let big = setup.work.join("big");
    if ["target.png", "source.png", "mask.png"]
        .iter()
        .all(|f| big.join(f).is_file())
    {
        return Ok(big);
    }
    eprintln!(
        "lapclone-bench opencv: writing the 6000×5000 test images into {}",
        big.display()
    );
    let script = [
        "benches/make_big_images.py".into(),
        big.clone().into_os_string(),
    ];
    let make = invocation(setup, "make_big_images", &setup.python, script);
    child_run::run(&make, &setup.work.join("logs"))?;
    Ok(big)
}

/// Runs `warmup` unmeasured rounds, then `runs` measured ones, each command once per round
/// in `order`; gives each command's measured runs by name.
fn rounds(
    setup: &Setup,
    order: &[Invocation],
) -> anyhow::Result<BTreeMap<&'static str, Vec<Measured>>> {
    let logs = setup.work.join("logs");
    let mut measured: BTreeMap<&'static str, Vec<Measured>> = BTreeMap::new();
    for round in 0..setup.warmup + setup.runs {
        let label = if round < setup.warmup {
            "warm-up".to_string()
        } else {
            format!("round {}/{}", round - setup.warmup + 1, setup.runs)
        };
        let names: Vec<&str> = order.iter().map(|i| i.name).collect();
        eprintln!("lapclone-bench opencv: {label}: {}", names.join(", "));
        for invocation in order {
            let run = child_run::run(invocation, &logs)?;
            if round >= setup.warmup {
                measured.entry(invocation.name).or_default().push(run);
            }
        }
    }
    Ok(measured)
}

fn walls(runs: &[Measured]) -> Vec<f64> {
    runs.iter().map(|m| m.wall_s).collect()
}

/// Round-by-round `a / b`.
fn ratios(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(a, b)| a / b).collect()
}

/// The middle value (the mean of the two middle ones for an even count); NaN when empty.
pub fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => sorted[n / 2],
        _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
    }
}

/// The seconds in clone_big.py's `seamlessClone: 16.743 s` line.
pub fn seamless_clone_seconds(stdout: &str) -> anyhow::Result<f64> {
    stdout
        .lines()
        .find_map(|line| line.strip_prefix("seamlessClone:"))
        .and_then(|rest| rest.trim().trim_end_matches('s').trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
        .with_context(|| {
            format!("clone_big.py printed no `seamlessClone: <seconds> s` line: {stdout:?}")
        })
}

/// The most figure `name` (a key of the JSON's `figures`) may measure, if it is one.
pub fn budget(name: &str) -> Option<f64> {
    TARGETS
        .iter()
        .find(|(n, ..)| *n == name)
        .map(|&(.., limit)| limit)
}

fn target_of(name: &str) -> (&'static str, f64) {
    TARGETS
        .iter()
        .find(|(n, ..)| *n == name)
        .map(|&(_, unit, limit)| (unit, limit))
        // invariant: every figure name used in this module is in TARGETS.
        .expect("a figure of TARGETS")
}

fn measured(name: &str, per_round: Vec<f64>, summary: impl Fn(&[f64]) -> f64) -> Figure {
    let (unit, target) = target_of(name);
    Figure {
        measured: Some(summary(&per_round)),
        bound: "at_most",
        target,
        unit,
        per_round,
        skipped: None,
    }
}

fn skipped(name: &str, why: &str) -> Figure {
    let (unit, target) = target_of(name);
    eprintln!("lapclone-bench opencv: {name} skipped: {why}");
    Figure {
        measured: None,
        bound: "at_most",
        target,
        unit,
        per_round: Vec::new(),
        skipped: Some(why.to_string()),
    }
}

fn times(command: String, wall_s: Vec<f64>, peak_rss_mb: Option<f64>) -> CommandTimes {
    let min_s = wall_s.iter().copied().fold(f64::INFINITY, f64::min);
    let max_s = wall_s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    CommandTimes {
        command,
        median_s: median(&wall_s),
        min_s,
        max_s,
        wall_s,
        peak_rss_mb,
    }
}

fn record_commands(
    order: &[Invocation],
    runs: &BTreeMap<&'static str, Vec<Measured>>,
    report: &mut Report,
) {
    for invocation in order {
        let Some(list) = runs.get(invocation.name) else {
            continue;
        };
        let peak = list
            .iter()
            .filter_map(|m| m.peak_rss_bytes)
            .max()
            .map(|bytes| bytes as f64 / 1e6);
        report.commands.insert(
            invocation.name,
            times(invocation.display(), walls(list), peak),
        );
    }
}

fn print_table(report: &Report) {
    println!(
        "opencv bench: whole processes, {} rounds after {} warm-up, {}",
        report.runs, report.warmup, report.lapclone
    );
    let load = &report.load_average;
    for (when, figures) in [("before", load.before), ("after", load.after)] {
        if let Some([one, five, fifteen]) = figures {
            println!("  load average {when}: {one:.2} {five:.2} {fifteen:.2}");
        }
    }
    for warning in &report.warnings {
        println!("  warning: {warning}");
    }
    println!(
        "{:<24} {:>10} {:>10} {:>12}  per round",
        "command", "median s", "min s", "peak MB"
    );
    for (name, c) in &report.commands {
        let peak = c
            .peak_rss_mb
            .map_or_else(|| "—".into(), |mb| format!("{mb:.0}"));
        println!(
            "{name:<24} {:>10.3} {:>10.3} {peak:>12}  {}",
            c.median_s,
            c.min_s,
            list(&c.wall_s)
        );
    }
    println!("{:<24} {:>10} {:>10}  ok", "figure", "measured", "target");
    for (name, f) in &report.figures {
        let with_unit = |value: f64| match f.unit {
            "MB" => format!("{value:.0} MB"),
            unit => format!("{value:.3}{unit}"),
        };
        match (f.measured, &f.skipped) {
            (Some(value), _) => println!(
                "{name:<24} {:>10} {:>10}  {}   ({} of rounds: {})",
                with_unit(value),
                format!("≤ {}", with_unit(f.target)),
                if value <= f.target { "✓" } else { "✗" },
                if f.unit == "MB" { "largest" } else { "median" },
                list(&f.per_round)
            ),
            (None, why) => println!("{name:<24} skipped: {}", why.as_deref().unwrap_or("")),
        }
    }
}

fn list(values: &[f64]) -> String {
    values
        .iter()
        .map(|v| format!("{v:.3}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::{median, seamless_clone_seconds};

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn reads_the_seamless_clone_line() {
        let out = "loading\nseamlessClone: 16.743 s\n";
        assert_eq!(seamless_clone_seconds(out).unwrap(), 16.743);
        assert!(seamless_clone_seconds("seamlessClone: fast\n").is_err());
        assert!(seamless_clone_seconds("").is_err());
    }
}
