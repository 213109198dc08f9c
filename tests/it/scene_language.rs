//! Scene language: parsing, evaluation against closed-form easings, number acceptance,
//! positioned errors, the sandbox and importing scripts/motion.rhai.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use glam::DVec2;
use lapclone::scene::{
    Background, BoundaryData, BoundaryPlacement, CloneMode, Easing, LaplacianKind, Scene, Shape,
};
use lapclone::script::{parse_scene, ErrorKind, Limits, SceneError, ScriptOptions};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn options() -> ScriptOptions {
    ScriptOptions {
        scene_dir: root(),
        scripts_dir: Some(root().join("scripts")),
        limits: Limits::default(),
        cancel: Default::default(),
    }
}

fn scene_file() -> PathBuf {
    root().join("test_scene.rhai")
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    parse_scene(text, &scene_file(), &options()).map(|l| l.scene)
}

fn parse_err(text: &str) -> SceneError {
    match parse(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

const HEAD: &str = r#"canvas(64, 48, #{ fps: 10, duration: 3, background: "assets/coffee.png" });
let p = patch("p", #{ source: "assets/astronaut.png", mask: "assets/horse_mask.png" });
"#;

/// The easing formulas, written out independently of the library.
fn closed_form(easing: Easing, s: f64) -> f64 {
    match easing {
        Easing::Linear => s,
        Easing::Hold => 0.0,
        Easing::EaseIn => s.powi(3),
        Easing::EaseOut => 1.0 - (1.0 - s).powi(3),
        Easing::EaseInOut if s < 0.5 => 4.0 * s.powi(3),
        Easing::EaseInOut => 1.0 - (2.0 - 2.0 * s).powi(3) / 2.0,
        Easing::Smooth => 3.0 * s * s - 2.0 * s.powi(3),
    }
}

#[test]
fn full_scene_parses_with_defaults() {
    let scene = parse(HEAD).unwrap();
    assert_eq!((scene.canvas.width, scene.canvas.height), (64, 48));
    assert_eq!(scene.canvas.fps, 10.0);
    assert_eq!(scene.canvas.frame_count(), 30);
    assert_eq!(
        scene.canvas.background,
        Background::Image(root().join("assets/coffee.png"))
    );
    let p = &scene.patches[0];
    assert_eq!(p.source, root().join("assets/astronaut.png"));
    assert_eq!(p.shape, Shape::Mask(root().join("assets/horse_mask.png")));
    assert_eq!(
        (p.laplacian, p.mode, p.density),
        (LaplacianKind::Combinatorial, CloneMode::Normal, None)
    );
    let state = scene.evaluate(1.0);
    assert_eq!(state.patches[0].position, None);
    assert_eq!(state.patches[0].scale, 1.0);
}

#[test]
fn every_easing_matches_its_formula_between_keys() {
    for easing in Easing::ALL {
        let text = format!(
            "{HEAD}p.key(0.5, #{{ at: [10, 20], rotate: 0, scale: 1 }});\n\
             p.key(2.5, #{{ at: [110, -30], rotate: 90, scale: 3 }}, \"{}\");\n",
            easing.name()
        );
        let scene = parse(&text).unwrap();
        for t in [0.0, 0.5, 0.9, 1.5, 1.73, 2.2, 2.5, 3.0] {
            let s: f64 = ((t - 0.5) / 2.0_f64).clamp(0.0, 1.0);
            let w = if s >= 1.0 {
                1.0
            } else {
                closed_form(easing, s)
            };
            let state = scene.evaluate(t);
            let p = &state.patches[0];
            let expected = DVec2::new(10.0 + 100.0 * w, 20.0 - 50.0 * w);
            assert!(
                (p.position.unwrap() - expected).length() < 1e-12,
                "{easing:?} t={t}"
            );
            assert!((p.rotation - 90.0 * w).abs() < 1e-12, "{easing:?} t={t}");
            assert!(
                (p.scale - (1.0 + 2.0 * w)).abs() < 1e-12,
                "{easing:?} t={t}"
            );
        }
    }
}

#[test]
fn easing_governs_the_segment_ending_at_its_key() {
    let text = format!(
        "{HEAD}p.at(0, [0, 0]);\np.at(1, [10, 0], \"hold\");\np.at(2, [20, 0], \"linear\");\n"
    );
    let scene = parse(&text).unwrap();
    let x = |t: f64| scene.evaluate(t).patches[0].position.unwrap().x;
    assert_eq!(x(0.99), 0.0, "hold keeps the previous value until its key");
    assert_eq!(x(1.0), 10.0);
    assert!((x(1.5) - 15.0).abs() < 1e-12, "the next segment is linear");
}

#[test]
fn integers_and_floats_are_accepted_alike() {
    let ints = parse(&format!("{HEAD}p.key(1, #{{ at: [3, 4], scale: 2, rotate: 45, depth: 1 }});\np.drag([5, 6], 7).key(1, [8, 9]);\np.pin([1, 2], #{{ start: 0, end: 2 }});")).unwrap();
    let floats = parse(&format!("{HEAD}p.key(1.0, #{{ at: [3.0, 4.0], scale: 2.0, rotate: 45.0, depth: 1.0 }});\np.drag([5.0, 6.0], 7.0).key(1.0, [8.0, 9.0]);\np.pin([1.0, 2.0], #{{ start: 0.0, end: 2.0 }});")).unwrap();
    assert_eq!(ints, floats);
    let canvas = parse("canvas(64.0, 48, #{ fps: 12.5, duration: 2 });")
        .unwrap()
        .canvas;
    assert_eq!(
        (canvas.width, canvas.height, canvas.fps, canvas.duration),
        (64, 48, 12.5, 2.0)
    );
}

#[test]
fn handles_pins_and_layers_evaluate() {
    let text = format!(
        "{HEAD}let h = p.drag([10, 10], 20, #{{ depth: 2, pivot: [5, 5] }});\n\
         h.key(0, [10, 10]).key(2, [30, 10], \"linear\");\nh.rotate(1, 30);\n\
         p.pin([1, 1], #{{ start: 1, end: 2 }});\n\
         let q = patch(\"q\", #{{ source: \"assets/astronaut.png\", polygons: [[[0, 0], [10, 0], [0, 10]]] }});\n\
         p.depth(0, 1);\n"
    );
    let scene = parse(&text).unwrap();
    let s = scene.evaluate(1.0);
    let h = s.patches[0].handles[0];
    assert_eq!(h.to, DVec2::new(20.0, 10.0));
    assert_eq!(
        (h.radius, h.depth, h.pivot, h.rotation),
        (20.0, Some(2.0), Some(DVec2::new(5.0, 5.0)), Some(30.0))
    );
    assert_eq!(s.patches[0].pins, vec![DVec2::new(1.0, 1.0)]);
    assert!(scene.evaluate(0.5).patches[0].pins.is_empty());
    assert!(
        scene.evaluate(2.0).patches[0].pins.is_empty(),
        "`until` is exclusive"
    );
    assert_eq!(s.draw_order, vec![1, 0], "higher depth is drawn later");
}

#[test]
fn frames_are_evaluated_at_index_over_fps() {
    let scene = parse(&format!("{HEAD}p.at(0, [0, 0]);\np.at(3, [300, 0]);")).unwrap();
    for i in [0u64, 1, 7, 29] {
        let x = scene.evaluate_frame(i).patches[0].position.unwrap().x;
        assert!((x - 100.0 * (i as f64 / 10.0)).abs() < 1e-9);
    }
    let mut reused = lapclone::scene::FrameState::default();
    scene.evaluate_into(1.25, &mut reused);
    assert_eq!(reused, scene.evaluate(1.25));
}

/// (script, line, column, message fragment)
fn assert_error_at(text: &str, line: usize, column: usize, fragment: &str) {
    let e = parse_err(text);
    assert_eq!(
        (e.line(), e.column()),
        (Some(line), Some(column)),
        "{e}\nfor:\n{text}"
    );
    assert!(
        e.message.contains(fragment),
        "message `{}` lacks `{fragment}`",
        e.message
    );
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("{}:{line}:{column}: ", scene_file().display())),
        "{shown}"
    );
    assert!(
        shown
            .lines()
            .nth(2)
            .is_some_and(|caret| caret.ends_with('^')),
        "{shown}"
    );
}

#[test]
fn bad_inputs_are_positioned() {
    assert_error_at("canvas(64, 48);\nlet x = (1 + ;\n", 2, 14, "syntax error");
    assert_error_at("canvas(64, 48);\n  nosuch(1);\n", 2, 3, "nosuch");
    assert_error_at(
        "canvas(\"wide\", 48);",
        1,
        1,
        "canvas width must be a number",
    );
    assert_error_at("canvas(64, 48, #{ fps: 0 });", 1, 1, "fps must be > 0");
    assert_error_at("canvas(64, 48, #{ fps: -24 });", 1, 1, "fps must be > 0");
    // Past what outputs can state: Y4M wrote `F0:1` for 1e-5 and an overflowed 1e300.
    for fps in ["1e-5", "0.005", "1e300", "1000.5"] {
        let scene = format!("canvas(64, 48, #{{ fps: {fps} }});");
        assert_error_at(&scene, 1, 1, "fps must be between 0.01 and 1000");
    }
    assert_error_at("canvas(0, 48);", 1, 1, "canvas width");
    assert_error_at("canvas(64, -1);", 1, 1, "canvas height");
    assert_error_at("canvas(64, 48, #{ duration: 1.0 / 0.0 });", 1, 1, "finite");
    assert_error_at("canvas(64, 48, #{ fsp: 3 });", 1, 1, "unknown option `fsp`");
    assert_error_at(
        "canvas(64, 48);\nlet p = patch(\"p\", #{ source: \"assets/nope.png\", mask: \"assets/horse_mask.png\" });",
        2, 9, "nope.png",
    );
    assert_error_at(
        &format!("{HEAD}p.key(1, #{{ at: [1, 2] }});\np.remove_key(0.5);"),
        4,
        3,
        "no key at t = 0.5 on patch \"p\"; its keys are at 1",
    );
    assert_error_at(
        &format!("{HEAD}p.at(-1, [0, 0]);"),
        3,
        3,
        "key time must be ≥ 0",
    );
    assert_error_at(
        &format!("{HEAD}p.at(1, [0, 0], \"bouncy\");"),
        3,
        3,
        "unknown easing `bouncy`",
    );
    assert_error_at(&format!("{HEAD}p.at(1, [0, 0.0 / 0.0]);"), 3, 3, "finite");
    assert_error_at(
        &format!("{HEAD}p.at(1, \"here\");"),
        3,
        3,
        "must be a point",
    );
    assert_error_at(&format!("{HEAD}p.scale(1, 0);"), 3, 3, "must be > 0");
    assert_error_at(
        &format!("{HEAD}p.drag([1, 1], -2);"),
        3,
        3,
        "radius must be > 0",
    );
    assert_error_at(
        &format!("{HEAD}\np.drag([1, 1], 2).key(1, [2, 2]).remove_key(0);"),
        4,
        34,
        "no key at t = 0 on handle 0 of patch \"p\"; its keys are at 1",
    );
    assert_error_at(
        "canvas(64, 48);\nlet p = patch(\"p\", #{ source: \"assets/astronaut.png\", mask: \"assets/horse_mask.png\", boundary_sampling: \"pointy\" });",
        2, 9, "unknown boundary data \"pointy\"",
    );
    assert_error_at(
        "canvas(64, 48);\nlet p = patch(\"p\", #{ source: \"assets/astronaut.png\", mask: \"assets/horse_mask.png\", mesh_boundary: \"edges\" });",
        2, 9, "unknown boundary placement \"edges\"",
    );
}

#[test]
fn the_boundary_defaults_to_the_outside_centres_and_can_be_the_cracks() {
    assert_eq!(
        parse(HEAD).unwrap().patches[0].boundary,
        BoundaryPlacement::OutsideCentres
    );
    let text = HEAD.replace(
        "horse_mask.png\"",
        "horse_mask.png\", mesh_boundary: \"cracks\"",
    );
    assert_eq!(
        parse(&text).unwrap().patches[0].boundary,
        BoundaryPlacement::Cracks
    );
}

#[test]
fn boundary_data_defaults_to_the_hat_average_and_can_be_the_vertex_sample() {
    assert_eq!(
        parse(HEAD).unwrap().patches[0].boundary_data,
        BoundaryData::HatAverage
    );
    let text = HEAD.replace(
        "horse_mask.png\"",
        "horse_mask.png\", boundary_sampling: \"vertex\"",
    );
    assert_eq!(
        parse(&text).unwrap().patches[0].boundary_data,
        BoundaryData::Vertex
    );
}

#[test]
fn errors_inside_functions_point_inside_them() {
    let text = format!("{HEAD}fn shift(q) {{\n    q.at(-2, [0, 0]);\n}}\nshift(p);\n");
    let e = parse_err(&text);
    assert_eq!((e.line(), e.column()), (Some(4), Some(7)), "{e}");
}

#[test]
fn a_scene_without_canvas_is_refused() {
    let e = parse_err("let x = 1;");
    assert_eq!(e.kind, ErrorKind::Validation);
    assert!(e.message.contains("no canvas"));
}

#[test]
fn runaway_loop_ends_with_an_error() {
    let e = parse_err("canvas(8, 8);\nloop { }");
    assert_eq!(e.kind, ErrorKind::Limit, "{e}");
}

/// A scene cannot wait or read a clock: the same scene gives the same frames on every
/// run, in bounded time (`sleep(1e9)` hung even a render told to stop).
#[test]
fn sleep_and_timestamp_are_refused() {
    for call in ["sleep(1e9)", "sleep(5)", "timestamp()"] {
        let e = parse_err(&format!("canvas(8, 8);\nlet x = {call};"));
        assert_eq!((e.line(), e.column()), (Some(2), Some(9)), "{e}");
        assert!(e.message.contains("not available in scenes"), "{e}");
    }
}

/// Growing a list by `push` costs Rhai a walk over it at each push, which the operation
/// limit does not count: the time limit stops it with a hint.
#[test]
fn an_evaluation_past_its_time_limit_is_stopped() {
    let options = ScriptOptions {
        limits: Limits {
            max_seconds: 1,
            ..Limits::default()
        },
        ..options()
    };
    let text = "canvas(8, 8);\nlet a = [];\nfor i in 0..1000000 { a.push([1.0, 2.0]); }";
    let e = parse_scene(text, &scene_file(), &options).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Limit, "{e}");
    assert!(e.message.contains("ran for over 1 s"), "{e}");
}

