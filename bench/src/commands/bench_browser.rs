//! `lapclone-bench browser`: the live view's drag as a user sees it — takes the release
//! `lapclone` and Debian's `chromium`, starts `lapclone repl SCENE --view` on the two
//! 1920×1080 scenes of `lapclone-bench view` (the cat moved across the canvas; the horse's
//! depth handle dragged so the leg folds over its belly), opens the page in headless chromium
//! and drags with dispatched pointer moves, 60 a second by default, each at its own point of
//! the display's frame and none waiting for the page, as a mouse's reports come. Gives, from
//! the page's own timings (`window.lapcloneTimings`: pointer event → the frame showing the
//! answer painted), the median, 95th percentile, updates painted per second and the medians
//! of where the time went (table or JSON); and chromium's floor, a page that paints each
//! move itself, at once or a set delay after it (`--floor-after`). Without chromium it
//! reports the drags as skipped, saying why.

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use serde_json::{json, Value};

use super::bench_view::{
    cat_at, cat_scene, horse_scene, horse_target, spread, ViewBenchArgs, ViewServer,
};
use crate::cdp::{find_chromium, Browser};

/// The server-side drag bench's options, and the rate the pointer reports at.
#[derive(clap::Args, Debug)]
pub struct BrowserBenchArgs {
    #[command(flatten)]
    pub view: ViewBenchArgs,
    /// Pointer moves per second.
    #[arg(long, default_value_t = 60.0)]
    pub pointer_hz: f64,
    /// Wait for chromium to answer each move before the next. Chromium answers once the page
    /// has handled the move, so this paces the moves by the page's own frames (a mouse does
    /// not wait); the figures it gives depend on where the moves fall in the frame.
    #[arg(long)]
    pub acked: bool,
    /// Chromium's floor is also measured with each move answered this many ms after it
    /// (comma-separated; 0 paints in the pointer handler itself), as if a server with no
    /// other cost answered then: what a round trip of that length leaves at best.
    #[arg(long, value_delimiter = ',', default_value = "0,4,8")]
    pub floor_after: Vec<f64>,
}

/// The browser window: a full-HD screen (the 1920×1080 canvas is shown scaled to fit).
const WINDOW: (u32, u32) = (1920, 1080);

/// How long the page may take to connect, draw and commit.
const PAGE_TIMEOUT: Duration = Duration::from_secs(60);

/// How a drag's pointer moves are dispatched.
#[derive(Clone, Copy)]
struct Pacing {
    steps: usize,
    /// The time between two moves.
    period: Duration,
    /// Wait for chromium's reply to each move before the next.
    acked: bool,
}

#[derive(serde::Serialize)]
struct Drag {
    scene: String,
    /// The floor's answer delay, ms (the floors only).
    answer_after_ms: Option<f64>,
    steps: usize,
    /// Pointer events dispatched per second (60 unless the browser held the dispatch back).
    pointer_hz: f64,
    /// Previews painted during the drag.
    painted: usize,
    median_ms: f64,
    p95_ms: f64,
    max_ms: f64,
    /// Previews painted per second, from the first pointer event answered to the last paint.
    updates_per_s: f64,
    /// Medians of where the time went (the live view's page only), ms: waiting to be sent,
    /// the round trip to the pixels put in the canvas, waiting for the frame, its paint.
    parts_median_ms: Option<[f64; 4]>,
}

