//! Fuzzing scene evaluation with proptest (docs/robustness.md): seed scenes (the demo
//! scenes and small ones of our own, on tiny generated images) are mutated — ranges deleted
//! or duplicated, tokens from a dictionary of scene syntax and hostile values inserted,
//! numbers replaced by extreme ones — and run through the whole front end: parse, evaluate,
//! validate, and for small canvases build the renderer and render frames. Nothing may
//! panic; every error must name the scene file (or the imported module it arose in), and syntax, runtime and limit errors must
//! carry a line and column.
//!
//! The small fixed-seed run is part of the normal suite. The long run is opt-in:
//! `LAPCLONE_FUZZ_CASES=20000 cargo test --release --test it fuzz_scene:: -- --ignored`
//! (default 10 000 cases). Crashing inputs found are kept as explicit regression cases below.

use std::path::{Path, PathBuf};

use lapclone::render::Renderer;
use lapclone::script::{parse_scene, validate_scene, ErrorKind, Limits, ScriptOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};

const DICTIONARY: &[&str] = &[
    "(", ")", "[", "]", "{", "}", ";", ",", "\"", "#{", ":", ".", " ", "\n", "//", "/*", "*/",
    "0", "-1", "-0", "0.5", "1e308", "-1e308", "1e-320", "9223372036854775807",
    "99999999999999999999", "0.0 / 0.0", "1.0 / 0.0", "-1.0 / 0.0", "1 / 0", "NaN",
    "\"bouncy\"", "\"smooth\"", "\"hold\"", "\"ease_in_out\"", "\"\"", "\"#12345\"", "\"#ff00ff80\"",
    "let x = ", "p", "q", "h", "= ", "+", "*", "..", "true", "()", "x",
    "p.at(0, [1, 2]);", "p.at(2, [5, 5], \"smooth\");", "p.scale(1, 0);", "p.rotate(0.5, 720);",
    "p.depth(0, -3);", "p.key(0.25, #{ at: [3, 4], scale: 2 });", "p.keys([#{ t: 0.1, at: [1, 1] }]);",
    "let h = p.drag([5, 5], 4); h.key(0.5, [9, 2]);", "p.drag([5, 5], 1e-9);", "p.pin([2, 2]);",
    "p.pin([3, 3], #{ start: 0.5, end: 0.25 });", "get_patch(\"p\")", "get_patch(\"zz\")",
    "loop {}", "while true {}", "fn f(n) { f(n + 1) } f(0);", "import \"motion\" as m;",
    "import \"../x\" as y;", "canvas(8, 8);", "canvas(24, 20, #{ fps: 0.001 });",
    "canvas(3, 2, #{ duration: 1e-9 });",
    "patch(\"q\", #{ source: \"src.png\", polygons: [[[0, 0], [5, 0], [0, 5]]] });",
    "patch(\"r\", #{ source: \"src.png\", mask: \"mask.png\", feather: 3 });",
    "patch(\"s\", #{ source: \"src.png\", polygons: [#{ outer: [[0, 0], [9, 0], [9, 9], [0, 9]], holes: [[[3, 3], [6, 3], [6, 6]]] }] });",
    "polygons: [[[1, 1], [1, 1], [1, 1]]]", "density: 0.05", "density: 1e9", "mode: \"monochrome\"",
    "laplacian: \"cotangent\"", "[[0, 0], [1e300, 0], [0, 1e300]]",
];

const EXTREME_NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-308",
    "0.0 / 0.0",
    "1.0 / 0.0",
    "4294967296",
    "65536",
    "16384",
    "0.0001",
];