#[test]
fn deep_recursion_ends_with_an_error() {
    let e = parse_err("fn down(n) { down(n + 1) }\ndown(0);");
    assert_eq!(e.kind, ErrorKind::Limit, "{e}");
}

#[test]
fn eval_is_disabled() {
    let e = parse_err("canvas(8, 8);\neval(\"1\");");
    assert!(
        matches!(e.kind, ErrorKind::Syntax | ErrorKind::Runtime),
        "{e}"
    );
}

#[test]
fn cancel_flag_stops_evaluation() {
    let options = options();
    options.cancel.store(true, Ordering::Relaxed);
    let e = parse_scene(
        "canvas(8, 8);\nlet i = 0;\nwhile i < 1000 { i += 1; }",
        &scene_file(),
        &options,
    )
    .unwrap_err();
    assert_eq!(e.kind, ErrorKind::Cancelled, "{e}");
}

#[test]
fn imports_outside_the_allowed_folders_are_refused() {
    for name in ["../etc/passwd", "/etc/passwd", "src/nothing_here", "nope"] {
        let e = parse_err(&format!("import \"{name}\" as x;\ncanvas(8, 8);"));
        assert_eq!((e.line(), e.column()), (Some(1), Some(8)), "{name}: {e}");
    }
}

#[test]
fn scripts_resolve_from_the_scene_folder_too() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("local.rhai"), "fn size() { 32 }").unwrap();
    std::fs::write(dir.path().join("broken.rhai"), "fn size() {\n  1 +\n}").unwrap();
    let options = ScriptOptions {
        scene_dir: dir.path().to_path_buf(),
        ..options()
    };
    let file = dir.path().join("s.rhai");
    let loaded = parse_scene(
        "import \"local\" as l;\ncanvas(l::size(), 16);",
        &file,
        &options,
    )
    .unwrap();
    assert_eq!(loaded.scene.canvas.width, 32);
    let e = parse_scene("import \"broken\" as b;\ncanvas(8, 8);", &file, &options).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Syntax);
    assert!(e.file.ends_with("broken.rhai"), "{e}");
    assert_eq!(e.line(), Some(3), "{e}");
}

