//! `lapclone-bench paper --quick`: the table has every column, the JSON every documented key,
//! and bad arguments exit with code 2.

use std::path::Path;
use std::process::Command;

fn bench_paper(extra: &[&str]) -> std::process::Output {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets");
    Command::new(env!("CARGO_BIN_EXE_lapclone-bench"))
        .args(["paper", "--quick", "--assets"])
        .arg(&assets)
        .args(extra)
        .output()
        .expect("the binary runs")
}

#[test]
fn quick_table_prints_every_column() {
    let output = bench_paper(&[]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = String::from_utf8(output.stdout).unwrap();
    for column in [
        "model",
        "pixels",
        "vertices",
        "pre MVC",
        "pre ours",
        "mem MVC",
        "mem ours",
        "PSNR cmb",
        "PSNR cot",
        "PSNR MVC",
        "seam cmb",
        "seam ref",
        "uncovered",
    ] {
        assert!(text.contains(column), "missing column {column}:\n{text}");
    }
    let row = text
        .lines()
        .find(|l| l.starts_with("mouth"))
        .expect("a mouth row");
    assert!(row.contains("121x85"), "{row}");
    assert!(!row.contains("NaN"), "{row}");
}

#[test]
fn quick_json_has_the_documented_keys() {
    let output = bench_paper(&["--json", "--sweep"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    for key in ["density", "repeats", "models", "figure", "sweep"] {
        assert!(json.get(key).is_some(), "missing {key}");
    }
    assert_eq!(json["boundary_data"], "hat-average");
    assert_eq!(json["boundary"], "outside-centres");
    let model = &json["models"][0];
    for key in [
        "model",
        "width",
        "height",
        "inside_pixels",
        "vertices",
        "triangles",
        "boundary_vertices",
        "mesh_ms",
        "reference_factor_ms",
        "reference_solve_ms",
        "uncovered",
    ] {
        assert!(model.get(key).is_some(), "missing models[].{key}");
    }
    for method in ["combinatorial", "cotangent", "mvc"] {
        for key in [
            "psnr_db",
            "seam_step",
            "reference_seam_step",
            "preprocess_ms",
            "membrane_ms",
        ] {
            assert!(
                model[method].get(key).is_some(),
                "missing models[].{method}.{key}"
            );
        }
        assert!(model[method]["psnr_db"].as_f64().unwrap() > 20.0);
    }
    let row = &json["sweep"][0];
    for key in [
        "density",
        "vertices",
        "mesh_ms",
        "psnr_combinatorial_db",
        "psnr_cotangent_db",
        "uncovered",
        "reclone_ms",
    ] {
        assert!(row.get(key).is_some(), "missing sweep[].{key}");
    }
}

#[test]
fn zero_repeat_is_a_usage_error() {
    let output = bench_paper(&["--repeat", "0"]);
    assert_eq!(output.status.code(), Some(2));
}