pub fn run(args: BrowserBenchArgs) -> anyhow::Result<()> {
    if args.view.steps < 2 {
        return Err(super::UsageError("--steps must be at least 2".into()).into());
    }
    if !(1.0..=1000.0).contains(&args.pointer_hz) {
        return Err(super::UsageError("--pointer-hz must be within 1 to 1000".into()).into());
    }
    if !args.floor_after.iter().all(|ms| (0.0..=100.0).contains(ms)) {
        return Err(
            super::UsageError("--floor-after takes delays within 0 to 100 ms".into()).into(),
        );
    }
    let report = match find_chromium() {
        Some(chromium) => json!({ "drags": drags(&args, &chromium)?, "skipped": null }),
        None => json!({
            "drags": [],
            "skipped": "chromium is not installed (apt-get install chromium)",
        }),
    };
    if args.view.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    if let Some(reason) = report["skipped"].as_str() {
        println!("live view drag in chromium: skipped: {reason}");
        return Ok(());
    }
    println!("live view drag in headless chromium, pointer event → pixels painted (1920×1080):");
    for d in report["drags"].as_array().into_iter().flatten() {
        println!(
            "  {:<7} {} steps at {:.0} Hz: median {:.1} ms, p95 {:.1} ms, max {:.1} ms, {:.1} updates/s ({} painted)   ({})",
            d["scene"].as_str().unwrap_or(""),
            d["steps"],
            d["pointer_hz"].as_f64().unwrap_or(f64::NAN),
            d["median_ms"].as_f64().unwrap_or(f64::NAN),
            d["p95_ms"].as_f64().unwrap_or(f64::NAN),
            d["max_ms"].as_f64().unwrap_or(f64::NAN),
            d["updates_per_s"].as_f64().unwrap_or(f64::NAN),
            d["painted"],
            match d["answer_after_ms"].as_f64() {
                Some(ms) if ms > 0.0 => format!(
                    "chromium alone, each move painted {ms} ms after it: no server, as if one answered then"
                ),
                Some(_) => "chromium alone: the page paints each move itself, no server".into(),
                None => "targets ≤ 16, ≤ 33 ms, ≥ 50/s".into(),
            },
        );
        if let Some(parts) = d["parts_median_ms"].as_array() {
            let part = |k: usize| parts.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN);
            println!(
                "         medians of its parts: {:.1} ms to be sent, {:.1} ms round trip to the canvas, {:.1} ms waiting for the frame, {:.1} ms its paint",
                part(0),
                part(1),
                part(2),
                part(3),
            );
        }
    }
    Ok(())
}