#[test]
fn motion_helpers_import_and_produce_keys() {
    let text = format!(
        "import \"motion\" as m;\n{HEAD}p.keys(m::wiggle([32, 24], 5, 1, 0, 2, 0.25));\n\
         let h = p.drag([10, 10], 8);\nh.keys(m::orbit([10, 10], 4, 2, 0, 2, 0.5));\n\
         let q = patch(\"q\", #{{ source: \"assets/astronaut.png\", mask: \"assets/horse_mask.png\" }});\n\
         q.keys(m::bounce([0, 40], [60, 40], 10, 3, 0, 3, 0.1));\nq.keys(m::swing([1, 1], [2, 2], 1, 3.5, 2));"
    );
    let scene = parse(&text).unwrap();
    let wiggle = scene.patches[0].placement.position.keys();
    assert_eq!(wiggle.len(), 9);
    assert_eq!(wiggle.last().unwrap().time, 2.0);
    assert!(wiggle
        .iter()
        .all(|k| (k.value - DVec2::new(32.0, 24.0)).abs().max_element() <= 5.0 + 1e-9));
    let orbit = scene.patches[0].handles[0].to.keys();
    assert!(orbit
        .iter()
        .all(|k| ((k.value - DVec2::new(10.0, 10.0)).length() - 4.0).abs() < 1e-9));
    let keys = scene.patches[1].placement.position.keys();
    let (bounce, swing) = keys.split_at(31);
    assert!(bounce
        .iter()
        .all(|k| k.value.y <= 40.0 && k.value.y >= 30.0 - 1e-9));
    assert_eq!(bounce.last().unwrap().value, DVec2::new(60.0, 40.0));
    let swing_times: Vec<f64> = swing.iter().map(|k| k.time).collect();
    assert_eq!(swing_times, [3.5, 4.0, 4.5, 5.0, 5.5]);
    assert!(swing.iter().all(|k| k.easing == Easing::EaseInOut));
}

