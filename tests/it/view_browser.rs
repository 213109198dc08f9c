//! The live view in a real browser: Debian's `chromium`, headless, driven over the Chrome
//! DevTools Protocol (spoken over a WebSocket here, so no extra crate): load the page, drag
//! the cat 40 px with dispatched pointer events, then check the REPL's new line and that
//! the canvas pixels read back from the page equal `lapclone preview` of the `:save`d
//! scene. Skips, saying why, when chromium is not installed.

use std::path::Path;
use std::time::Duration;

use base64::Engine as _;
use tempfile::TempDir;

use super::view_ws::{cat_scene, handle_scene, preview_png, ViewRepl};

// The DevTools client the browser benchmark uses too: one copy, in the bench crate (which the
// tests cannot depend on, as it depends on lapclone). The tests wait for every dispatched
// event, so the benchmark's unanswered moves go unused here.
#[allow(dead_code)]
#[path = "../../bench/src/cdp.rs"]
mod cdp;

use cdp::{find_chromium, Browser};

const PAGE_TIMEOUT: Duration = Duration::from_secs(60);

#[test]
fn a_drag_in_chromium_becomes_one_line_and_the_canvas_shows_the_saved_scene() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let Some((mut repl, mut browser, _profile)) = open_page(dir.path(), &scene, (1000, 800)) else {
        return;
    };
    // Where canvas pixel (x, y) is on the page.
    let rect = browser
        .eval(
            "(() => { const r = document.getElementById('overlay').getBoundingClientRect();
          return [r.left, r.top, r.width / 600, r.height / 400]; })()",
        )
        .unwrap();
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
    browser.mouse("mouseMoved", x0, y0).unwrap();
    browser.mouse("mousePressed", x0, y0).unwrap();
    for step in 1..=8 {
        browser
            .mouse("mouseMoved", x0 + 5.0 * step as f64, y0)
            .unwrap();
    }
    browser.mouse("mouseReleased", x0 + 40.0, y0).unwrap();
    repl.wait_line(|l| l == "(view) cat.at(0, [328, 147]);");
    browser
        .wait_for(
            "window.lapcloneScene().patches[0].at[0] === 328",
            PAGE_TIMEOUT,
        )
        .unwrap();
    let saved = dir.path().join("saved.rhai");
    repl.type_line(&format!(":save {}", saved.display()));
    repl.wait_line(|l| l.starts_with("saved "));
    let encoded = browser.eval(
        "(() => { const c = document.getElementById('frame');
          const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
          let s = ''; for (let i = 0; i < d.length; i += 8192) s += String.fromCharCode.apply(null, d.subarray(i, i + 8192));
          return btoa(s); })()",
        )
        .unwrap();
    let pixels = base64::engine::general_purpose::STANDARD
        .decode(encoded.as_str().unwrap())
        .unwrap();
    let reference = preview_png(dir.path(), &saved, 0.0);
    assert!(
        pixels == reference.as_raw()[..],
        "the page's canvas differs from lapclone preview"
    );
    let timings = browser.eval("window.lapcloneTimings.length").unwrap();
    assert!(
        timings.as_u64().unwrap() > 0,
        "no preview frame was painted during the drag"
    );
    drop(browser);
    assert!(repl.finish().success());
}

/// The REPL on `scene` with its page open in chromium (a `window`-sized window) and its
/// first scene message in; `None`, saying why, when chromium is not installed. The profile
/// folder lives as long as the last item.
fn open_page(dir: &Path, scene: &Path, window: (u32, u32)) -> Option<(ViewRepl, Browser, TempDir)> {
    let Some(program) = find_chromium() else {
        println!("skipped: chromium is not installed (apt-get install chromium)");
        return None;
    };
    let repl = ViewRepl::start(dir, scene);
    let profile = tempfile::tempdir().unwrap();
    let mut browser = Browser::launch(&program, profile.path(), window, &repl.url).unwrap();
    wait_for(
        &mut browser,
        "!!(window.lapcloneScene && window.lapcloneScene())",
    );
    Some((repl, browser, profile))
}

fn wait_for(browser: &mut Browser, expression: &str) {
    browser.wait_for(expression, PAGE_TIMEOUT).unwrap();
}

/// A pointer drag from (x0, y0) to (x1, y1) in `steps` moves.
fn drag(browser: &mut Browser, (x0, y0): (f64, f64), (x1, y1): (f64, f64), steps: u32) {
    browser.mouse("mouseMoved", x0, y0).unwrap();
    browser.mouse("mousePressed", x0, y0).unwrap();
    for step in 1..=steps {
        let f = step as f64 / steps as f64;
        browser
            .mouse("mouseMoved", x0 + (x1 - x0) * f, y0 + (y1 - y0) * f)
            .unwrap();
    }
    browser.mouse("mouseReleased", x1, y1).unwrap();
}

