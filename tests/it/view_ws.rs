//! `lapclone repl --view` driven as a page would drive it: a WebSocket client on port 0
//! sends a drag and checks the frame update against `lapclone preview` of the `:save`d
//! scene byte for byte; `:undo` restores the frame; a missing or wrong token, a foreign
//! Origin and 1,000 malformed messages are refused with no change to the scene.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

use serde_json::{json, Value};
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

use crate::files::asset;

const WAIT: Duration = Duration::from_secs(60);

/// The cat's face on the coffee, 600×400, keyed so a drag at t = 1.25 adds a key.
pub(super) fn cat_scene(dir: &Path) -> PathBuf {
    let text = format!(
        r#"canvas(600, 400, #{{ fps: 24, duration: 2, background: "{}" }});
let cat = patch("cat", #{{ source: "{}", mask: "{}" }});
cat.at(0, [288, 147]).at(2, [320, 170]);
cat.scale(0, 0.42);
"#,
        asset("coffee.png"),
        asset("chelsea.png"),
        asset("masks/chelsea_face.png")
    );
    let path = dir.join("cat.rhai");
    std::fs::write(&path, text).unwrap();
    path
}

/// A `lapclone repl SCENE --view --port 0` whose stdin the test writes.
pub(super) struct ViewRepl {
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
    pub(super) url: String,
}

impl ViewRepl {
    pub(super) fn start(dir: &Path, scene: &Path) -> ViewRepl {
        Self::start_with(dir, scene, &[])
    }

    fn start_with(dir: &Path, scene: &Path, extra: &[&str]) -> ViewRepl {
        Self::start_in(
            Command::new(env!("CARGO_BIN_EXE_lapclone")),
            dir,
            scene,
            extra,
        )
    }

    /// Started by `command`, which runs `lapclone` with the arguments it is given (the
    /// binary itself, or a program that runs it such as `prlimit`).
    pub(super) fn start_in(
        mut command: Command,
        dir: &Path,
        scene: &Path,
        extra: &[&str],
    ) -> ViewRepl {
        let mut child = command
            .args(["repl", scene.to_str().unwrap(), "--view", "--port", "0"])
            .args(extra)
            .arg("--preview")
            .arg(dir.join("preview.png"))
            .current_dir(dir)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, lines) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let stdin = child.stdin.take();
        let mut repl = ViewRepl {
            child,
            stdin,
            lines,
            url: String::new(),
        };
        let first = repl.wait_line(|l| l.starts_with("view: "));
        repl.url = first.trim_start_matches("view: ").to_string();
        repl.wait_line(|l| l.starts_with("preview"));
        repl
    }

    pub(super) fn wait_line(&self, found: impl Fn(&str) -> bool) -> String {
        loop {
            match self.lines.recv_timeout(WAIT) {
                Ok(line) if found(&line) => return line,
                Ok(_) => {}
                Err(RecvTimeoutError::Timeout) => panic!("no such line from the REPL"),
                Err(RecvTimeoutError::Disconnected) => panic!("the REPL ended"),
            }
        }
    }

    /// The REPL's next line, whatever it is.
    pub(super) fn next_line(&self) -> String {
        self.wait_line(|_| true)
    }

    pub(super) fn type_line(&mut self, line: &str) {
        let stdin = self.stdin.as_mut().unwrap();
        writeln!(stdin, "{line}").unwrap();
        stdin.flush().unwrap();
    }

    pub(super) fn host(&self) -> String {
        self.url
            .trim_start_matches("http://")
            .split('/')
            .next()
            .unwrap()
            .to_string()
    }

    pub(super) fn socket_url(&self) -> String {
        self.url
            .replacen("/?token=", "/ws?token=", 1)
            .replacen("http://", "ws://", 1)
    }

    pub(super) fn connect(
        &self,
        url: &str,
        origin: Option<&str>,
    ) -> Result<Page, tungstenite::Error> {
        let mut request = url.into_client_request().unwrap();
        if let Some(origin) = origin {
            request
                .headers_mut()
                .insert("Origin", origin.parse().unwrap());
        }
        let (socket, _) = tungstenite::connect(request)?;
        if let MaybeTlsStream::Plain(s) = socket.get_ref() {
            s.set_read_timeout(Some(WAIT)).unwrap();
        }
        let mut page = Page {
            socket,
            frame: Vec::new(),
            width: 0,
            height: 0,
            scene: Value::Null,
            rects: Vec::new(),
        };
        page.until_scene();
        Ok(page)
    }

    pub(super) fn page(&self) -> Page {
        let origin = format!("http://{}", self.host());
        self.connect(&self.socket_url(), Some(&origin)).unwrap()
    }

    pub(super) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Closes stdin (the server ends with the input) and waits for the exit.
    pub(super) fn finish(mut self) -> std::process::ExitStatus {
        drop(self.stdin.take());
        self.child.wait().unwrap()
    }
}

/// A page's view of the session: the frame rebuilt from the updates, and the last scene
/// message.
pub(super) struct Page {
    pub(super) socket: WebSocket<MaybeTlsStream<TcpStream>>,
    frame: Vec<u8>,
    width: u32,
    height: u32,
    pub(super) scene: Value,
    /// The rectangles of the frame updates since the last `until_scene`.
    rects: Vec<[u32; 4]>,
}

impl Page {
    pub(super) fn send(&mut self, message: &Value) {
        self.socket
            .send(Message::Text(message.to_string().into()))
            .unwrap();
    }

    fn send_text(&mut self, text: &str) {
        self.socket.send(Message::Text(text.into())).unwrap();
    }

    /// Reads messages until a text one for which `done` holds; frames are applied.
    pub(super) fn until(&mut self, done: impl Fn(&Value) -> bool) -> Value {
        loop {
            match self.socket.read().unwrap() {
                Message::Binary(bytes) => self.apply(&bytes),
                Message::Text(text) => {
                    let value: Value = serde_json::from_str(text.as_str()).unwrap();
                    if value["type"] == "scene" {
                        self.scene = value.clone();
                    }
                    if done(&value) {
                        return value;
                    }
                    assert!(value["type"] != "error", "unexpected {value}");
                }
                _ => {}
            }
        }
    }

    fn until_scene(&mut self) -> Value {
        self.rects.clear();
        self.until(|v| v["type"] == "scene")
    }

