//! The hostile-input catalogue (docs/robustness.md): the real `lapclone` binary over a table
//! of bad and odd inputs, generated in a temporary folder at test time. Every failing case
//! must exit with its code (1 failure, 2 usage), say what was wrong (a substring of stderr),
//! never print panic text, and leave the folder exactly as it was (no output, no temporary
//! file). Odd but valid masks (full, touching every border, 1 px wide, speckled,
//! checkerboard) must succeed and clone every mask pixel.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const W: u32 = 24;
const H: u32 = 20;

/// A temporary working folder: `in/` holds the inputs, `out/` is where outputs go.
struct Fixture {
    root: tempfile::TempDir,
}

impl Fixture {
    fn new() -> Self {
        let root = tempfile::tempdir().unwrap();
        for dir in ["in", "out", "scenes"] {
            std::fs::create_dir(root.path().join(dir)).unwrap();
        }
        let fixture = Fixture { root };
        fixture.write_images();
        fixture
    }

    fn path(&self, relative: &str) -> PathBuf {
        self.root.path().join(relative)
    }

    fn run(&self, args: &[String]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .args(args)
            .current_dir(self.root.path())
            .env("RUST_BACKTRACE", "0")
            .output()
            .unwrap()
    }

    fn write_images(&self) {
        let source = image::RgbImage::from_fn(W, H, |x, y| {
            image::Rgb([
                (40 + x * 7 + y * 3) as u8,
                (200 - x * 5 + (x * y) % 13) as u8,
                (90 + y * 6) as u8,
            ])
        });
        source.save(self.path("in/src.png")).unwrap();
        // The source's colours, fully transparent: an in-place clone onto it must give the
        // source back, opaque exactly where it cloned.
        image::RgbaImage::from_fn(W, H, |x, y| {
            let [r, g, b] = source.get_pixel(x, y).0;
            image::Rgba([r, g, b, 0])
        })
        .save(self.path("in/clear.png"))
        .unwrap();
        image::RgbImage::from_fn(32, 28, |x, y| {
            image::Rgb([(x * 8) as u8, (y * 9) as u8, 120])
        })
        .save(self.path("in/tgt.png"))
        .unwrap();
        save_mask(&self.path("in/mask.png"), &disc());
        save_mask(&self.path("in/empty.png"), &Mask::new(W, H, |_, _| false));
        save_mask(
            &self.path("in/one_pixel.png"),
            &Mask::new(W, H, |x, y| (x, y) == (5, 5)),
        );
        save_mask(&self.path("in/small.png"), &Mask::new(10, 10, |_, _| true));
        for (name, mask) in odd_masks() {
            save_mask(&self.path(&format!("in/{name}.png")), &mask);
        }
        let valid = std::fs::read(self.path("in/src.png")).unwrap();
        for (name, len) in [
            ("trunc8", 8),
            ("trunc33", 33),
            ("trunc_half", valid.len() / 2),
        ] {
            std::fs::write(self.path(&format!("in/{name}.png")), &valid[..len]).unwrap();
        }
        let last = valid.len() - 12; // drop the IEND chunk only
        std::fs::write(self.path("in/no_iend.png"), &valid[..last]).unwrap();
        std::fs::write(self.path("in/zero.png"), b"").unwrap();
        std::fs::write(self.path("in/text.png"), "this is not a picture\n").unwrap();
        std::fs::create_dir(self.path("in/folder.png")).unwrap();
        write_zero_grey_png(&self.path("in/huge.png"), 20_000, 20_000);
        write_zero_grey_png(&self.path("in/wide.png"), 20_000, 3);
        write_png_header_only(&self.path("in/header.png"), i32::MAX as u32, 1);
    }

    /// Every file and folder under the root with its size (folders: 0).
    fn snapshot(&self) -> BTreeMap<PathBuf, u64> {
        let mut files = BTreeMap::new();
        let mut stack = vec![self.root.path().to_path_buf()];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let entry = entry.unwrap();
                let meta = std::fs::symlink_metadata(entry.path()).unwrap();
                let relative = entry.path().strip_prefix(self.root.path()).unwrap().into();
                if meta.is_dir() {
                    stack.push(entry.path());
                    files.insert(relative, 0);
                } else {
                    files.insert(relative, meta.len());
                }
            }
        }
        files
    }

    fn scene(&self, name: &str, body: &str) -> String {
        let path = format!("scenes/{name}.rhai");
        std::fs::write(self.path(&path), body).unwrap();
        path
    }
}

/// One failing case of the catalogue.
struct Case {
    args: Vec<String>,
    code: i32,
    message: String,
}

fn case(args: &[&str], code: i32, message: &str) -> Case {
    Case {
        args: args.iter().map(|s| s.to_string()).collect(),
        code,
        message: message.to_string(),
    }
}

