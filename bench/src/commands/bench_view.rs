//! `lapclone-bench view`: the live view's drag latency — starts the release `lapclone repl
//! --view` on a 1920×1080 scene, connects as a page and sends a scripted pointer drag (one
//! preview edit per step, the next sent when the previous frame update arrived), timing each
//! message in → changed pixels out (the binary frame update received). Two scenes: the cat
//! moved across the canvas, and the horse with a depth handle dragged so the leg folds over
//! its belly. Prints the median and 95th percentile per scene (table or JSON).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Instant;

use anyhow::Context as _;
use serde_json::{json, Value};
use tungstenite::client::IntoClientRequest;
use tungstenite::Message;

#[derive(clap::Args, Debug)]
pub struct ViewBenchArgs {
    /// Pointer steps per drag.
    #[arg(long, default_value_t = 200)]
    pub steps: usize,
    /// Folder holding the bundled photos.
    #[arg(long, default_value = "assets")]
    pub assets: PathBuf,
    /// The `lapclone` binary (default: the one beside this program).
    #[arg(long)]
    pub lapclone: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(serde::Serialize)]
struct Drag {
    scene: &'static str,
    steps: usize,
    median_ms: f64,
    p95_ms: f64,
    max_ms: f64,
    /// Mean bytes of pixels per update (the changed rectangle, not the whole frame).
    mean_update_bytes: f64,
}

pub fn run(args: ViewBenchArgs) -> anyhow::Result<()> {
    if args.steps == 0 {
        return Err(super::UsageError("--steps must be positive".into()).into());
    }
    let binary = match &args.lapclone {
        Some(path) => path.clone(),
        None => super::bench_opencv::beside_this_program("lapclone")?,
    };
    let assets = args
        .assets
        .canonicalize()
        .context("cannot find the assets folder")?;
    let dir = std::env::temp_dir().join(format!("lapclone-bench-view-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let result = (|| {
        let cat = drag(
            &binary,
            &write(&dir, "cat", &cat_scene(&assets))?,
            "cat",
            args.steps,
            |i, n| json!({"op": "at", "patch": "cat", "value": cat_at(i, n)}),
        )?;
        let horse = drag(
            &binary,
            &write(&dir, "horse", &horse_scene(&assets))?,
            "horse",
            args.steps,
            |i, n| json!({"op": "handle_key", "patch": "horse", "handle": 0, "value": horse_target(i, n)}),
        )?;
        Ok::<_, anyhow::Error>(vec![cat, horse])
    })();
    let _ = std::fs::remove_dir_all(&dir);
    let drags = result?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&json!({ "drags": drags }))?
        );
    } else {
        println!("live view drag, pointer message in → changed pixels out (1920×1080):");
        for d in &drags {
            println!(
                "  {:<6} {} steps: median {:.2} ms, p95 {:.2} ms, max {:.2} ms, {:.0} kB per update   (targets ≤ 8, ≤ 16 ms)",
                d.scene, d.steps, d.median_ms, d.p95_ms, d.max_ms, d.mean_update_bytes / 1e3
            );
        }
    }
    Ok(())
}

fn write(dir: &Path, name: &str, text: &str) -> anyhow::Result<PathBuf> {
    let path = dir.join(format!("{name}.rhai"));
    std::fs::write(&path, text)?;
    Ok(path)
}