    fn apply(&mut self, bytes: &[u8]) {
        let u = |i: usize| u32::from_le_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap());
        let (width, height, x, y, w, h) = (u(1), u(2), u(3), u(4), u(5), u(6));
        // Each row's run of changed pixels: [first column from x, length].
        let runs: Vec<[u32; 2]> = match u(0) {
            1 => vec![[0, w]; h as usize],
            2 => (0..h as usize)
                .map(|j| [u(7 + 2 * j), u(8 + 2 * j)])
                .collect(),
            kind => panic!("frame message kind {kind}"),
        };
        let table = if u(0) == 2 { 8 * h as usize } else { 0 };
        let pixels: usize = runs.iter().map(|r| r[1] as usize * 4).sum();
        assert_eq!(bytes.len(), 28 + table + pixels);
        assert!(runs.iter().all(|&[first, length]| first + length <= w));
        if (width, height) != (self.width, self.height) {
            assert_eq!(
                (x, y, w, h),
                (0, 0, width, height),
                "a new size comes whole"
            );
            self.frame = vec![0; (width * height * 4) as usize];
            (self.width, self.height) = (width, height);
        }
        let mut src = 28 + table;
        for (j, [first, length]) in (0..).zip(runs) {
            let dst = (((y + j) * width + x + first) * 4) as usize;
            let len = (length * 4) as usize;
            self.frame[dst..dst + len].copy_from_slice(&bytes[src..src + len]);
            src += len;
        }
        self.rects.push([x, y, w, h]);
    }

    /// The page's connection itself, for bytes sent as no WebSocket client would send them.
    fn raw_stream(&self) -> TcpStream {
        match self.socket.get_ref() {
            MaybeTlsStream::Plain(s) => s.try_clone().unwrap(),
            _ => unreachable!("the tests connect without TLS"),
        }
    }

    fn rev(&self) -> u64 {
        self.scene["rev"].as_u64().unwrap()
    }

    fn cat_at(&self) -> [f64; 2] {
        let at = &self.scene["patches"][0]["at"];
        [at[0].as_f64().unwrap(), at[1].as_f64().unwrap()]
    }
}

pub(super) fn preview_png(dir: &Path, scene: &Path, t: f64) -> image::RgbaImage {
    let out = dir.join(format!("preview-{t}.png"));
    let status = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args([
            "preview",
            scene.to_str().unwrap(),
            "--t",
            &t.to_string(),
            "-o",
        ])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    image::open(&out).unwrap().to_rgba8()
}

#[test]
fn a_drag_updates_the_frame_as_preview_renders_the_saved_scene_and_undo_restores_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    repl.type_line(":t 1.25");
    page.until(|v| v["type"] == "scene" && v["t"] == 1.25);
    let before = page.frame.clone();
    let [x, y] = page.cat_at().map(f64::round);
    let rev = page.rev();
    // The pointer moves: previews follow (no history), then the gesture ends.
    for step in 1..=4 {
        let value = [x + 10.0 * step as f64, y];
        page.send(&json!({"type": "edit", "rev": rev, "commit": false, "edit": {"op": "at", "patch": "cat", "value": value}}));
        page.until_scene();
        assert_eq!(page.rev(), rev, "a preview is not a change of the scene");
    }
    page.send(&json!({"type": "edit", "rev": rev, "commit": true, "edit": {"op": "at", "patch": "cat", "value": [x + 40.0, y]}}));
    let line = page.until(|v| v["type"] == "line");
    let expected = format!("cat.at(1.25, [{}, {}]);", x + 40.0, y);
    assert_eq!(line["text"], expected.as_str());
    repl.wait_line(|l| l == format!("(view) {expected}"));
    let saved = dir.path().join("saved.rhai");
    repl.type_line(&format!(":save {}", saved.display()));
    repl.wait_line(|l| l.starts_with("saved "));
    // Every update was a rectangle, never more than the frame; the rebuilt frame is exactly
    // what `lapclone preview` writes for the saved scene.
    let reference = preview_png(dir.path(), &saved, 1.25);
    assert_eq!((page.width, page.height), reference.dimensions());
    assert!(
        page.frame == reference.as_raw()[..],
        "frame differs from lapclone preview"
    );
    assert!(page.frame != before, "the drag changed nothing");
    // :undo from the page restores the frame byte for byte.
    page.send(&json!({"type": "undo"}));
    // The frame and scene message come before the line.
    page.until(|v| v["type"] == "line" && v["text"] == ":undo");
    assert!(page.frame == before, ":undo did not restore the frame");
    assert!(repl.finish().success());
}

/// Escape leaves no trace; an edit against a revision the scene never had is refused as
/// such, and one against a past revision as stale, with the scene sent again to redo it
/// against; neither changes anything.
#[test]
fn escape_leaves_no_trace_and_stale_edits_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    let before = page.frame.clone();
    let rev = page.rev();
    let [x, y] = page.cat_at();
    page.send(&json!({"type": "edit", "rev": rev, "commit": false, "edit": {"op": "rotate", "patch": "cat", "value": 30}}));
    page.until_scene();
    assert!(page.frame != before);
    page.send(&json!({"type": "cancel"}));
    page.until_scene();
    assert!(page.frame == before, "cancel did not restore the frame");
    let moved = json!({"op": "at", "patch": "cat", "value": [x + 5.0, y]});
    page.send(&json!({"type": "edit", "rev": rev + 7, "commit": true, "edit": moved}));
    let error = page.until(|v| v["type"] == "error");
    let expected = format!(
        "edit against revision {}: the scene is at revision {rev}",
        rev + 7
    );
    assert!(
        error["message"].as_str().unwrap().contains(&expected),
        "{error}"
    );
    page.send(&json!({"type": "mesh", "on": false}));
    page.until_scene();
    assert_eq!(page.rev(), rev);
    assert!(page.frame == before);
    // A typed entry moves the scene on; the page's edit against the revision before is stale.
    repl.type_line("cat.scale(0, 0.43);");
    let now = page.until(|v| v["type"] == "scene" && v["rev"].as_u64() != Some(rev))["rev"].clone();
    page.send(&json!({"type": "edit", "rev": rev, "commit": true, "edit": moved}));
    let error = page.until(|v| v["type"] == "error");
    let expected = format!("stale edit: the scene changed since (revision {rev}, now {now})");
    assert!(
        error["message"].as_str().unwrap().contains(&expected),
        "{error}"
    );
    // The scene sent again came before the error, and the cat is where it was.
    assert_eq!((page.rev(), page.cat_at()), (now.as_u64().unwrap(), [x, y]));
    assert!(repl.finish().success());
}

