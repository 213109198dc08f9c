//! `lapclone test` end to end on a tiny scene: goldens made by `--update` pass byte-exact; a
//! patch moved by 2 px fails with the largest error and position of a difference computed
//! here from the golden and the pending PNG; thresholds, accept / reject / CI, bad inputs and
//! the JUnit file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

struct Fixture {
    _dir: tempfile::TempDir,
    root: PathBuf,
}

impl Fixture {
    /// A folder with a 12×12 textured source and `tiny.rhai` with the patch at x = `at_x`.
    fn new(at_x: i32) -> Fixture {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().to_path_buf();
        let source = image::RgbImage::from_fn(12, 12, |x, y| {
            image::Rgb([(x * 20) as u8, (y * 20) as u8, ((x * y) % 7 * 30) as u8])
        });
        source.save(root.join("src.png")).unwrap();
        let fixture = Fixture { _dir: dir, root };
        fixture.write_scene(at_x, "");
        fixture
    }

    fn write_scene(&self, at_x: i32, extra: &str) {
        let text = format!(
            "canvas(24, 16, #{{ fps: 4, duration: 1, background: \"#204080\" }});\n\
             let p = patch(\"p\", #{{ source: \"src.png\", polygons: [[[2, 2], [10, 2], [10, 10], [2, 10]]] }});\n\
             p.at(0, [{at_x}, 8]);\n{extra}"
        );
        std::fs::write(self.scene(), text).unwrap();
    }

    fn scene(&self) -> PathBuf {
        self.root.join("tiny.rhai")
    }

    fn golden(&self, frame: u64) -> PathBuf {
        self.root
            .join("goldens/tiny")
            .join(format!("frame_{frame:04}.png"))
    }

    fn pending(&self, frame: u64) -> PathBuf {
        self.root
            .join("goldens/tiny")
            .join(format!("frame_{frame:04}.new.png"))
    }

    fn run(&self, args: &[&str]) -> Output {
        self.run_env(args, &[])
    }

    fn run_env(&self, args: &[&str], env: &[(&str, &str)]) -> Output {
        let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
        command.current_dir(&self.root).arg("test").args(args);
        command.env_remove("CI");
        for (k, v) in env {
            command.env(k, v);
        }
        let output = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!stderr.contains("panicked"), "panic: {stderr}");
        output
    }

    /// Every file under the folder (relative paths), sorted.
    fn files(&self) -> Vec<String> {
        let mut out = Vec::new();
        collect(&self.root, &self.root, &mut out);
        out.sort();
        out
    }
}

fn collect(root: &Path, dir: &Path, out: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect(root, &path, out);
        } else {
            out.push(path.strip_prefix(root).unwrap().display().to_string());
        }
    }
}

