//! `lapclone repl` driven through its non-interactive mode (stdin piped into the binary):
//! load, edit, error recovery, undo, multi-line input, `:list`, and `:save` → `lapclone
//! render` giving byte-identical frames to the live scene's `:render`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use crate::files;
use files::asset;

/// A tiny scene (64×48, 3 frames) with one polygon patch of the cat photo.
fn tiny_scene(dir: &Path) -> PathBuf {
    let text = format!(
        r#"canvas(64, 48, #{{ fps: 6, duration: 0.5, background: [0.2, 0.3, 0.4] }});
let blob = patch("blob", #{{
    source: "{}",
    polygons: [[[150, 60], [185, 60], [190, 90], [160, 95]]],
}});
blob.at(0, [30, 24]);
"#,
        asset("chelsea.png")
    );
    let path = dir.join("tiny.rhai");
    std::fs::write(&path, text).unwrap();
    path
}

fn repl(dir: &Path, args: &[&str], input: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("repl")
        .args(args)
        .arg("--preview")
        .arg(dir.join("preview.png"))
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn edits_list_and_write_the_preview() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let out = repl(
        dir.path(),
        &[scene.to_str().unwrap()],
        "blob.at(0.4, [36, 20]);\n:list\n40 + 2\n",
    );
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("canvas 64×48, 6 fps, 0.5 s (3 frames)"),
        "{stdout}"
    );
    assert!(stdout.contains("patch \"blob\""), "{stdout}");
    assert!(stdout.contains("boundary data hat-average"), "{stdout}");
    assert!(stdout.contains("boundary outside-centres"), "{stdout}");
    assert!(stdout.contains("keys: position 2, scale 0"), "{stdout}");
    assert!(stdout.contains("variables: blob"), "{stdout}");
    assert!(stdout.lines().any(|l| l == "42"), "{stdout}");
    assert!(
        !stdout.contains('\x1b'),
        "no escape sequences when not interactive"
    );
    assert_eq!(
        stdout.matches("preview:").count(),
        1,
        "path shown once: {stdout}"
    );
    let preview = image::open(dir.path().join("preview.png")).unwrap();
    assert_eq!((preview.width(), preview.height()), (64, 48));
}

/// A handle shows which handle of which patch it is, by its index now, and says so once it
/// is removed (it showed `handle` whatever it was).
#[test]
fn a_handle_shows_its_patch_and_index() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let input = "let a = blob.drag([160, 70], 10);\nlet b = blob.drag([170, 80], 10);\n\
                 b\nblob.remove_handle(0);\nb\na\n";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let shown: Vec<&str> = stdout.lines().filter(|l| l.contains("handle")).collect();
    assert_eq!(
        shown,
        [
            "handle 1 of get_patch(\"blob\")",
            "handle 0 of get_patch(\"blob\")",
            "a handle removed from the scene"
        ],
        "{stdout}"
    );
}

/// A patch shows as the call that gives it back (it showed `patch("blob")`, which makes a
/// new patch, or fails without its options), and says so once it is removed.
#[test]
fn a_patch_shows_as_the_call_that_gives_it_back() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let input = "blob\nget_patch(\"blob\")\nremove_patch(\"blob\");\nblob\n";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert_eq!(
        values(&stdout),
        [
            "get_patch(\"blob\")",
            "get_patch(\"blob\")",
            "a patch removed from the scene"
        ],
        "{stdout}"
    );
}

/// An entry that ends in `;` is a statement and shows no value; one that ends in an
/// expression shows it, whatever comments or strings follow it or hold a `;`.
#[test]
fn an_entry_ending_in_a_semicolon_shows_no_value() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let input = "\
40 + 1;
40 + 2
blob.at(0.1, [40, 30]);
40 + 3; // a note
40 + 4 /* a block; */
\"45;\"
`46;`
let s = \";\"; s
40 + 7; /* one /* nested */ comment */
40 + 8 // a note; with a semicolon
[40,
 9];
";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert_eq!(
        values(&stdout),
        ["42", "44", "45;", "46;", ";", "48"],
        "{stdout}"
    );
}

/// The values a piped session printed: its output less the load and preview lines.
fn values(stdout: &str) -> Vec<&str> {
    let noise = |l: &str| l.starts_with("loaded ") || l.starts_with("preview:");
    stdout.lines().filter(|l| !noise(l)).collect()
}

#[test]
fn a_failed_line_changes_nothing_and_the_session_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let input = "\
blob.at(0.2, [31, 24]); let extra = 1; nope(3);
extra
blob.at(0.1, [40, 30]);
:list
";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(1), "a failed entry gives exit 1");
    // The first entry failed at its third statement: position, source line and caret.
    assert!(
        stderr.contains("<entry 1>:1:40: unknown function or wrong argument types: nope"),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!("\n{}^", " ".repeat(39))),
        "{stderr}"
    );
    // Its variable is gone and its key was not kept: `extra` fails, the third line works.
    assert!(stderr.contains("<entry 2>"), "{stderr}");
    assert!(stdout.contains("keys: position 2"), "{stdout}");
    assert!(stdout.contains("variables: blob\n"), "{stdout}");
}

