//! Editing a scene: keys inserted, replaced, removed and moved at any time; patches, handles
//! and pins removed; renames, layer order and opacity. Each check compares rendered frames
//! byte for byte with a scene written without the edit (or with the background), and every
//! refused call must be a positioned error that leaves the scene as it was.

use std::path::{Path, PathBuf};
use std::process::Command;

use lapclone::pixels::{Canvas, CanvasPixels};
use lapclone::render::Renderer;
use lapclone::scene::{Easing, Scene, Track};
use lapclone::script::{parse_scene, SceneEngine, ScriptOptions};

use crate::files;
use files::asset;

/// Canvas and two small polygon patches of the cat photo; `b` is in front of `a`.
fn base() -> String {
    let source = asset("chelsea.png");
    format!(
        r#"canvas(64, 48, #{{ fps: 8, duration: 1, background: [0.1, 0.2, 0.3] }});
let a = patch("a", #{{ source: "{source}", polygons: [[[150, 60], [185, 60], [190, 90], [160, 95]]] }});
let b = patch("b", #{{ source: "{source}", polygons: [[[120, 100], [150, 100], [150, 125], [120, 128]]] }});
a.at(0, [30, 24]);
b.at(0, [36, 26]).depth(0, 1);
"#
    )
}

fn options() -> ScriptOptions {
    ScriptOptions::for_scene_file(Path::new("scene.rhai"))
}

fn load(text: &str) -> Scene {
    parse_scene(text, Path::new("scene.rhai"), &options())
        .unwrap_or_else(|e| panic!("{e}\n---\n{text}"))
        .scene
}

fn frames(scene: &Scene) -> Vec<Canvas> {
    let mut renderer = Renderer::new(scene.clone()).unwrap();
    (0..renderer.frame_count())
        .map(|i| renderer.render_frame(i).unwrap().clone())
        .collect()
}

fn render(text: &str) -> Vec<Canvas> {
    frames(&load(text))
}

fn bytes(canvas: &Canvas) -> &[[u8; 4]] {
    match canvas.pixels() {
        CanvasPixels::Eight(p) => p,
        CanvasPixels::Sixteen(_) => panic!("8-bit canvas expected"),
    }
}

#[test]
fn an_inserted_key_renders_like_keys_written_in_order() {
    let inserted = base() + "a.at(1, [44, 30]); a.at(0.5, [20, 10], \"smooth\");";
    let in_order = base() + "a.at(0.5, [20, 10], \"smooth\"); a.at(1, [44, 30]);";
    assert_eq!(load(&inserted), load(&in_order));
    assert!(render(&inserted) == render(&in_order));
}

#[test]
fn an_inserted_key_in_the_repl_renders_like_keys_written_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.rhai");
    std::fs::write(&scene, base() + "a.at(1, [44, 30]);\n").unwrap();
    let in_order = dir.path().join("in_order.rhai");
    let in_order_text = base() + "a.at(0.5, [20, 10], \"smooth\");\na.at(1, [44, 30]);\n";
    std::fs::write(&in_order, in_order_text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["repl", "scene.rhai", "--preview", "preview.png", "--script"])
        .arg(write(
            dir.path(),
            "entries.txt",
            "a.at(0.5, [20, 10], \"smooth\");\n:render -o live\n",
        ))
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let render = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["render", "in_order.rhai", "-o", "file"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(
        render.status.success(),
        "{}",
        String::from_utf8_lossy(&render.stderr)
    );
    let live = files_in(&dir.path().join("live"));
    assert_eq!(live.len(), 8);
    assert!(live == files_in(&dir.path().join("file")), "frames differ");
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn files_in(dir: &Path) -> Vec<Vec<u8>> {
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    paths.sort();
    paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

#[test]
fn replacing_a_key_changes_only_the_two_segments_around_it() {
    // Keys every 0.25 s; frames every 0.125 s. Replacing the key at 0.5 may change only
    // frames strictly between 0.25 and 0.75 (frames 3, 4, 5).
    let keys =
        "a.at(0.25, [34, 20]); a.at(0.5, [38, 24]); a.at(0.75, [30, 30]); a.at(1, [26, 24]);";
    let before = render(&(base() + keys));
    let after = render(&(base() + keys + "a.at(0.5, [20, 12], \"ease_in\");"));
    for i in [0, 1, 2, 6, 7] {
        assert!(before[i] == after[i], "frame {i} changed");
    }
    for i in [3, 4, 5] {
        assert!(before[i] != after[i], "frame {i} did not change");
    }
}

#[test]
fn opacity_zero_shows_the_layers_below_and_one_is_todays_clone() {
    let background =
        render("canvas(64, 48, #{ fps: 8, duration: 1, background: [0.1, 0.2, 0.3] });");
    let hidden = render(&(base() + "a.opacity(0, 0); b.key(0, #{ opacity: 0 });"));
    assert!(hidden == background);
    let without_b = base() + "remove_patch(\"b\");";
    let b_hidden = render(&(base() + "b.opacity(0, 0);"));
    assert!(b_hidden == render(&without_b));
    let plain = render(&base());
    assert!(render(&(base() + "a.opacity(0, 1); b.opacity(0.5, 1);")) == plain);
    let half = render(&(base() + "b.opacity(0, 0.5);"));
    let below = render(&without_b);
    let mut drawn = 0;
    for ((h, full), under) in half.iter().zip(&plain).zip(&below) {
        for ((h, f), u) in bytes(h).iter().zip(bytes(full)).zip(bytes(under)) {
            drawn += usize::from(f != u);
            for k in 0..4 {
                let average = (f64::from(f[k]) + f64::from(u[k])) / 2.0;
                assert!(
                    (f64::from(h[k]) - average).abs() <= 1.0,
                    "{h:?} {f:?} {u:?}"
                );
            }
        }
    }
    assert!(drawn > 1000, "the patch covers only {drawn} pixels");
}

#[test]
fn a_fade_blends_between_its_keys() {
    let fade = load(&(base() + "b.opacity(0, 0).opacity(1, 1, \"smooth\");"));
    let state = fade.evaluate(0.5);
    assert_eq!(state.patches[1].opacity, 0.5);
    assert_eq!(state.patches[0].opacity, 1.0);
}

#[test]
fn removing_a_patch_handle_or_pin_renders_like_a_scene_without_it() {
    let drags = "let h1 = a.drag([160, 70], 10); h1.key(0, [160, 70]).key(1, [166, 66]);
let h2 = a.drag([180, 85], 10); h2.key(0, [180, 85]).key(1, [176, 90]);
a.pin([170, 62]); a.pin([165, 90]);";
    let only_h2 = "let h2 = a.drag([180, 85], 10); h2.key(0, [180, 85]).key(1, [176, 90]);
a.pin([165, 90]);";
    let by_value = base() + drags + "a.remove_handle(h1); a.remove_pin([170, 62]);";
    let by_index = base() + drags + "a.remove_handle(0).remove_pin(0);";
    let written = base() + only_h2;
    assert_eq!(load(&by_value), load(&written));
    assert_eq!(load(&by_index), load(&written));
    assert!(render(&by_value) == render(&written));
    // A removed handle's value no longer edits anything; the other handle still does.
    let later = base() + drags + "a.remove_handle(h1); h2.key(0.5, [182, 80]);";
    assert_eq!(load(&later).patches[0].handles[0].to.keys().len(), 3);
    let removed = base() + "remove_patch(\"a\"); b.at(0.5, [20, 20]);";
    let without_a = format!(
        "canvas(64, 48, #{{ fps: 8, duration: 1, background: [0.1, 0.2, 0.3] }});
let b = patch(\"b\", #{{ source: \"{}\", polygons: [[[120, 100], [150, 100], [150, 125], [120, 128]]] }});
b.at(0, [36, 26]).depth(0, 1); b.at(0.5, [20, 20]);",
        asset("chelsea.png")
    );
    assert_eq!(load(&removed), load(&without_a));
    assert!(render(&removed) == render(&without_a));
}

#[test]
fn a_handle_radius_set_later_renders_like_the_radius_written_in_drag() {
    let keys = "h.key(0, [160, 70]).key(1, [166, 64]);";
    let set = base() + "let h = a.drag([160, 70], 10); " + keys + " h.radius(14.5);";
    let by_index = base() + "let h = a.drag([160, 70], 10); " + keys + " a.handle(0).radius(14.5);";
    let written = base() + "let h = a.drag([160, 70], 14.5); " + keys;
    assert_eq!(load(&set), load(&written));
    assert_eq!(load(&by_index), load(&written));
    assert_eq!(load(&set).patches[0].handles[0].radius, 14.5);
    assert!(render(&set) == render(&written));
    // The radius changes what the drag pulls: the frames differ from the first radius's.
    assert!(render(&set) != render(&(base() + "let h = a.drag([160, 70], 10); " + keys)));
}

#[test]
fn rename_reorder_remove_and_move_keys() {
    let scene = load(
        &(base()
            + "a.rename(\"cat\").to_front(); b.to_back(); a.at(1, [1, 2]).at(2, [3, 4]);
a.move_key(1, 0.5, \"at\"); a.scale(2, 2); a.remove_key(2); a.rename(\"cat\");"),
    );
    let names: Vec<&str> = scene.patches.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["b", "cat"]);
    let times: Vec<f64> = scene.patches[1].placement.position.times().collect();
    assert_eq!(times, [0.0, 0.5]);
    assert!(scene.patches[1].placement.scale.is_empty());
    // Equal depths draw in scene order: to_front puts a patch last.
    let flat = load(&(base() + "b.depth(0, 0); a.to_front();"));
    assert_eq!(flat.patches[1].name, "a");
    assert_eq!(flat.evaluate(0.0).draw_order, [0, 1]);
    let back = load(&(base() + "b.depth(0, 0); b.to_back();"));
    assert_eq!(back.patches[0].name, "b");
}

/// Runs `bad` after the base scene: it must fail with a `file:line:col` error containing
/// `expected`, and leave the scene exactly as it was.
fn refused(bad: &str, expected: &str) {
    let engine = SceneEngine::new(&options());
    let mut scope = rhai::Scope::new();
    let setup = base() + "let h = a.drag([160, 70], 10); h.key(0, [160, 70]); a.pin([170, 62]); a.at(1, [40, 30]); a.at(3, [40, 20]);";
    let _ = engine
        .run(&mut scope, &setup, Path::new("scene.rhai"))
        .unwrap();
    let before = engine.draft();
    let error = engine
        .run(&mut scope, bad, Path::new("edit.rhai"))
        .expect_err(bad)
        .to_string();
    assert!(error.starts_with("edit.rhai:1:"), "{bad}: {error}");
    assert!(error.contains(expected), "{bad}: {error}");
    assert_eq!(engine.draft(), before, "{bad} changed the scene");
}

#[test]
fn bad_arguments_are_positioned_errors_that_change_nothing() {
    refused("get_patch(\"dog\")", "no patch \"dog\"; patches: a, b");
    refused("remove_patch(\"dog\")", "no patch \"dog\"; patches: a, b");
    refused(
        "a.remove_key(1.5, \"at\")",
        "no \"at\" key at t = 1.5 on patch \"a\"; its keys are at 0, 1, 3",
    );
    refused(
        "a.remove_key(1.5)",
        "no key at t = 1.5 on patch \"a\"; its keys are at 0, 1, 3",
    );
    refused("a.remove_key(0, \"colour\")", "unknown track \"colour\"");
    refused("a.move_key(0, 2, \"colour\")", "unknown track \"colour\"");
    refused("a.move_key(2, 1)", "no key at t = 2");
    refused("a.move_key(1, -1)", "≥ 0");
    refused("a.remove_key(-1)", "≥ 0");
    refused("a.at(-1, [0, 0])", "≥ 0");
    refused("a.remove_key(0.0 / 0.0)", "finite");
    refused("a.opacity(0.0 / 0.0, 1)", "finite");
    refused("a.opacity(0, 2)", "`opacity` must be in [0, 1], got 2");
    refused("a.opacity(0, -0.5)", "in [0, 1]");
    refused("a.key(0, #{ opacity: 2 })", "in [0, 1]");
    refused(
        "h.remove_key(2)",
        "no key at t = 2 on handle 0 of patch \"a\"; its keys are at 0",
    );
    refused("h.remove_key(0, \"depth\")", "tracks: at, rotate");
    refused(
        "a.remove_handle(3)",
        "no handle 3 on patch \"a\"; its handles: 0 from [160, 70]",
    );
    refused("b.remove_handle(h)", "belongs to patch \"a\"");
    refused("b.remove_handle(0)", "it has no handles");
    refused(
        "a.remove_pin([1, 2])",
        "no pin at [1, 2] on patch \"a\"; its pins: 0 at [170, 62]",
    );
    refused("a.remove_pin(\"x\")", "index");
    refused("h.radius(0)", "drag radius must be > 0, got 0");
    refused("h.radius(-3)", "drag radius must be > 0");
    refused("h.radius(\"big\")", "drag radius");
    refused("a.rename(\"b\")", "a patch named \"b\" already exists");
    refused("a.rename(\"\")", "must not be empty");
}

#[test]
fn a_removed_patch_value_is_refused() {
    let engine = SceneEngine::new(&options());
    let mut scope = rhai::Scope::new();
    let file = Path::new("scene.rhai");
    let _ = engine
        .run(&mut scope, &(base() + "remove_patch(a);"), file)
        .unwrap();
    let before = engine.draft();
    let error = engine.run(&mut scope, "a.at(0, [1, 1])", file).unwrap_err();
    assert!(
        error
            .to_string()
            .contains("scene.rhai:1:3: this patch no longer exists"),
        "{error}"
    );
    assert_eq!(engine.draft(), before);
    assert_eq!(before.patches.len(), 1);
}

#[test]
fn the_repl_goes_on_after_refused_edits() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.rhai"), base()).unwrap();
    let entries =
        "a.opacity(0, 2);\nremove_patch(\"dog\");\na.remove_key(7);\n:keys a\n:keys dog\n";
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["repl", "scene.rhai", "--preview", "preview.png", "--script"])
        .arg(write(dir.path(), "entries.txt", entries))
        .current_dir(dir.path())
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("<entry 1>:1:3: `opacity` must be in [0, 1], got 2"),
        "{stderr}"
    );
    assert!(
        stderr.contains("no patch \"dog\"; patches: a, b"),
        "{stderr}"
    );
    assert!(
        stderr.contains("no key at t = 7 on patch \"a\"; its keys are at 0"),
        "{stderr}"
    );
    assert!(
        stdout
            .contains("patch \"a\"\n  track  t  value     easing\n  at     0  [30, 24]  linear\n"),
        "{stdout}"
    );
    assert!(stderr.contains("4 failed entries"), "{stderr}");
}

#[test]
fn undo_takes_back_every_kind_of_edit_and_save_follows() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.rhai"), base()).unwrap();
    let entries = ":list
remove_patch(\"b\");
a.rename(\"cat\");
a.opacity(0, 0.5).to_front();
a.at(0.5, [20, 10]);
a.remove_key(0.5);
a.move_key(0, 0.25);
:save one_edit_left.rhai
:undo
:undo
:undo
:undo
:undo
:undo
:list
:save saved.rhai
";
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["repl", "scene.rhai", "--preview", "preview.png", "--script"])
        .arg(write(dir.path(), "entries.txt", entries))
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lists: Vec<&str> = stdout
        .split("canvas 64×48")
        .skip(1)
        .map(|l| l.split("variables").next().unwrap())
        .collect();
    assert_eq!(lists.len(), 2, "{stdout}");
    assert_eq!(lists[0], lists[1]);
    assert!(
        lists[0].contains("layers at t = 0 s, back to front: \"a\" (depth 0), \"b\" (depth 1)"),
        "{stdout}"
    );
    let saved = std::fs::read_to_string(dir.path().join("saved.rhai")).unwrap();
    assert_eq!(saved, base());
    let one_left = std::fs::read_to_string(dir.path().join("one_edit_left.rhai")).unwrap();
    assert!(
        one_left.ends_with("a.remove_key(0.5);\na.move_key(0, 0.25);\n"),
        "{one_left}"
    );
}

#[test]
fn check_warns_about_keys_past_the_end() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "late.rhai", &(base() + "a.at(3.5, [1, 1]);"));
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("check")
        .arg(&scene)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr
            .contains("warning: patch \"a\": \"at\" key(s) at t = 3.5 after the scene's end (1 s)"),
        "{stderr}"
    );
}

