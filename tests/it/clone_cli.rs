//! Bad input through `lapclone clone`: missing files, mismatched mask, empty mask, a patch
//! entirely outside the target, non-finite numbers, a missing output folder, a zero scale —
//! each with its exit code (0 ok, 1 failure, 2 usage), a message, and never a partial file.

use crate::fixtures;

use std::path::Path;
use std::process::{Command, Output};

use crate::synth;
use lapclone::mesh::BitMask;
use lapclone::pixels::FloatImage;

use fixtures::*;

/// Writes source (64²), mask (64² disc), target (96×80) into `dir`.
fn inputs(dir: &Path) {
    save(&textured_source(64, 64), &dir.join("source.png"));
    save(&smooth_target(96, 80), &dir.join("target.png"));
    synth::disc(64, 64, 20.0)
        .to_image()
        .save(dir.join("mask.png"))
        .unwrap();
}

fn clone(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("clone")
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// The usual arguments with `replace` substituted for the flag of the same name.
fn args_with<'a>(replace: &[(&'a str, &'a str)]) -> Vec<&'a str> {
    let mut args = vec![
        "--source",
        "source.png",
        "--mask",
        "mask.png",
        "--target",
        "target.png",
        "--at",
        "48,40",
        "-o",
        "out.png",
    ];
    for (flag, value) in replace {
        match args.iter().position(|a| a == flag) {
            Some(i) => args[i + 1] = value,
            None => args.extend([*flag, *value]),
        }
    }
    args
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The folder holds exactly the three inputs (no output, no temporary file).
fn assert_only_inputs(dir: &Path) {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["mask.png", "source.png", "target.png"]);
}

fn assert_fails(dir: &Path, args: &[&str], code: i32, message: &str) {
    let output = clone(dir, args);
    assert_eq!(
        output.status.code(),
        Some(code),
        "{args:?}: {}",
        stderr(&output)
    );
    assert!(
        stderr(&output).contains(message),
        "{args:?}: stderr lacks `{message}`: {}",
        stderr(&output)
    );
    assert_only_inputs(dir);
}

#[test]
fn good_input_succeeds_with_stats() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    let output = clone(dir.path(), &args_with(&[("--stats", "--show-mesh")]));
    assert!(output.status.success(), "{}", stderr(&output));
    let stats: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    for key in [
        "vertices",
        "boundary_vertices",
        "constrained",
        "mesh_ms",
        "factor_ms",
        "solve_ms",
        "raster_ms",
        "total_ms",
        "reclone_ms",
        "load_ms",
    ] {
        assert!(stats[key].is_number(), "stats lack {key}: {stats}");
    }
    // total_ms is the first clone (mesh through raster), decoding the inputs excluded.
    let ms = |key: &str| stats[key].as_f64().unwrap();
    assert!(ms("total_ms") >= ms("mesh_ms") + ms("solve_ms"), "{stats}");
    assert_eq!(stats["constrained"], stats["boundary_vertices"]);
    assert!(dir.path().join("out.png").is_file());
}

#[test]
fn missing_or_unreadable_files_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    for flag in ["--source", "--mask", "--target"] {
        assert_fails(
            dir.path(),
            &args_with(&[(flag, "nowhere.png")]),
            1,
            "nowhere.png",
        );
    }
    std::fs::write(dir.path().join("garbage.png"), b"not a png").unwrap();
    for flag in ["--source", "--mask", "--target"] {
        let output = clone(dir.path(), &args_with(&[(flag, "garbage.png")]));
        assert_eq!(output.status.code(), Some(1), "{flag}: {}", stderr(&output));
        assert!(
            stderr(&output).contains("garbage.png"),
            "{flag}: {}",
            stderr(&output)
        );
        assert!(!dir.path().join("out.png").exists());
    }
}

#[test]
fn mask_size_must_match_the_source_unless_offset() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    synth::disc(40, 40, 15.0)
        .to_image()
        .save(dir.path().join("small.png"))
        .unwrap();
    let output = clone(dir.path(), &args_with(&[("--mask", "small.png")]));
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("mask is 40×40 but the source is 64×64"),
        "{}",
        stderr(&output)
    );
    assert!(!dir.path().join("out.png").exists());
    let output = clone(
        dir.path(),
        &args_with(&[("--mask", "small.png"), ("--mask-offset", "12,12")]),
    );
    assert!(output.status.success(), "{}", stderr(&output));
}

#[test]
fn empty_mask_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    BitMask::new(64, 64)
        .to_image()
        .save(dir.path().join("mask.png"))
        .unwrap();
    assert_fails(dir.path(), &args_with(&[]), 1, "mask has no inside pixels");
}

#[test]
fn patch_entirely_outside_gives_the_target_and_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    for at in ["-200,40", "48,500", "400,-300"] {
        let output = clone(dir.path(), &args_with(&[("--at", at)]));
        assert_eq!(output.status.code(), Some(0), "{at}: {}", stderr(&output));
        assert!(
            stderr(&output).contains("warning"),
            "{at}: {}",
            stderr(&output)
        );
        let out = FloatImage::load(&dir.path().join("out.png")).unwrap();
        let target = FloatImage::load(&dir.path().join("target.png")).unwrap();
        assert_eq!(out, target, "{at}: output differs from the target");
    }
}

#[test]
fn non_finite_numbers_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    for (flag, value) in [
        ("--at", "NaN,40"),
        ("--at", "48,inf"),
        ("--at", "-inf,3"),
        ("--scale", "NaN"),
        ("--scale", "inf"),
        ("--rotate", "nan"),
        ("--rotate", "-inf"),
        ("--scale", "0"),
        ("--scale", "-1"),
    ] {
        assert_fails(dir.path(), &args_with(&[(flag, value)]), 2, flag);
    }
}

#[test]
fn output_in_a_missing_folder_fails_without_a_file() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    assert_fails(
        dir.path(),
        &args_with(&[("-o", "missing/out.png")]),
        1,
        "missing",
    );
    assert!(!dir.path().join("missing").exists());
}

#[test]
fn boundary_data_is_chosen_by_name_and_changes_the_result() {
    let dir = tempfile::tempdir().unwrap();
    inputs(dir.path());
    assert_fails(
        dir.path(),
        &args_with(&[("--boundary-data", "pointy")]),
        2,
        "unknown boundary data",
    );
    let mut written = Vec::new();
    for (data, name) in [("vertex", "vertex.png"), ("hat-average", "hat.png")] {
        let output = clone(
            dir.path(),
            &args_with(&[("--boundary-data", data), ("-o", name)]),
        );
        assert!(output.status.success(), "{data}: {}", stderr(&output));
        written.push(std::fs::read(dir.path().join(name)).unwrap());
    }
    // The default is the hat average.
    let output = clone(dir.path(), &args_with(&[]));
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(
        std::fs::read(dir.path().join("out.png")).unwrap(),
        written[1]
    );
    assert_ne!(
        written[0], written[1],
        "the textured source's boundary data differ"
    );
}
