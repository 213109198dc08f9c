//! The live view in a real browser: Debian's `chromium`, headless, driven over the Chrome
//! DevTools Protocol (spoken over a WebSocket here, so no extra crate): load the page, drag
//! the cat 40 px with dispatched pointer events, then check the REPL's new line and that
//! the canvas pixels read back from the page equal `lapclone preview` of the `:save`d
//! scene. Skips, saying why, when chromium is not installed.

use std::time::Duration;

use base64::Engine as _;

use super::view_ws::{cat_scene, preview_png, ViewRepl};

// The DevTools client the browser benchmark uses too: one copy, in the bench crate (which the
// tests cannot depend on, as it depends on lapclone).
#[path = "../../bench/src/cdp.rs"]
mod cdp;

use cdp::{find_chromium, Browser};

const PAGE_TIMEOUT: Duration = Duration::from_secs(60);

#[test]
fn a_drag_in_chromium_becomes_one_line_and_the_canvas_shows_the_saved_scene() {
    let Some(program) = find_chromium() else {
        println!("skipped: chromium is not installed (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut repl = ViewRepl::start(dir.path(), &scene);
    let profile = tempfile::tempdir().unwrap();
    let mut browser = Browser::launch(&program, profile.path(), (1000, 800), &repl.url).unwrap();
    browser
        .wait_for(
            "!!(window.lapcloneScene && window.lapcloneScene())",
            PAGE_TIMEOUT,
        )
        .unwrap();
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
