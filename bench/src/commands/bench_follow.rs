//! `lapclone-bench follow`: a scene that follows a track against the same scene with the
//! keys written out. Takes the release `lapclone` binary and a frame count; writes a
//! two-point-style track (`frame,x,y,rotate,scale`, one sub-pixel row per frame) and two
//! 1920×1080 scenes over the rocket plate — one calling `cat.follow("track.csv")`, one with
//! a `cat.key(t, #{ at, rotate, scale })` line per row — and times whole `lapclone render`
//! processes (scene load, every frame, PNG files) in rounds, each round running both in
//! alternating order. Gives the median of the rounds' ratios followed ÷ written out, the
//! wall times, and whether the two renders' frames are byte-identical (they must be: the
//! figure compares the same work).

use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;

use super::bench_opencv::{beside_this_program, stale_binary};
use super::child_run::{self, Invocation};

#[derive(clap::Args, Debug)]
pub struct FollowBenchArgs {
    /// Frames of the scene (24 fps), one track row and one key per frame.
    #[arg(long, default_value_t = 96)]
    pub frames: u32,
    /// Measured rounds (each renders both scenes once); the median ratio is reported.
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// The `lapclone` binary (default: the one beside this program, i.e. target/release/lapclone).
    #[arg(long)]
    pub lapclone: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

const FPS: f64 = 24.0;

#[derive(serde::Serialize)]
struct Report {
    frames: u32,
    runs: usize,
    lapclone: String,
    warnings: Vec<String>,
    followed_s: Vec<f64>,
    written_out_s: Vec<f64>,
    /// Median of the rounds' followed ÷ written-out ratios.
    follow_over_keys: f64,
    identical_frames: bool,
    load_average: Option<String>,
}

pub fn run(args: FollowBenchArgs) -> anyhow::Result<()> {
    if args.frames == 0 || args.runs == 0 {
        return Err(super::UsageError("--frames and --runs must be positive".into()).into());
    }
    let explicit = args.lapclone.is_some();
    let lapclone = match args.lapclone.clone() {
        Some(path) => path,
        None => beside_this_program("lapclone")?,
    };
    anyhow::ensure!(
        lapclone.is_file(),
        "no lapclone binary at {}: build it with `cargo build --release` (or pass --lapclone)",
        lapclone.display()
    );
    let root = std::fs::canonicalize(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))?;
    let warnings = if explicit {
        Vec::new()
    } else {
        stale_binary(&lapclone, &root).into_iter().collect()
    };
    let dir = std::env::temp_dir().join(format!("lapclone-bench-follow-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let measured = measure(&args, &lapclone, &root, &dir);
    let _ = std::fs::remove_dir_all(&dir);
    let (followed_s, written_out_s, follow_over_keys, identical_frames) = measured?;
    let report = Report {
        frames: args.frames,
        runs: args.runs,
        lapclone: lapclone.display().to_string(),
        warnings,
        followed_s,
        written_out_s,
        follow_over_keys,
        identical_frames,
        load_average: std::fs::read_to_string("/proc/loadavg")
            .ok()
            .map(|l| l.trim().to_string()),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        for warning in &report.warnings {
            eprintln!("warning: {warning}");
        }
        println!(
            "follow bench: 1920×1080, {} frames, {} rounds (load {})",
            report.frames,
            report.runs,
            report.load_average.as_deref().unwrap_or("unknown")
        );
        println!(
            "  followed ÷ keys written out: {:.3}× median (target ≤ 1); frames identical: {}",
            report.follow_over_keys, report.identical_frames
        );
    }
    Ok(())
}

type Measured = (Vec<f64>, Vec<f64>, f64, bool);

fn measure(
    args: &FollowBenchArgs,
    lapclone: &Path,
    root: &Path,
    dir: &Path,
) -> anyhow::Result<Measured> {
    let rows = track_rows(args.frames);
    std::fs::write(dir.join("track.csv"), track_csv(&rows))?;
    let followed = dir.join("followed.rhai");
    let written = dir.join("written_out.rhai");
    std::fs::write(
        &followed,
        scene(root, args.frames, "cat.follow(\"track.csv\");\n"),
    )?;
    std::fs::write(&written, scene(root, args.frames, &written_keys(&rows)))?;
    let render = |name: &'static str, scene: &Path| -> anyhow::Result<f64> {
        let out = dir.join(name);
        let _ = std::fs::remove_dir_all(&out);
        let args: Vec<OsString> = vec!["render".into(), scene.into(), "-o".into(), out.into()];
        let invocation = Invocation {
            name,
            program: lapclone.to_path_buf(),
            args,
            cwd: dir.to_path_buf(),
        };
        Ok(child_run::run(&invocation, dir)?.wall_s)
    };
    // One unmeasured round: the page cache holds the binary and the images for both.
    render("followed_frames", &followed)?;
    render("written_frames", &written)?;
    let identical = same_files(&dir.join("followed_frames"), &dir.join("written_frames"))?;
    let (mut a, mut b, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    for round in 0..args.runs {
        // Alternating which goes first cancels a steady drift in the machine's load.
        let (f, w) = if round % 2 == 0 {
            let f = render("followed_frames", &followed)?;
            (f, render("written_frames", &written)?)
        } else {
            let w = render("written_frames", &written)?;
            (render("followed_frames", &followed)?, w)
        };
        a.push(f);
        b.push(w);
        ratios.push(f / w);
    }
    ratios.sort_by(f64::total_cmp);
    Ok((a, b, ratios[ratios.len() / 2], identical))
}

/// `(frame, x, y, rotate, scale)`: a slow loop across the plate with a tracker's sub-pixel
/// jitter, turning and breathing.
fn track_rows(frames: u32) -> Vec<(u32, f64, f64, f64, f64)> {
    (1..=frames)
        .map(|n| {
            let s = f64::from(n - 1) / f64::from(frames.max(2) - 1);
            let turn = s * std::f64::consts::TAU;
            let jitter = (f64::from(n) * 12.9898).sin() * 0.37;
            (
                n,
                960.0 + 600.0 * turn.cos() + jitter,
                540.0 + 300.0 * turn.sin() - jitter,
                -10.0 + 25.0 * s + jitter,
                1.0 + 0.3 * (turn * 0.5).sin(),
            )
        })
        .collect()
}

fn track_csv(rows: &[(u32, f64, f64, f64, f64)]) -> String {
    let mut text = String::from("frame,x,y,rotate,scale\n");
    for (n, x, y, r, s) in rows {
        let _ = writeln!(text, "{n},{x:?},{y:?},{r:?},{s:?}");
    }
    text
}

/// The keys `follow` makes from `rows` (frame n at t = (n − 1) / fps, no offset), as text.
fn written_keys(rows: &[(u32, f64, f64, f64, f64)]) -> String {
    let mut text = String::new();
    for (n, x, y, r, s) in rows {
        let t = f64::from(n - 1) / FPS;
        let _ = writeln!(
            text,
            "cat.key({t:?}, #{{ at: [{x:?}, {y:?}], rotate: {r:?}, scale: {s:?} }});"
        );
    }
    text
}

fn scene(root: &Path, frames: u32, body: &str) -> String {
    let asset = |p: &str| root.join(p).display().to_string();
    format!(
        "canvas(1920, 1080, #{{ fps: {FPS}, duration: {}, background: {:?} }});\n\
         let cat = patch(\"cat\", #{{ source: {:?}, mask: {:?} }});\n{body}",
        f64::from(frames) / FPS,
        asset("benches/assets/rocket_1080p.jpg"),
        asset("assets/chelsea.png"),
        asset("assets/masks/chelsea_face.png"),
    )
}

/// Whether the two folders hold the same file names with the same bytes.
fn same_files(a: &Path, b: &Path) -> anyhow::Result<bool> {
    let names = |dir: &Path| -> anyhow::Result<Vec<OsString>> {
        let mut names = std::fs::read_dir(dir)
            .with_context(|| format!("cannot list {}", dir.display()))?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<Result<Vec<_>, _>>()?;
        names.sort();
        Ok(names)
    };
    let (left, right) = (names(a)?, names(b)?);
    if left != right || left.is_empty() {
        return Ok(false);
    }
    for name in &left {
        if std::fs::read(a.join(name))? != std::fs::read(b.join(name))? {
            return Ok(false);
        }
    }
    Ok(true)
}
