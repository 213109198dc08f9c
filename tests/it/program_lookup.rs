//! Finding ffmpeg on `PATH`: takes a temporary folder holding stand-in programs and gives
//! which of them `find_program_in` (and the `lapclone` binary, through `PATH`) finds.

use std::ffi::OsStr;
use std::path::Path;
use std::process::Command;

use lapclone::util::find_program_in;

/// Writes an executable stand-in called `name` into `dir` that records its arguments in
/// `called` and fails.
fn stand_in(dir: &Path, name: &str, called: &Path) {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!("#!/bin/sh\necho \"$@\" > '{}'\nexit 1\n", called.display()),
    )
    .unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

#[test]
fn only_executable_files_are_found_in_the_folders_given() {
    let tools = tempfile::tempdir().unwrap();
    let empty = tempfile::tempdir().unwrap();
    let called = tools.path().join("called");
    stand_in(tools.path(), "ffmpeg", &called);
    std::fs::create_dir(tools.path().join("ffplay")).unwrap();
    let search = std::env::join_paths([empty.path(), tools.path()]).unwrap();
    assert_eq!(
        find_program_in("ffmpeg", &search),
        Some(tools.path().join("ffmpeg"))
    );
    assert_eq!(find_program_in("ffplay", &search), None, "a folder");
    assert_eq!(find_program_in("ffprobe", &search), None, "absent");
    assert_eq!(find_program_in("ffmpeg", OsStr::new("")), None);
    #[cfg(unix)]
    {
        std::fs::write(tools.path().join("ffprobe"), "not executable").unwrap();
        assert_eq!(find_program_in("ffprobe", &search), None, "not executable");
    }
}

#[cfg(windows)]
#[test]
fn an_extension_of_pathext_is_tried() {
    let tools = tempfile::tempdir().unwrap();
    std::fs::write(tools.path().join("ffmpeg.exe"), "stand-in").unwrap();
    let found = find_program_in("ffmpeg", tools.path().as_os_str()).unwrap();
    assert!(
        found
            .to_string_lossy()
            .to_lowercase()
            .ends_with("ffmpeg.exe"),
        "{found:?}"
    );
}

#[cfg(unix)]
#[test]
fn a_video_render_runs_the_ffmpeg_of_the_temporary_path() {
    let dir = tempfile::tempdir().unwrap();
    let tools = tempfile::tempdir().unwrap();
    let called = dir.path().join("called");
    stand_in(tools.path(), "ffmpeg", &called);
    let scene = dir.path().join("scene.rhai");
    std::fs::write(&scene, "canvas(16, 16, #{ fps: 2, duration: 1 });\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(dir.path().join("out.mp4"))
        .env("PATH", tools.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "the stand-in fails");
    let args = std::fs::read_to_string(&called).expect("the stand-in ffmpeg ran");
    assert!(args.contains("out.mp4"), "{args}");
    assert!(!dir.path().join("out.mp4").exists());
}