#[test]
fn undo_goes_back_one_change() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let input = "\
blob.at(0.2, [31, 24]);
blob.scale(0, 1.2);
:undo
:list
:undo
:list
:undo
";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    let lists: Vec<&str> = stdout.lines().filter(|l| l.contains("keys:")).collect();
    assert_eq!(
        lists,
        [
            "  keys: position 2, scale 0, rotation 0, depth 0, opacity 0",
            "  keys: position 1, scale 0, rotation 0, depth 0, opacity 0"
        ],
        "{stdout}"
    );
    assert!(stderr.contains("nothing to undo"), "{stderr}");
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn unfinished_input_continues_on_the_next_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let input = "\
let k = [1,
  2,
  3];
k.len()
fn shift(x) {
  x + 5
}
blob.key(0.3, #{
  at: [shift(30), 24],
});
:list
";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.lines().any(|l| l == "3"), "{stdout}");
    assert!(stdout.contains("keys: position 2"), "{stdout}");
}

#[test]
fn functions_and_imports_persist_across_entries() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    std::fs::write(dir.path().join("helpers.rhai"), "fn twice(x) { 2 * x }\n").unwrap();
    let input = "\
import \"helpers\" as h;
fn add1(x) { x + 1 }
add1(h::twice(20))
";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.lines().any(|l| l == "41"), "{stdout}");
}

fn frames_in(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

#[test]
fn saved_scene_renders_the_live_frames_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let saved_dir = dir.path().join("elsewhere");
    std::fs::create_dir(&saved_dir).unwrap();
    let input = "\
blob.at(0.3, [40, 26], \"ease_in_out\").rotate(0, 0).rotate(0.5, 25);
blob.drag([170, 75], 12).key(0, [170, 75]).key(0.4, [176, 70], \"smooth\");
:t 0.25
:save elsewhere/saved.rhai
:render -o live
";
    let out = repl(dir.path(), &[scene.to_str().unwrap()], input);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let render = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["render", "saved.rhai", "-o"])
        .arg(dir.path().join("from_file"))
        .current_dir(&saved_dir)
        .output()
        .unwrap();
    assert!(render.status.success(), "{}", text(&render.stderr));
    let live = frames_in(&dir.path().join("live"));
    let from_file = frames_in(&dir.path().join("from_file"));
    assert_eq!(live.len(), 3);
    assert!(live == from_file, "frames differ");
}

#[test]
fn script_file_mode_and_bad_commands() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    std::fs::write(
        dir.path().join("edit.txt"),
        ":frame 2\n:stats\n:frame 9\n:bogus\n:t 0.75\n:t 0.5\n",
    )
    .unwrap();
    let out = repl(
        dir.path(),
        &[scene.to_str().unwrap(), "--script", "edit.txt"],
        "",
    );
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(stdout.contains("ms total"), "{stdout}");
    assert!(
        stderr.contains("frame 9: the scene has 3 frames"),
        "{stderr}"
    );
    assert!(stderr.contains("unknown command `:bogus`"), "{stderr}");
    // A playhead past the end is refused as `preview --t` refuses it; the end is inside.
    assert!(
        stderr.contains("t = 0.75 s is past the scene's end: it lasts 0.5 s"),
        "{stderr}"
    );
    assert!(stderr.contains("3 failed entries"), "{stderr}");
}

/// The session warns as `lapclone check` does, once each: a second `canvas` call and an old
/// option name are named at their entries, as a key past the end already was.
#[test]
fn the_session_warns_about_a_second_canvas_and_an_old_name_once() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let input = format!(
        "canvas(64, 48, #{{ fps: 6, duration: 1 }});\nlet n = 1;\n\
         let q = patch(\"q\", #{{ source: \"{}\", polygons: [[[10, 10], [60, 12], [30, 50]]], boundary_data: \"vertex\" }});\n",
        asset("chelsea.png")
    );
    let out = repl(dir.path(), &[scene.to_str().unwrap()], &input);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let canvas = format!(
        "warning: <entry 1>:1:1: `canvas` again: this canvas replaces the one of {}:1:1 (a scene has one)",
        scene.display()
    );
    assert_eq!(stderr.matches(&canvas).count(), 1, "{stderr}");
    let renamed = "warning: <entry 3>:1:9: `boundary_data` is now `boundary_sampling` (the old name still works)";
    assert_eq!(stderr.matches(renamed).count(), 1, "{stderr}");
}
