//! `cargo bench`: every performance and quality target the issues set, in one table. Takes
//! the release binary (`lapclone-bench … --json`, the same measurements the closing notes
//! quote) and gives, per target, the issue, the figure, what was measured, the target and
//! whether it holds. The measuring code lives in `lapclone-bench`'s commands; this file only
//! runs them and compares, so the two can never disagree.
//!
//! Arguments after `--`: `--quick` (fewer repeats, and no 495k-vertex factor), `--strict`
//! (exit 1 when a target is missed; by default a miss is reported, not failed, since wall-clock
//! figures on a shared machine move with its load) and `--json` (one JSON array on stdout
//! instead of the table: `issue`, `figure`, `measured`, `bound` ("at_most" or "at_least"),
//! `target`, `holds`, and `skipped`: why a figure was not measured, with `measured` and `holds`
//! null). Exit 2 on a bad argument, 1 when a bench command fails. Run as a test
//! (`cargo test --benches`, without cargo bench's `--bench` flag) it checks nothing.
//!
//! The whole-process figures (`lapclone-bench opencv`) time the `lapclone` binary beside
//! `lapclone-bench`, which `cargo bench -p lapclone-bench` does not build: run `cargo build
//! --release` first. They are skipped, with the reason, where python3 cannot import cv2 or
//! ffmpeg is missing.

use std::path::Path;
use std::process::{Command, ExitCode};

use lapclone_bench::commands::bench_opencv::{
    budget, CLONE_PEAK, CLONE_VS_SEAMLESS, MP4_VS_PNG, PNG_VS_OPENCV,
};
use serde_json::Value;

/// Which side of the target a figure must stay on.
#[derive(Clone, Copy)]
enum Bound {
    AtMost(f64),
    AtLeast(f64),
}

impl Bound {
    fn holds(self, measured: f64) -> bool {
        match self {
            Bound::AtMost(limit) => measured <= limit,
            Bound::AtLeast(limit) => measured >= limit,
        }
    }

    fn describe(self) -> String {
        match self {
            Bound::AtMost(limit) => format!("≤ {}", figure(limit)),
            Bound::AtLeast(limit) => format!("≥ {}", figure(limit)),
        }
    }
}

/// One measured figure beside its target.
struct Check {
    issue: u32,
    what: String,
    measured: f64,
    bound: Bound,
}

/// A figure that could not be measured here (a missing tool), and why.
struct Skipped {
    issue: u32,
    what: String,
    bound: Bound,
    reason: String,
}

/// The run's settings, from the command line.
struct Settings {
    quick: bool,
    strict: bool,
    json: bool,
    /// `cargo bench` passes `--bench`; `cargo test --benches` (or `--all-targets`) does not,
    /// and builds the binary without full optimisation, so timing there would mean nothing.
    benching: bool,
}

impl Settings {
    /// `quick` under `--quick`, `full` otherwise.
    fn pick<T>(&self, quick: T, full: T) -> T {
        if self.quick {
            quick
        } else {
            full
        }
    }
}

/// CHOLMOD's figures from issue #3: vertices, numeric factor, 3-RHS solve, one switch (ms).
const CHOLMOD: [(usize, f64, f64, f64); 3] = [
    (2_034, 1.16, 0.048, 0.030),
    (52_054, 102.0, 3.3, 0.57),
    (495_037, 4_450.0, 278.0, 16.5),
];