/// A motion helper given a step or duration it cannot sample (≤ 0, or too fine) fails with
/// its own words, positioned in the helper and naming the scene's call; before, a negative
/// step silently gave no keys and 0 failed on an overflow inside the helper.
#[test]
fn motion_helpers_refuse_steps_they_cannot_sample() {
    for (args, fragment) in [
        ("0, 1, -0.5", "step must be > 0 seconds, got -0.5"),
        ("0, 1, 0", "step must be > 0 seconds, got 0"),
        (
            "0, 1, 1e-300",
            "step 1e-300 gives more than 10000 keys over 1 s",
        ),
        ("0, -2, 0.5", "duration must be > 0 seconds, got -2"),
        ("0, 0, 0.5", "duration must be > 0 seconds, got 0"),
    ] {
        let text =
            format!("import \"motion\" as m;\n{HEAD}p.keys(m::wiggle([3, 4], 5, 1, {args}));\n");
        let e = parse_err(&text);
        assert!(e.file.ends_with("scripts/motion.rhai"), "{e}");
        assert!(e.message.contains(fragment), "{e}");
        let called_at = format!(
            "(called at {}:{}:",
            scene_file().display(),
            HEAD.lines().count() + 2
        );
        assert!(e.message.ends_with(&format!("{called_at}11)")), "{e}");
    }
}