/// A page's playhead past the scene's end is refused, as `preview --t` and `:t` refuse it:
/// a seek there, and an edit keyed there, get an error and change nothing.
#[test]
fn a_page_seeking_or_keying_past_the_scene_s_end_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    let (before, rev) = (page.frame.clone(), page.rev());
    let t = page.scene["t"].as_f64().unwrap();
    page.send(&json!({"type": "seek", "t": 2.5}));
    let error = page.until(|v| v["type"] == "error");
    let message = error["message"].as_str().unwrap();
    assert!(
        message.contains("t = 2.5 s is past the scene's end: it lasts 2 s"),
        "{error}"
    );
    let edit = json!({"op": "at", "patch": "cat", "value": [300, 150]});
    page.send(&json!({"type": "edit", "rev": rev, "commit": true, "t": 3, "edit": edit}));
    let error = page.until(|v| v["type"] == "error");
    assert!(
        error["message"]
            .as_str()
            .unwrap()
            .contains("past the scene's end"),
        "{error}"
    );
    // Nor can a key be moved there (the cat's `at` has a key at 0).
    let edit = json!({"op": "move_key", "patch": "cat", "track": "at", "from": 0, "to": 999999.5});
    page.send(&json!({"type": "edit", "rev": rev, "commit": true, "edit": edit}));
    let error = page.until(|v| v["type"] == "error");
    let message = error["message"].as_str().unwrap();
    assert!(
        message.contains("t = 999999.5 s is past the scene's end"),
        "{error}"
    );
    // The end itself is inside.
    page.send(&json!({"type": "seek", "t": 2}));
    page.until(|v| v["type"] == "scene" && v["t"].as_f64() == Some(2.0));
    page.send(&json!({"type": "seek", "t": t}));
    page.until(|v| v["type"] == "scene" && v["t"].as_f64() == Some(t));
    assert!(page.frame == before);
    assert_eq!(page.rev(), rev);
    assert!(repl.finish().success());
}

/// A page's save is acknowledged as its other entries are: the `:save` line in every page.
#[test]
fn a_page_save_is_shown_as_its_line_in_every_page() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let (mut page, mut other) = (repl.page(), repl.page());
    let rev = page.rev();
    let edit = json!({"op": "at", "patch": "cat", "value": [300, 150]});
    page.send(&json!({"type": "edit", "rev": rev, "commit": true, "edit": edit}));
    page.until(|v| v["type"] == "scene" && v["rev"].as_u64() > Some(rev));
    page.send(&json!({"type": "save", "rev": page.rev()}));
    for p in [&mut page, &mut other] {
        let line = p.until(|v| {
            v["type"] == "line" && v["text"].as_str().is_some_and(|t| t.starts_with(":save "))
        });
        assert!(
            line["text"].as_str().unwrap().ends_with("cat.rhai"),
            "{line}"
        );
    }
    let saved = std::fs::read_to_string(&scene).unwrap();
    assert!(saved.contains("cat.at(0, [300, 150]);"), "{saved}");
    assert!(repl.finish().success());
}

/// A preview lasts only until the session runs an entry: one that shows nothing (a plain
/// `let`) or a commit that changes nothing still puts the committed scene back on every page.
#[test]
fn no_preview_outlives_an_entry_that_shows_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    let mut other = repl.page();
    let before = page.frame.clone();
    let rev = page.rev();
    let preview = json!({"type": "edit", "rev": rev, "commit": false, "edit": {"op": "scale", "patch": "cat", "value": 0.8}});
    page.send(&preview);
    page.until_scene();
    assert!(page.frame != before, "the preview changed nothing");
    repl.type_line("let unrelated = 1;");
    page.until_scene();
    assert!(
        page.frame == before,
        "a typed line left the preview on the page"
    );
    page.send(&preview);
    page.until_scene();
    assert!(page.frame != before);
    // The other page commits the value the scene already has: one line, no change.
    other.send(&json!({"type": "edit", "rev": rev, "commit": true, "edit": {"op": "scale", "patch": "cat", "value": 0.42}}));
    page.until(|v| v["type"] == "line" && v["text"] == "cat.scale(0, 0.42);");
    assert!(
        page.frame == before,
        "a commit that changed nothing left the preview"
    );
    page.send(&json!({"type": "seek", "t": 0}));
    page.until_scene();
    assert!(page.frame == before, "the preview outlived the commit");
    assert_eq!(page.rev(), rev);
    assert!(repl.finish().success());
}

/// A page closed mid-gesture takes its preview with it, as Escape would: the other pages
/// go back to the committed scene.
#[test]
fn a_page_closed_mid_gesture_leaves_no_preview_behind() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut gone = repl.page();
    let mut other = repl.page();
    let (before, [x, y]) = (other.frame.clone(), other.cat_at());
    let edit = json!({"op": "at", "patch": "cat", "value": [x + 40.0, y]});
    gone.send(&json!({"type": "edit", "rev": gone.rev(), "commit": false, "edit": edit}));
    other.until_scene();
    assert!(other.frame != before, "the preview changed nothing");
    drop(gone);
    other.until_scene();
    assert!(other.frame == before, "the closed page's preview stayed");
    assert_eq!(other.cat_at(), [x, y]);
    assert!(repl.finish().success());
}

/// A page's line names a patch by a variable only while that variable, as entries see it,
/// holds the patch: after `let cat = dog;` (the scope keeps the old `cat` behind the new one)
/// or `let cat = 5;`, the line says `get_patch("cat")` and moves the cat, not the dog.
#[test]
fn a_page_line_never_names_a_patch_through_a_shadowed_variable() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut text = std::fs::read_to_string(&scene).unwrap();
    text.push_str(&format!(
        "let dog = patch(\"dog\", #{{ source: \"{}\", mask: \"{}\" }});\ndog.at(0, [100, 100]);\n",
        asset("chelsea.png"),
        asset("masks/chelsea_face.png")
    ));
    std::fs::write(&scene, text).unwrap();
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    let at = |page: &Page, i: usize| page.scene["patches"][i]["at"].clone();
    for (shadow, x) in [("let cat = dog;", 40), ("let cat = 5;", 60)] {
        repl.type_line(shadow);
        // `:t` publishes the frame: the shadowing line has run before it.
        repl.type_line(":t 0");
        page.until_scene();
        let dog = at(&page, 1);
        let edit = json!({"op": "at", "patch": "cat", "value": [x, 50]});
        page.send(&json!({"type": "edit", "rev": page.rev(), "commit": true, "edit": edit}));
        let line = page.until(|v| v["type"] == "line");
        let want = format!("get_patch(\"cat\").at(0, [{x}, 50]);");
        assert_eq!(line["text"], want.as_str(), "after {shadow}");
        // The entry's scene message came before its line.
        assert_eq!(at(&page, 0), json!([x as f64, 50.0]), "after {shadow}");
        assert_eq!(at(&page, 1), dog, "the dog moved after {shadow}");
    }
    assert!(repl.finish().success());
}

