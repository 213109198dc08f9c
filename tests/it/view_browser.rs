//! The live view in a real browser: Debian's `chromium`, headless, driven over the Chrome
//! DevTools Protocol (spoken over a WebSocket here, so no extra crate): load the page, drag
//! the cat 40 px with dispatched pointer events, then check the REPL's new line and that
//! the canvas pixels read back from the page equal `lapclone preview` of the `:save`d
//! scene. Skips, saying why, when chromium is not installed.

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use base64::Engine as _;
use serde_json::{json, Value};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

use super::view_ws::{cat_scene, handle_scene, preview_png, ViewRepl};

fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser"].iter().find_map(|name| {
        std::env::split_paths(&path)
            .map(|d| d.join(name))
            .find(|p| p.is_file())
    })
}

/// A headless chromium and a DevTools connection to one page of it.
struct Browser {
    child: Child,
    socket: WebSocket<MaybeTlsStream<TcpStream>>,
    session: String,
    next_id: u64,
    _profile: tempfile::TempDir,
}

impl Browser {
    fn launch(program: &PathBuf, url: &str) -> Browser {
        let profile = tempfile::tempdir().unwrap();
        let mut child = Command::new(program)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                "--window-size=1000,800",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stderr = BufReader::new(child.stderr.take().unwrap());
        let endpoint = stderr
            .lines()
            .map_while(Result::ok)
            .find_map(|l| {
                l.split_once("DevTools listening on ")
                    .map(|(_, u)| u.trim().to_string())
            })
            .expect("chromium printed no DevTools address");
        let (socket, _) = tungstenite::connect(endpoint.as_str()).unwrap();
        let mut browser = Browser {
            child,
            socket,
            session: String::new(),
            next_id: 0,
            _profile: profile,
        };
        let target = browser.call("Target.createTarget", json!({ "url": url }));
        let target_id = target["targetId"].as_str().unwrap().to_string();
        let attached = browser.call(
            "Target.attachToTarget",
            json!({ "targetId": target_id, "flatten": true }),
        );
        browser.session = attached["sessionId"].as_str().unwrap().to_string();
        browser
    }

    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if !self.session.is_empty() {
            message["sessionId"] = json!(self.session);
        }
        self.socket
            .send(Message::Text(message.to_string().into()))
            .unwrap();
        loop {
            if let Message::Text(text) = self.socket.read().unwrap() {
                let reply: Value = serde_json::from_str(text.as_str()).unwrap();
                if reply["id"] == id {
                    assert!(reply.get("error").is_none(), "{method}: {reply}");
                    return reply["result"].clone();
                }
            }
        }
    }

    fn eval(&mut self, expression: &str) -> Value {
        let result = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true }),
        );
        result["result"]["value"].clone()
    }

    /// Waits until `expression` is true in the page.
    fn wait_for(&mut self, expression: &str) {
        let started = Instant::now();
        while self.eval(expression) != json!(true) {
            if started.elapsed() > Duration::from_secs(60) {
                let said = self.eval(
                    "document.getElementById('notice').textContent + ' | ' + document.getElementById('log').textContent",
                );
                panic!("page never had {expression}; it says {said}");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn key(&mut self, key: &str, code: u32) {
        for kind in ["keyDown", "keyUp"] {
            self.call(
                "Input.dispatchKeyEvent",
                json!({ "type": kind, "key": key, "code": key, "windowsVirtualKeyCode": code }),
            );
        }
    }

    /// A pointer drag from (x0, y0) to (x1, y1) in `steps` moves.
    fn drag(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), steps: u32) {
        self.mouse("mouseMoved", x0, y0);
        self.mouse("mousePressed", x0, y0);
        for step in 1..=steps {
            let f = step as f64 / steps as f64;
            self.mouse("mouseMoved", x0 + (x1 - x0) * f, y0 + (y1 - y0) * f);
        }
        self.mouse("mouseReleased", x1, y1);
    }

    /// Numbers the page's expression gives as an array.
    fn numbers(&mut self, expression: &str) -> Vec<f64> {
        let value = self.eval(expression);
        value
            .as_array()
            .unwrap_or_else(|| panic!("{expression}: {value}"))
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64) {
        let buttons = if kind == "mouseReleased" { 0 } else { 1 };
        self.call(
            "Input.dispatchMouseEvent",
            json!({ "type": kind, "x": x, "y": y, "button": "left", "buttons": buttons, "clickCount": 1 }),
        );
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn a_drag_in_chromium_becomes_one_line_and_the_canvas_shows_the_saved_scene() {
    let Some(program) = chromium() else {
        println!("skipped: chromium is not installed (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let mut browser = Browser::launch(&program, &repl.url);
    browser.wait_for("!!(window.lapcloneScene && window.lapcloneScene())");
    // Where canvas pixel (x, y) is on the page.
    let rect = browser.eval(
        "(() => { const r = document.getElementById('overlay').getBoundingClientRect();
          return [r.left, r.top, r.width / 600, r.height / 400]; })()",
    );
    let r: Vec<f64> = rect
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(
        (r[2] - 1.0).abs() < 1e-9 && (r[3] - 1.0).abs() < 1e-9,
        "canvas not shown 1:1: {rect}"
    );
    let (x0, y0) = (r[0] + 288.0, r[1] + 147.0);
    browser.mouse("mouseMoved", x0, y0);
    browser.mouse("mousePressed", x0, y0);
    for step in 1..=8 {
        browser.mouse("mouseMoved", x0 + 5.0 * step as f64, y0);
    }
    browser.mouse("mouseReleased", x0 + 40.0, y0);
    repl.wait_line(|l| l == "(view) cat.at(0, [328, 147]);");
    browser.wait_for("window.lapcloneScene().patches[0].at[0] === 328");
    let saved = dir.path().join("saved.rhai");
    repl.type_line(&format!(":save {}", saved.display()));
    repl.wait_line(|l| l.starts_with("saved "));
    let encoded = browser.eval(
        "(() => { const c = document.getElementById('frame');
          const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
          let s = ''; for (let i = 0; i < d.length; i += 8192) s += String.fromCharCode.apply(null, d.subarray(i, i + 8192));
          return btoa(s); })()",
    );
    let pixels = base64::engine::general_purpose::STANDARD
        .decode(encoded.as_str().unwrap())
        .unwrap();
    let reference = preview_png(dir.path(), &saved, 0.0);
    assert!(
        pixels == reference.as_raw()[..],
        "the page's canvas differs from lapclone preview"
    );
    let timings = browser.eval("window.lapcloneTimings.length");
    assert!(
        timings.as_u64().unwrap() > 0,
        "no preview frame was painted during the drag"
    );
    drop(browser);
    assert!(repl.finish().success());
}

/// Where the handle's target of the cat is on the page, the screen radius of its circle
/// and the patch's scale (from the page's last scene message).
const HANDLE_ON_PAGE: &str = "(() => {
  const r = document.getElementById('overlay').getBoundingClientRect();
  const p = window.lapcloneScene().patches[0], h = p.handles[0];
  const a = p.rotation * Math.PI / 180, c = Math.cos(a), s = Math.sin(a);
  const dx = h.to[0] - p.pivot[0], dy = h.to[1] - p.pivot[1];
  return [r.left + p.at[0] + p.scale * (c * dx - s * dy), r.top + p.at[1] + p.scale * (s * dx + c * dy),
          h.radius * p.scale, p.scale];
})()";

