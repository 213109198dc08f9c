//! `lapclone mesh` end to end: --stats JSON keys, -o picture, --laplacian-out files, and bad
//! inputs with their exit codes.

use std::path::Path;
use std::process::Command;

use crate::synth;

fn lapclone(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(args)
        .output()
        .expect("runs")
}

fn save_mask(dir: &Path, name: &str, mask: &lapclone::mesh::BitMask) -> String {
    let path = dir.join(name);
    mask.to_image().save(&path).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn stats_json_has_exactly_the_contract_keys() {
    let dir = tempfile::tempdir().unwrap();
    let mask = save_mask(dir.path(), "ring.png", &synth::annulus(80, 80, 12.0, 35.0));
    let out = lapclone(&["mesh", &mask, "--stats"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut keys: Vec<&str> = json
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    keys.sort_unstable();
    let mut expected = vec![
        "vertices",
        "triangles",
        "boundary_vertices",
        "pieces",
        "holes",
        "min_angle_deg",
        "uncovered_mask_pixels",
        "max_boundary_deviation_px",
        "mesh_ms",
        // Beyond the contract: where the boundary runs.
        "boundary",
    ];
    expected.sort_unstable();
    assert_eq!(keys, expected);
    assert_eq!(json["pieces"], 1);
    assert_eq!(json["holes"], 1);
    assert_eq!(json["uncovered_mask_pixels"], 0);
    assert_eq!(json["boundary"], "outside-centres");
    let out = lapclone(&["mesh", &mask, "--stats", "--boundary", "cracks"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["boundary"], "cracks");
}

#[test]
fn picture_and_laplacian_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let mask = save_mask(dir.path(), "disc.png", &synth::disc(40, 30, 12.0));
    let png = dir.path().join("mesh.png");
    let mtx = dir.path().join("L.mtx");
    let out = lapclone(&[
        "mesh",
        &mask,
        "-o",
        png.to_str().unwrap(),
        "--laplacian-out",
        mtx.to_str().unwrap(),
        "--stats",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let vertices = json["vertices"].as_u64().unwrap() as usize;
    let picture = image::open(&png).unwrap();
    assert!(picture.width() >= 40 && picture.height() >= 30);

    // The Laplacian: header, size line, rows that sum to zero.
    let text = std::fs::read_to_string(&mtx).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    assert!(text.starts_with("%%MatrixMarket matrix coordinate real symmetric\n"));
    let size: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!((size[0], size[1]), (vertices, vertices));
    let mut row_sum = vec![0.0f64; vertices];
    let mut count = 0;
    for line in lines {
        let f: Vec<&str> = line.split_whitespace().collect();
        let (i, j, v): (usize, usize, f64) = (
            f[0].parse().unwrap(),
            f[1].parse().unwrap(),
            f[2].parse().unwrap(),
        );
        assert!(i >= j && j >= 1 && i <= vertices, "lower triangle, 1-based");
        row_sum[i - 1] += v;
        if i != j {
            row_sum[j - 1] += v;
        }
        count += 1;
    }
    assert_eq!(count, size[2]);
    assert!(row_sum.iter().all(|&s| s == 0.0));

    let boundary = std::fs::read_to_string(dir.path().join("L.mtx.boundary")).unwrap();
    let ids: Vec<usize> = boundary.lines().map(|l| l.parse().unwrap()).collect();
    assert_eq!(
        ids.len() as u64,
        json["boundary_vertices"].as_u64().unwrap()
    );
    assert!(ids.iter().all(|&v| v < vertices));
}

#[test]
fn empty_mask_fails_with_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let mask = save_mask(dir.path(), "empty.png", &lapclone::mesh::BitMask::new(8, 8));
    let out = lapclone(&["mesh", &mask, "--stats"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("mask has no inside pixels"));
    assert!(out.stdout.is_empty());
}

#[test]
fn missing_file_error_names_the_path() {
    let out = lapclone(&["mesh", "/no/such/mask.png"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/no/such/mask.png"));
}

#[test]
fn unreadable_file_error_names_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("garbage.png");
    std::fs::write(&path, b"not an image").unwrap();
    let out = lapclone(&["mesh", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("garbage.png"));
}

#[test]
fn bad_options_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mask = save_mask(dir.path(), "disc.png", &synth::disc(20, 20, 8.0));
    for args in [
        vec!["--density", "0"],
        vec!["--min-angle", "50"],
        vec!["--threshold", "2"],
        vec!["--density", "nan"],
    ] {
        let mut all = vec!["mesh", mask.as_str()];
        all.extend(args.iter());
        let out = lapclone(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
    }
}

#[test]
fn hard_masks_mesh_or_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let masks = [
        (
            "full.png",
            lapclone::mesh::BitMask::from_fn(20, 15, |_, _| true),
        ),
        ("line.png", synth::line(40, 9, 40)),
        ("comb.png", synth::comb(100, 60, 3, 1)),
        ("nested.png", synth::nested(90, 90)),
        ("speckle.png", synth::speckle(40, 40, 0.4, 3)),
    ];
    for (name, mask) in masks {
        let path = save_mask(dir.path(), name, &mask);
        let out = lapclone(&["mesh", &path, "--stats"]);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert!(json["triangles"].as_u64().unwrap() > 0, "{name}");
    }
}

/// The quality flags `clone` has work on `mesh` too: the exact boundary passes through
/// pixel centres (zero deviation from them, more boundary vertices, nothing uncovered),
/// relaxation keeps the vertex and triangle counts and the angle bound (or the smallest input
/// angle, when that is below it),
/// and a negative maximum area is a usage error naming it.
#[test]
fn quality_flags_shape_the_mask_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mask = save_mask(dir.path(), "ring.png", &synth::annulus(80, 80, 12.0, 35.0));
    let stats = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["mesh", mask.as_str(), "--stats"];
        args.extend_from_slice(extra);
        let out = lapclone(&args);
        assert!(
            out.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let plain = stats(&[]);
    let exact = stats(&["--boundary", "outside-centres", "--density", "1"]);
    assert_eq!(exact["max_boundary_deviation_px"], 0.0);
    assert_eq!(exact["uncovered_mask_pixels"], 0);
    assert!(exact["boundary_vertices"].as_u64() > plain["boundary_vertices"].as_u64());
    let relaxed = stats(&["--relax", "5"]);
    assert_eq!(relaxed["vertices"], plain["vertices"]);
    assert_eq!(relaxed["triangles"], plain["triangles"]);
    let smallest = |stats: &serde_json::Value| stats["min_angle_deg"].as_f64().unwrap();
    assert!(
        smallest(&relaxed) >= smallest(&plain).min(25.0) - 1e-9,
        "{} → {}",
        smallest(&plain),
        smallest(&relaxed)
    );
    let preset = stats(&["--seam-quality"]);
    assert!(preset["vertices"].as_u64() > plain["vertices"].as_u64());
    let out = lapclone(&["mesh", &mask, "--max-area", "-4"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("area"));
}

#[test]
fn the_laplacian_text_of_two_triangles_is_exact_and_reads_back() {
    use crate::matrix_market::read_matrix_market;
    use lapclone::glam::DVec2;
    use lapclone::solve::{laplacian, write_matrix_market, LaplacianKind};
    let p = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    let mesh = lapclone::mesh::assemble_mesh(p, vec![[0, 1, 2], [0, 2, 3]]);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("L.mtx");
    write_matrix_market(&path, &l, "combinatorial Laplacian of a lapclone mesh").unwrap();
    let expected = "%%MatrixMarket matrix coordinate real symmetric\n\
                    % combinatorial Laplacian of a lapclone mesh\n\
                    4 4 9\n1 1 3\n2 1 -1\n3 1 -1\n4 1 -1\n2 2 2\n3 2 -1\n3 3 3\n4 3 -1\n4 4 2\n";
    assert_eq!(std::fs::read_to_string(&path).unwrap(), expected);
    let back = read_matrix_market(&path).unwrap();
    assert_eq!(
        (back.col_ptr, back.row_idx, back.values),
        (l.col_ptr, l.row_idx, l.values)
    );
    // Values that are not integers read back exactly too.
    let mut cot = laplacian(&mesh, LaplacianKind::Cotangent);
    cot.values.iter_mut().for_each(|v| *v /= 3.0);
    write_matrix_market(&path, &cot, "").unwrap();
    assert_eq!(read_matrix_market(&path).unwrap().values, cot.values);
}

/// The `.boundary` list beside `--laplacian-out` is an output too: it never replaces the
/// mask, two outputs never name one file, and when one output cannot be written none is.
#[test]
fn every_output_is_checked_and_a_failure_writes_none() {
    let dir = tempfile::tempdir().unwrap();
    let original = synth::disc(40, 40, 15.0).to_image();
    let mask = dir.path().join("m.boundary");
    original
        .save_with_format(&mask, image::ImageFormat::Png)
        .unwrap();
    let before = std::fs::read(&mask).unwrap();
    let at = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let mask_arg = mask.to_string_lossy().into_owned();
    let fails = |args: &[&str], code: i32, message: &str| {
        let out = lapclone(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
    };
    fails(
        &["mesh", &mask_arg, "--laplacian-out", &at("m")],
        1,
        "would replace an input",
    );
    assert_eq!(std::fs::read(&mask).unwrap(), before, "the mask is intact");
    assert!(!dir.path().join("m").exists());

    std::fs::create_dir(dir.path().join("x.mtx.boundary")).unwrap();
    for (picture, laplacian, code, message) in [
        ("out", "out", 2, "two outputs name the same file"),
        (
            "y.mtx.boundary",
            "y.mtx",
            2,
            "two outputs name the same file",
        ),
        ("pic.png", "x.mtx", 1, "it is a folder"),
    ] {
        let (picture, laplacian) = (at(picture), at(laplacian));
        let args = [
            "mesh",
            &mask_arg,
            "-o",
            &picture,
            "--laplacian-out",
            &laplacian,
        ];
        fails(&args, code, message);
    }
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["m.boundary", "x.mtx.boundary"],
        "nothing written, no temporary left"
    );
}