fn code(output: &Output) -> i32 {
    output.status.code().unwrap()
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn json_lines(output: &Output) -> Vec<serde_json::Value> {
    stdout(output)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The largest channel difference and its first position (row order, then R, G, B, A),
/// computed directly from two PNG files.
fn reference_max(a: &Path, b: &Path) -> (u8, u32, u32, &'static str) {
    let a = image::open(a).unwrap().to_rgba8();
    let b = image::open(b).unwrap().to_rgba8();
    let mut best = (0u8, 0, 0, "R");
    for y in 0..a.height() {
        for x in 0..a.width() {
            let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
            for (c, name) in ["R", "G", "B", "A"].into_iter().enumerate() {
                let d = p[c].abs_diff(q[c]);
                if d > best.0 {
                    best = (d, x, y, name);
                }
            }
        }
    }
    best
}

/// Goldens made, then the patch moved by 2 px: the check fails.
fn moved_fixture() -> Fixture {
    let fixture = Fixture::new(10);
    assert_eq!(code(&fixture.run(&["--update"])), 0);
    fixture.write_scene(12, "");
    fixture
}

#[test]
fn goldens_made_by_update_pass_byte_exact() {
    let fixture = Fixture::new(10);
    let update = fixture.run(&["--update"]);
    assert_eq!(code(&update), 0, "{}", stderr(&update));
    for frame in [1, 2, 4] {
        assert!(fixture.golden(frame).is_file(), "golden {frame}");
    }
    let check = fixture.run(&["--json"]);
    assert_eq!(code(&check), 0, "{}", stderr(&check));
    let lines = json_lines(&check);
    assert_eq!(lines.len(), 3);
    for line in lines {
        assert_eq!(line["verdict"], "pass");
        assert_eq!(line["max_error"], 0.0);
        assert_eq!(line["failing_pixels"], 0);
        assert!(
            line["psnr"].is_null(),
            "identical frames have infinite PSNR"
        );
    }
    // The goldens are the frames `lapclone render` writes, byte for byte.
    let rendered = fixture.root.join("rendered");
    let render = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .current_dir(&fixture.root)
        .args(["render", "tiny.rhai", "-o", "rendered"])
        .output()
        .unwrap();
    assert!(render.status.success());
    for frame in [1, 2, 4] {
        let ours = image::open(fixture.golden(frame)).unwrap().to_rgba8();
        let theirs = image::open(rendered.join(format!("frame_{frame:04}.png")))
            .unwrap()
            .to_rgba8();
        assert_eq!(ours, theirs, "frame {frame}");
    }
}

#[test]
fn a_patch_moved_by_two_pixels_fails_with_the_hand_computed_largest_error() {
    let fixture = moved_fixture();
    let check = fixture.run(&["--frames", "1"]);
    assert_eq!(code(&check), 1, "{}", stdout(&check));
    let pending = fixture.pending(1);
    assert!(pending.is_file(), "pending frame written");
    let out = fixture.root.join("lapclone-test-out");
    assert!(out.join("index.html").is_file());
    assert!(out.join("tiny/frame_0001.triptych.png").is_file());
    assert!(out.join("tiny/frame_0001.diff.png").is_file());
    assert!(out.join("tiny/frame_0001.actual.png").is_file());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("src=\"tiny/frame_0001.triptych.png\""),
        "{html}"
    );
    let triptych = image::open(out.join("tiny/frame_0001.triptych.png")).unwrap();
    assert_eq!((triptych.width(), triptych.height()), (24 * 3 + 4, 16));

    let (value, x, y, channel) = reference_max(&fixture.golden(1), &pending);
    assert!(
        value > 1,
        "moving the patch changes pixels by more than a level"
    );
    let expected = format!("max {value} @ ({x}, {y}, {channel})");
    let text = stdout(&check);
    assert!(
        text.lines()
            .any(|l| l.starts_with("FAIL") && l.contains(&expected)),
        "{expected} in {text}"
    );
    let json = json_lines(&fixture.run(&["--frames", "1", "--json"]));
    assert_eq!(json[0]["max_error"], f64::from(value));
    assert_eq!(json[0]["max_x"], x);
    assert_eq!(json[0]["max_y"], y);
    assert_eq!(json[0]["max_channel"], channel);
    assert_eq!(json[0]["verdict"], "fail");
}

#[test]
fn fail_percent_passes_it_and_hard_fail_fails_it_again() {
    let fixture = moved_fixture();
    assert_eq!(code(&fixture.run(&["--frames", "1"])), 1);
    let lenient = fixture.run(&["--frames", "1", "--fail-percent", "100"]);
    assert_eq!(code(&lenient), 0, "{}", stdout(&lenient));
    assert!(stdout(&lenient).starts_with("WARN"), "{}", stdout(&lenient));
    // A passing frame removes its stale pending file, as insta does.
    assert!(!fixture.pending(1).exists());
    let hard = fixture.run(&["--frames", "1", "--fail-percent", "100", "--hard-fail", "1"]);
    assert_eq!(code(&hard), 1, "{}", stdout(&hard));
    // The scene's own thresholds apply, and flags override them.
    fixture.write_scene(12, "golden(#{ frames: [1], fail_percent: 100 });\n");
    assert_eq!(code(&fixture.run(&[])), 0);
    assert_eq!(code(&fixture.run(&["--fail-percent", "0"])), 1);
    // An SSIM floor fails a frame the percentage let through.
    assert_eq!(code(&fixture.run(&["--min-ssim", "0.999"])), 1);
}

#[test]
fn accept_makes_the_next_run_pass_and_reject_keeps_the_golden() {
    let fixture = moved_fixture();
    let golden_before = std::fs::read(fixture.golden(1)).unwrap();
    assert_eq!(code(&fixture.run(&[])), 1);
    assert!(fixture.pending(1).is_file());
    let reject = fixture.run(&["--reject"]);
    assert_eq!(code(&reject), 0);
    assert!(!fixture.pending(1).exists());
    assert_eq!(std::fs::read(fixture.golden(1)).unwrap(), golden_before);
    assert_eq!(code(&fixture.run(&[])), 1, "rejected: still failing");
    let accept = fixture.run(&["--accept"]);
    assert_eq!(code(&accept), 0);
    assert!(stdout(&accept).contains("accepted"));
    assert!(!fixture.pending(1).exists());
    assert_ne!(std::fs::read(fixture.golden(1)).unwrap(), golden_before);
    let after = fixture.run(&[]);
    assert_eq!(code(&after), 0, "{}", stdout(&after));
}

#[test]
fn review_accepts_rejects_and_skips_from_its_input() {
    let fixture = moved_fixture();
    assert_eq!(code(&fixture.run(&[])), 1);
    let pending: Vec<u64> = [1, 2, 4]
        .into_iter()
        .filter(|&f| fixture.pending(f).is_file())
        .collect();
    assert_eq!(pending.len(), 3);
    let golden_2 = std::fs::read(fixture.golden(2)).unwrap();
    // Under CI a review shows no picture it cannot show inline, and writes nothing.
    let before = fixture.files();
    let ci = review(&fixture, b"s\ns\ns\n", &[("CI", "1")]);
    assert_eq!(code(&ci), 0);
    assert!(stdout(&ci).contains("0 accepted, 0 rejected, 3 skipped"));
    assert!(
        stdout(&ci).contains("no picture: CI is set"),
        "{}",
        stdout(&ci)
    );
    assert_eq!(fixture.files(), before, "nothing written under CI");
    // Its pictures may not go into the goldens either.
    let inside = fixture.run(&["--review", "--out", "goldens/tiny/pictures"]);
    assert_eq!(code(&inside), 2, "{}", stderr(&inside));
    assert!(
        stderr(&inside).contains("it lies in the goldens folder goldens"),
        "{}",
        stderr(&inside)
    );
    assert_eq!(fixture.files(), before, "nothing written into the goldens");
    let output = review(&fixture, b"a\nr\ns\n", &[]);
    assert_eq!(code(&output), 0);
    let text = stdout(&output);
    assert!(text.contains("1 accepted, 1 rejected, 1 skipped"), "{text}");
    assert!(text.contains("expected | difference | actual:"), "{text}");
    assert!(!fixture.pending(1).exists() && !fixture.pending(2).exists());
    assert!(fixture.pending(4).is_file(), "skipped stays pending");
    assert_eq!(std::fs::read(fixture.golden(2)).unwrap(), golden_2);
}

/// `lapclone test --review` in the fixture, answering `answers`.
fn review(fixture: &Fixture, answers: &[u8], env: &[(&str, &str)]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
    command
        .current_dir(&fixture.root)
        .args(["test", "--review"]);
    command.env_remove("CI").envs(env.iter().copied());
    let mut child = command
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write as _;
    child.stdin.take().unwrap().write_all(answers).unwrap();
    child.wait_with_output().unwrap()
}

#[test]
fn with_ci_set_nothing_is_written() {
    let fixture = moved_fixture();
    let before = fixture.files();
    let check = fixture.run_env(&[], &[("CI", "1")]);
    assert_eq!(code(&check), 1);
    assert_eq!(
        fixture.files(),
        before,
        "no golden, pending file or picture under CI"
    );
    // An explicit --out asks for the failure pictures, CI or not; still no pending file.
    let report = fixture.run_env(&["--out", "report"], &[("CI", "1")]);
    assert_eq!(code(&report), 1);
    let written: Vec<String> = fixture
        .files()
        .into_iter()
        .filter(|f| !before.contains(f))
        .collect();
    assert!(!written.is_empty(), "pictures under --out");
    assert!(
        written.iter().all(|f| f.starts_with("report")),
        "{written:?}"
    );
    std::fs::remove_dir_all(fixture.root.join("report")).unwrap();
    // A new scene under CI: missing goldens fail, and none is created.
    std::fs::remove_dir_all(fixture.root.join("goldens")).unwrap();
    assert_eq!(code(&fixture.run_env(&[], &[("CI", "true")])), 1);
    assert!(!fixture.root.join("goldens").exists());
    // --update still writes under CI.
    assert_eq!(code(&fixture.run_env(&["--update"], &[("CI", "1")])), 0);
    assert!(fixture.golden(1).is_file());
}

#[test]
fn bad_inputs_give_clear_messages_and_exit_codes() {
    let fixture = Fixture::new(10);
    // No goldens folder: every frame is new, exit 1, and the message says so.
    let missing = fixture.run(&[]);
    assert_eq!(code(&missing), 1);
    assert!(
        stdout(&missing).contains("no goldens folder"),
        "{}",
        stdout(&missing)
    );
    assert_eq!(code(&fixture.run(&["--reject"])), 0);
    // A named goldens folder that does not exist is a usage error.
    let named = fixture.run(&["--goldens", "nowhere"]);
    assert_eq!(code(&named), 2);
    assert!(
        stderr(&named).contains("--goldens nowhere"),
        "{}",
        stderr(&named)
    );
    // A file where the goldens folder should be is no missing folder, --update or not.
    for update in [&[][..], &["--update"]] {
        let file = fixture.run(&[&["--goldens", "tiny.rhai"][..], update].concat());
        assert_eq!(code(&file), 2, "{}", stderr(&file));
        assert!(
            stderr(&file).contains("--goldens tiny.rhai: it is not a folder"),
            "{}",
            stderr(&file)
        );
    }

    assert_eq!(code(&fixture.run(&["--update"])), 0);
    // An --out that is a file (here the scene) is a usage error before anything runs.
    for mode in [&[][..], &["--review"], &["--accept"]] {
        let out = fixture.run(&[mode, &["--out", "tiny.rhai"]].concat());
        assert_eq!(code(&out), 2, "{mode:?}");
        assert!(
            stderr(&out).contains("--out tiny.rhai: not a folder"),
            "{}",
            stderr(&out)
        );
    }
    // A report folder in the goldens would mix its pictures with them (and be committed).
    for out in ["goldens", "goldens/report", "goldens/tiny"] {
        let run = fixture.run(&["--out", out]);
        assert_eq!(code(&run), 2, "{}", stderr(&run));
        assert!(
            stderr(&run).contains(&format!("--out {out}: it lies in the goldens folder")),
            "{}",
            stderr(&run)
        );
        assert_eq!(stdout(&run), "", "nothing ran");
    }
    assert!(!fixture.root.join("goldens/index.html").exists());
    // A --junit that cannot be written (a folder, a link to nothing) is a usage error before
    // anything runs: no frame is compared, no line printed.
    std::fs::create_dir(fixture.root.join("reports")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("nowhere.xml", fixture.root.join("dangling.xml")).unwrap();
    for (junit, what) in [
        ("reports", "it is a folder"),
        ("dangling.xml", "it is a symbolic link to nothing"),
    ] {
        if !cfg!(unix) && junit == "dangling.xml" {
            continue;
        }
        let out = fixture.run(&["--junit", junit]);
        assert_eq!(code(&out), 2, "{}", stderr(&out));
        assert!(
            stderr(&out).contains(&format!("--junit {junit}: {what}")),
            "{}",
            stderr(&out)
        );
        assert_eq!(stdout(&out), "", "nothing ran");
    }
    // A golden of another size.
    image::RgbImage::new(5, 3).save(fixture.golden(1)).unwrap();
    let size = fixture.run(&["--frames", "1"]);
    assert_eq!(code(&size), 1);
    assert!(
        stdout(&size).contains("size mismatch: golden is 5×3, frame is 24×16"),
        "{}",
        stdout(&size)
    );
    // A corrupt golden.
    std::fs::write(fixture.golden(2), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let corrupt = fixture.run(&["--frames", "2"]);
    assert_eq!(code(&corrupt), 1);
    assert!(
        stdout(&corrupt).contains("is not a readable PNG"),
        "{}",
        stdout(&corrupt)
    );
    // A frame number past the end, from the flag and from the scene.
    let past = fixture.run(&["--frames", "9"]);
    assert_eq!(code(&past), 2);
    assert!(stderr(&past).contains("frame 9 is past the end (the scene has 4 frames)"));
    fixture.write_scene(10, "golden(#{ frames: [1, 7] });\n");
    let past_in_scene = fixture.run(&[]);
    assert_eq!(code(&past_in_scene), 2);
    assert!(
        stderr(&past_in_scene).contains("tiny.rhai:4:1"),
        "{}",
        stderr(&past_in_scene)
    );
    // A syntax error: positioned like `lapclone check`.
    fixture.write_scene(10, "let = ;\n");
    let syntax = fixture.run(&[]);
    assert_eq!(code(&syntax), 2);
    assert!(
        stderr(&syntax).contains("tiny.rhai:4:"),
        "{}",
        stderr(&syntax)
    );
    // No temporary or partial files anywhere.
    assert!(
        fixture.files().iter().all(|f| !f.ends_with(".tmp")),
        "{:?}",
        fixture.files()
    );
}

/// The number in `attr="N"` of the first element named `tag`.
fn attribute(xml: &str, tag: &str, attr: &str) -> usize {
    let start = xml.find(&format!("<{tag} ")).unwrap();
    let element = &xml[start..start + xml[start..].find('>').unwrap()];
    let key = format!("{attr}=\"");
    let at = element.find(&key).unwrap() + key.len();
    element[at..at + element[at..].find('"').unwrap()]
        .parse()
        .unwrap()
}

#[test]
fn junit_counts_match_the_printed_summary() {
    let fixture = moved_fixture();
    // tiny.rhai: three failing frames; other.rhai: two passing; broken.rhai: does not load.
    let other = fixture.root.join("other.rhai");
    std::fs::write(&other, "canvas(8, 8, #{ fps: 2, duration: 1 });\n").unwrap();
    let broken = fixture.root.join("broken.rhai");
    std::fs::write(&broken, "canvas(8, 8\n").unwrap();
    assert_eq!(code(&fixture.run(&["other.rhai", "--update"])), 0);
    let check = fixture.run(&["--junit", "report.xml"]);
    assert_eq!(code(&check), 2, "a scene that does not load wins");
    let summary = stdout(&check);
    let summary = summary
        .lines()
        .find(|l| l.starts_with("test result"))
        .unwrap();
    assert!(
        summary.contains(
            "2 passed; 0 warned; 3 failed; 0 new; 1 scene error(s) — 5 frames in 3 scenes"
        ),
        "{summary}"
    );
    let xml = std::fs::read_to_string(fixture.root.join("report.xml")).unwrap();
    assert!(xml.starts_with("<?xml"));
    assert_eq!(attribute(&xml, "testsuites", "tests"), 6);
    assert_eq!(attribute(&xml, "testsuites", "failures"), 3);
    assert_eq!(attribute(&xml, "testsuites", "errors"), 1);
    assert_eq!(xml.matches("<testsuite ").count(), 3);
    assert_eq!(xml.matches("<testcase ").count(), 6);
    assert_eq!(xml.matches("<failure ").count(), 3);
    assert_eq!(xml.matches("<error ").count(), 1);
    assert_eq!(xml.matches("</testsuite>").count(), 3);
    assert!(xml.contains("max "), "figures in the failure message");
    assert!(xml.trim_end().ends_with("</testsuites>"));
}

#[test]
fn pending_frames_are_the_same_bytes_on_one_thread_or_several() {
    let fixture = moved_fixture();
    std::fs::copy(fixture.scene(), fixture.root.join("twin.rhai")).unwrap();
    let mut runs = Vec::new();
    for jobs in ["1", "3"] {
        let _ = std::fs::remove_dir_all(fixture.root.join("goldens/twin"));
        let check = fixture.run(&["--jobs", jobs, "--json"]);
        assert_eq!(code(&check), 1);
        let mut bytes = Vec::new();
        for dir in ["goldens/tiny", "goldens/twin"] {
            for frame in [1, 2, 4] {
                let path = fixture
                    .root
                    .join(dir)
                    .join(format!("frame_{frame:04}.new.png"));
                bytes.push(std::fs::read(path).unwrap());
            }
        }
        let lines: Vec<String> = stdout(&check).lines().map(str::to_string).collect();
        runs.push((bytes, lines));
    }
    assert_eq!(runs[0], runs[1]);
}

/// A golden-frame run in CI says what `check` would: a key past the scene's end is named on
/// standard error, once, and the frames still pass.
#[test]
fn a_scene_s_warnings_are_printed_once_and_the_run_passes() {
    let fixture = Fixture::new(10);
    fixture.write_scene(10, "p.at(5, [12, 8]);\n");
    let update = fixture.run(&["--update"]);
    assert_eq!(code(&update), 0, "{}", stderr(&update));
    let check = fixture.run(&[]);
    assert_eq!(code(&check), 0, "{}", stderr(&check));
    let warnings = stderr(&check);
    let late: Vec<&str> = warnings
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(late.len(), 1, "{warnings}");
    assert!(
        late[0].contains("\"at\" key(s) at t = 5 after the scene's end"),
        "{warnings}"
    );
}