/// A gesture's keys go at the playhead it began at, even when another page seeks while it
/// runs: its values were measured in that frame.
#[test]
fn a_seek_from_another_page_mid_gesture_leaves_the_gestures_keys_where_it_began() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    let mut other = repl.page();
    repl.type_line(":t 1.25");
    page.until(|v| v["type"] == "scene" && v["t"] == 1.25);
    let rev = page.rev();
    let [x, y] = page.cat_at().map(f64::round);
    let edit = |value: [f64; 2], commit: bool| {
        json!({"type": "edit", "rev": rev, "commit": commit, "t": 1.25,
               "edit": {"op": "at", "patch": "cat", "value": value}})
    };
    page.send(&edit([x + 10.0, y], false));
    page.until_scene();
    other.send(&json!({"type": "seek", "t": 0.5}));
    page.until(|v| v["type"] == "scene" && v["t"] == 0.5);
    page.send(&edit([x + 20.0, y], false));
    page.until_scene();
    page.send(&edit([x + 20.0, y], true));
    let line = page.until(|v| v["type"] == "line");
    let expected = format!("cat.at(1.25, [{}, {}]);", x + 20.0, y);
    assert_eq!(line["text"], expected.as_str());
    // The session stays where the other page put it, showing the committed scene there (the
    // frame and scene message come before the line).
    assert_eq!(page.scene["t"], 0.5);
    let saved = dir.path().join("saved.rhai");
    repl.type_line(&format!(":save {}", saved.display()));
    repl.wait_line(|l| l.starts_with("saved "));
    let reference = preview_png(dir.path(), &saved, 0.5);
    assert!(
        page.frame == reference.as_raw()[..],
        "frame differs from preview at 0.5"
    );
    assert!(repl.finish().success());
}

#[test]
fn wrong_tokens_foreign_origins_and_malformed_messages_change_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let own = format!("http://{}", repl.host());
    let url = repl.socket_url();
    let (base, token) = url.split_once("?token=").unwrap();
    let wrong: String = token.chars().rev().collect();
    for (attempt, origin) in [
        (base.to_string(), Some(own.as_str())),
        (format!("{base}?token={wrong}"), Some(own.as_str())),
        (format!("{base}?token="), Some(own.as_str())),
        (url.clone(), Some("http://evil.example")),
        (url.clone(), None),
    ] {
        match repl.connect(&attempt, origin) {
            Err(tungstenite::Error::Http(response)) => assert_eq!(response.status(), 403),
            Err(other) => panic!("{attempt}: {other}"),
            Ok(_) => panic!("{attempt} with Origin {origin:?} was accepted"),
        }
    }
    let mut page = repl.page();
    let before = page.frame.clone();
    let rev = page.rev();
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    for i in 0..1000 {
        let text = malformed(i, &mut seed);
        page.send_text(&text);
        let reply = page.until(|v| v["type"] == "error");
        assert!(reply["message"].is_string(), "{text}");
    }
    page.send(&json!({"type": "mesh", "on": false}));
    page.until_scene();
    assert_eq!(page.rev(), rev, "a malformed message changed the scene");
    assert!(page.frame == before);
    // Too large for the server: refused, and the session goes on.
    page.send_text(&format!(
        "{{\"type\":\"seek\",\"t\":1{}}}",
        " ".repeat(20_000)
    ));
    let mut again = repl.page();
    assert_eq!(again.rev(), rev);
    again.send(&json!({"type": "seek", "t": 0.5}));
    again.until(|v| v["type"] == "scene" && v["t"] == 0.5);
    assert!(repl.finish().success());
}

fn next(seed: &mut u64) -> u64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    *seed
}

/// Message `i` of the malformed set: every tenth is random characters, the rest valid
/// shapes with one part broken (unknown type or op, missing or extra field, wrong type,
/// out-of-range or non-finite number, unknown patch, handle or key, code instead of values).
fn malformed(i: usize, seed: &mut u64) -> String {
    let r = next(seed);
    if i % 10 == 0 {
        let len = (r % 200) as usize;
        return (0..len)
            .map(|_| char::from_u32((next(seed) % 0x250) as u32).unwrap_or('?'))
            .collect();
    }
    let n = (r >> 8) % 1000;
    let cases = [
        json!({"type": "eval", "code": "canvas(1, 1)"}),
        json!({"type": "seek"}),
        json!({"type": "seek", "t": -1.0 - n as f64}),
        json!({"type": "seek", "t": "1"}),
        json!({"type": "seek", "t": 1e300}),
        json!({"type": "locate", "x": 1, "y": 2, "z": n}),
        json!({"type": "edit", "rev": 0, "commit": true, "edit": {"op": "at", "patch": "cat", "value": [1, 2, 3]}}),
        json!({"type": "edit", "rev": 1, "commit": true, "edit": {"op": "at", "patch": format!("dog{n}"), "value": [1, 2]}}),
        json!({"type": "edit", "rev": 1, "commit": true, "edit": {"op": "load", "path": "/etc/passwd"}}),
        json!({"type": "edit", "rev": 1, "commit": true, "edit": {"op": "scale", "patch": "cat", "value": -(n as f64)}}),
        json!({"type": "edit", "rev": 1, "commit": true, "edit": {"op": "remove_handle", "patch": "cat", "handle": n}}),
        json!({"type": "edit", "rev": 1, "commit": true, "edit": {"op": "remove_key", "patch": "cat", "track": "at", "t": 0.5 + n as f64}}),
        json!({"type": "edit", "rev": 1, "commit": true, "edit": {"op": "move_key", "patch": "cat", "track": "colour", "from": 0, "to": 1}}),
        json!({"type": "edit", "rev": 1, "commit": false, "edit": {"op": "add_pin", "patch": "cat", "at": [1, 2]}}),
        json!({"type": "edit", "rev": 1, "commit": true, "edit": {"op": "at", "patch": "cat", "value": "cat.at(0, [0, 0])"}}),
        json!({"type": "save", "rev": 1u64 << 40}),
        json!({"type": "mesh", "on": "yes"}),
        json!([1, 2, 3]),
        json!("undo"),
    ];
    let mut text = cases[(r as usize / 7) % cases.len()].to_string();
    if r % 3 == 0 {
        // Truncated somewhere inside.
        let cut = (next(seed) as usize) % text.len().max(1);
        text.truncate(cut);
    }
    text
}

