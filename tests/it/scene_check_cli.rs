//! `lapclone check`: success summary, positioned errors with a caret, exit codes; and the
//! `preview` flag group.

use std::path::Path;
use std::process::Command;

use crate::files;
use files::asset;

fn check(dir: &Path, text: &str) -> (i32, String, String) {
    run(dir, text, &["check"], &[])
}

/// Runs `lapclone COMMAND scene.rhai ARGS…` on `text` written to `dir/scene.rhai`.
fn run(dir: &Path, text: &str, command: &[&str], args: &[&str]) -> (i32, String, String) {
    let scene = dir.join("scene.rhai");
    std::fs::write(&scene, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .current_dir(dir)
        .args(command)
        .arg(&scene)
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn head() -> String {
    format!(
        "canvas(320, 240, #{{ fps: 12, duration: 2, background: \"{}\" }});\n\
         let p = patch(\"tri\", #{{ source: \"{}\", polygons: [[[10, 10], [200, 20], [50, 180]]] }});\n",
        asset("coffee.png"),
        asset("astronaut.png")
    )
}

#[test]
fn a_valid_scene_passes_with_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stdout, _) = check(
        dir.path(),
        &format!(
            "{}p.at(0, [100, 100]);\np.at(2, [200, 100], \"smooth\");\n",
            head()
        ),
    );
    assert_eq!(code, 0);
    assert!(
        stdout.contains("ok") && stdout.contains("24 frames") && stdout.contains("1 patches"),
        "{stdout}"
    );
}

#[test]
fn a_missing_key_is_shown_with_a_caret() {
    let dir = tempfile::tempdir().unwrap();
    let (code, _, stderr) = check(
        dir.path(),
        &format!("{}p.at(1, [0, 0]);\n  p.remove_key(0.5, \"at\");\n", head()),
    );
    assert_eq!(code, 1);
    let scene = dir.path().join("scene.rhai");
    let expected = format!(
        "{}:4:5: no \"at\" key at t = 0.5 on patch \"tri\"; its keys are at 1",
        scene.display()
    );
    assert!(stderr.contains(&expected), "{stderr}");
    assert!(
        stderr.contains("\n  p.remove_key(0.5, \"at\");\n    ^"),
        "{stderr}"
    );
}

#[test]
fn a_mask_of_the_wrong_size_points_at_its_patch() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "canvas(64, 64);\n\nlet m = patch(\"m\", #{{ source: \"{}\", mask: \"{}\" }});\n",
        asset("astronaut.png"),
        asset("horse_mask.png")
    );
    let (code, _, stderr) = check(dir.path(), &text);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("scene.rhai:3:9: ") && stderr.contains("mask is 400×328"),
        "{stderr}"
    );
}

#[test]
fn an_empty_polygon_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "canvas(64, 64);\nlet z = patch(\"z\", #{{ source: \"{}\", polygons: [[[0, 0], [10, 0], [20, 0]]] }});\n",
        asset("astronaut.png")
    );
    let (code, _, stderr) = check(dir.path(), &text);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("scene.rhai:2:9: ") && stderr.contains("empty"),
        "{stderr}"
    );
}

#[test]
fn missing_scene_and_syntax_errors_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let (code, _, stderr) = check(dir.path(), "canvas(8, 8;\n");
    assert_eq!(code, 1);
    assert!(
        stderr.contains("scene.rhai:1:") && stderr.contains("syntax error"),
        "{stderr}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["check", "/no/such/scene.rhai"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn preview_time_and_frame_are_exclusive() {
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args([
            "preview", "s.rhai", "--t", "1", "--frame", "3", "-o", "x.png",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// An error Rhai raises without a position (`range` with a step of 0) is reported at the
/// call that raised it, as every other error is.
#[test]
fn a_range_with_step_zero_is_reported_at_its_call() {
    let dir = tempfile::tempdir().unwrap();
    let text = "canvas(32, 24);\nlet n = 0;\nfor i in range(0, 10, 0) { n += i; }\n";
    let (code, _, stderr) = check(dir.path(), text);
    assert_eq!(code, 1, "{stderr}");
    let scene = dir.path().join("scene.rhai");
    let expected = format!("{}:3:10: step value cannot be zero", scene.display());
    assert!(stderr.contains(&expected), "{stderr}");
    assert!(stderr.contains("for i in range(0, 10, 0)"), "{stderr}");
}

/// A scene has one canvas: a second `canvas` call (a module's, or one left in) replaces the
/// first, and `check` says where both are; the later one is the scene's.
#[test]
fn check_warns_about_a_second_canvas_at_both_calls() {
    let dir = tempfile::tempdir().unwrap();
    let text = "canvas(320, 240);\nlet n = 1;\n  canvas(100, 80, #{ fps: 12 });\n";
    let (code, stdout, stderr) = check(dir.path(), text);
    assert_eq!(code, 0, "{stderr}");
    let scene = dir.path().join("scene.rhai");
    let expected = format!(
        "warning: {0}:3:3: `canvas` again: this canvas replaces the one of {0}:1:1 (a scene has one)",
        scene.display()
    );
    assert!(stderr.contains(&expected), "{stderr}");
    assert!(stdout.contains("100×80, 12 fps"), "{stdout}");
}

#[test]
fn check_warns_about_an_old_option_name_at_its_call() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "canvas(320, 240);\nlet p = patch(\"p\", #{{ source: \"{}\", polygons: [[[10, 10], [200, 20], [50, 180]]], boundary_data: \"vertex\" }});\n",
        asset("astronaut.png")
    );
    let (code, _, stderr) = check(dir.path(), &text);
    assert_eq!(code, 0, "{stderr}");
    let scene = dir.path().join("scene.rhai");
    let expected = format!(
        "warning: {}:2:9: `boundary_data` is now `boundary_sampling` (the old name still works)",
        scene.display()
    );
    assert!(stderr.contains(&expected), "{stderr}");
}

/// What `check` warns about, `render` and `preview` warn about too, each once: a user who
/// only renders still learns of an old name or a key past the scene's end.
#[test]
fn render_and_preview_warn_as_check_does() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "canvas(64, 48, #{{ fps: 2, duration: 1 }});\nlet p = patch(\"p\", #{{ source: \"{}\", polygons: [[[4, 4], [40, 6], [10, 40]]], boundary_data: \"vertex\" }});\np.at(3, [20, 20]);\n",
        asset("astronaut.png")
    );
    let scene = dir.path().join("scene.rhai");
    let old_name = format!(
        "warning: {}:2:9: `boundary_data` is now `boundary_sampling` (the old name still works)",
        scene.display()
    );
    let runs: [(&[&str], &[&str]); 3] = [
        (&["check"], &[]),
        (&["render"], &["-o", "frames"]),
        (&["preview"], &["--frame", "1", "-o", "one.png"]),
    ];
    for (command, args) in runs {
        let (code, _, stderr) = run(dir.path(), &text, command, args);
        assert_eq!(code, 0, "{command:?}: {stderr}");
        assert_eq!(
            stderr.matches(&old_name).count(),
            1,
            "{command:?}: {stderr}"
        );
        let late = stderr
            .lines()
            .filter(|l| l.contains("after the scene's end"))
            .count();
        assert_eq!(late, 1, "{command:?}: {stderr}");
    }
}