pub(crate) fn cat_scene(assets: &Path) -> String {
    format!(
        r#"canvas(1920, 1080, #{{ fps: 24, duration: 2, background: [0.45, 0.3, 0.2] }});
let cat = patch("cat", #{{ source: "{a}/chelsea.png", mask: "{a}/masks/chelsea_face.png" }});
cat.at(0, [500, 400]);
"#,
        a = assets.display()
    )
}

pub(crate) fn horse_scene(assets: &Path) -> String {
    format!(
        r#"canvas(1920, 1080, #{{ fps: 24, duration: 2, background: [0.1, 0.15, 0.3] }});
let horse = patch("horse", #{{ source: "{a}/horse_texture.png", mask: "{a}/horse_mask.png", density: 2 }});
horse.at(0, [900, 540]).scale(0, 1.5);
let hind = horse.drag([118, 298], 70, #{{ depth: 1 }});
horse.drag([268, 300], 55);
horse.pin([360, 70]);
horse.pin([30, 150]);
"#,
        a = assets.display()
    )
}

/// The cat's drag: its `at` across the canvas, step `i` of `n`.
pub(crate) fn cat_at(i: usize, n: usize) -> [f64; 2] {
    let s = i as f64 / n as f64;
    [500.0 + 900.0 * s, 400.0 + 200.0 * s]
}

/// The horse's drag: its depth handle's target (source coordinates), step `i` of `n`, so the
/// hind leg folds over the belly.
pub(crate) fn horse_target(i: usize, n: usize) -> [f64; 2] {
    let s = i as f64 / n as f64;
    [118.0 + 150.0 * s, 298.0 - 160.0 * s]
}

/// A running `lapclone repl SCENE --view --port 0`; dropping it ends the input, so the
/// session and its server stop.
pub(crate) struct ViewServer {
    child: Child,
    /// The page's address, with its token.
    pub url: String,
}

impl ViewServer {
    pub(crate) fn start(binary: &Path, scene: &Path) -> anyhow::Result<ViewServer> {
        let mut child = Command::new(binary)
            .args([
                "repl",
                &scene.display().to_string(),
                "--view",
                "--port",
                "0",
            ])
            .arg("--preview")
            .arg(scene.with_extension("png"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .with_context(|| format!("cannot run {}", binary.display()))?;
        let stdout = child.stdout.take().context("no stdout")?;
        let mut lines = BufReader::new(stdout).lines();
        let url = lines
            .by_ref()
            .map_while(Result::ok)
            .find_map(|l| l.strip_prefix("view: ").map(str::to_string));
        // The REPL goes on printing (the page's lines); keep its pipe drained.
        std::thread::spawn(move || lines.map_while(Result::ok).for_each(drop));
        let mut server = ViewServer {
            child,
            url: String::new(),
        };
        server.url = url.context("lapclone printed no view URL")?;
        Ok(server)
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        drop(self.child.stdin.take());
        let _ = self.child.wait();
    }
}

/// One scripted drag against a fresh `lapclone repl SCENE --view`.
fn drag(
    binary: &Path,
    scene: &Path,
    name: &'static str,
    steps: usize,
    edit: impl Fn(usize, usize) -> Value,
) -> anyhow::Result<Drag> {
    let server = ViewServer::start(binary, scene)?;
    let url = &server.url;
    let host = url
        .trim_start_matches("http://")
        .split('/')
        .next()
        .unwrap_or("")
        .to_string();
    let mut request = url
        .replacen("http://", "ws://", 1)
        .replacen("/?token=", "/ws?token=", 1)
        .into_client_request()?;
    request
        .headers_mut()
        .insert("Origin", format!("http://{host}").parse()?);
    let (mut socket, _) = tungstenite::connect(request)?;
    let mut rev = 0;
    read_until(&mut socket, &mut rev, false)?;
    let mut times = Vec::with_capacity(steps);
    let mut bytes = 0usize;
    for i in 1..=steps {
        let message = json!({"type": "edit", "rev": rev, "commit": false, "edit": edit(i, steps)});
        let started = Instant::now();
        socket.send(Message::Text(message.to_string().into()))?;
        bytes += read_until(&mut socket, &mut rev, true)?;
        times.push(started.elapsed().as_secs_f64() * 1e3);
        read_until(&mut socket, &mut rev, false)?;
    }
    socket.send(Message::Text(json!({"type": "cancel"}).to_string().into()))?;
    drop(socket);
    drop(server);
    let (median_ms, p95_ms, max_ms) = spread(&mut times);
    Ok(Drag {
        scene: name,
        steps,
        median_ms,
        p95_ms,
        max_ms,
        mean_update_bytes: bytes as f64 / steps as f64,
    })
}

/// Median, 95th percentile and maximum of `times` (not empty), which it sorts.
pub(crate) fn spread(times: &mut [f64]) -> (f64, f64, f64) {
    times.sort_by(f64::total_cmp);
    let at = |q: f64| times[((times.len() as f64 - 1.0) * q).round() as usize];
    (at(0.5), at(0.95), at(1.0))
}

type Socket = tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<std::net::TcpStream>>;

/// Reads until a frame update (its pixel bytes) or, without `want_frame`, a scene message;
/// keeps `rev` current.
fn read_until(socket: &mut Socket, rev: &mut u64, want_frame: bool) -> anyhow::Result<usize> {
    loop {
        match socket.read()? {
            Message::Binary(b) if want_frame => return Ok(b.len() - 28),
            Message::Text(t) => {
                let v: Value = serde_json::from_str(t.as_str())?;
                anyhow::ensure!(v["type"] != "error", "the view refused: {v}");
                if v["type"] == "scene" {
                    *rev = v["rev"].as_u64().unwrap_or(0);
                    if !want_frame {
                        return Ok(0);
                    }
                }
            }
            _ => {}
        }
    }
}
