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
//! `target`, `holds`). Exit 2 on a bad argument, 1 when a bench command fails. Run as a test
//! (`cargo test --benches`, without cargo bench's `--bench` flag) it checks nothing.

use std::path::Path;
use std::process::{Command, ExitCode};

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
    let checks = match measure(&settings) {
        Ok(checks) => checks,
        Err(message) => {
            eprintln!("targets: {message}");
            return ExitCode::from(1);
        }
    };
    let missed = checks.iter().filter(|c| !c.bound.holds(c.measured)).count();
    if settings.json {
        println!("{}", checks_json(&checks));
    } else {
        print_table(&checks);
        println!(
            "\n{} of {} targets hold{}",
            checks.len() - missed,
            checks.len(),
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

fn measure(settings: &Settings) -> Result<Vec<Check>, String> {
    let mut checks = Vec::new();
    mesh_checks(settings, &mut checks)?;
    factor_checks(settings, &mut checks)?;
    clone_checks(settings, &mut checks)?;
    render_checks(settings, &mut checks)?;
    paper_checks(&mut checks)?;
    Ok(checks)
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

fn checks_json(checks: &[Check]) -> Value {
    let rows = checks.iter().map(|check| {
        let (bound, target) = match check.bound {
            Bound::AtMost(limit) => ("at_most", limit),
            Bound::AtLeast(limit) => ("at_least", limit),
        };
        serde_json::json!({
            "issue": check.issue,
            "figure": check.what,
            "measured": check.measured,
            "bound": bound,
            "target": target,
            "holds": check.bound.holds(check.measured),
        })
    });
    Value::Array(rows.collect())
}

fn print_table(checks: &[Check]) {
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