fn main() -> ExitCode {
    let settings = match parse_arguments(std::env::args().skip(1)) {
        Ok(settings) => settings,
        Err(message) => {
            eprintln!("targets: {message}; arguments: [--quick] [--strict] [--json]");
            return ExitCode::from(2);
        }
    };
    if !settings.benching {
        println!("targets: run by `cargo bench` (release build); nothing to check in a test run");
        return ExitCode::SUCCESS;
    }
    let (checks, skipped) = match measure(&settings) {
        Ok(measured) => measured,
        Err(message) => {
            eprintln!("targets: {message}");
            return ExitCode::from(1);
        }
    };
    let missed = checks.iter().filter(|c| !c.bound.holds(c.measured)).count();
    if settings.json {
        println!("{}", checks_json(&checks, &skipped));
    } else {
        print_table(&checks, &skipped);
        println!(
            "\n{} of {} targets hold{}{}",
            checks.len() - missed,
            checks.len(),
            if skipped.is_empty() {
                String::new()
            } else {
                format!(", {} skipped", skipped.len())
            },
            if settings.quick { " (--quick)" } else { "" }
        );
    }
    if settings.strict && missed > 0 {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}

fn parse_arguments(arguments: impl Iterator<Item = String>) -> Result<Settings, String> {
    let mut settings = Settings {
        quick: false,
        strict: false,
        json: false,
        benching: false,
    };
    for argument in arguments {
        match argument.as_str() {
            "--quick" => settings.quick = true,
            "--strict" => settings.strict = true,
            "--json" => settings.json = true,
            "--bench" => settings.benching = true,
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(settings)
}

fn measure(settings: &Settings) -> Result<(Vec<Check>, Vec<Skipped>), String> {
    let mut checks = Vec::new();
    let mut skipped = Vec::new();
    mesh_checks(settings, &mut checks)?;
    factor_checks(settings, &mut checks)?;
    clone_checks(settings, &mut checks)?;
    render_checks(settings, &mut checks)?;
    paper_checks(&mut checks)?;
    whole_process_checks(settings, &mut checks, &mut skipped)?;
    track_checks(settings, &mut checks, &mut skipped)?;
    follow_checks(settings, &mut checks, &mut skipped)?;
    view_checks(settings, &mut checks, &mut skipped)?;
    browser_checks(settings, &mut checks, &mut skipped)?;
    Ok((checks, skipped))
}

/// Issue #2: the 770×743 spiral meshes in ≤ 20 ms at the defaults.
fn mesh_checks(settings: &Settings, checks: &mut Vec<Check>) -> Result<(), String> {
    let repeat = settings.pick("3", "9");
    let rows = run_bench(&["mesh", "--filter", "spiral-770x743", "--repeat", repeat])?;
    let row = rows
        .as_array()
        .and_then(|rows| rows.first())
        .ok_or("bench mesh gave no spiral-770x743 row")?;
    checks.push(Check {
        issue: 2,
        what: format!("mesh the 770×743 spiral, best of {repeat} (ms)"),
        measured: number(row, "/best_ms")?,
        bound: Bound::AtMost(20.0),
    });
    Ok(())
}

/// Issue #3: numeric factor, 3-RHS solve and one rank-1 switch at or below CHOLMOD.
fn factor_checks(settings: &Settings, checks: &mut Vec<Check>) -> Result<(), String> {
    let cases = settings.pick(&CHOLMOD[..2], &CHOLMOD[..]);
    for &(vertices, factor_ms, solve_ms, switch_ms) in cases {
        let row = run_bench(&["factor", "--sizes", &vertices.to_string()])?;
        let n = number(&row, "/n")?;
        for (key, label, limit) in [
            ("factor_ms", "numeric factor", factor_ms),
            ("solve3_ms", "3-RHS solve", solve_ms),
            ("update_ms", "one rank-1 switch", switch_ms),
        ] {
            checks.push(Check {
                issue: 3,
                what: format!("{label}, {n} vertices (ms)"),
                measured: number(&row, &format!("/{key}"))?,
                bound: Bound::AtMost(limit),
            });
        }
    }
    Ok(())
}

/// Issues #4 and #5: the spiral's first clone and re-clone, and the deform frame.
fn clone_checks(settings: &Settings, checks: &mut Vec<Check>) -> Result<(), String> {
    let (repeats, frames) = settings.pick(("5", "30"), ("20", "200"));
    let report = run_bench(&["clone", "--repeats", repeats, "--frames", frames])?;
    let spirals = report
        .pointer("/spiral")
        .and_then(Value::as_array)
        .ok_or("bench clone gave no spiral rows")?;
    for row in spirals {
        let size = number(row, "/size")?;
        for (key, target_key, label) in [
            ("first_ms", "first_target_ms", "first clone, best"),
            ("reclone_ms", "reclone_target_ms", "re-clone, best"),
        ] {
            checks.push(Check {
                issue: 4,
                what: format!("spiral {size}² {label} (ms)"),
                measured: number(row, &format!("/{key}"))?,
                bound: Bound::AtMost(number(row, &format!("/{target_key}"))?),
            });
        }
    }
    checks.push(Check {
        issue: 5,
        what: format!("deform frame, 2,500 vertices in 1920×1080, median of {frames} (ms)"),
        measured: number(&report, "/deform/frame_median_ms")?,
        bound: Bound::AtMost(number(&report, "/deform/frame_target_ms")?),
    });
    Ok(())
}

/// Issue #6: a two-patch 1920×1080 scene's frame, and parallel PNG encoding.
fn render_checks(settings: &Settings, checks: &mut Vec<Check>) -> Result<(), String> {
    let (frames, encode) = settings.pick(("30", "8"), ("120", "24"));
    let report = run_bench(&["render", "--frames", frames, "--encode-frames", encode])?;
    checks.push(Check {
        issue: 6,
        what: format!("scene frame compute, median of {frames} (ms)"),
        measured: number(&report, "/frame_ms_median")?,
        bound: Bound::AtMost(4.0),
    });
    checks.push(Check {
        issue: 6,
        what: "PNG encoding, 2 jobs against 1 (speed-up ×)".into(),
        measured: number(&report, "/encode_speedup")?,
        bound: Bound::AtLeast(1.7),
    });
    Ok(())
}

/// Issue #40: the live view's drag at 1920×1080, pointer message in → changed pixels out,
/// through the release `lapclone repl --view` (skipped when that binary is not built).
fn view_checks(
    settings: &Settings,
    checks: &mut Vec<Check>,
    skipped: &mut Vec<Skipped>,
) -> Result<(), String> {
    let steps = settings.pick("50", "200");
    let lapclone = Path::new(env!("CARGO_BIN_EXE_lapclone-bench"))
        .with_file_name(format!("lapclone{}", std::env::consts::EXE_SUFFIX));
    let report = if lapclone.is_file() {
        Some(run_bench(&["view", "--steps", steps])?)
    } else {
        None
    };
    for (index, scene) in ["cat", "horse folding"].iter().enumerate() {
        for (key, label, limit) in [
            ("median_ms", "median", 8.0),
            ("p95_ms", "95th percentile", 16.0),
        ] {
            let what = format!("live view drag, {scene}, 1920×1080, {label} of {steps} steps (ms)");
            let bound = Bound::AtMost(limit);
            match &report {
                Some(report) => checks.push(Check {
                    issue: 40,
                    what,
                    measured: number(report, &format!("/drags/{index}/{key}"))?,
                    bound,
                }),
                None => skipped.push(Skipped {
                    issue: 40,
                    what,
                    bound,
                    reason: format!(
                        "no {}: run `cargo build --release` first",
                        lapclone.display()
                    ),
                }),
            }
        }
    }
    Ok(())
}

/// Issue #40: the same drags in headless chromium, pointer events at 60 Hz: pointer event →
/// pixels painted (the page's own timing) and previews painted per second (skipped without
/// chromium or the release `lapclone`).
fn browser_checks(
    settings: &Settings,
    checks: &mut Vec<Check>,
    skipped: &mut Vec<Skipped>,
) -> Result<(), String> {
    let steps = settings.pick("50", "200");
    let lapclone = Path::new(env!("CARGO_BIN_EXE_lapclone-bench"))
        .with_file_name(format!("lapclone{}", std::env::consts::EXE_SUFFIX));
    let report = if lapclone.is_file() {
        run_bench(&["browser", "--steps", steps])?
    } else {
        let reason = format!(
            "no {}: run `cargo build --release` first",
            lapclone.display()
        );
        serde_json::json!({ "skipped": reason })
    };
    let reason = report.pointer("/skipped").and_then(Value::as_str);
    for (index, scene) in ["cat", "horse folding"].iter().enumerate() {
        for (key, label, bound) in [
            ("median_ms", "median (ms)", Bound::AtMost(16.0)),
            ("p95_ms", "p95 (ms)", Bound::AtMost(33.0)),
            ("updates_per_s", "painted/s", Bound::AtLeast(50.0)),
        ] {
            let what = format!("chromium drag, {scene}, {steps} moves at 60 Hz, {label}");
            match reason {
                Some(reason) => skipped.push(Skipped {
                    issue: 40,
                    what,
                    bound,
                    reason: reason.to_string(),
                }),
                None => checks.push(Check {
                    issue: 40,
                    what,
                    measured: number(&report, &format!("/drags/{index}/{key}"))?,
                    bound,
                }),
            }
        }
    }
    Ok(())
}

/// Issue #8: the spiral's PSNR against the pixel-grid reference at the default density.
fn paper_checks(checks: &mut Vec<Check>) -> Result<(), String> {
    let report = run_bench(&[
        "paper",
        "--filter",
        "spiral",
        "--repeat",
        "1",
        "--no-figure",
    ])?;
    let model = report
        .pointer("/models/0")
        .ok_or("bench paper gave no spiral model")?;
    for (key, label, limit) in [
        ("/combinatorial/psnr_db", "combinatorial", 45.0),
        ("/cotangent/psnr_db", "cotangent", 52.0),
    ] {
        checks.push(Check {
            issue: 8,
            what: format!("spiral PSNR, {label}, default density (dB)"),
            measured: number(model, key)?,
            bound: Bound::AtLeast(limit),
        });
    }
    checks.push(Check {
        issue: 8,
        what: "spiral uncovered mask pixels".into(),
        measured: number(model, "/uncovered")?,
        bound: Bound::AtMost(0.0),
    });
    Ok(())
}

/// Issue #32: whole processes of the release `lapclone` binary against OpenCV and ffmpeg.
/// The budgets are the command's own ([`budget`]), so the two cannot disagree.
fn whole_process_checks(
    settings: &Settings,
    checks: &mut Vec<Check>,
    skipped: &mut Vec<Skipped>,
) -> Result<(), String> {
    let runs = settings.pick("3", "5");
    let lapclone = Path::new(env!("CARGO_BIN_EXE_lapclone-bench"))
        .with_file_name(format!("lapclone{}", std::env::consts::EXE_SUFFIX));
    let report = if lapclone.is_file() {
        run_bench(&["opencv", "--runs", runs])?
    } else {
        let reason = format!(
            "no {}: run `cargo build --release` first",
            lapclone.display()
        );
        serde_json::json!({ "missing": reason })
    };
    for warning in report
        .pointer("/warnings")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
    {
        eprintln!("targets: warning: {warning}");
    }
    for (key, what) in [
        (
            PNG_VS_OPENCV,
            format!("hd_move 1920×1080×48 to PNG ÷ OpenCV loop, median of {runs} (×)"),
        ),
        (
            MP4_VS_PNG,
            format!("hd_move to MP4 ÷ to PNG files, median of {runs} (×)"),
        ),
        (
            CLONE_VS_SEAMLESS,
            format!("6000×5000 clone ÷ seamlessClone call, median of {runs} (×)"),
        ),
        (
            CLONE_PEAK,
            format!("6000×5000 clone peak memory, max of {runs} (MB, 10⁶ B)"),
        ),
    ] {
        let bound =
            Bound::AtMost(budget(key).ok_or_else(|| format!("bench opencv has no budget {key}"))?);
        match whole_process_figure(&report, key)? {
            Ok(measured) => checks.push(Check {
                issue: 32,
                what,
                measured,
                bound,
            }),
            Err(reason) => skipped.push(Skipped {
                issue: 32,
                what,
                bound,
                reason,
            }),
        }
    }
    Ok(())
}

/// Issue #41: one point through 1920×1080 PNG footage against decoding alone and an OpenCV
/// calcOpticalFlowPyrLK loop, and the tracked path's error beside OpenCV's (skipped without
/// cv2).
fn track_checks(
    settings: &Settings,
    checks: &mut Vec<Check>,
    skipped: &mut Vec<Skipped>,
) -> Result<(), String> {
    let (runs, frames) = settings.pick(("1", "60"), ("3", "240"));
    let report = run_bench(&["track", "--runs", runs, "--frames", frames])?;
    checks.push(Check {
        issue: 41,
        what: format!("track 1 point through {frames} 1920×1080 PNG ÷ decoding them (×)"),
        measured: number(&report, "/track_over_decode")?,
        bound: Bound::AtMost(1.2),
    });
    let opencv_missing = report
        .pointer("/opencv_skipped")
        .and_then(Value::as_str)
        .map(str::to_string);
    let mut figures = vec![(
        format!("track {frames} 1920×1080 PNG ÷ OpenCV imread + calcOpticalFlowPyrLK loop (×)"),
        report.pointer("/track_over_opencv").and_then(Value::as_f64),
        0.5,
    )];
    for motion in ["translation", "similarity"] {
        let ours = number(&report, &format!("/accuracy/{motion}/lapclone_rms_px"))?;
        let theirs = report
            .pointer(&format!("/accuracy/{motion}/opencv_rms_px"))
            .and_then(Value::as_f64);
        figures.push((
            format!("{motion} track RMS error ÷ calcOpticalFlowPyrLK's (×)"),
            theirs.map(|t| ours / t),
            1.0,
        ));
    }
    for (what, measured, limit) in figures {
        let bound = Bound::AtMost(limit);
        match (measured, &opencv_missing) {
            (Some(measured), _) => checks.push(Check {
                issue: 41,
                what,
                measured,
                bound,
            }),
            (None, reason) => skipped.push(Skipped {
                issue: 41,
                what,
                bound,
                reason: reason.clone().unwrap_or_else(|| "no OpenCV figure".into()),
            }),
        }
    }
    Ok(())
}

/// Issue #41: a 1920×1080 scene following a track against the same scene with the keys
/// written out, whole `lapclone render` processes (skipped when that binary is not built).
fn follow_checks(
    settings: &Settings,
    checks: &mut Vec<Check>,
    skipped: &mut Vec<Skipped>,
) -> Result<(), String> {
    let (runs, frames) = settings.pick(("3", "48"), ("5", "96"));
    let what = format!(
        "render following a track ÷ keys written out, {frames} frames, median of {runs} (×)"
    );
    let bound = Bound::AtMost(1.0);
    let lapclone = Path::new(env!("CARGO_BIN_EXE_lapclone-bench"))
        .with_file_name(format!("lapclone{}", std::env::consts::EXE_SUFFIX));
    if !lapclone.is_file() {
        skipped.push(Skipped {
            issue: 41,
            what,
            bound,
            reason: format!(
                "no {}: run `cargo build --release` first",
                lapclone.display()
            ),
        });
        return Ok(());
    }
    let report = run_bench(&["follow", "--runs", runs, "--frames", frames])?;
    if report.pointer("/identical_frames").and_then(Value::as_bool) != Some(true) {
        return Err(
            "bench follow: the followed scene's frames differ from the written-out keys'".into(),
        );
    }
    checks.push(Check {
        issue: 41,
        what,
        measured: number(&report, "/follow_over_keys")?,
        bound,
    });
    Ok(())
}

/// Figure `key` of `lapclone-bench opencv`'s report: measured, or why it was skipped (the
/// report's own reason, or its `missing` when the command could not run).
fn whole_process_figure(report: &Value, key: &str) -> Result<Result<f64, String>, String> {
    if let Some(reason) = report.pointer("/missing").and_then(Value::as_str) {
        return Ok(Err(reason.to_string()));
    }
    let figure = report
        .pointer(&format!("/figures/{key}"))
        .ok_or_else(|| format!("bench opencv gave no figure {key}"))?;
    match figure.pointer("/skipped").and_then(Value::as_str) {
        Some(reason) => Ok(Err(reason.to_string())),
        None => number(figure, "/measured").map(Ok),
    }
}

/// Runs `lapclone-bench <arguments> --json` from the repository root (where `assets/` is)
/// and parses its stdout.
fn run_bench(arguments: &[&str]) -> Result<Value, String> {
    let binary = env!("CARGO_BIN_EXE_lapclone-bench");
    eprintln!("running lapclone-bench {} --json", arguments.join(" "));
    let output = Command::new(binary)
        .args(arguments)
        .arg("--json")
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .map_err(|e| format!("cannot run {binary}: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "`lapclone-bench {}` failed ({}): {}",
            arguments.join(" "),
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        ));
    }
    serde_json::from_slice(&output.stdout).map_err(|e| {
        format!(
            "`lapclone-bench {}` gave bad JSON: {e}",
            arguments.join(" ")
        )
    })
}

fn number(value: &Value, pointer: &str) -> Result<f64, String> {
    value
        .pointer(pointer)
        .and_then(Value::as_f64)
        .ok_or_else(|| format!("no number at {pointer} in {value}"))
}

fn checks_json(checks: &[Check], skipped: &[Skipped]) -> Value {
    let rows = checks.iter().map(|check| {
        let (bound, target) = bound_json(check.bound);
        serde_json::json!({
            "issue": check.issue,
            "figure": check.what,
            "measured": check.measured,
            "bound": bound,
            "target": target,
            "holds": check.bound.holds(check.measured),
            "skipped": null,
        })
    });
    let skipped_rows = skipped.iter().map(|skip| {
        let (bound, target) = bound_json(skip.bound);
        serde_json::json!({
            "issue": skip.issue,
            "figure": skip.what,
            "measured": null,
            "bound": bound,
            "target": target,
            "holds": null,
            "skipped": skip.reason,
        })
    });
    Value::Array(rows.chain(skipped_rows).collect())
}

fn bound_json(bound: Bound) -> (&'static str, f64) {
    match bound {
        Bound::AtMost(limit) => ("at_most", limit),
        Bound::AtLeast(limit) => ("at_least", limit),
    }
}

fn print_table(checks: &[Check], skipped: &[Skipped]) {
    println!(
        "{:<6} {:<62} {:>10} {:>10}  ok",
        "issue", "figure", "measured", "target"
    );
    for check in checks {
        println!(
            "#{:<5} {:<62} {:>10} {:>10}  {}",
            check.issue,
            check.what,
            figure(check.measured),
            check.bound.describe(),
            if check.bound.holds(check.measured) {
                "✓"
            } else {
                "✗"
            }
        );
    }
    for skip in skipped {
        println!(
            "#{:<5} {:<62} {:>10} {:>10}  skipped: {}",
            skip.issue,
            skip.what,
            "—",
            skip.bound.describe(),
            skip.reason
        );
    }
}

/// Four significant digits, enough for every figure here.
fn figure(value: f64) -> String {
    if value == 0.0 || value.abs() >= 1000.0 {
        format!("{value:.0}")
    } else {
        let decimals = (3 - value.abs().log10().floor() as i32).max(0) as usize;
        format!("{value:.decimals$}")
    }
}
