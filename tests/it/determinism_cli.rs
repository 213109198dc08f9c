//! Determinism (docs/robustness.md): a scene with two layers, one of them deformed, renders
//! byte-identical PNG frames, GIF and APNG on two runs and with `--jobs 1` and `--jobs 2`.
//! (tests/render_cli.rs covers one undeformed-layer PNG sequence across job counts.)

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::files;
use files::asset;

/// 80 × 60, 5 frames: a dragged and pinned triangle over a moving, rotating quad.
fn write_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("layers.rhai");
    let text = format!(
        "canvas(80, 60, #{{ fps: 5, duration: 1, background: \"{coffee}\" }});\n\
         let back = patch(\"back\", #{{ source: \"{cat}\", polygons: [[[20, 20], [90, 25], [85, 80], [25, 70]]] }});\n\
         back.at(0, [40, 30]).at(1, [46, 28], \"smooth\").rotate(1, 20);\n\
         let front = patch(\"front\", #{{ source: \"{astronaut}\", polygons: [[[10, 10], [70, 14], [30, 56]]], feather: 2 }});\n\
         front.depth(0, 1).at(0, [36, 34]);\n\
         front.drag([50, 16], 18).key(0, [50, 16]).key(1, [58, 26], \"ease_in_out\");\n\
         front.pin([20, 20]);\n",
        coffee = asset("coffee.png"),
        cat = asset("chelsea.png"),
        astronaut = asset("astronaut.png"),
    );
    std::fs::write(&scene, text).unwrap();
    scene
}

fn render(scene: &Path, out: &Path, extra: &[&str]) {
    let output = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
}

fn folder_bytes(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    files.sort();
    files
}

#[test]
fn two_layers_with_deformation_render_identically_across_runs_and_jobs() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let runs = [("a", "1"), ("b", "2"), ("c", "2")];
    for (name, jobs) in runs {
        render(&scene, &dir.path().join(name), &["--jobs", jobs]);
    }
    let first = folder_bytes(&dir.path().join("a"));
    assert_eq!(first.len(), 5);
    for (name, _) in &runs[1..] {
        assert!(
            folder_bytes(&dir.path().join(name)) == first,
            "run {name} differs from run a"
        );
    }
    // The deformation and motion are real: no two frames are the same.
    for pair in first.windows(2) {
        assert_ne!(pair[0].1, pair[1].1, "{} = {}", pair[0].0, pair[1].0);
    }
    for format in ["gif", "apng"] {
        let files: Vec<Vec<u8>> = ["1", "2", "2"]
            .iter()
            .enumerate()
            .map(|(run, jobs)| {
                let out = dir.path().join(format!("{format}_{run}.out"));
                render(&scene, &out, &["--format", format, "--jobs", jobs]);
                std::fs::read(&out).unwrap()
            })
            .collect();
        assert!(files[0].len() > 100, "{format}: tiny file");
        assert!(
            files.iter().all(|f| *f == files[0]),
            "{format}: runs differ"
        );
    }
}