#[test]
fn keys_past_the_end_are_warned_about() {
    let scene = load(&(base() + "a.at(3.5, [1, 1]); b.opacity(1, 0.5);"));
    let warnings = scene.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("patch \"a\": \"at\" key(s) at t = 3.5 after the scene's end (1 s)")
    );
}

#[test]
fn ten_thousand_keys_evaluate_like_a_scan() {
    // The lookup is a binary search (`partition_point`); this checks it against a linear
    // scan over a 10 000-key track, at key times, between keys and outside the track.
    let mut track = Track::new();
    let mut reference = Vec::new();
    for i in 0..10_000u32 {
        let (t, v) = (f64::from(i) * 0.01, f64::from(i % 97) - 40.0);
        let easing = Easing::ALL[i as usize % Easing::ALL.len()];
        // Inserted out of order: odd keys first, then even ones.
        reference.push((t, v, easing));
    }
    for &(t, v, e) in reference
        .iter()
        .skip(1)
        .step_by(2)
        .chain(reference.iter().step_by(2))
    {
        track.push(t, v, e).unwrap();
    }
    let scan = |t: f64| -> f64 {
        if t <= reference[0].0 {
            return reference[0].1;
        }
        let last = reference[reference.len() - 1];
        if t >= last.0 {
            return last.1;
        }
        let end = reference.iter().position(|k| k.0 > t).unwrap();
        let (a, b) = (reference[end - 1], reference[end]);
        a.1 + (b.1 - a.1) * b.2.apply((t - a.0) / (b.0 - a.0))
    };
    for j in 0..4_000u32 {
        let t = f64::from(j) * 0.02503 - 1.0;
        assert_eq!(track.value_at(t), Some(scan(t)), "t = {t}");
    }
    let started = std::time::Instant::now();
    let mut sum = 0.0;
    for j in 0..100_000u32 {
        sum += track.value_at(f64::from(j) * 0.000999).unwrap();
    }
    // Reported, not asserted: wall-clock time depends on the machine.
    println!(
        "10 000-key track: {:.1} ns per lookup (checksum {sum})",
        started.elapsed().as_secs_f64() * 1e9 / 100_000.0
    );
}