#[test]
fn in_chromium_a_circle_drag_sets_the_radius_and_handle_keys_and_deletes_are_lines() {
    let Some(program) = chromium() else {
        println!("skipped: chromium is not installed (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = handle_scene(dir.path());
    let mut text = std::fs::read_to_string(&scene).unwrap();
    text.push_str("cat.pin([200, 150]);\n");
    std::fs::write(&scene, text).unwrap();
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut browser = Browser::launch(&program, &repl.url);
    browser.wait_for("!!(window.lapcloneScene && window.lapcloneScene())");
    // The circle's right edge, dragged 20 px further out: the radius follows.
    let h = browser.numbers(HANDLE_ON_PAGE);
    let (tx, ty, edge, scale) = (h[0], h[1], h[2], h[3]);
    browser.drag((tx + edge, ty), (tx + edge + 20.0, ty), 5);
    let line = repl.wait_line(|l| l.starts_with("(view) cat.handle(0).radius("));
    let radius: f64 = line
        .trim_start_matches("(view) cat.handle(0).radius(")
        .trim_end_matches(");")
        .parse()
        .unwrap();
    let expected = (edge + 20.0) / scale;
    assert!(
        (radius - expected).abs() <= 0.011,
        "{line}: expected {expected}"
    );
    browser.wait_for(&format!(
        "window.lapcloneScene().patches[0].handles[0].radius === {radius}"
    ));
    assert!(
        browser
            .eval("window.lapcloneTimings.length")
            .as_u64()
            .unwrap()
            > 0,
        "the circle drag previewed nothing"
    );
    // The handle's key marker at t = 1, dragged to three quarters of the 2 s timeline.
    let marker = browser.numbers(
        "(() => { const m = [...document.querySelectorAll('.marker.handle')]
            .find((m) => JSON.parse(m.dataset.key).t === 1);
          const r = m.getBoundingClientRect(), b = document.getElementById('markers').getBoundingClientRect();
          return [r.left + r.width / 2, r.top + r.height / 2, b.left, b.width]; })()",
    );
    let to = marker[2] + marker[3] * 0.75;
    browser.drag((marker[0], marker[1]), (to, marker[1]), 4);
    browser.wait_for("window.lapcloneScene().patches[0].handles[0].keys.at[1] === 1.5");
    repl.wait_line(|l| l == "(view) cat.handle(0).move_key(1, 1.5, \"at\");");
    // Click the handle's target, then Delete; the same for the pin.
    let h = browser.numbers(HANDLE_ON_PAGE);
    browser.drag((h[0], h[1]), (h[0], h[1]), 0);
    browser.key("Delete", 46);
    repl.wait_line(|l| l == "(view) cat.remove_handle(0);");
    browser.wait_for("window.lapcloneScene().patches[0].handles.length === 0");
    let pin = browser.numbers(
        "(() => { const r = document.getElementById('overlay').getBoundingClientRect();
          const p = window.lapcloneScene().patches[0], q = p.pins[0].at;
          return [r.left + p.at[0] + p.scale * (q[0] - p.pivot[0]), r.top + p.at[1] + p.scale * (q[1] - p.pivot[1])]; })()",
    );
    browser.drag((pin[0], pin[1]), (pin[0], pin[1]), 0);
    browser.key("Delete", 46);
    repl.wait_line(|l| l == "(view) cat.remove_pin(0);");
    browser.wait_for("window.lapcloneScene().patches[0].pins.length === 0");
    drop(browser);
    assert!(repl.finish().success());
}