/// Both drags, each against a fresh server and browser.
fn drags(args: &BrowserBenchArgs, chromium: &Path) -> anyhow::Result<Vec<Drag>> {
    let binary = match &args.view.lapclone {
        Some(path) => path.clone(),
        None => super::bench_opencv::beside_this_program("lapclone")?,
    };
    let assets = args
        .view
        .assets
        .canonicalize()
        .context("cannot find the assets folder")?;
    let dir = std::env::temp_dir().join(format!("lapclone-bench-browser-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let result = (|| {
        let steps = args.view.steps;
        let pacing = Pacing {
            steps,
            period: Duration::from_secs_f64(1.0 / args.pointer_hz),
            acked: args.acked,
        };
        let cat = drag(
            &binary,
            chromium,
            &dir,
            "cat",
            &cat_scene(&assets),
            pacing,
            |_, i| Ok(cat_at(i, steps)),
        )?;
        let horse = drag(
            &binary,
            chromium,
            &dir,
            "horse",
            &horse_scene(&assets),
            pacing,
            |scene, i| place(&scene["patches"][0], horse_target(i, steps)),
        )?;
        let mut drags = vec![cat, horse];
        for &after in &args.floor_after {
            drags.push(floor_drag(chromium, &dir, pacing, after)?);
        }
        Ok::<_, anyhow::Error>(drags)
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// Chromium's own floor for the same measure: a page with the live view's two canvases,
/// scaled the same way, that paints a cat-sized rectangle (216 kB, what a cat preview
/// carries) for every pointer move itself (the same pointer event the live view reads),
/// with no server, timed as the live view times: in the pointer handler, or `ANSWER_AFTER`
/// ms after the move from a timer task, as a server's answer would come.
const FLOOR_PAGE: &str = r#"<!doctype html><html><head><style>
body { margin: 0; background: #222; }
#stage { position: relative; display: inline-block; margin: 10px; }
#stage canvas { display: block; max-width: calc(100vw - 20px); max-height: calc(100vh - 170px); }
#overlay { position: absolute; left: 0; top: 0; width: 100%; height: 100%; }
</style></head><body><div id="stage"><canvas id="frame" width="1920" height="1080"></canvas>
<canvas id="overlay" width="1920" height="1080"></canvas></div><script>
const ctx = document.getElementById('frame').getContext('2d', { desynchronized: true });
const block = new ImageData(240, 225);
const timings = (window.lapcloneTimings = []), paintedAt = (window.lapclonePaintedAt = []);
let n = 0, down = false;
const overlay = document.getElementById('overlay');
overlay.addEventListener('pointerdown', () => { down = true; });
overlay.addEventListener('pointerup', () => { down = false; window.lapcloneReleased = true; });
// The live view's own choice: pointerrawupdate where the browser has it.
const move = 'onpointerrawupdate' in window ? 'pointerrawupdate' : 'pointermove';
overlay.addEventListener(move, (e) => {
  if (!down) return;
  const from = e.timeStamp;
  const answer = () => {
    block.data.fill(n++ & 255);
    ctx.putImageData(block, 600 + (n % 400), 400);
    requestAnimationFrame(() => setTimeout(() => {
      const now = performance.now();
      timings.push(now - from); paintedAt.push(now);
    }, 0));
  };
  if (ANSWER_AFTER > 0) setTimeout(answer, ANSWER_AFTER); else answer();
});
window.lapcloneReady = true;
</script></body></html>"#;

/// One drag over the floor page, each move answered `after` ms after it (0: at once).
fn floor_drag(chromium: &Path, dir: &Path, pacing: Pacing, after: f64) -> anyhow::Result<Drag> {
    let steps = pacing.steps;
    let page = dir.join(format!("floor-{after}.html"));
    std::fs::write(
        &page,
        FLOOR_PAGE.replace("ANSWER_AFTER", &after.to_string()),
    )?;
    let profile = dir.join(format!("profile-floor-{after}"));
    let url = format!("file://{}", page.display());
    let mut browser = Browser::launch(chromium, &profile, WINDOW, &url)?;
    browser.wait_for("window.lapcloneReady === true", PAGE_TIMEOUT)?;
    let dispatched = pointer_drag(&mut browser, pacing, |i| Ok(cat_at(i, steps)))?;
    browser.wait_for("window.lapcloneReleased === true", PAGE_TIMEOUT)?;
    browser.eval(
        "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => setTimeout(r, 0))))",
    )?;
    let timings = numbers(&browser.eval("window.lapcloneTimings")?);
    let painted_at = numbers(&browser.eval("window.lapclonePaintedAt")?);
    let name = if after > 0.0 {
        format!("floor+{after}")
    } else {
        "floor".into()
    };
    let mut drag = summary(name, steps, dispatched, timings, &painted_at)?;
    drag.answer_after_ms = Some(after);
    Ok(drag)
}

/// Canvas point of a patch's source point `q`, from the page's scene message (the page's
/// own placement: pivot, rotation, scale, then `at`).
fn place(patch: &Value, q: [f64; 2]) -> anyhow::Result<[f64; 2]> {
    let number = |key: &str| {
        patch
            .pointer(key)
            .and_then(Value::as_f64)
            .with_context(|| format!("the scene message has no {key}"))
    };
    let (sin, cos) = number("/rotation")?.to_radians().sin_cos();
    let scale = number("/scale")?;
    let (dx, dy) = (q[0] - number("/pivot/0")?, q[1] - number("/pivot/1")?);
    Ok([
        number("/at/0")? + scale * (cos * dx - sin * dy),
        number("/at/1")? + scale * (sin * dx + cos * dy),
    ])
}

/// One 60 Hz drag through the page: pressed at canvas point `point(scene, 0)`, moved through
/// `point(scene, 1..=steps)`, released at the last one.
fn drag(
    binary: &Path,
    chromium: &Path,
    dir: &Path,
    name: &'static str,
    scene_text: &str,
    pacing: Pacing,
    point: impl Fn(&Value, usize) -> anyhow::Result<[f64; 2]>,
) -> anyhow::Result<Drag> {
    let steps = pacing.steps;
    let scene_path = dir.join(format!("{name}.rhai"));
    std::fs::write(&scene_path, scene_text)?;
    let server = ViewServer::start(binary, &scene_path)?;
    let profile = dir.join(format!("profile-{name}"));
    let mut browser = Browser::launch(chromium, &profile, WINDOW, &server.url)?;
    browser.wait_for(
        "!!(window.lapcloneScene && window.lapcloneScene()) && document.getElementById('frame').width === 1920",
        PAGE_TIMEOUT,
    )?;
    let scene = browser.eval("window.lapcloneScene()")?;
    let rev = scene["rev"]
        .as_u64()
        .context("the scene message has no rev")?;
    let dispatched = pointer_drag(&mut browser, pacing, |i| point(&scene, i))?;
    // The commit's scene message comes after every preview's frame; then let the last
    // preview's paint be recorded.
    browser.wait_for(&format!("window.lapcloneScene().rev > {rev}"), PAGE_TIMEOUT)?;
    browser.eval(
        "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => setTimeout(r, 0))))",
    )?;
    let timings = numbers(&browser.eval("window.lapcloneTimings")?);
    let painted_at = numbers(&browser.eval("window.lapclonePaintedAt")?);
    let parts = browser.eval("window.lapcloneTimingParts")?;
    drop(browser);
    drop(server);
    let mut drag = summary(name.into(), steps, dispatched, timings, &painted_at)?;
    drag.parts_median_ms = Some(part_medians(&parts));
    Ok(drag)
}

/// Presses at canvas point `point(0)`, moves through `point(1..=steps)`, one a `period` (a
/// move that falls behind goes at once), and releases; gives how long the moves took.
fn pointer_drag(
    browser: &mut Browser,
    pacing: Pacing,
    point: impl Fn(usize) -> anyhow::Result<[f64; 2]>,
) -> anyhow::Result<Duration> {
    let r = canvas_on_page(browser)?;
    let page = |i: usize| point(i).map(|p| (r[0] + p[0] * r[2], r[1] + p[1] * r[3]));
    let (x, y) = page(0)?;
    browser.mouse("mouseMoved", x, y)?;
    browser.mouse("mousePressed", x, y)?;
    let started = Instant::now();
    for i in 1..=pacing.steps {
        // The pointer's clock is not the display's: each move falls at its own point of its
        // period, spread evenly over the run (the golden-ratio sequence), so the figures
        // weigh every phase of chromium's frame alike instead of the one a fixed beat locks to.
        let phase = (i as f64 * 0.618_033_988_749_895).fract();
        let due = pacing.period.mul_f64(i as f64 - 1.0 + phase);
        if let Some(wait) = due.checked_sub(started.elapsed()) {
            std::thread::sleep(wait);
        }
        let (x, y) = page(i)?;
        if pacing.acked {
            browser.mouse("mouseMoved", x, y)?;
        } else {
            browser.mouse_unacked("mouseMoved", x, y)?;
        }
    }
    let dispatched = started.elapsed();
    let (x, y) = page(pacing.steps)?;
    browser.mouse("mouseReleased", x, y)?;
    Ok(dispatched)
}

/// Where the canvas is on the page: left, top and page pixels per canvas pixel across and
/// down (the canvas is shown scaled to fit the window).
fn canvas_on_page(browser: &mut Browser) -> anyhow::Result<[f64; 4]> {
    let rect = browser.eval(
        "(() => { const o = document.getElementById('overlay'), r = o.getBoundingClientRect();
          return [r.left, r.top, r.width / o.width, r.height / o.height]; })()",
    )?;
    let r = numbers(&rect);
    r.try_into()
        .map_err(|_| anyhow::anyhow!("the page gave no canvas rectangle: {rect}"))
}

/// The figures of one drag from the page's timings and paint times (ms, page clock).
fn summary(
    name: String,
    steps: usize,
    dispatched: Duration,
    mut timings: Vec<f64>,
    painted_at: &[f64],
) -> anyhow::Result<Drag> {
    anyhow::ensure!(
        !timings.is_empty() && timings.len() == painted_at.len(),
        "the page recorded no preview painted during the {name} drag"
    );
    // From the first pointer event answered (the first paint less its latency) to the last paint.
    let span = painted_at[painted_at.len() - 1] - (painted_at[0] - timings[0]);
    let painted = timings.len();
    let (median_ms, p95_ms, max_ms) = spread(&mut timings);
    Ok(Drag {
        scene: name,
        answer_after_ms: None,
        steps,
        pointer_hz: steps as f64 / dispatched.as_secs_f64(),
        painted,
        median_ms,
        p95_ms,
        max_ms,
        updates_per_s: painted as f64 / (span / 1e3),
        parts_median_ms: None,
    })
}

/// The median of each of the page's four timing parts.
fn part_medians(parts: &Value) -> [f64; 4] {
    std::array::from_fn(|k| {
        let mut column: Vec<f64> = parts
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|row| row[k].as_f64())
            .collect();
        if column.is_empty() {
            return f64::NAN;
        }
        spread(&mut column).0
    })
}

fn numbers(value: &Value) -> Vec<f64> {
    value
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_f64)
        .collect()
}