#[test]
fn failed_call_leaves_the_patch_unchanged() {
    let options = options();
    let engine = lapclone::script::SceneEngine::new(&options);
    let mut scope = rhai::Scope::new();
    let _ = engine.run(&mut scope, HEAD, &scene_file()).unwrap();
    let _ = engine
        .run(
            &mut scope,
            "p.key(1, #{ at: [1, 1], scale: 2 });",
            &scene_file(),
        )
        .unwrap();
    let before = engine.draft();
    // `at` is valid, `scale` is not: neither track may change.
    engine
        .run(
            &mut scope,
            "p.key(2, #{ at: [2, 2], scale: -1 });",
            &scene_file(),
        )
        .unwrap_err();
    assert_eq!(engine.draft(), before);
}

/// A scene's distinct still sources may hold only so many pixels in all, checked from their
/// headers before any is decoded; patches sharing one file count it once.
#[test]
fn a_scene_s_sources_are_bounded_in_all_and_a_shared_one_counts_once() {
    use lapclone::render::Renderer;
    let dir = tempfile::tempdir().unwrap();
    // The head of a 4096×4096 RGB PNG and no pixels: enough to be sized, not decoded.
    let header = |path: &Path| {
        let mut ihdr = b"IHDR".to_vec();
        ihdr.extend_from_slice(&4096u32.to_be_bytes());
        ihdr.extend_from_slice(&4096u32.to_be_bytes());
        ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        png.extend_from_slice(&13u32.to_be_bytes());
        png.extend_from_slice(&ihdr);
        png.extend_from_slice(&crc32(&ihdr).to_be_bytes());
        // An empty IDAT: the decoder reads up to the first one for the image's size.
        png.extend_from_slice(&0u32.to_be_bytes());
        png.extend_from_slice(b"IDAT");
        png.extend_from_slice(&crc32(b"IDAT").to_be_bytes());
        std::fs::write(path, png).unwrap();
    };
    for i in 0..33 {
        header(&dir.path().join(format!("s{i}.png")));
    }
    let scene = |sources: &str| {
        format!(
            "canvas(64, 48);\nfor i in 0..33 {{ patch(\"p\" + i, #{{ source: {sources}, \
             polygons: [[[10, 10], [30, 10], [30, 30]]] }}); }}\n"
        )
    };
    let file = dir.path().join("scene.rhai");
    let options = ScriptOptions::for_scene_file(&file);
    let load = |text: &str| parse_scene(text, &file, &options).unwrap().scene;
    let error = Renderer::new(load(&scene("\"s\" + i + \".png\"")))
        .err()
        .unwrap();
    assert_eq!(error.patch_name(), Some("p32"), "{error}");
    assert!(error.to_string().contains("source images hold"), "{error}");
    // One file for all 33: within the limit, so the decode is what fails (a header only).
    let error = Renderer::new(load(&scene("\"s0.png\""))).err().unwrap();
    assert!(!error.to_string().contains("source images hold"), "{error}");
}