/// Seed scenes of our own (tiny canvases, so they also render).
const SEEDS: &[&str] = &[
    "canvas(24, 20, #{ fps: 4, duration: 1, background: \"tgt.png\" });\n\
     let p = patch(\"p\", #{ source: \"src.png\", mask: \"mask.png\" });\n\
     p.at(0, [12, 10]).at(1, [14, 9], \"smooth\");\n\
     p.scale(0.5, 1.2).rotate(1, 30, \"ease_in\");\n",
    "canvas(24, 20, #{ fps: 6, duration: 0.5, background: [0.2, 0.3, 0.4] });\n\
     let p = patch(\"p\", #{ source: \"src.png\", polygons: [[[2, 2], [20, 3], [8, 17]]], density: 2 });\n\
     let h = p.drag([12, 6], 5);\n\
     h.key(0, [12, 6]).key(0.5, [15, 8], \"hold\");\n\
     p.pin([4, 4], #{ start: 0, end: 0.25 });\n",
    "import \"motion\" as m;\n\
     canvas(24, 20, #{ fps: 4, duration: 1, background: \"#203040\" });\n\
     let a = patch(\"a\", #{ source: \"src.png\", mask: \"mask.png\", mode: \"monochrome\" });\n\
     let b = patch(\"b\", #{ source: \"src.png\", polygons: [#{ outer: [[1, 1], [22, 1], [22, 18], [1, 18]], holes: [[[8, 6], [14, 6], [14, 12], [8, 12]]] }] });\n\
     a.keys(m::wiggle([12, 10], 3, 1, 0, 1, 0.25));\n\
     b.depth(0, 1).at(0, [10, 10]).at(1, [30, 10]);\n",
];

#[derive(Clone, Debug)]
enum Mutation {
    Delete { at: f64, len: usize },
    Insert { at: f64, token: usize },
    Duplicate { at: f64, len: usize },
    ReplaceNumber { nth: usize, with: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0.0..1.0f64, 1usize..24).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (0.0..1.0f64, 0..DICTIONARY.len()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        (0.0..1.0f64, 1usize..40).prop_map(|(at, len)| Mutation::Duplicate { at, len }),
        (0usize..64, 0..EXTREME_NUMBERS.len())
            .prop_map(|(nth, with)| Mutation::ReplaceNumber { nth, with }),
    ]
}

/// A byte offset on a char boundary near `fraction` of the text.
fn boundary(text: &str, fraction: f64) -> usize {
    let mut at = ((text.len() as f64) * fraction) as usize;
    while at < text.len() && !text.is_char_boundary(at) {
        at += 1;
    }
    at.min(text.len())
}

fn apply(text: &mut String, mutation: &Mutation) {
    match *mutation {
        Mutation::Delete { at, len } => {
            let start = boundary(text, at);
            let end = boundary(text, (start + len) as f64 / text.len().max(1) as f64);
            text.replace_range(start..end.max(start), "");
        }
        Mutation::Insert { at, token } => {
            let at = boundary(text, at);
            text.insert_str(at, DICTIONARY[token]);
        }
        Mutation::Duplicate { at, len } => {
            let start = boundary(text, at);
            let end = boundary(text, (start + len) as f64 / text.len().max(1) as f64).max(start);
            let copy = text[start..end].to_string();
            text.insert_str(end, &copy);
        }
        Mutation::ReplaceNumber { nth, with } => {
            let numbers: Vec<(usize, usize)> = number_spans(text);
            if let Some(&(start, end)) = numbers.get(nth % numbers.len().max(1)) {
                text.replace_range(start..end, EXTREME_NUMBERS[with]);
            }
        }
    }
}

fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// A folder with the seed scenes' images, `scripts/motion.rhai`, and the demo scenes'
/// assets replaced by tiny images of the same names.
struct World {
    dir: tempfile::TempDir,
    seeds: Vec<String>,
}

impl World {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        let scenes = root.join("scenes");
        std::fs::create_dir_all(&scenes).unwrap();
        std::fs::create_dir_all(root.join("scripts")).unwrap();
        std::fs::create_dir_all(root.join("assets/masks")).unwrap();
        let project = Path::new(env!("CARGO_MANIFEST_DIR"));
        for script in ["motion.rhai", "shapes.rhai"] {
            std::fs::copy(
                project.join("scripts").join(script),
                root.join("scripts").join(script),
            )
            .unwrap();
        }
        write_tiny_images(&scenes);
        let mut seeds: Vec<String> = SEEDS.iter().map(|s| s.to_string()).collect();
        for entry in std::fs::read_dir(project.join("scenes")).unwrap() {
            // Scene files only: scenes/goldens/ holds their golden frames.
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "rhai") {
                continue;
            }
            let text = std::fs::read_to_string(path).unwrap();
            for path in quoted_png_paths(&text) {
                let target = scenes.join(&path);
                if let Some(parent) = target.parent() {
                    std::fs::create_dir_all(parent).unwrap();
                }
                if !target.exists() {
                    std::fs::copy(scenes.join("mask_white.png"), &target).unwrap();
                }
            }
            seeds.push(text);
        }
        World { dir, seeds }
    }

    fn scene_path(&self) -> PathBuf {
        self.dir.path().join("scenes").join("fuzz.rhai")
    }
}