/// Runs every case and fails once, listing every case that misbehaved.
fn run_catalogue(fixture: &Fixture, cases: &[Case]) {
    let before = fixture.snapshot();
    let mut problems = Vec::new();
    for case in cases {
        let output = fixture.run(&case.args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        let stdout = String::from_utf8_lossy(&output.stdout);
        let mut wrong = Vec::new();
        if output.status.code() != Some(case.code) {
            wrong.push(format!(
                "exit {:?} (wanted {})",
                output.status.code(),
                case.code
            ));
        }
        // Only the message lines count: a scene error also echoes the source line.
        let messages: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("lapclone:") || l.starts_with("error:"))
            .collect();
        if !messages.iter().any(|l| l.contains(&case.message)) {
            wrong.push(format!("no `{}` in the message", case.message));
        }
        // A cause is named once (typed errors end with their cause's text already).
        for line in &messages {
            let parts: Vec<&str> = line.split(": ").filter(|p| p.len() >= 8).collect();
            if parts
                .iter()
                .enumerate()
                .any(|(k, p)| parts[..k].contains(p))
            {
                wrong.push(format!("a repeated cause in `{line}`"));
            }
        }
        if (stderr.clone() + stdout.clone()).contains("panicked")
            || stderr.contains("RUST_BACKTRACE")
        {
            wrong.push("panic text".into());
        }
        let after = fixture.snapshot();
        if after != before {
            let extra: Vec<_> = after.keys().filter(|k| !before.contains_key(*k)).collect();
            wrong.push(format!("files changed: {extra:?}"));
            // Clean up so that the next case starts from the same folder.
            for path in extra.iter().rev() {
                let path = fixture.root.path().join(path);
                let _ = std::fs::remove_file(&path).or_else(|_| std::fs::remove_dir_all(&path));
            }
        }
        if !wrong.is_empty() {
            problems.push(format!(
                "{:?}: {}\n    stderr: {}",
                case.args,
                wrong.join("; "),
                stderr.trim()
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "{} of {} cases misbehaved:\n{}",
        problems.len(),
        cases.len(),
        problems.join("\n")
    );
    eprintln!("{} catalogue cases passed", cases.len());
}

/// `lapclone clone` with the usual inputs and `replace` substituted for flags of that name.
fn clone_args(replace: &[(&str, &str)]) -> Vec<String> {
    let mut args: Vec<String> = [
        "clone",
        "--source",
        "in/src.png",
        "--mask",
        "in/mask.png",
        "--target",
        "in/tgt.png",
        "--at",
        "16,14",
        "-o",
        "out/o.png",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for (flag, value) in replace {
        match args.iter().position(|a| a == flag) {
            Some(i) => args[i + 1] = value.to_string(),
            None => args.extend([flag.to_string(), value.to_string()]),
        }
    }
    args
}

fn clone_case(replace: &[(&str, &str)], code: i32, message: &str) -> Case {
    Case {
        args: clone_args(replace),
        code,
        message: message.to_string(),
    }
}

#[test]
fn unreadable_images_fail_with_their_name() {
    let fixture = Fixture::new();
    let mut cases = Vec::new();
    let broken = [
        ("in/missing.png", "in/missing.png"),
        ("in/zero.png", "in/zero.png"),
        ("in/text.png", "in/text.png"),
        ("in/folder.png", "in/folder.png"),
        ("in/trunc8.png", "in/trunc8.png"),
        ("in/trunc33.png", "in/trunc33.png"),
        ("in/trunc_half.png", "in/trunc_half.png"),
    ];
    for (file, message) in broken {
        for flag in ["--source", "--mask", "--target"] {
            cases.push(clone_case(&[(flag, file)], 1, message));
        }
        cases.push(case(&["mesh", file, "--stats"], 1, message));
    }
    // Mismatched sizes: a mask that is not the source's size (without an offset).
    cases.push(clone_case(
        &[("--mask", "in/small.png")],
        1,
        "mask is 10×10 but the source is 24×20",
    ));
    // Masks with nothing to clone.
    cases.push(clone_case(
        &[("--mask", "in/empty.png")],
        1,
        "no inside pixels",
    ));
    cases.push(case(&["mesh", "in/empty.png"], 1, "no inside pixels"));
    cases.push(clone_case(
        &[("--mask", "in/one_pixel.png")],
        1,
        "minimum piece area",
    ));
    run_catalogue(&fixture, &cases);
}

#[test]
fn images_over_the_size_limit_are_refused_before_decoding() {
    let fixture = Fixture::new();
    let limit = "exceeds the size limit";
    let mut cases = vec![
        case(
            &["mesh", "in/huge.png"],
            1,
            "20000×20000 image exceeds the size limit",
        ),
        case(&["mesh", "in/wide.png", "--stats"], 1, limit),
        clone_case(&[("--mask", "in/huge.png")], 1, limit),
        clone_case(&[("--source", "in/huge.png")], 1, limit),
        clone_case(&[("--target", "in/huge.png")], 1, limit),
        clone_case(&[("--target", "in/wide.png")], 1, limit),
        // A header past what the decoder would allocate is refused by the same rule.
        clone_case(
            &[("--target", "in/header.png")],
            1,
            "2147483647×1 image exceeds the size limit",
        ),
    ];
    let background = fixture.scene(
        "huge_background",
        "canvas(32, 28, #{ background: \"../in/huge.png\" });\n",
    );
    let source = fixture.scene(
        "huge_source",
        "canvas(32, 28);\npatch(\"p\", #{ source: \"../in/huge.png\", polygons: [[[1, 1], [9, 1], [1, 9]]] });\n",
    );
    let mask = fixture.scene(
        "huge_mask",
        "canvas(32, 28);\npatch(\"p\", #{ source: \"../in/src.png\", mask: \"../in/huge.png\" });\n",
    );
    for scene in [&background, &source, &mask] {
        cases.push(case(&["check", scene], 1, limit));
        cases.push(case(&["render", scene, "-o", "out/frames"], 1, limit));
    }
    let canvas = fixture.scene("huge_canvas", "canvas(16384, 16384);\n");
    cases.push(case(&["check", &canvas], 1, limit));
    let frames = fixture.scene("endless", "canvas(8, 8, #{ fps: 1000, duration: 1e9 });\n");
    cases.push(case(
        &["check", &frames],
        1,
        "duration 1e9 s at 1000 fps is 1e12 frames, over the limit of 1000000 frames",
    ));
    // A product past 2^64 is named, not the count it saturates to.
    let far = fixture.scene("far", "canvas(8, 8, #{ fps: 24, duration: 1e300 });\n");
    cases.push(case(
        &["check", &far],
        1,
        "is 2.4e301 frames, over the limit",
    ));
    run_catalogue(&fixture, &cases);
}

#[test]
fn every_numeric_flag_refuses_nan_infinity_and_bad_signs() {
    let fixture = Fixture::new();
    let mut cases = Vec::new();
    let not_finite = ["NaN", "nan", "inf", "-inf", "infinity", "1e999"];
    for value in not_finite {
        for flag in [
            "--scale",
            "--rotate",
            "--density",
            "--threshold",
            "--feather",
        ] {
            cases.push(clone_case(&[(flag, value)], 2, "finite"));
        }
        let point = format!("{value},3");
        let point_y = format!("3,{value}");
        for flag in ["--at", "--mask-offset", "--pin"] {
            cases.push(clone_case(&[(flag, &point)], 2, "finite"));
            cases.push(clone_case(&[(flag, &point_y)], 2, "finite"));
        }
        for drag in [
            format!("{value},4:5,6"),
            format!("4,4:{value},6"),
            format!("4,4:5,6:{value}"),
        ] {
            cases.push(clone_case(&[("--drag", &drag)], 2, "finite"));
        }
        for flag in ["--density", "--min-angle", "--threshold"] {
            cases.push(case(&["mesh", "in/mask.png", flag, value], 2, "finite"));
        }
        cases.push(case(
            &["preview", "s.rhai", "--t", value, "-o", "out/p.png"],
            2,
            "finite",
        ));
    }
    for value in ["-1", "0", "-0"] {
        cases.push(clone_case(
            &[("--scale", value)],
            2,
            "must be > 0 and at most 1e6",
        ));
        cases.push(clone_case(
            &[("--density", value)],
            2,
            "--density must be positive",
        ));
        cases.push(clone_case(
            &[("--drag", &format!("4,4:5,6:{value}"))],
            2,
            "radius must be positive",
        ));
        cases.push(case(
            &["mesh", "in/mask.png", "--density", value],
            2,
            "density",
        ));
        cases.push(case(
            &["mesh", "in/mask.png", "--max-vertices", value],
            2,
            "max",
        ));
        cases.push(case(&["render", "s.rhai", "--jobs", value], 2, "jobs"));
        cases.push(case(
            &["preview", "s.rhai", "--frame", value, "-o", "out/p.png"],
            2,
            "frame",
        ));
    }
    cases.extend([
        clone_case(
            &[("--threshold", "-1")],
            2,
            "--threshold must lie in [0, 1]",
        ),
        clone_case(
            &[("--threshold", "1.5")],
            2,
            "--threshold must lie in [0, 1]",
        ),
        clone_case(
            &[("--feather", "-1")],
            2,
            "--feather must lie in [0, 65536]",
        ),
        clone_case(
            &[("--feather", "4e9")],
            2,
            "--feather must lie in [0, 65536]",
        ),
        clone_case(&[("--density", "0.01")], 2, "density"),
        clone_case(&[("--at", "3")], 2, "is not a point"),
        // Positions and scales have the bounds a scene's have (`lapclone::limits`).
        clone_case(
            &[("--scale", "1e300")],
            2,
            "--scale: 1e300 must be > 0 and at most 1e6",
        ),
        clone_case(&[("--at", "1e300,4")], 2, "1e300 is past ±1e9 px"),
        clone_case(&[("--pin", "4,-2e9")], 2, "-2e9 is past ±1e9 px"),
        clone_case(&[("--mask-offset", "1e10,0")], 2, "1e10 is past ±1e9 px"),
        clone_case(&[("--drag", "4,4:1e300,6")], 2, "1e300 is past ±1e9 px"),
        clone_case(
            &[("--threshold", "1e300")],
            2,
            "--threshold must lie in [0, 1], not 1e300",
        ),
        case(
            &["mesh", "in/mask.png", "--density", "1e-300"],
            2,
            "got 1e-300",
        ),
        clone_case(&[("--drag", "1,2")], 2, "is not a drag"),
        case(
            &["mesh", "in/mask.png", "--threshold", "-1"],
            2,
            "threshold",
        ),
        case(
            &["mesh", "in/mask.png", "--min-angle", "-1"],
            2,
            "min angle",
        ),
        case(
            &["mesh", "in/mask.png", "--min-angle", "60"],
            2,
            "min angle",
        ),
        case(&["mesh", "in/mask.png", "--density", "0.01"], 2, "density"),
        case(
            &["mesh", "in/mask.png", "--max-vertices", "2"],
            2,
            "max_vertices",
        ),
        case(&["render", "s.rhai", "--jobs", "NaN"], 2, "jobs"),
        case(&["render", "s.rhai", "--frames", "0..2"], 2, "1 ≤ A ≤ B"),
        case(&["render", "s.rhai", "--frames", "5..2"], 2, "1 ≤ A ≤ B"),
        case(&["render", "s.rhai", "--frames", "-1..2"], 2, "frame"),
        case(
            &["preview", "s.rhai", "--t", "-1", "-o", "out/p.png"],
            2,
            "--t must be ≥ 0",
        ),
        // A negative number is the flag's value, refused by its own rule, not an unknown
        // argument.
        case(
            &["mesh", "in/mask.png", "--relax", "-1"],
            2,
            "'-1' for '--relax",
        ),
        case(&["test", "s.rhai", "--fail", "-1"], 2, "must be ≥ 0"),
        case(
            &["test", "s.rhai", "--fail-percent", "-1"],
            2,
            "'-1' for '--fail-percent",
        ),
        case(&["test", "s.rhai", "--hard-fail", "-1"], 2, "must be ≥ 0"),
        case(
            &["test", "s.rhai", "--min-ssim", "-1"],
            2,
            "must be in 0..=1",
        ),
        case(
            &["render", "s.rhai", "--crf", "-1"],
            2,
            "-1 is not in 0..=63",
        ),
    ]);
    run_catalogue(&fixture, &cases);
}

#[test]
fn outputs_into_missing_or_unwritable_places_fail_cleanly() {
    let fixture = Fixture::new();
    let scene = fixture.scene("ok", &tiny_scene());
    let mut cases = vec![
        clone_case(&[("-o", "out/missing/o.png")], 1, "does not exist"),
        clone_case(
            &[("-o", "out/missing/o.png"), ("--show-mesh", "")],
            1,
            "does not exist",
        ),
        case(
            &["mesh", "in/mask.png", "-o", "out/missing/m.png"],
            1,
            "out/missing/m.png",
        ),
        case(
            &[
                "mesh",
                "in/mask.png",
                "--laplacian-out",
                "out/missing/L.mtx",
            ],
            1,
            "out/missing/L.mtx",
        ),
        case(
            &["preview", &scene, "-o", "out/missing/p.png"],
            1,
            "does not exist",
        ),
        case(
            &["render", &scene, "-o", "out/missing/frames"],
            1,
            "does not exist",
        ),
        case(
            &[
                "render",
                &scene,
                "--format",
                "gif",
                "-o",
                "out/missing/a.gif",
            ],
            1,
            "does not exist",
        ),
        case(
            &[
                "render",
                &scene,
                "--format",
                "apng",
                "-o",
                "out/missing/a.png",
            ],
            1,
            "does not exist",
        ),
        // The output names an existing folder: the rename fails and the temp file goes.
        clone_case(&[("-o", "in/folder.png")], 1, "in/folder.png"),
        case(
            &["preview", &scene, "-o", "in/folder.png"],
            1,
            "in/folder.png",
        ),
        case(
            &["render", &scene, "--format", "gif", "-o", "in/folder.png"],
            1,
            "in/folder.png",
        ),
        case(&["render", &scene, "-o", "in/src.png"], 1, "in/src.png"),
    ];
    // `--show-mesh` takes no value: drop the empty string the helper appended.
    cases[1].args.retain(|a| !a.is_empty());
    if read_only_folders_are_enforced(&fixture.path("in/ro_probe")) {
        let ro = fixture.path("out/ro");
        std::fs::create_dir(&ro).unwrap();
        set_read_only(&ro, true);
        cases.extend([
            clone_case(&[("-o", "out/ro/o.png")], 1, "out/ro/o.png"),
            case(
                &["mesh", "in/mask.png", "-o", "out/ro/m.png"],
                1,
                "out/ro/m.png",
            ),
            case(
                &["preview", &scene, "-o", "out/ro/p.png"],
                1,
                "out/ro/p.png",
            ),
            case(
                &["render", &scene, "-o", "out/ro/frames"],
                1,
                "out/ro/frames",
            ),
            case(
                &["render", &scene, "--format", "apng", "-o", "out/ro/a.png"],
                1,
                "out/ro/a.png",
            ),
        ]);
        run_catalogue(&fixture, &cases);
        set_read_only(&ro, false);
    } else {
        eprintln!("read-only folder cases skipped: running as a user who can write anyway (root)");
        run_catalogue(&fixture, &cases);
    }
}

/// Whether a folder without write permission really refuses writes (it does not for root).
fn read_only_folders_are_enforced(probe_dir: &Path) -> bool {
    std::fs::create_dir(probe_dir).unwrap();
    set_read_only(probe_dir, true);
    let refused = std::fs::write(probe_dir.join("probe"), b"x").is_err();
    set_read_only(probe_dir, false);
    let _ = std::fs::remove_file(probe_dir.join("probe"));
    std::fs::remove_dir(probe_dir).unwrap();
    refused
}

fn set_read_only(dir: &Path, read_only: bool) {
    let mut permissions = std::fs::metadata(dir).unwrap().permissions();
    permissions.set_readonly(read_only);
    std::fs::set_permissions(dir, permissions).unwrap();
}

#[test]
fn hostile_scenes_fail_at_a_position_without_output() {
    let fixture = Fixture::new();
    std::fs::write(fixture.path("evil.rhai"), "fn boom() { 1 }\n").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(fixture.path("evil.rhai"), fixture.path("scenes/link.rhai"))
        .unwrap();
    #[cfg(unix)]
    for (link, to) in [
        ("scenes/loop.rhai", "loop_b.rhai"),
        ("scenes/loop_b.rhai", "loop.rhai"),
    ] {
        std::os::unix::fs::symlink(to, fixture.path(link)).unwrap();
    }
    let head = "canvas(32, 28, #{ fps: 4, duration: 1, background: \"../in/tgt.png\" });\n\
                let p = patch(\"p\", #{ source: \"../in/src.png\", mask: \"../in/mask.png\" });\n";
    let with_head = |body: &str| format!("{head}{body}");
    let table: Vec<(&str, String, &str)> = vec![
        ("syntax", with_head("p.at(0, [1, 2);\n"), "syntax error"),
        ("unterminated", "canvas(8, 8\n".into(), "syntax error"),
        ("runaway_loop", with_head("loop { }\n"), "operations"),
        ("runaway_while", with_head("let i = 0; while true { i += 1; }\n"), "operations"),
        ("deep_recursion", with_head("fn down(n) { down(n + 1) }\ndown(0);\n"), "call stack"),
        ("mutual_recursion", with_head("fn a(n) { b(n) }\nfn b(n) { a(n) }\na(0);\n"), "call stack"),
        ("deep_nesting", with_head(&format!("let x = {}1{};\n", "(".repeat(400), ")".repeat(400))), "maximum complexity"),
        ("huge_array", with_head("let a = []; a.pad(100000000, 0);\n"), "Size of array"),
        ("growing_array", with_head("let a = [0]; loop { a += a; }\n"), "Size of array"),
        ("huge_string", with_head("let s = \"x\"; loop { s += s; }\n"), "Length of string"),
        ("huge_map", with_head("let m = #{}; for i in 0..1000 { m.set(`k${i}`, i); }\nlet a = []; a.pad(2000, m);\n"), "object map"),
        // Rhai does not size-check `m[k] = v`: such growth ends at the operation limit.
        ("growing_map", with_head("let m = #{}; let i = 0; loop { m[`k${i}`] = i; i += 1; }\n"), "operations"),
        ("unknown_easing", with_head("p.at(0, [1, 2]).at(1, [3, 4], \"bouncy\");\n"), "bouncy"),
        ("missing_key", with_head("p.at(1, [1, 2]).remove_key(0.5);\n"), "no key at t = 0.5"),
        ("opacity_above_one", with_head("p.opacity(0.5, 2);\n"), "in [0, 1]"),
        ("negative_time", with_head("p.at(-1, [1, 2]);\n"), "≥ 0"),
        ("nan_position", with_head("p.at(0, [0.0 / 0.0, 2]);\n"), "finite"),
        ("inf_scale", with_head("p.scale(0, 1.0 / 0.0);\n"), "finite"),
        ("zero_scale", with_head("p.scale(0, 0);\n"), "must be > 0"),
        // Finite but past reach: refused at the call, not when a render overflows.
        ("huge_scale", with_head("p.scale(0, 1e308);\n"), "`scale`: 1e308 must be > 0 and at most 1e6"),
        ("far_position", with_head("p.at(1, [5, -2e9]);\n"), "`at`: -2e9 is past ±1e9 px"),
        ("far_target", with_head("p.drag([5, 5], 3).key(1, [1e300, 5]);\n"), "handle target: 1e300 is past"),
        ("far_pin", with_head("p.pin([5, 1e10]);\n"), "pin point: 1e10 is past"),
        ("zero_radius", with_head("p.drag([5, 5], 0);\n"), "drag radius must be > 0"),
        ("import_parent", with_head("import \"../evil\" as e;\n"), "plain relative name"),
        ("import_absolute", with_head("import \"/etc/passwd\" as e;\n"), "plain relative name"),
        ("import_missing", with_head("import \"nowhere\" as e;\n"), "nowhere"),
        ("eval", with_head("eval(\"1\");\n"), "'eval' is disabled"),
        ("no_canvas", "let x = 1;\n".into(), "no canvas"),
        ("empty_file", String::new(), "no canvas"),
        ("zero_canvas", "canvas(0, 10);\n".into(), "canvas width"),
        ("fractional_canvas", "canvas(10.5, 10);\n".into(), "canvas width"),
        ("canvas_too_wide", "canvas(16385, 10);\n".into(), "canvas width"),
        ("zero_fps", "canvas(8, 8, #{ fps: 0 });\n".into(), "fps must be > 0"),
        ("unknown_key", "canvas(8, 8, #{ fsp: 3 });\n".into(), "fsp"),
        ("missing_source", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/missing.png\", polygons: [[[1, 1], [6, 1], [1, 6]]] });\n".into(), "missing.png"),
        ("text_source", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/text.png\", polygons: [[[1, 1], [6, 1], [1, 6]]] });\n".into(), "text.png"),
        ("truncated_mask", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", mask: \"../in/trunc_half.png\" });\n".into(), "trunc_half.png"),
        ("mask_wrong_size", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", mask: \"../in/small.png\" });\n".into(), "10×10"),
        ("empty_mask", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", mask: \"../in/empty.png\" });\n".into(), "no inside pixels"),
        ("flat_polygon", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", polygons: [[[1, 1], [6, 1], [3, 1]]] });\n".into(), "enclose no area"),
        ("bowtie_polygon", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", polygons: [[[1, 1], [9, 9], [9, 1], [1, 9]]] });\n".into(), "enclose no area"),
        ("nan_polygon", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", polygons: [[[1, 1], [0.0 / 0.0, 1], [1, 6]]] });\n".into(), "finite"),
        ("far_polygon", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", polygons: [[[1, 1], [1e308, 1], [1, 6]]] });\n".into(), "beyond"),
        ("long_polygon", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", density: 0.05, polygons: [[[1, 1], [1.6e7, 1], [1, 6]]] });\n".into(), "this mask needs; raise the density"),
        ("huge_feather", "canvas(8, 8);\npatch(\"p\", #{ source: \"../in/src.png\", feather: 1e10, polygons: [[[1, 1], [6, 1], [1, 6]]] });\n".into(), "huge_feather.rhai:2:1: feather must be in [0, 65536], got 1e10"),
        ("duplicate_patch", with_head("patch(\"p\", #{ source: \"../in/src.png\", mask: \"../in/mask.png\" });\n"), "already exists"),
        ("wrong_types", with_head("p.at(\"soon\", [1, 2]);\n"), "must be a number"),
        ("throw", with_head("throw \"custom failure\";\n"), "custom failure"),
    ];
    #[cfg(unix)]
    let table = {
        let mut table = table;
        table.push((
            "import_link_outside",
            with_head("import \"link\" as e;\n"),
            "is a link to",
        ));
        table.push((
            "import_link_loop",
            with_head("import \"loop\" as e;\n"),
            "module `loop` is a symbolic link to nothing (or a loop of links)",
        ));
        table
    };
    let mut cases = Vec::new();
    for (name, text, message) in &table {
        let scene = fixture.scene(name, text);
        let position = format!("{name}.rhai:");
        cases.push(case(&["check", &scene], 1, message));
        cases.push(case(&["check", &scene], 1, &position));
        cases.push(case(&["render", &scene, "-o", "out/frames"], 1, message));
        cases.push(case(&["preview", &scene, "-o", "out/p.png"], 1, message));
    }
    std::fs::write(
        fixture.path("scenes/binary.rhai"),
        [0xff, 0xfe, 0x00, 0x9f, 0x80],
    )
    .unwrap();
    cases.extend([
        case(&["check", "scenes/binary.rhai"], 1, "binary.rhai"),
        case(&["check", "scenes/none.rhai"], 1, "scenes/none.rhai"),
        case(&["check", "scenes"], 1, "scenes"),
        case(
            &["render", "scenes/none.rhai", "-o", "out/frames"],
            1,
            "scenes/none.rhai",
        ),
    ]);
    run_catalogue(&fixture, &cases);
}

/// A tiny valid scene (4 frames) on the fixture's images.
fn tiny_scene() -> String {
    "canvas(32, 28, #{ fps: 4, duration: 1, background: \"../in/tgt.png\" });\n\
     let p = patch(\"p\", #{ source: \"../in/src.png\", mask: \"../in/mask.png\" });\n\
     p.at(0, [12, 10]).at(1, [18, 14]);\n"
        .into()
}

// ---- odd but valid masks ------------------------------------------------------------------

/// A row-major inside/outside grid.
#[derive(Clone)]
struct Mask {
    width: u32,
    height: u32,
    inside: Vec<bool>,
}

impl Mask {
    /// Whether the pixel and its 8 neighbours are all inside (beyond the image: outside).
    fn is_surrounded(&self, x: u32, y: u32) -> bool {
        (-1..=1).all(|dy| {
            (-1..=1).all(|dx| {
                let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                (0..self.width as i64).contains(&nx)
                    && (0..self.height as i64).contains(&ny)
                    && self.inside[(ny * self.width as i64 + nx) as usize]
            })
        })
    }

    fn new(width: u32, height: u32, inside: impl Fn(u32, u32) -> bool) -> Self {
        let inside = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| inside(x, y))
            .collect();
        Mask {
            width,
            height,
            inside,
        }
    }

    fn get(&self, x: i64, y: i64) -> bool {
        x >= 0
            && y >= 0
            && x < self.width as i64
            && y < self.height as i64
            && self.inside[(y as u32 * self.width + x as u32) as usize]
    }

    /// Pixels of the 8-connected pieces with at least `min` pixels (the mesher drops
    /// smaller ones, with a warning).
    fn kept_pieces(&self, min: usize) -> Vec<(u32, u32)> {
        let mut seen = vec![false; self.inside.len()];
        let mut kept = Vec::new();
        for start in 0..self.inside.len() {
            if !self.inside[start] || seen[start] {
                continue;
            }
            seen[start] = true;
            let mut piece = vec![start];
            let mut next = 0;
            while next < piece.len() {
                let (x, y) = (
                    (piece[next] as u32 % self.width) as i64,
                    (piece[next] as u32 / self.width) as i64,
                );
                next += 1;
                for (dx, dy) in [
                    (-1, -1),
                    (0, -1),
                    (1, -1),
                    (-1, 0),
                    (1, 0),
                    (-1, 1),
                    (0, 1),
                    (1, 1),
                ] {
                    let (nx, ny) = (x + dx, y + dy);
                    if self.get(nx, ny) {
                        let index = (ny as u32 * self.width + nx as u32) as usize;
                        if !seen[index] {
                            seen[index] = true;
                            piece.push(index);
                        }
                    }
                }
            }
            if piece.len() >= min {
                kept.extend(
                    piece
                        .iter()
                        .map(|&i| (i as u32 % self.width, i as u32 / self.width)),
                );
            }
        }
        kept
    }

    /// Centre of the bounding box of the inside pixels (pixel corners).
    fn bbox_centre(&self) -> (f64, f64) {
        let inside: Vec<(u32, u32)> = (0..self.inside.len() as u32)
            .filter(|&i| self.inside[i as usize])
            .map(|i| (i % self.width, i / self.width))
            .collect();
        let min_x = inside.iter().map(|p| p.0).min().unwrap();
        let max_x = inside.iter().map(|p| p.0).max().unwrap() + 1;
        let min_y = inside.iter().map(|p| p.1).min().unwrap();
        let max_y = inside.iter().map(|p| p.1).max().unwrap() + 1;
        (
            f64::from(min_x + max_x) / 2.0,
            f64::from(min_y + max_y) / 2.0,
        )
    }
}

fn save_mask(path: &Path, mask: &Mask) {
    let pixels = mask
        .inside
        .iter()
        .map(|&b| if b { 255 } else { 0 })
        .collect();
    image::GrayImage::from_raw(mask.width, mask.height, pixels)
        .unwrap()
        .save(path)
        .unwrap();
}

fn disc() -> Mask {
    Mask::new(W, H, |x, y| {
        let (dx, dy) = (x as f64 + 0.5 - 12.0, y as f64 + 0.5 - 10.0);
        dx * dx + dy * dy <= 49.0
    })
}

/// Masks OpenCV's seamlessClone is known to choke on; all must clone.
fn odd_masks() -> Vec<(&'static str, Mask)> {
    // Fixed-seed speckle (SplitMix64), 40 % inside.
    let mut state = 0x5eed_u64;
    let mut speckle = Vec::new();
    for _ in 0..W * H {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        speckle.push((z ^ (z >> 31)) % 100 < 40);
    }
    vec![
        ("full", Mask::new(W, H, |_, _| true)),
        (
            "frame",
            Mask::new(W, H, |x, y| x < 3 || y < 3 || x >= W - 3 || y >= H - 3),
        ),
        (
            "plus",
            Mask::new(W, H, |x, y| (9..11).contains(&y) || (11..13).contains(&x)),
        ),
        (
            "vline",
            Mask::new(W, H, |x, y| x == 7 && (2..18).contains(&y)),
        ),
        ("top_row", Mask::new(W, H, |_, y| y == 0)),
        ("diagonal", Mask::new(W, H, |x, y| x == y + 2)),
        ("checker", Mask::new(W, H, |x, y| (x + y) % 2 == 0)),
        (
            "corners",
            Mask::new(W, H, |x, y| {
                !(2..W - 2).contains(&x) && !(2..H - 2).contains(&y)
            }),
        ),
        (
            "speckle",
            Mask {
                width: W,
                height: H,
                inside: speckle,
            },
        ),
    ]
}

#[test]
fn odd_masks_mesh_and_clone_every_pixel() {
    let fixture = Fixture::new();
    let mut problems = Vec::new();
    for (name, mask) in odd_masks() {
        let mask_path = format!("in/{name}.png");
        let kept = mask.kept_pieces(4);
        let inside = mask.inside.iter().filter(|&&b| b).count();
        // mesh: succeeds, and only pixels of dropped specks are uncovered.
        let output = fixture.run(&strings(&["mesh", &mask_path, "--stats"]));
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        if !output.status.success() || stderr.contains("panicked") {
            problems.push(format!("{name}: mesh failed: {stderr}"));
            continue;
        }
        let stats: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
        let uncovered = stats["uncovered_mask_pixels"].as_u64().unwrap() as usize;
        if uncovered != inside - kept.len() {
            problems.push(format!(
                "{name}: {uncovered} uncovered, {} in dropped specks",
                inside - kept.len()
            ));
        }
        // clone in place onto a transparent target: every kept pixel becomes opaque.
        let (cx, cy) = mask.bbox_centre();
        let out = format!("out/{name}.png");
        let output = fixture.run(&strings(&[
            "clone",
            "--source",
            "in/src.png",
            "--mask",
            &mask_path,
            "--target",
            "in/clear.png",
            "--at",
            &format!("{cx},{cy}"),
            "-o",
            &out,
        ]));
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        if !output.status.success() || stderr.contains("panicked") {
            problems.push(format!("{name}: clone failed: {stderr}"));
            continue;
        }
        let result = image::open(fixture.path(&out)).unwrap().to_rgba8();
        assert_eq!(result.dimensions(), (W, H));
        // The anti-aliased edge runs through the outside pixels' centres, thinned to chords
        // that may cut a convex corner pixel, by at most half its square.
        let alpha = |&(x, y): &(u32, u32)| result.get_pixel(x, y).0[3];
        let least_alpha = |&(x, y): &(u32, u32)| match mask.is_surrounded(x, y) {
            true => 255,
            false => 128,
        };
        let missed = kept.iter().filter(|p| alpha(p) < least_alpha(p)).count();
        if missed > 0 {
            problems.push(format!(
                "{name}: {missed} of {} kept mask pixels not cloned",
                kept.len()
            ));
        }
        // In place, the membrane is ≈ 0: the clone reproduces the source.
        let source = image::open(fixture.path("in/src.png")).unwrap().to_rgb8();
        let worst = kept
            .iter()
            .flat_map(|&(x, y)| {
                let (a, b) = (result.get_pixel(x, y).0, source.get_pixel(x, y).0);
                (0..3).map(move |c| (i32::from(a[c]) - i32::from(b[c])).abs())
            })
            .max()
            .unwrap_or(0);
        if worst > 1 {
            problems.push(format!(
                "{name}: in-place clone differs from the source by {worst}/255"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

/// A `width` × `height` 1-bit grey PNG of zeros, written row by row (a few KB on disk).
fn write_zero_grey_png(path: &Path, width: u32, height: u32) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::One);
    let mut writer = encoder
        .write_header()
        .unwrap()
        .into_stream_writer()
        .unwrap();
    let row = vec![0u8; width.div_ceil(8) as usize];
    for _ in 0..height {
        std::io::Write::write_all(&mut writer, &row).unwrap();
    }
    writer.finish().unwrap();
}

/// A PNG of `width`×`height` 8-bit RGB pixels whose data stops after the header (one empty
/// row's worth of compressed bytes): for headers too large to write in full.
fn write_png_header_only(path: &Path, width: u32, height: u32) {
    let chunk = |kind: &[u8; 4], data: &[u8]| {
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        let crc = crc32fast::hash(&[&kind[..], data].concat());
        out.extend_from_slice(&crc.to_be_bytes());
        out
    };
    let mut header = [width.to_be_bytes(), height.to_be_bytes()].concat();
    header.extend_from_slice(&[8, 2, 0, 0, 0]);
    // zlib of one empty filter byte.
    let data = [0x78, 0x9c, 0x63, 0x00, 0x00, 0x00, 0x01, 0x00, 0x01];
    let mut png = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    png.extend(chunk(b"IHDR", &header));
    png.extend(chunk(b"IDAT", &data));
    png.extend(chunk(b"IEND", &[]));
    std::fs::write(path, png).unwrap();
}

/// Finite but extreme numbers: each either works (exit 0, a whole PNG of the target's size)
/// or fails cleanly (exit 1 with a message, no file); never a panic, never exit 2 for a
/// value the usage allows.
#[test]
fn extreme_finite_numbers_work_or_fail_cleanly() {
    let fixture = Fixture::new();
    let scene = fixture.scene("ok", &tiny_scene());
    let mut runs: Vec<Vec<String>> = [
        vec![("--at", "1e300,1e300")],
        vec![("--at", "-1e300,5")],
        vec![("--at", "-12,-10")],
        vec![("--scale", "1e-300")],
        vec![("--scale", "1e300")],
        vec![("--scale", "1e6")],
        vec![("--rotate", "1e300")],
        vec![("--rotate", "-1e-300")],
        vec![("--density", "1e300")],
        vec![("--density", "0.05")],
        vec![("--feather", "1e300")],
        vec![("--feather", "1e6")],
        vec![("--threshold", "0")],
        vec![("--threshold", "1")],
        vec![("--mask-offset", "1e300,1e300")],
        vec![("--mask-offset", "-1e300,0")],
        vec![("--mask-offset", "-30,-30")],
        vec![("--drag", "12,10:1e300,1e300:5")],
        vec![("--drag", "12,10:14,12:1e300")],
        vec![("--drag", "12,10:14,12:1e-300")],
        vec![("--drag", "1e300,1e300:0,0")],
        vec![("--pin", "1e300,-1e300")],
        vec![("--drag", "12,10:14,12"), ("--pin", "12,10")],
        vec![("--show-mesh", "-"), ("--scale", "1e300")],
    ]
    .iter()
    .map(|replace| {
        let mut args = clone_args(replace);
        if let Some(i) = args.iter().position(|a| a == "--show-mesh") {
            args.remove(i + 1);
        }
        args
    })
    .collect();
    for extra in [
        ["--t", "1e300"],
        ["--t", "0"],
        ["--frame", "4"],
        ["--frame", "18446744073709551615"],
    ] {
        runs.push(strings(&[
            "preview",
            &scene,
            extra[0],
            extra[1],
            "-o",
            "out/o.png",
        ]));
    }
    runs.push(strings(&["mesh", "in/mask.png", "--max-vertices", "3"]));
    runs.push(strings(&[
        "mesh",
        "in/mask.png",
        "--max-vertices",
        "18446744073709551615",
    ]));
    runs.push(strings(&[
        "mesh",
        "in/mask.png",
        "--density",
        "1e300",
        "--min-angle",
        "0",
    ]));
    let mut problems = Vec::new();
    let output_file = fixture.path("out/o.png");
    for args in &runs {
        let output = fixture.run(args);
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        let code = output.status.code();
        let fine = match code {
            Some(0) => {
                !args.contains(&"-o".to_string())
                    || image::open(&output_file).is_ok_and(|i| i.width() == 32 && i.height() == 28)
            }
            Some(1) => !output_file.exists() && stderr.contains("error"),
            // A value past a documented bound is a usage error naming the bound.
            Some(2) => {
                let bounds = [
                    "must lie in",
                    "and at most 1e6",
                    "is past ±1e9 px",
                    "the scene ",
                ];
                !output_file.exists() && bounds.iter().any(|b| stderr.contains(b))
            }
            _ => false,
        };
        if !fine || stderr.contains("panicked") {
            problems.push(format!("{args:?}: exit {code:?}: {}", stderr.trim()));
        }
        let _ = std::fs::remove_file(&output_file);
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
