//! `lapclone-bench render`: the issue-6 frame budget — a 1920×1080 scene with two deforming
//! patches of ≈2,500 vertices each, 120 frames: per-frame computation (timeline, deformation,
//! switches, membrane, raster; no encoding), then PNG encoding of rendered frames with 1 and
//! with N jobs. Use a release build.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use glam::DVec2;
use lapclone::output::{Frame, FrameData, PngCompression, PngSequenceWriter};
use lapclone::pixels::CanvasPixels;
use lapclone::render::Renderer;
use lapclone::scene::{
    Background, Canvas as SceneCanvas, Easing, Handle, Patch, Polygon, Scene, Shape, Track,
};

#[derive(clap::Args, Debug)]
pub struct RenderBenchArgs {
    /// Frames rendered for the compute timing.
    #[arg(long, default_value_t = 120)]
    pub frames: u64,
    /// Frames encoded for the PNG timing (each 1920×1080 RGBA frame is 8 MB in memory).
    #[arg(long = "encode-frames", default_value_t = 24)]
    pub encode_frames: usize,
    /// Encoder threads for the parallel run.
    #[arg(long, default_value_t = 2)]
    pub jobs: usize,
    /// Folder holding the bundled photos.
    #[arg(long, default_value = "assets")]
    pub assets: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(serde::Serialize)]
struct Report {
    width: u32,
    height: u32,
    patch_vertices: Vec<usize>,
    frames: u64,
    build_ms: f64,
    frame_ms_median: f64,
    frame_ms_mean: f64,
    frame_ms_max: f64,
    deform_ms_mean: f64,
    solve_ms_mean: f64,
    raster_ms_mean: f64,
    encode_frames: usize,
    encode_ms_per_frame_1_job: f64,
    encode_ms_per_frame_n_jobs: f64,
    jobs: usize,
    encode_speedup: f64,
}

pub fn run(args: RenderBenchArgs) -> anyhow::Result<()> {
    if args.frames == 0 || args.encode_frames == 0 || args.jobs == 0 {
        return Err(super::UsageError(
            "--frames, --encode-frames and --jobs must be positive".into(),
        )
        .into());
    }
    let scene = bench_scene(&args.assets, args.frames);
    let started = Instant::now();
    let mut renderer = Renderer::new(scene)?;
    let build_ms = started.elapsed().as_secs_f64() * 1e3;
    let mut totals = Vec::with_capacity(args.frames as usize);
    let (mut deform, mut solve, mut raster) = (0.0, 0.0, 0.0);
    let mut kept: Vec<Frame> = Vec::new();
    for index in 0..args.frames {
        renderer.render_frame(index)?;
        let stats = renderer.last_stats();
        totals.push(stats.total_ms);
        deform += stats.deform_ms;
        solve += stats.solve_ms;
        raster += stats.raster_ms;
        if kept.len() < args.encode_frames {
            kept.push(owned_frame(&renderer));
        }
    }
    let frames = args.frames as f64;
    totals.sort_by(f64::total_cmp);
    let one = encode_ms_per_frame(&kept, 1)?;
    let many = encode_ms_per_frame(&kept, args.jobs)?;
    let canvas = &renderer.scene().canvas;
    let report = Report {
        width: canvas.width,
        height: canvas.height,
        patch_vertices: renderer.vertex_counts(),
        frames: args.frames,
        build_ms,
        frame_ms_median: totals[totals.len() / 2],
        frame_ms_mean: totals.iter().sum::<f64>() / frames,
        frame_ms_max: totals[totals.len() - 1],
        deform_ms_mean: deform / frames,
        solve_ms_mean: solve / frames,
        raster_ms_mean: raster / frames,
        encode_frames: kept.len(),
        encode_ms_per_frame_1_job: one,
        encode_ms_per_frame_n_jobs: many,
        jobs: args.jobs,
        encode_speedup: one / many,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report);
    }
    Ok(())
}

fn print_table(r: &Report) {
    println!(
        "render bench: {}×{}, patches of {:?} vertices, {} frames (build {:.1} ms)",
        r.width, r.height, r.patch_vertices, r.frames, r.build_ms
    );
    println!(
        "  frame compute  median {:.2} ms  mean {:.2} ms  max {:.2} ms   (target ≤ 4 ms)",
        r.frame_ms_median, r.frame_ms_mean, r.frame_ms_max
    );
    println!(
        "    of which     deform {:.2} ms  switches+solve {:.2} ms  raster {:.2} ms (mean)",
        r.deform_ms_mean, r.solve_ms_mean, r.raster_ms_mean
    );
    println!(
        "  PNG encoding   1 job {:.1} ms/frame   {} jobs {:.1} ms/frame   speed-up {:.2}× (target ≥ 1.7× with 2 jobs)",
        r.encode_ms_per_frame_1_job, r.jobs, r.encode_ms_per_frame_n_jobs, r.encode_speedup
    );
}