#[test]
fn each_page_edit_is_one_line_and_gives_the_scene_typing_it_gives() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    repl.type_line(":t 0.5");
    page.until(|v| v["type"] == "scene" && v["t"] == 0.5);
    let edits = [
        (
            json!({"op": "at", "patch": "cat", "value": [300.126, 150]}),
            "cat.at(0.5, [300.13, 150]);",
        ),
        (
            json!({"op": "rotate", "patch": "cat", "value": 15}),
            "cat.rotate(0.5, 15);",
        ),
        (
            json!({"op": "scale", "patch": "cat", "value": 0.5}),
            "cat.scale(0.5, 0.5);",
        ),
        (
            json!({"op": "add_handle", "patch": "cat", "from": [250, 200], "radius": 60}),
            "let h = cat.drag([250, 200], 60);",
        ),
        (
            json!({"op": "handle_key", "patch": "cat", "handle": 0, "value": [262, 190]}),
            "cat.handle(0).key(0.5, [262, 190]);",
        ),
        (
            json!({"op": "handle_radius", "patch": "cat", "handle": 0, "value": 75.004}),
            "cat.handle(0).radius(75);",
        ),
        (
            json!({"op": "move_key", "patch": "cat", "handle": 0, "track": "at", "from": 0.5, "to": 1}),
            "cat.handle(0).move_key(0.5, 1, \"at\");",
        ),
        (
            json!({"op": "handle_key", "patch": "cat", "handle": 0, "value": [258, 186]}),
            "cat.handle(0).key(0.5, [258, 186]);",
        ),
        (
            json!({"op": "remove_key", "patch": "cat", "handle": 0, "track": "at", "t": 1}),
            "cat.handle(0).remove_key(1, \"at\");",
        ),
        (
            json!({"op": "add_pin", "patch": "cat", "at": [200, 150]}),
            "cat.pin([200, 150]);",
        ),
        (
            json!({"op": "add_handle", "patch": "cat", "from": [300, 250], "radius": 30}),
            "let h2 = cat.drag([300, 250], 30);",
        ),
        (
            json!({"op": "remove_handle", "patch": "cat", "handle": 1}),
            "cat.remove_handle(1);",
        ),
        (
            json!({"op": "remove_pin", "patch": "cat", "pin": 0}),
            "cat.remove_pin(0);",
        ),
        (
            json!({"op": "move_key", "patch": "cat", "track": "at", "from": 2, "to": 1.5}),
            "cat.move_key(2, 1.5, \"at\");",
        ),
        (
            json!({"op": "remove_key", "patch": "cat", "track": "scale", "t": 0}),
            "cat.remove_key(0, \"scale\");",
        ),
    ];
    let mut handle_keys = Vec::new();
    for (edit, line) in &edits {
        // A handle's target and radius preview before they commit, as a drag would.
        if edit["op"] == "handle_key" || edit["op"] == "handle_radius" {
            page.send(&json!({"type": "edit", "rev": page.rev(), "commit": false, "edit": edit}));
            page.until_scene();
        }
        page.send(&json!({"type": "edit", "rev": page.rev(), "commit": true, "edit": edit}));
        let reply = page.until(|v| v["type"] == "line");
        assert_eq!(reply["text"], *line);
        // The scene message came before the line.
        if let Some(handle) = page.scene["patches"][0]["handles"].get(0) {
            handle_keys.push(handle["keys"]["at"].clone());
        }
    }
    // The scene messages carry the handle's keys for its markers, as the lines left them.
    assert!(handle_keys.contains(&json!([0.5, 1.0])), "{handle_keys:?}");
    assert_eq!(handle_keys.last(), Some(&json!([0.5])));
    assert_eq!(page.scene["patches"][0]["handles"][0]["radius"], 75.0);
    let from_page = dir.path().join("from_page.rhai");
    repl.type_line(&format!(":save {}", from_page.display()));
    repl.wait_line(|l| l.starts_with("saved "));
    let frame = page.frame.clone();
    assert!(repl.finish().success());
    // The same lines typed into a fresh session give the same saved scene.
    let typed = dir.path().join("typed.rhai");
    let mut script: Vec<String> = vec![":t 0.5".into()];
    script.extend(edits.iter().map(|(_, line)| line.to_string()));
    script.push(format!(":save {}", typed.display()));
    run_typed(dir.path(), &scene, &script);
    assert_eq!(
        std::fs::read_to_string(&from_page).unwrap(),
        std::fs::read_to_string(&typed).unwrap()
    );
    assert!(frame == preview_png(dir.path(), &typed, 0.5).as_raw()[..]);
}