/// The CRC-32 a PNG chunk ends with.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A patch name holding a control or bidirectional formatting character is refused, at the
/// call and on a rename: messages quote names as they are, and a newline split them.
#[test]
fn patch_names_hold_no_control_or_bidi_characters() {
    for name in ["x\\nfake: ok", "a\\u202eb", "tab\\there", "\\u2066"] {
        let text = format!(
            "canvas(8, 8);\nlet p = patch(\"{name}\", #{{ source: \"assets/chelsea.png\", \
             polygons: [[[1, 1], [5, 1], [1, 5]]] }});"
        );
        let e = parse_err(&text);
        assert!(e.message.contains("bidirectional"), "{name}: {e}");
        let text = format!(
            "canvas(8, 8);\nlet p = patch(\"ok\", #{{ source: \"assets/chelsea.png\", \
             polygons: [[[1, 1], [5, 1], [1, 5]]] }});\np.rename(\"{name}\");"
        );
        let e = parse_err(&text);
        assert!(e.message.contains("bidirectional"), "{name}: {e}");
        assert_eq!(e.line(), Some(3), "{e}");
    }
    parse("canvas(8, 8);\npatch(\"日本 ☕ é\", #{ source: \"assets/chelsea.png\", polygons: [[[1, 1], [5, 1], [1, 5]]] });")
        .unwrap();
}

/// Rotations and depths are bounded as positions are: two keys of ±1e308 each finite eased
/// to ∞ between them, reported at the patch's call as "non-finite values at frame 1".
#[test]
fn rotations_and_depths_are_bounded_at_the_call() {
    for (call, what) in [
        ("p.depth(0, 1e308);", "`depth`"),
        ("p.rotate(0.5, -1e10);", "`rotate`"),
        ("p.key(0, #{ rotate: 1e308 });", "`rotate`"),
        ("p.drag([5, 5], 3, #{ depth: 1e300 });", "depth"),
        ("p.drag([5, 5], 3).rotate(0, 1e300);", "handle rotation"),
    ] {
        let e = parse_err(&format!("{HEAD}{call}"));
        assert!(
            e.message.contains(what) && e.message.contains("past"),
            "{call}: {e}"
        );
        assert_eq!(e.line(), Some(HEAD.lines().count() + 1), "{call}: {e}");
    }
    parse(&format!("{HEAD}p.depth(0, 1e9).rotate(1, -1e9);")).unwrap();
}