/// Two disc patches (≈2,500 vertices each) crossing a 1920×1080 canvas, each with a drag
/// swinging back and forth.
fn bench_scene(assets: &Path, frames: u64) -> Scene {
    let fps = 24.0;
    let duration = frames as f64 / fps;
    let discs = [
        (
            "astronaut.png",
            [256.0, 256.0],
            [400.0, 900.0],
            [1500.0, 300.0],
        ),
        (
            "chelsea.png",
            [225.0, 150.0],
            [1500.0, 850.0],
            [400.0, 250.0],
        ),
    ];
    let patches = discs
        .into_iter()
        .enumerate()
        .map(|(k, (source, centre, from, to))| {
            let mut patch = disc_patch(k, assets.join(source), DVec2::from(centre));
            push_keys(
                &mut patch.placement.position,
                &[(0.0, DVec2::from(from)), (duration, DVec2::from(to))],
            );
            push_keys(
                &mut patch.placement.rotation,
                &[(0.0, -15.0), (duration, 15.0)],
            );
            patch
                .handles
                .push(swinging_handle(DVec2::from(centre), duration));
            patch
        })
        .collect();
    Scene {
        canvas: SceneCanvas {
            width: 1920,
            height: 1080,
            fps,
            duration,
            background: Background::Image(assets.join("hubble_deep_field.jpg")),
        },
        patches,
        golden: None,
    }
}

/// The bench's disc radius, px.
const DISC_RADIUS: f64 = 150.0;

/// Patch `disc{k}`: a 160-gon of [`DISC_RADIUS`] about `centre` of `source`, at density 1.
fn disc_patch(k: usize, source: std::path::PathBuf, centre: DVec2) -> Patch {
    let outer = (0..160)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 160.0;
            centre + DISC_RADIUS * DVec2::new(a.cos(), a.sin())
        })
        .collect();
    let polygon = Polygon {
        outer,
        holes: Vec::new(),
    };
    let mut patch = Patch::new(format!("disc{k}"), source, Shape::Polygons(vec![polygon]));
    patch.density = Some(1.0);
    patch
}

/// A depth handle right of `centre` whose target swings back and forth once a second.
fn swinging_handle(centre: DVec2, duration: f64) -> Handle {
    let grab = centre + DVec2::new(DISC_RADIUS * 0.6, 0.0);
    let mut to_track = Track::new();
    let swing = [grab, grab + DVec2::new(-40.0, 60.0)];
    let mut t = 0.0;
    let mut i = 0;
    while t <= duration {
        let _ = to_track.push(t, swing[i % 2], Easing::EaseInOut);
        t += 1.0;
        i += 1;
    }
    Handle {
        from: grab,
        to: to_track,
        radius: 70.0,
        depth: Some(1.0),
        pivot: None,
        rotation: Track::new(),
    }
}

fn push_keys<T: lapclone::scene::Interpolate>(track: &mut Track<T>, keys: &[(f64, T)]) {
    for &(t, v) in keys {
        // invariant: the keys above are finite and in increasing time.
        let _ = track.push(t, v, Easing::Smooth);
    }
}

fn owned_frame(renderer: &Renderer) -> Frame {
    let canvas = renderer.frame();
    let data = match canvas.pixels() {
        CanvasPixels::Eight(p) => FrameData::Rgba8(p.as_flattened().to_vec()),
        CanvasPixels::Sixteen(p) => FrameData::Rgba16(p.as_flattened().to_vec()),
    };
    Frame {
        width: canvas.width(),
        height: canvas.height(),
        data,
    }
}

/// Wall time per frame to encode and write `frames` as a PNG sequence with `jobs` threads.
fn encode_ms_per_frame(frames: &[Frame], jobs: usize) -> anyhow::Result<f64> {
    let dir = std::env::temp_dir().join(format!("lapclone-bench-{}-{jobs}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let cancel = Arc::new(AtomicBool::new(false));
    // Copied before the clock starts: the writer takes frames by value, and an 8 MB copy
    // per frame on the submitting thread is not encoding work.
    let owned: Vec<Frame> = frames.to_vec();
    let started = Instant::now();
    let mut writer = PngSequenceWriter::new(
        &dir,
        frames.len() as u64,
        jobs,
        PngCompression::Fast,
        cancel,
    )?;
    for (i, frame) in owned.into_iter().enumerate() {
        writer.submit(i as u64 + 1, frame)?;
    }
    writer.finish()?;
    let ms = started.elapsed().as_secs_f64() * 1e3 / frames.len() as f64;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(ms)
}