/// 16 × 16 images: every asset of a demo scene becomes one of these, so masks match sources.
fn write_tiny_images(dir: &Path) {
    let side = 24;
    image::RgbImage::from_fn(side, 20, |x, y| {
        image::Rgb([(x * 9) as u8, (y * 11) as u8, 77])
    })
    .save(dir.join("src.png"))
    .unwrap();
    image::RgbImage::from_fn(24, 20, |x, y| {
        image::Rgb([90, (x * 5) as u8, (y * 7) as u8])
    })
    .save(dir.join("tgt.png"))
    .unwrap();
    image::GrayImage::from_fn(24, 20, |x, y| {
        let (dx, dy) = (x as i32 - 12, y as i32 - 10);
        image::Luma([if dx * dx + dy * dy < 40 { 255 } else { 0 }])
    })
    .save(dir.join("mask.png"))
    .unwrap();
    image::GrayImage::from_pixel(24, 20, image::Luma([255]))
        .save(dir.join("mask_white.png"))
        .unwrap();
}

fn quoted_png_paths(text: &str) -> Vec<String> {
    text.split('"')
        .skip(1)
        .step_by(2)
        .filter(|s| s.ends_with(".png") || s.ends_with(".jpg"))
        .map(|s| s.to_string())
        .collect()
}

/// How far a mutated scene got.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Outcome {
    /// Parsing, running or validating it failed with a well-formed error.
    Refused,
    /// Valid, but too large to render here or refused by the renderer.
    NotRendered,
    /// Frames rendered (each of the canvas's size) or failed with a message.
    Rendered,
}

/// Runs one mutated scene through the front end; an `Err` is a finding.
fn check(world: &World, text: &str) -> Result<Outcome, TestCaseError> {
    let file = world.scene_path();
    let options = ScriptOptions {
        // Small enough that runaway loops end quickly, large enough for the seeds.
        limits: Limits {
            max_operations: 200_000,
            ..Limits::default()
        },
        ..ScriptOptions::for_scene_file(&file)
    };
    let loaded = match parse_scene(text, &file, &options) {
        Ok(loaded) => loaded,
        Err(error) => return check_error(&file, &error).map(|()| Outcome::Refused),
    };
    if let Err(error) = validate_scene(&loaded) {
        return check_error(&file, &error).map(|()| Outcome::Refused);
    }
    let canvas = &loaded.scene.canvas;
    if u64::from(canvas.width) * u64::from(canvas.height) > 64 * 64 {
        return Ok(Outcome::NotRendered);
    }
    let mut renderer = match Renderer::new(loaded.scene.clone()) {
        Ok(renderer) => renderer,
        Err(error) => {
            // A refusal names the patch it is about, when it is about one.
            let names: Vec<&str> = loaded
                .scene
                .patches
                .iter()
                .map(|p| p.name.as_str())
                .collect();
            let named = error.patch_name().is_none_or(|n| names.contains(&n));
            prop_assert!(named, "{error} names no patch of {names:?}");
            return Ok(Outcome::NotRendered);
        }
    };
    prop_assert_eq!(renderer.frame_count(), canvas.frame_count());
    let last = renderer.frame_count() - 1;
    for index in [0, last / 2, last] {
        match renderer.render_frame(index) {
            Ok(frame) => prop_assert_eq!(
                (frame.width(), frame.height()),
                (canvas.width, canvas.height),
                "frame {} of a {}×{} canvas",
                index,
                canvas.width,
                canvas.height
            ),
            Err(error) => prop_assert!(!error.to_string().is_empty(), "an empty error"),
        }
    }
    Ok(Outcome::Rendered)
}

fn check_error(file: &Path, error: &lapclone::script::SceneError) -> Result<(), TestCaseError> {
    let shown = error.to_string();
    // Errors inside an imported module name that module's file (and position) instead.
    let named = shown.starts_with(&file.display().to_string())
        || (error.file.is_file() && shown.starts_with(&error.file.display().to_string()))
        || matches!(error.kind, ErrorKind::Validation);
    prop_assert!(named, "error does not name the scene: {}", shown);
    if matches!(
        error.kind,
        ErrorKind::Syntax | ErrorKind::Runtime | ErrorKind::Limit
    ) {
        prop_assert!(
            error.line().is_some(),
            "{:?} error without a position: {}",
            error.kind,
            shown
        );
    }
    Ok(())
}

