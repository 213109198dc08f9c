//! `lapclone-bench opencv`'s arguments, its JSON shape and its skips, with a stand-in for the
//! `lapclone` binary (`/bin/true`, `/bin/false`) and a Python that does not exist, so nothing
//! heavy runs. Its figures themselves are measured by `cargo bench`, never asserted here.

use std::path::Path;
use std::process::{Command, Output};

fn bench_opencv(extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lapclone-bench"))
        .arg("opencv")
        .args(extra)
        .output()
        .expect("the binary runs")
}

/// Whether `ffmpeg -version` runs (the MP4 figure needs it).
fn ffmpeg_present() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// A program that exists on this machine, or `None` (the test then says it skipped).
fn stand_in(path: &str) -> Option<&str> {
    if Path::new(path).is_file() {
        Some(path)
    } else {
        eprintln!("skipped: no {path} to stand in for lapclone");
        None
    }
}

#[test]
fn zero_runs_and_unknown_cases_are_usage_errors() {
    assert_eq!(bench_opencv(&["--runs", "0"]).status.code(), Some(2));
    assert_eq!(bench_opencv(&["--cases", "gif"]).status.code(), Some(2));
}

#[test]
fn a_missing_binary_is_a_failure_that_says_how_to_build_it() {
    let output = bench_opencv(&["--lapclone", "/nonexistent/lapclone"]);
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("no lapclone binary at /nonexistent/lapclone"),
        "{stderr}"
    );
    assert!(stderr.contains("cargo build --release"), "{stderr}");
}

#[test]
fn without_opencv_its_figures_are_skipped_and_the_json_has_every_key() {
    let Some(fake) = stand_in("/bin/true") else {
        return;
    };
    let output = bench_opencv(&[
        "--lapclone",
        fake,
        "--python",
        "/nonexistent/python3",
        "--runs",
        "2",
        "--warmup",
        "0",
        "--json",
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(json["runs"], 2);
    assert!(json["load_average"].get("before").is_some());
    assert!(json["warnings"].as_array().unwrap().is_empty(), "{json}");
    for (key, target) in [
        ("png_vs_opencv", 0.10),
        ("mp4_vs_png", 1.5),
        ("clone_vs_seamless_clone", 0.08),
        ("clone_peak_rss_mb", 1000.0),
    ] {
        let figure = &json["figures"][key];
        assert_eq!(figure["bound"], "at_most", "{key}");
        assert_eq!(figure["target"].as_f64(), Some(target), "{key}");
    }
    for key in [
        "png_vs_opencv",
        "clone_vs_seamless_clone",
        "clone_peak_rss_mb",
    ] {
        let figure = &json["figures"][key];
        assert!(figure["measured"].is_null(), "{key}: {figure}");
        let reason = figure["skipped"].as_str().unwrap();
        assert!(reason.contains("OpenCV not available"), "{key}: {reason}");
    }
    let mp4 = &json["figures"]["mp4_vs_png"];
    if ffmpeg_present() {
        assert!(mp4["skipped"].is_null(), "{mp4}");
        assert_eq!(mp4["per_round"].as_array().unwrap().len(), 2);
        assert!(mp4["measured"].as_f64().unwrap() > 0.0, "{mp4}");
        for name in ["lapclone_png", "lapclone_mp4"] {
            let command = &json["commands"][name];
            assert_eq!(command["wall_s"].as_array().unwrap().len(), 2, "{name}");
            for key in ["command", "median_s", "min_s", "max_s", "peak_rss_mb"] {
                assert!(command.get(key).is_some(), "commands.{name}.{key}");
            }
            assert!(command["peak_rss_mb"].as_f64().unwrap() > 0.0, "{command}");
        }
    } else {
        eprintln!("ffmpeg not on PATH: checking the MP4 figure's skip instead");
        assert!(mp4["skipped"].as_str().unwrap().contains("ffmpeg"), "{mp4}");
    }
}

#[test]
fn a_failing_run_is_a_failure_not_a_fast_figure() {
    if !ffmpeg_present() {
        eprintln!("skipped: ffmpeg not on PATH, so the MP4 figure runs nothing");
        return;
    }
    let Some(fake) = stand_in("/bin/false") else {
        return;
    };
    let output = bench_opencv(&["--lapclone", fake, "--cases", "mp4", "--runs", "1"]);
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("failed"), "{stderr}");
}