/// Runs `lines` as a typed REPL session on `scene` (with a preview) and checks it succeeds.
fn run_typed(dir: &Path, scene: &Path, lines: &[String]) {
    let script = dir.join("typed_script.txt");
    std::fs::write(&script, lines.join("\n") + "\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args(["repl", scene.to_str().unwrap(), "--preview"])
        .arg(dir.join("typed.png"))
        .arg("--script")
        .arg(script)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn watch_reloads_a_changed_file_keeping_the_playhead_unless_edits_are_unsaved() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start_with(dir.path(), &scene, &["--watch"]);
    let mut page = repl.page();
    repl.type_line(":t 1");
    page.until(|v| v["type"] == "scene" && v["t"] == 1.0);
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(
        &scene,
        text.replace("cat.scale(0, 0.42);", "cat.scale(0, 0.5);"),
    )
    .unwrap();
    repl.wait_line(|l| l.starts_with("loaded "));
    page.until(|v| v["type"] == "scene" && v["patches"][0]["scale"] == 0.5);
    assert_eq!(page.scene["t"], 1.0, "the playhead moved");
    repl.type_line("cat.rotate(0, 10);");
    page.until(|v| v["type"] == "scene" && v["patches"][0]["rotation"] == 10.0);
    std::fs::write(&scene, &text).unwrap();
    repl.wait_line(|l| l.contains("not reloaded: the session has unsaved edits"));
    // The session's own `:save` of the loaded file is no change to reload: its history stays.
    repl.type_line(&format!(":save {}", scene.display()));
    repl.wait_line(|l| l.starts_with("saved "));
    std::thread::sleep(Duration::from_millis(1500));
    repl.type_line(":undo");
    let line = repl.wait_line(|l| l.starts_with("undone") || l.starts_with("loaded "));
    assert!(line.starts_with("undone"), "the save was reloaded: {line}");
    // As many edits as were saved, but not the saved ones: still unsaved.
    repl.type_line("cat.rotate(0, 20);");
    page.until(|v| v["type"] == "scene" && v["patches"][0]["rotation"] == 20.0);
    std::fs::write(&scene, text.replace("0.42", "0.45")).unwrap();
    repl.wait_line(|l| l.contains("not reloaded: the session has unsaved edits"));
    assert!(repl.finish().success());
}

/// The cat scene with a drag handle on its face, keyed so it pulls at t = 1.
pub(super) fn handle_scene(dir: &Path) -> PathBuf {
    let path = cat_scene(dir);
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push_str("let h = cat.drag([225, 175], 30);\nh.key(0, [225, 175]).key(1, [250, 160]);\n");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_circle_drag_changes_the_radius_live_and_commits_one_line_preview_agrees_with() {
    let dir = tempfile::tempdir().unwrap();
    let scene = handle_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    repl.type_line(":t 1");
    page.until(|v| v["type"] == "scene" && v["t"] == 1.0);
    let before = page.frame.clone();
    let rev = page.rev();
    let mut frames = Vec::new();
    // The pointer moves the circle's edge out: the clone follows every move, uncommitted.
    for radius in [40.0, 55.5, 70.123] {
        let edit = json!({"op": "handle_radius", "patch": "cat", "handle": 0, "value": radius});
        page.send(&json!({"type": "edit", "rev": rev, "commit": false, "edit": edit}));
        page.until_scene();
        assert_eq!(page.rev(), rev, "a preview is not a change of the scene");
        assert_eq!(
            page.scene["patches"][0]["handles"][0]["radius"],
            (radius * 100.0_f64).round() / 100.0
        );
        frames.push(page.frame.clone());
    }
    assert!(
        frames[0] != before && frames[1] != frames[0],
        "the radius changed nothing"
    );
    let edit = json!({"op": "handle_radius", "patch": "cat", "handle": 0, "value": 70.123});
    page.send(&json!({"type": "edit", "rev": rev, "commit": true, "edit": edit}));
    let line = page.until(|v| v["type"] == "line");
    assert_eq!(line["text"], "cat.handle(0).radius(70.12);");
    repl.wait_line(|l| l == "(view) cat.handle(0).radius(70.12);");
    assert!(
        page.frame == frames[2],
        "the committed frame is not the last previewed one"
    );
    let saved = dir.path().join("saved.rhai");
    repl.type_line(&format!(":save {}", saved.display()));
    // The page's line is not followed by the value its call gave back.
    let next = repl.next_line();
    assert!(next.starts_with("saved "), "after the page's line: {next}");
    assert!(page.frame == preview_png(dir.path(), &saved, 1.0).as_raw()[..]);
    assert!(repl.finish().success());
    // Typing the line gives the same scene.
    let typed = dir.path().join("typed.rhai");
    let script = [
        "cat.handle(0).radius(70.12);".to_string(),
        format!(":save {}", typed.display()),
    ];
    run_typed(dir.path(), &scene, &script);
    assert_eq!(
        std::fs::read_to_string(&saved).unwrap(),
        std::fs::read_to_string(&typed).unwrap()
    );
}

#[test]
fn the_scene_message_carries_a_followed_tracks_path() {
    let dir = tempfile::tempdir().unwrap();
    let mut track = String::from("frame,x,y\n");
    let points: Vec<[f64; 2]> = (0..48)
        .map(|k| [280.25 + 1.5 * k as f64, 150.5 - 0.75 * k as f64])
        .collect();
    for (k, [x, y]) in points.iter().enumerate() {
        track.push_str(&format!("{},{x},{y}\n", k + 1));
    }
    std::fs::write(dir.path().join("track.csv"), track).unwrap();
    let scene = handle_scene(dir.path());
    let mut text = std::fs::read_to_string(&scene).unwrap();
    text.push_str(
        "cat.follow(\"track.csv\", #{ offset: [5, -3] });\nh.follow(\"track.csv\", #{ offset: [-60, 30] });\n",
    );
    std::fs::write(&scene, text).unwrap();
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    repl.type_line(":t 0.2");
    page.until(|v| v["type"] == "scene" && v["t"] == 0.2);
    let patch = page.scene["patches"][0].clone();
    let path = |offset: [f64; 2]| -> Value {
        points
            .iter()
            .map(|p| json!([p[0] + offset[0], p[1] + offset[1]]))
            .collect()
    };
    let follow = &patch["follow"];
    assert_eq!(follow["file"], "track.csv");
    assert_eq!(follow["keys"], 48);
    assert_eq!(follow["path"], path([5.0, -3.0]));
    // Frame 5 (t = 4/24 ≤ 0.2 < 5/24) is the current one.
    assert_eq!(follow["current"], 4);
    let handle = &patch["handles"][0]["follow"];
    assert_eq!(handle["path"], path([-60.0, 30.0]));
    assert_eq!(handle["current"], 4);
    // A key of the page's own replaces the followed keys: the patch no longer follows.
    let rev = page.rev();
    page.send(&json!({"type": "edit", "rev": rev, "commit": true, "edit": {"op": "at", "patch": "cat", "value": [300, 160]}}));
    page.until(|v| v["type"] == "line");
    assert_eq!(page.scene["patches"][0]["follow"], Value::Null);
    assert_eq!(page.scene["patches"][0]["handles"][0]["follow"]["keys"], 48);
    // :undo puts the followed keys back, and with them the path.
    repl.type_line(":undo");
    page.until(|v| v["type"] == "scene" && !v["patches"][0]["follow"].is_null());
    assert_eq!(
        page.scene["patches"][0]["follow"]["path"],
        path([5.0, -3.0])
    );
    assert!(repl.finish().success());
}

/// The page's HTTP answer, read whole.
pub(super) fn get_page(repl: &ViewRepl) -> String {
    use std::io::Read as _;
    let mut stream = TcpStream::connect(repl.host()).unwrap();
    stream.set_read_timeout(Some(WAIT)).unwrap();
    let path = repl.url.split_once(&repl.host()).unwrap().1.to_string();
    let request = format!("GET {path} HTTP/1.1\r\nHost: {}\r\n\r\n", repl.host());
    stream.write_all(request.as_bytes()).unwrap();
    let mut answer = String::new();
    stream.read_to_string(&mut answer).unwrap();
    answer
}

#[test]
fn a_connection_past_the_limit_is_told_why_and_a_closed_page_frees_its_place() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut pages: Vec<Page> = (0..32).map(|_| repl.page()).collect();
    // Both the page and its WebSocket are told why.
    let busy = get_page(&repl);
    assert!(busy.starts_with("HTTP/1.1 503"), "{busy}");
    assert!(busy.contains("serves at most 32 pages at once"), "{busy}");
    let origin = format!("http://{}", repl.host());
    match repl.connect(&repl.socket_url(), Some(&origin)) {
        Err(tungstenite::Error::Http(answer)) => assert_eq!(answer.status(), 503),
        Err(other) => panic!("{other:?}"),
        Ok(_) => panic!("a 33rd page was served"),
    }
    drop(pages.pop());
    // The closed page's thread notices at once; then the page is served.
    let last = (0..100).find_map(|_| {
        let page = repl.connect(&repl.socket_url(), Some(&origin)).ok();
        page.or_else(|| {
            std::thread::sleep(Duration::from_millis(50));
            None
        })
    });
    let mut last = last.expect("the freed place serves a page");
    last.send(&json!({"type": "seek", "t": 0.5}));
    last.until(|v| v["type"] == "scene" && v["t"] == 0.5);
    drop((pages, last));
    assert!(repl.finish().success());
}

/// A client that sends its request head a byte at a time is answered `408` once the head's
/// whole time is up: trickling cannot hold one of the server's few connections for good.
#[test]
fn a_request_head_sent_a_byte_at_a_time_times_out_as_a_whole() {
    use std::io::Read as _;
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut stream = TcpStream::connect(repl.host()).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(400)))
        .unwrap();
    let trickle = b"GET / HTTP/1.1\r\nX-Slow: "
        .iter()
        .chain([b'a'; 200].iter());
    let mut answer = Vec::new();
    for &byte in trickle {
        if stream.write_all(&[byte]).is_err() {
            break;
        }
        let mut buffer = [0u8; 512];
        match stream.read(&mut buffer) {
            Ok(0) => break,
            Ok(n) => answer.extend_from_slice(&buffer[..n]),
            Err(_) => continue,
        }
        if !answer.is_empty() {
            break;
        }
    }
    stream.set_read_timeout(Some(WAIT)).unwrap();
    let _ = stream.read_to_end(&mut answer);
    let answer = String::from_utf8_lossy(&answer);
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer:?}");
    assert!(answer.contains("did not arrive within 5 s"), "{answer:?}");
    assert!(repl.finish().success());
}