/// Numbers the page's expression gives as an array.
fn numbers(browser: &mut Browser, expression: &str) -> Vec<f64> {
    let value = browser.eval(expression).unwrap();
    value
        .as_array()
        .unwrap_or_else(|| panic!("{expression}: {value}"))
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
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
    let dir = tempfile::tempdir().unwrap();
    let scene = handle_scene(dir.path());
    let mut text = std::fs::read_to_string(&scene).unwrap();
    text.push_str("cat.pin([200, 150]);\n");
    std::fs::write(&scene, text).unwrap();
    let Some((repl, mut browser, _profile)) = open_page(dir.path(), &scene, (1000, 800)) else {
        return;
    };
    // The circle's right edge, dragged 20 px further out: the radius follows.
    let h = numbers(&mut browser, HANDLE_ON_PAGE);
    let (tx, ty, edge, scale) = (h[0], h[1], h[2], h[3]);
    drag(&mut browser, (tx + edge, ty), (tx + edge + 20.0, ty), 5);
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
    wait_for(
        &mut browser,
        &format!("window.lapcloneScene().patches[0].handles[0].radius === {radius}"),
    );
    assert!(
        browser
            .eval("window.lapcloneTimings.length")
            .unwrap()
            .as_u64()
            .unwrap()
            > 0,
        "the circle drag previewed nothing"
    );
    // The handle's key marker at t = 1, dragged to three quarters of the 2 s timeline; found
    // once the page's log shows the radius line, as that line moves the timeline down.
    wait_for(
        &mut browser,
        "document.getElementById('log').textContent.includes('radius(')",
    );
    const MARKER: &str = "(() => { const m = [...document.querySelectorAll('.marker.handle')]
            .find((m) => JSON.parse(m.dataset.key).t === 1);
          const r = m.getBoundingClientRect(), b = document.getElementById('markers').getBoundingClientRect();
          const x = r.left + r.width / 2, y = r.top + r.height / 2;
          return [x, y, b.left, b.width, document.elementFromPoint(x, y) === m ? 1 : 0]; })()";
    wait_for(&mut browser, &format!("{MARKER}[4] === 1"));
    let marker = numbers(&mut browser, MARKER);
    let to = marker[2] + marker[3] * 0.75;
    drag(&mut browser, (marker[0], marker[1]), (to, marker[1]), 4);
    wait_for(
        &mut browser,
        "window.lapcloneScene().patches[0].handles[0].keys.at[1] === 1.5",
    );
    repl.wait_line(|l| l == "(view) cat.handle(0).move_key(1, 1.5, \"at\");");
    // Click the handle's target, then Delete; the same for the pin.
    let h = numbers(&mut browser, HANDLE_ON_PAGE);
    drag(&mut browser, (h[0], h[1]), (h[0], h[1]), 0);
    browser.key("Delete", 46).unwrap();
    repl.wait_line(|l| l == "(view) cat.remove_handle(0);");
    wait_for(
        &mut browser,
        "window.lapcloneScene().patches[0].handles.length === 0",
    );
    let pin = numbers(&mut browser,
        "(() => { const r = document.getElementById('overlay').getBoundingClientRect();
          const p = window.lapcloneScene().patches[0], q = p.pins[0].at;
          return [r.left + p.at[0] + p.scale * (q[0] - p.pivot[0]), r.top + p.at[1] + p.scale * (q[1] - p.pivot[1])]; })()",
    );
    drag(&mut browser, (pin[0], pin[1]), (pin[0], pin[1]), 0);
    browser.key("Delete", 46).unwrap();
    repl.wait_line(|l| l == "(view) cat.remove_pin(0);");
    wait_for(
        &mut browser,
        "window.lapcloneScene().patches[0].pins.length === 0",
    );
    drop(browser);
    assert!(repl.finish().success());
}

#[test]
fn in_a_small_window_the_frame_fits_and_the_pointer_reads_the_pixel_under_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    // Narrow enough that the help text wraps over several lines, leaving the frame less
    // height than its width alone would give it.
    let Some((repl, mut browser, _profile)) = open_page(dir.path(), &scene, (640, 560)) else {
        return;
    };
    wait_for(
        &mut browser,
        "document.getElementById('frame').width === 600",
    );
    // Frame, pointer canvas and stage: left, top, width, height; then the room it has.
    let boxes = numbers(
        &mut browser,
        "(() => { const out = [];
          for (const id of ['frame', 'overlay', 'stage']) { const r = document.getElementById(id).getBoundingClientRect(); out.push(r.left, r.top, r.width, r.height); }
          const m = document.querySelector('main').getBoundingClientRect();
          out.push(m.left, m.top, m.right, m.bottom); return out; })()",
    );
    let (frame, room) = (&boxes[0..4], &boxes[12..16]);
    for other in [&boxes[4..8], &boxes[8..12]] {
        assert_eq!(
            frame, other,
            "the frame and the pointer's canvas differ: {boxes:?}"
        );
    }
    assert!(frame[2] < 600.0, "the frame was not scaled down: {boxes:?}");
    assert!(
        (frame[2] / frame[3] - 1.5).abs() < 0.01,
        "the frame's aspect changed: {boxes:?}"
    );
    assert!(
        frame[0] >= room[0]
            && frame[1] >= room[1]
            && frame[0] + frame[2] <= room[2] + 0.01
            && frame[1] + frame[3] <= room[3] + 0.01,
        "the frame overflows the room it has: {boxes:?}"
    );
    // The pointer over the frame's pixel (300, 380), near its bottom, reads that pixel.
    let k = frame[2] / 600.0;
    let (x, y) = (frame[0] + 300.25 * k, frame[1] + 380.25 * k);
    browser.mouse("mouseMoved", x, y).unwrap();
    wait_for(
        &mut browser,
        "document.getElementById('coords').textContent.startsWith('canvas [300, 380]')",
    );
    drop(browser);
    assert!(repl.finish().success());
}