fn scene_strategy(seeds: usize) -> impl Strategy<Value = (usize, Vec<Mutation>)> {
    (0..seeds, prop::collection::vec(mutation(), 0..6))
}

/// Runs `cases` mutated scenes; gives how many ended each way.
fn run(world: &World, cases: u32, seed: u64) -> std::collections::BTreeMap<String, u32> {
    let config = Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner = TestRunner::new(config);
    let tally = std::cell::RefCell::new(std::collections::BTreeMap::new());
    let outcome = runner.run(&scene_strategy(world.seeds.len()), |(seed, mutations)| {
        let mut text = world.seeds[seed].clone();
        for m in &mutations {
            apply(&mut text, m);
        }
        // For hunting inputs that kill the process (out of memory): the last case run.
        if let Ok(trace) = std::env::var("LAPCLONE_FUZZ_TRACE") {
            let _ = std::fs::write(trace, &text);
        }
        let outcome = check(world, &text)
            .map_err(|e| TestCaseError::fail(format!("{e}\n--- scene ---\n{text}")))?;
        *tally
            .borrow_mut()
            .entry(format!("{outcome:?}"))
            .or_insert(0) += 1;
        Ok(())
    });
    if let Err(e) = outcome {
        panic!("{e}");
    }
    tally.into_inner()
}

#[test]
fn every_seed_scene_is_valid_before_mutation() {
    let world = World::new();
    for text in &world.seeds {
        let file = world.scene_path();
        let loaded = parse_scene(text, &file, &ScriptOptions::for_scene_file(&file));
        let loaded = loaded.unwrap_or_else(|e| panic!("{e}\n{text}"));
        validate_scene(&loaded).unwrap_or_else(|e| panic!("{e}\n{text}"));
    }
}

/// Inputs the fuzzer found failing, kept as explicit cases (docs/robustness.md).
#[test]
fn regressions_found_by_fuzzing() {
    let world = World::new();
    let found = [
        // A polygon vertex at 1e308 px: the boundary subdivision allocated until the
        // process was killed for lack of memory.
        "canvas(24, 20, #{ fps: 4, duration: 1, background: \"#203040\" });\n\
         let b = patch(\"b\", #{ source: \"src.png\", polygons: [#{ outer: [[1, 1], [1e308, 1], [22, 18], [1, 18]], holes: [[[8, 6], [14, 6], [14, 12], [8, 12]]] }] });\n",
        // An error inside an imported module names the module, not the scene.
        "import \"shapes\" as s;\ncanvas(24, 20);\nlet r = patch(\"r\", #{ source: \"src.png\", polygons: [#{ outer: s::circle(10, 10, 8, 1e308) }] });\n",
    ];
    for text in found {
        let outcome = check(&world, text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_ne!(outcome, Outcome::Rendered, "{text}");
    }
    let file = world.scene_path();
    let loaded = parse_scene(found[0], &file, &ScriptOptions::for_scene_file(&file)).unwrap();
    let error = Renderer::new(loaded.scene)
        .err()
        .expect("a 1e308 px polygon must be refused");
    assert!(error.to_string().contains("beyond"), "{error}");
}

#[test]
fn mutated_scenes_small_fixed_seed() {
    let world = World::new();
    let tally = run(&world, 48, 0x5ce7e);
    eprintln!("fuzz_scene: {tally:?}");
    assert_eq!(tally.values().sum::<u32>(), 48, "every case ran: {tally:?}");
    // The fixed seed reaches both ends: scenes refused with positioned errors, and frames.
    assert!(tally.get("Refused").is_some_and(|&n| n > 0), "{tally:?}");
    assert!(tally.get("Rendered").is_some_and(|&n| n > 0), "{tally:?}");
}

#[test]
#[ignore = "long fuzz run: cargo test --release --test it fuzz_scene:: -- --ignored"]
fn mutated_scenes_long() {
    let world = World::new();
    let cases: u32 = std::env::var("LAPCLONE_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000);
    let seed: u64 = std::env::var("LAPCLONE_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0xf022_5ce7);
    let tally = run(&world, cases, seed);
    eprintln!("fuzz_scene: {tally:?} (seed {seed})");
    assert_eq!(
        tally.values().sum::<u32>(),
        cases,
        "every case ran: {tally:?}"
    );
}