/// A request head past the size limit sent whole is answered `431` and the answer arrives:
/// closing with the rest of the head unread would reset the connection and could drop it.
#[test]
fn an_oversized_request_head_gets_its_answer_not_a_reset() {
    use std::io::Read as _;
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    // 9,000 bytes (past the 8 KiB limit, though read in one go), then far past it.
    for (round, size) in [9_000, 200_000, 200_000, 200_000, 200_000]
        .into_iter()
        .enumerate()
    {
        let mut stream = TcpStream::connect(repl.host()).unwrap();
        stream.set_read_timeout(Some(WAIT)).unwrap();
        let filler = "a".repeat(size);
        let request = format!(
            "GET / HTTP/1.1\r\nHost: {}\r\nX-Big: {filler}\r\n\r\n",
            repl.host()
        );
        // The server may stop reading (and answer) before all of it is sent.
        let _ = stream.write_all(request.as_bytes());
        let mut answer = Vec::new();
        let read = stream.read_to_end(&mut answer);
        let answer = String::from_utf8_lossy(&answer);
        assert!(read.is_ok(), "round {round}: {read:?} after {answer:?}");
        assert!(
            answer.starts_with("HTTP/1.1 431"),
            "round {round}: {answer:?}"
        );
        assert!(
            answer.contains("request head too large"),
            "round {round}: {answer:?}"
        );
    }
    assert!(repl.finish().success());
}

/// Wake-ups of the server's page threads so far (voluntary context switches, Linux).
#[cfg(target_os = "linux")]
fn page_thread_wakeups(pid: u32) -> u64 {
    let tasks = std::fs::read_dir(format!("/proc/{pid}/task")).unwrap();
    let mut total = 0;
    for task in tasks.flatten() {
        let comm = std::fs::read_to_string(task.path().join("comm")).unwrap_or_default();
        if comm.trim() != "view-page" {
            continue;
        }
        let status = std::fs::read_to_string(task.path().join("status")).unwrap_or_default();
        let switches = status
            .lines()
            .find_map(|l| l.strip_prefix("voluntary_ctxt_switches:"))
            .and_then(|n| n.trim().parse::<u64>().ok());
        total += switches.unwrap_or(0);
    }
    total
}

/// An idle page's thread sleeps until the page sends something or a frame is published
/// for it (a loop looking every 5 ms woke 200 times a second per page), and a line typed
/// at the terminal still reaches every page.
#[cfg(target_os = "linux")]
#[test]
fn idle_pages_sleep_and_still_follow_the_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut pages: Vec<Page> = (0..4).map(|_| repl.page()).collect();
    std::thread::sleep(Duration::from_millis(300));
    let pid = repl.child.id();
    let before = page_thread_wakeups(pid);
    std::thread::sleep(Duration::from_secs(2));
    let woken = page_thread_wakeups(pid) - before;
    // Four pages over two seconds: about eight with a one-second safety wake each.
    assert!(woken < 40, "{woken} wake-ups of 4 idle page threads in 2 s");
    repl.type_line(":t 1.5");
    for page in &mut pages {
        page.until(|v| v["type"] == "scene" && v["t"] == 1.5);
    }
    drop(pages);
    assert!(repl.finish().success());
}

/// A page message sent in the same write as the WebSocket handshake is applied at once
/// (its bytes are read with the request head, not left waiting for more input).
#[test]
fn a_message_sent_with_the_handshake_is_applied() {
    use std::io::Read as _;
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut stream = TcpStream::connect(repl.host()).unwrap();
    stream.set_read_timeout(Some(WAIT)).unwrap();
    let path = repl
        .socket_url()
        .split_once(&repl.host())
        .unwrap()
        .1
        .to_string();
    let head = format!(
        "GET {path} HTTP/1.1\r\nHost: {h}\r\nOrigin: http://{h}\r\nUpgrade: websocket\r\n\
         Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
         Sec-WebSocket-Version: 13\r\n\r\n",
        h = repl.host()
    );
    // One masked text frame (a zero mask leaves the payload as it is).
    let seek = br#"{"type":"seek","t":0.75}"#;
    let mut bytes = head.into_bytes();
    bytes.extend_from_slice(&[0x81, 0x80 | seek.len() as u8, 0, 0, 0, 0]);
    bytes.extend_from_slice(seek);
    stream.write_all(&bytes).unwrap();
    let mut answer = Vec::new();
    let mut byte = [0u8; 1];
    while !answer.ends_with(b"\r\n\r\n") {
        stream.read_exact(&mut byte).unwrap();
        answer.push(byte[0]);
    }
    assert!(
        answer.starts_with(b"HTTP/1.1 101"),
        "{}",
        String::from_utf8_lossy(&answer)
    );
    let mut socket = WebSocket::from_raw_socket(stream, tungstenite::protocol::Role::Client, None);
    loop {
        if let Message::Text(text) = socket.read().unwrap() {
            let value: Value = serde_json::from_str(text.as_str()).unwrap();
            if value["type"] == "scene" && value["t"] == 0.75 {
                break;
            }
        }
    }
    drop(socket);
    assert!(repl.finish().success());
}

