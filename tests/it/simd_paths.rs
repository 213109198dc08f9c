//! The same frames on every CPU: each demo scene (scenes/*.rhai, its first three frames)
//! renders to the same PNG bytes with lapclone's vector kernels and with the portable path
//! forced by `LAPCLONE_SIMD=portable` (src/simd.rs).

use std::path::Path;
use std::process::Command;

fn render(scene: &Path, out: &Path, portable: bool) -> Vec<(String, Vec<u8>)> {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
    command
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--frames", "1..3"])
        .env_remove("LAPCLONE_SIMD");
    if portable {
        command.env("LAPCLONE_SIMD", "portable");
    }
    let output = command.output().unwrap();
    assert!(
        output.status.success(),
        "{}: {}",
        scene.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    let mut frames: Vec<(String, Vec<u8>)> = std::fs::read_dir(out)
        .unwrap()
        .map(|entry| {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&path).unwrap())
        })
        .collect();
    frames.sort();
    frames
}

#[test]
fn demo_scenes_render_the_same_bytes_on_the_vector_and_portable_paths() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut names: Vec<_> = std::fs::read_dir(&scenes)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "rhai"))
        .collect();
    names.sort();
    assert!(names.len() >= 5, "demo scenes: {names:?}");
    let dir = tempfile::tempdir().unwrap();
    for (i, scene) in names.iter().enumerate() {
        let vector = render(scene, &dir.path().join(format!("{i}v")), false);
        let portable = render(scene, &dir.path().join(format!("{i}p")), true);
        assert_eq!(vector.len(), 3, "{}", scene.display());
        for ((name, a), (_, b)) in vector.iter().zip(&portable) {
            assert!(a == b, "{} {name}: the paths differ", scene.display());
        }
        assert_eq!(
            vector.iter().map(|f| &f.0).collect::<Vec<_>>(),
            portable.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
    }
}