/// A page's close is answered with a close, and a message over the size limit is refused
/// with an error, then a close with code 1009 (message too big), changing nothing: the
/// rest of a fragmented message past the limit is not applied.
#[test]
fn a_close_is_answered_and_an_oversized_message_closes_the_page() {
    use tungstenite::protocol::frame::coding::CloseCode;
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    page.socket.close(None).unwrap();
    let closed = loop {
        match page.socket.read() {
            Ok(_) => continue,
            Err(e) => break e,
        }
    };
    assert!(
        matches!(closed, tungstenite::Error::ConnectionClosed),
        "{closed:?}"
    );
    // Fragments: the start of a seek, a part past the limit, then the seek's end.
    let mut page = repl.page();
    let t = page.scene["t"].clone();
    let big = format!("{:<1$}", "", 17_000);
    let MaybeTlsStream::Plain(stream) = page.socket.get_mut() else {
        panic!("not a plain stream")
    };
    let parts = [
        (0x01, r#"{"type":"seek","t":0.9"#),
        (0x00, big.as_str()),
        (0x80, "}"),
    ];
    for (first_byte, text) in parts {
        // A masked client frame with a zero mask, which leaves the payload as it is.
        let mut frame = vec![first_byte, 0x80 | 126];
        frame.extend_from_slice(&(text.len() as u16).to_be_bytes());
        frame.extend_from_slice(&[0; 4]);
        frame.extend_from_slice(text.as_bytes());
        // The server may already have closed before the last fragment.
        let _ = stream.write_all(&frame);
    }
    let error = page.until(|v| v["type"] == "error");
    assert!(
        error["message"].as_str().unwrap().contains("refused"),
        "{error}"
    );
    let close = match page.socket.read() {
        Ok(Message::Close(frame)) => frame,
        Ok(other) => panic!("after the refusal: {other:?}"),
        Err(e) => panic!("no close frame: {e:?}"),
    };
    assert_eq!(close.map(|f| f.code), Some(CloseCode::Size));
    // Nothing of the refused message was applied.
    let other = repl.page();
    assert_eq!(other.scene["t"], t);
    drop(other);
    assert!(repl.finish().success());
}

/// A page sending a message slowly still gets what the session sends meanwhile: its thread
/// reads what has come and goes back to its queue, instead of waiting in the read for the
/// message's rest, which held every frame for that page until the message was whole.
#[test]
fn a_page_sending_a_message_slowly_still_gets_the_session_s_changes_meanwhile() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut page = repl.page();
    // A seek padded to 4 kB in one masked frame (a zero mask leaves the payload as it is),
    // sent a byte every millisecond: a read that waits for more is never left waiting long.
    let mut seek = br#"{"type":"seek","t":0.25}"#.to_vec();
    seek.resize(4000, b' ');
    let mut bytes = vec![0x81, 0x80 | 126];
    bytes.extend_from_slice(&(seek.len() as u16).to_be_bytes());
    bytes.extend_from_slice(&[0; 4]);
    bytes.extend_from_slice(&seek);
    let mut raw = page.raw_stream();
    raw.set_nonblocking(true).unwrap();
    // Each byte goes out at once, not held back until the last is acknowledged.
    raw.set_nodelay(true).unwrap();
    raw.write_all(&bytes[..10]).unwrap();
    repl.type_line(":t 0.5");
    let mut sent = 10;
    loop {
        assert!(
            sent < bytes.len(),
            "the page got nothing while it sent its message"
        );
        raw.write_all(&bytes[sent..sent + 1]).unwrap();
        sent += 1;
        std::thread::sleep(Duration::from_millis(1));
        match page.socket.read() {
            Ok(Message::Text(text)) => {
                let value: Value = serde_json::from_str(text.as_str()).unwrap();
                if value["type"] == "scene" && value["t"] == 0.5 {
                    break;
                }
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => panic!("{e}"),
        }
    }
    // The rest of the message: the seek is applied once it is whole.
    raw.set_nonblocking(false).unwrap();
    raw.write_all(&bytes[sent..]).unwrap();
    page.until(|v| v["type"] == "scene" && v["t"] == 0.25);
    assert!(repl.finish().success());
}

/// The resident memory of process `pid`, in bytes.
#[cfg(target_os = "linux")]
fn resident_bytes(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let kib = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok());
    kib.unwrap() * 1024
}

/// A page that sends pings and never reads gets its pongs sent under the page's deadline,
/// one at a time: it is disconnected when it has not taken them in time, holding no more
/// than a pong, instead of the server keeping every pong it owes (48 MiB of pings grew it
/// by about as much).
#[cfg(target_os = "linux")]
#[test]
fn a_page_sending_pings_and_never_reading_holds_no_memory_for_its_pongs() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let page = repl.page();
    let before = resident_bytes(repl.pid());
    let mut raw = page.raw_stream();
    raw.set_write_timeout(Some(WAIT)).unwrap();
    // Masked pings of 125 bytes (a zero mask leaves the payload as it is), 1 MiB a write.
    let mut ping = vec![0x89, 0x80 | 125, 0, 0, 0, 0];
    ping.resize(131, b'x');
    let burst: Vec<u8> = ping.iter().copied().cycle().take(131 * 8000).collect();
    let mut sent = 0usize;
    while sent < 48 << 20 && raw.write_all(&burst).is_ok() {
        sent += burst.len();
    }
    let grown = resident_bytes(repl.pid()).saturating_sub(before);
    assert!(
        grown < 16 << 20,
        "{grown} bytes more after {sent} bytes of pings"
    );
    drop(page);
    repl.type_line("40 + 2");
    repl.wait_line(|l| l == "42");
    assert!(repl.finish().success());
}
