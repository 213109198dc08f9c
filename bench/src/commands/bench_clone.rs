//! `lapclone-bench clone`: times the paper's spiral case end to end and one deformation
//! frame. Takes no input files beyond the bundled photos (synthetic stand-ins when they are
//! missing) and gives a table (or JSON) with the target beside each figure. Use a release build.
//!
//! - `spiral S²`: `synth::spiral(S, S)` cut from the astronaut photo (tiled to S×S) and cloned
//!   into the 1000×872 Hubble deep field at the default density. *first* = mesh + factor +
//!   membrane solve + raster on a fresh cloner, wall clock; *reclone* = the patch moved by
//!   (3, 2) px with mesh and factor kept (constraint switches + solve + raster). Best of
//!   `--repeats`.
//! - `deform`: a disc patch of about 2,500 vertices in a 1920×1080 canvas with one drag whose
//!   end point moves every frame: deform step (two solves) + boundary coverage + constraint
//!   switches + membrane + raster. Median and best over `--frames`.
//!
//! Restoring the canvas between runs is not timed (an application redraws its background
//! anyway); it is reported separately as `restore_ms`.

use std::path::Path;
use std::time::Instant;

use crate::synth;
use glam::DVec2;
use lapclone::clone::{mesh_from_mask, CloneOptions, CloneStats, PatchCloner, Placement};
use lapclone::deform::{DeformRig, Deformed, Handle};
use lapclone::mesh::{BitMask, MeshOptions};
use lapclone::pixels::{Canvas, ColorKind, Depth, FloatImage, PixelFormat};
use lapclone::solve::LaplacianKind;

#[derive(clap::Args, Debug)]
pub struct CloneBenchArgs {
    /// Spiral sizes (side in pixels).
    #[arg(long, value_delimiter = ',', default_values_t = vec![400usize, 800])]
    pub sizes: Vec<usize>,
    /// First clones per spiral (best reported); reclones: twice as many, at least 200 (best
    /// and median reported).
    #[arg(long, default_value_t = 10)]
    pub repeats: usize,
    /// Frames of the deformation case (median and best reported).
    #[arg(long, default_value_t = 100)]
    pub frames: usize,
    /// Approximate vertex count of the deformation case's patch.
    #[arg(long, default_value_t = 2_500)]
    pub vertices: usize,
    /// Threads the deformation case's raster runs on (its pixels are the same for any count).
    #[arg(long, default_value_t = 1)]
    pub raster_threads: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Maximum boundary edge length of the spiral meshes in px (default: the library's).
    #[arg(long, value_parser = super::finite_f64)]
    pub density: Option<f64>,
    /// The membrane's boundary values: `hat-average` (the default) or `vertex` (the paper's
    /// sample at the vertex).
    #[arg(long, default_value = "hat-average")]
    pub boundary_data: lapclone::clone::BoundaryData,
    #[command(flatten)]
    pub mesh: super::mesh_args::MeshQualityArgs,
}

/// OpenCV 5.0 `seamlessClone` (NORMAL) on the spiral masks, ms.
const OPENCV_MS: [(usize, f64); 2] = [(400, 40.0), (800, 184.0)];

#[derive(serde::Serialize)]
struct SpiralRow {
    size: usize,
    vertices: usize,
    boundary_vertices: usize,
    first_ms: f64,
    first_target_ms: Option<f64>,
    mesh_ms: f64,
    factor_ms: f64,
    solve_ms: f64,
    raster_ms: f64,
    reclone_ms: f64,
    reclone_median_ms: f64,
    reclone_count: usize,
    reclone_target_ms: Option<f64>,
    reclone_solve_ms: f64,
    reclone_raster_ms: f64,
    reclone_switches: usize,
    opencv_ms: Option<f64>,
}

#[derive(serde::Serialize)]
struct DeformRow {
    vertices: usize,
    boundary_vertices: usize,
    canvas: [u32; 2],
    frame_median_ms: f64,
    frame_best_ms: f64,
    frame_target_ms: f64,
    deform_median_ms: f64,
    solve_median_ms: f64,
    raster_median_ms: f64,
    switches_per_frame: f64,
    hidden_max: usize,
    restore_ms: f64,
}

#[derive(serde::Serialize)]
struct Report {
    spiral: Vec<SpiralRow>,
    deform: DeformRow,
}

pub fn run(args: CloneBenchArgs) -> anyhow::Result<()> {
    if args.repeats == 0 || args.frames == 0 || args.vertices < 10 || args.raster_threads == 0 {
        return Err(super::UsageError(
            "--repeats, --frames and --raster-threads must be positive, --vertices ≥ 10".into(),
        )
        .into());
    }
    if let Some(&bad) = args.sizes.iter().find(|&&s| !(32..=4000).contains(&s)) {
        return Err(super::UsageError(format!("spiral size {bad} outside 32..=4000")).into());
    }
    let target = load_or(asset("hubble_deep_field.jpg"), || synthetic(1000, 872, 0.3))?;
    let photo = load_or(asset("astronaut.png"), || synthetic(512, 512, 1.7))?;
    let mesh_options = args.mesh.options(args.density)?;
    let clone_options = CloneOptions {
        boundary_data: args.boundary_data,
        ..CloneOptions::default()
    };
    let mut spiral = Vec::new();
    for &size in &args.sizes {
        spiral.push(bench_spiral(
            size,
            &photo,
            &target,
            &mesh_options,
            &clone_options,
            args.repeats,
        )?);
    }
    let deform = bench_deform(
        args.vertices,
        args.frames,
        args.raster_threads,
        &clone_options,
    )?;
    let report = Report { spiral, deform };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report, args.repeats, args.frames);
    }
    Ok(())
}

fn asset(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../assets")
        .join(name)
}

fn load_or(
    path: std::path::PathBuf,
    fallback: impl FnOnce() -> anyhow::Result<FloatImage>,
) -> anyhow::Result<FloatImage> {
    match FloatImage::load(&path) {
        Ok(image) => Ok(image),
        Err(err) => {
            eprintln!("lapclone: warning: {err}; using a synthetic image");
            fallback()
        }
    }
}

const RGB8: PixelFormat = PixelFormat {
    color: ColorKind::Rgb,
    alpha: false,
    depth: Depth::Eight,
};

/// A smooth 8-bit test picture: its values are levels k / 255, as if loaded from an 8-bit
/// file (so the raster samples its 8-bit texels, like a photo's).
fn synthetic(width: u32, height: u32, phase: f32) -> anyhow::Result<FloatImage> {
    let level = |v: f32| (v * 255.0).round() / 255.0;
    Ok(FloatImage::from_fn(width, height, RGB8, |i, j| {
        let (x, y) = (i as f32 * 0.05 + phase, j as f32 * 0.07);
        [
            level(0.5 + 0.4 * x.sin() * y.cos()),
            level(0.5 + 0.3 * (x + y).sin()),
            level(0.4 + 0.3 * (x * 0.5 - y).cos()),
            1.0,
        ]
    })?)
}

/// The photo tiled (mirrored) to `size`².
fn tiled(photo: &FloatImage, size: u32) -> anyhow::Result<FloatImage> {
    let (w, h) = (photo.width(), photo.height());
    let mirror = |k: u32, n: u32| {
        let period = k % (2 * n);
        if period < n {
            period
        } else {
            2 * n - 1 - period
        }
    };
    Ok(FloatImage::from_fn(size, size, photo.format(), |i, j| {
        photo.pixels()[(mirror(j, h) * w + mirror(i, w)) as usize]
    })?)
}

fn bench_spiral(
    size: usize,
    photo: &FloatImage,
    target: &FloatImage,
    mesh_options: &MeshOptions,
    clone_options: &CloneOptions,
    repeats: usize,
) -> anyhow::Result<SpiralRow> {
    let mask = synth::spiral(size, size);
    let source = tiled(photo, size as u32)?;
    let background = Canvas::from_image(target);
    let mut canvas = background.clone();
    let centre = DVec2::new(f64::from(target.width()), f64::from(target.height())) * 0.5;
    let placement = Placement::translate(DVec2::splat(size as f64 * 0.5), centre);
    let job = FirstClones {
        mask: &mask,
        source: &source,
        background: &background,
        placement: &placement,
        mesh_options,
        clone_options,
    };
    let (first, mut cloner) = job.time(&mut canvas, repeats)?;
    let (reclone, mut reclones) =
        time_reclones(&mut cloner, &mut canvas, &background, &placement, repeats)?;
    let opencv = OPENCV_MS
        .iter()
        .find(|(s, _)| *s == size)
        .map(|&(_, ms)| ms);
    Ok(SpiralRow {
        size,
        vertices: cloner.mesh().vertex_count(),
        boundary_vertices: cloner.membrane().boundary_vertices().len(),
        first_ms: first.total_ms,
        first_target_ms: opencv.map(|ms| ms / 10.0),
        mesh_ms: first.mesh_ms,
        factor_ms: first.factor_ms,
        solve_ms: first.stats.solve_ms,
        raster_ms: first.stats.raster_ms,
        reclone_ms: reclones.iter().copied().fold(f64::INFINITY, f64::min),
        reclone_median_ms: median(&mut reclones),
        reclone_count: reclones.len(),
        reclone_target_ms: opencv.map(|ms| ms / 100.0),
        reclone_solve_ms: reclone.solve_ms,
        reclone_raster_ms: reclone.raster_ms,
        reclone_switches: reclone.membrane.switches.updates + reclone.membrane.switches.downdates,
        opencv_ms: opencv,
    })
}

/// What a spiral's first clone (mesh, factor, clone) is timed on.
struct FirstClones<'a> {
    mask: &'a BitMask,
    source: &'a FloatImage,
    background: &'a Canvas,
    placement: &'a Placement,
    mesh_options: &'a MeshOptions,
    clone_options: &'a CloneOptions,
}

/// The best of a spiral's first clones, and its parts.
struct FirstClone {
    total_ms: f64,
    mesh_ms: f64,
    /// The Laplacian assembled and factored by `PatchCloner::new`.
    factor_ms: f64,
    stats: CloneStats,
}

impl FirstClones<'_> {
    /// Meshes, factors and clones `repeats` times onto `canvas`; gives the best run and the
    /// last cloner, for the reclones.
    fn time(
        &self,
        canvas: &mut Canvas,
        repeats: usize,
    ) -> anyhow::Result<(FirstClone, PatchCloner)> {
        let mut best: Option<FirstClone> = None;
        let mut cloner = None;
        let size = (self.source.width(), self.source.height());
        for _ in 0..repeats {
            canvas.copy_from(self.background);
            // The cloner owns its source; copying it is the caller's business, not timed.
            let owned_source = self.source.clone();
            let started = Instant::now();
            let patch = mesh_from_mask(self.mask, None, size, self.mesh_options)?;
            let meshed = Instant::now();
            let mut fresh = PatchCloner::new(owned_source, patch.result.mesh, self.clone_options)?;
            let factored = Instant::now();
            let stats = fresh.clone_onto(canvas, self.placement)?;
            let total_ms = millis(started.elapsed());
            if best.as_ref().is_none_or(|b| total_ms < b.total_ms) {
                let (mesh_ms, factor_ms) = (millis(meshed - started), millis(factored - meshed));
                best = Some(FirstClone {
                    total_ms,
                    mesh_ms,
                    factor_ms,
                    stats,
                });
            }
            cloner = Some(fresh);
        }
        best.zip(cloner)
            .ok_or_else(|| anyhow::anyhow!("no repeat ran"))
    }
}

/// Re-clones `cloner`, alternately moved by (3, 2) px and back; gives the fastest one's
/// stats and every time, ms.
fn time_reclones(
    cloner: &mut PatchCloner,
    canvas: &mut Canvas,
    background: &Canvas,
    placement: &Placement,
    repeats: usize,
) -> anyhow::Result<(CloneStats, Vec<f64>)> {
    let mut best = (f64::INFINITY, CloneStats::default());
    // Like the scene renderer, each reclone restores only what the previous clone drew.
    let mut dirty = None;
    let mut times = Vec::with_capacity(reclone_count(repeats));
    for k in 0..reclone_count(repeats) {
        let shift = if k % 2 == 0 {
            DVec2::new(3.0, 2.0)
        } else {
            DVec2::ZERO
        };
        let moved = Placement {
            at: placement.at + shift,
            ..*placement
        };
        match dirty {
            Some(rect) => canvas.copy_rect_from(background, rect)?,
            None => canvas.copy_from(background),
        }
        let started = Instant::now();
        let stats = cloner.clone_onto(canvas, &moved)?;
        let elapsed = millis(started.elapsed());
        dirty = Some(stats.raster.work);
        times.push(elapsed);
        if elapsed < best.0 {
            best = (elapsed, stats);
        }
    }
    Ok((best.1, times))
}

/// A disc mask whose default-density mesh has at least about `vertices` vertices.
fn disc_patch(vertices: usize) -> anyhow::Result<lapclone::mesh::Mesh> {
    let mut radius = 20.0f64;
    loop {
        let side = (2.0 * radius).ceil() as usize + 4;
        let mask: BitMask = synth::disc(side, side, radius);
        let patch = mesh_from_mask(
            &mask,
            None,
            (side as u32, side as u32),
            &MeshOptions::default(),
        )?;
        if patch.result.mesh.vertex_count() >= vertices || radius > 2000.0 {
            return Ok(patch.result.mesh);
        }
        radius *= (vertices as f64 / patch.result.mesh.vertex_count() as f64)
            .sqrt()
            .clamp(1.02, 2.0);
    }
}

fn bench_deform(
    vertices: usize,
    frames: usize,
    raster_threads: usize,
    clone_options: &CloneOptions,
) -> anyhow::Result<DeformRow> {
    let mesh = disc_patch(vertices)?;
    let (min, max) = bounds(&mesh.positions);
    let side = (max - min).max_element().ceil() as u32 + 2;
    let source = synthetic(side, side, 0.9)?;
    let background = Canvas::from_image(&synthetic(1920, 1080, 2.1)?);
    let mut cloner = PatchCloner::new(source, mesh, clone_options)?;
    cloner.set_raster_threads(raster_threads);
    let rig = DeformRig::new(cloner.mesh(), LaplacianKind::Combinatorial)?;
    let centre = (min + max) * 0.5;
    let radius = 0.5 * (max - min).max_element();
    let mut case = DeformCase {
        canvas: background.clone(),
        background,
        cloner,
        rig,
        placement: Placement::translate(centre, DVec2::new(960.0, 540.0)),
        grab: centre + DVec2::new(0.6 * radius, 0.0),
        radius,
    };
    let mut t = case.time(frames)?;
    let best = t.frame.iter().copied().fold(f64::INFINITY, f64::min);
    Ok(DeformRow {
        vertices: case.cloner.mesh().vertex_count(),
        boundary_vertices: case.cloner.membrane().boundary_vertices().len(),
        canvas: [1920, 1080],
        frame_median_ms: median(&mut t.frame),
        frame_best_ms: best,
        frame_target_ms: 4.0,
        deform_median_ms: median(&mut t.deform),
        solve_median_ms: median(&mut t.solve),
        raster_median_ms: median(&mut t.raster),
        switches_per_frame: t.switches as f64 / frames as f64,
        hidden_max: t.hidden_max,
        restore_ms: t.restore_ms / frames as f64,
    })
}

/// A disc patch on a 1920×1080 canvas, deformed by one handle that circles around `grab`.
struct DeformCase {
    background: Canvas,
    canvas: Canvas,
    cloner: PatchCloner,
    rig: DeformRig,
    placement: Placement,
    grab: DVec2,
    radius: f64,
}

/// Per-frame times of the deform case, ms, and its totals.
#[derive(Default)]
struct DeformTimes {
    frame: Vec<f64>,
    deform: Vec<f64>,
    solve: Vec<f64>,
    raster: Vec<f64>,
    switches: usize,
    hidden_max: usize,
    restore_ms: f64,
}

impl DeformCase {
    /// Deforms and clones `frames` frames (after five of warm-up: the first factor touches,
    /// buffer growth).
    fn time(&mut self, frames: usize) -> anyhow::Result<DeformTimes> {
        let mut t = DeformTimes::default();
        let mut deformed = Deformed::default();
        // Like the scene renderer, each frame restores only what the previous one drew.
        let mut dirty = None;
        for k in 0..frames + 5 {
            // The handle circles around its grab point, reaching over the patch's centre.
            let angle = k as f64 * 0.15;
            let to = self.grab + 0.5 * self.radius * DVec2::new(angle.cos() - 1.0, angle.sin());
            let handle = Handle::drag(self.grab, to, 0.5 * self.radius);
            let restore_started = Instant::now();
            match dirty {
                Some(rect) => self.canvas.copy_rect_from(&self.background, rect)?,
                None => self.canvas.copy_from(&self.background),
            }
            let restored = Instant::now();
            self.rig.deform(&[handle], &[], &mut deformed)?;
            let deformed_at = Instant::now();
            let stats = self.cloner.clone_deformed(
                &mut self.canvas,
                &self.placement,
                &deformed.positions,
                Some(&deformed.depth),
            )?;
            let done = Instant::now();
            dirty = Some(stats.raster.work);
            if k < 5 {
                continue;
            }
            t.restore_ms += millis(restored - restore_started);
            t.frame.push(millis(done - restored));
            t.deform.push(millis(deformed_at - restored));
            t.solve.push(stats.solve_ms);
            t.raster.push(stats.raster_ms);
            t.switches += stats.membrane.switches.updates + stats.membrane.switches.downdates;
            t.hidden_max = t.hidden_max.max(stats.membrane.hidden);
        }
        Ok(t)
    }
}

/// Reclones per spiral: cheap next to a first clone, so many more of them (alternately moved
/// by (3, 2) px and back), for a steady best and median.
fn reclone_count(repeats: usize) -> usize {
    (repeats * 2).max(200)
}

fn bounds(points: &[DVec2]) -> (DVec2, DVec2) {
    points.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

fn millis(duration: std::time::Duration) -> f64 {
    duration.as_secs_f64() * 1e3
}

fn target(value: Option<f64>) -> String {
    value.map_or_else(|| "—".into(), |ms| format!("≤{ms:.1}"))
}

fn print_table(report: &Report, repeats: usize, frames: usize) {
    println!("clone bench (release build for meaningful figures); spiral: best of {repeats}, deform: {frames} frames");
    println!(
        "{:<14} {:>7} {:>6} {:>9} {:>8} {:>7} {:>7} {:>7} {:>7} {:>9} {:>8} {:>8}",
        "case",
        "verts",
        "bdry",
        "first",
        "target",
        "mesh",
        "factor",
        "solve",
        "raster",
        "reclone",
        "target",
        "opencv"
    );
    for r in &report.spiral {
        println!(
            "{:<14} {:>7} {:>6} {:>9.3} {:>8} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>9.3} {:>8} {:>8}",
            format!("spiral {}²", r.size),
            r.vertices,
            r.boundary_vertices,
            r.first_ms,
            target(r.first_target_ms),
            r.mesh_ms,
            r.factor_ms,
            r.solve_ms,
            r.raster_ms,
            r.reclone_ms,
            target(r.reclone_target_ms),
            r.opencv_ms
                .map_or_else(|| "—".into(), |ms| format!("{ms:.0}")),
        );
        println!(
            "{:<14} reclone: best of {} = solve {:.3} + raster {:.3} ms, {} switches; median {:.3} ms",
            "",
            r.reclone_count,
            r.reclone_solve_ms,
            r.reclone_raster_ms,
            r.reclone_switches,
            r.reclone_median_ms
        );
    }
    let d = &report.deform;
    println!(
        "{:<14} {:>7} {:>6} frame median {:.3} ms (best {:.3}, target ≤{:.1}) = deform {:.3} + solve {:.3} + raster {:.3}; {:.1} switches/frame, ≤{} hidden; canvas restore {:.3} ms (untimed)",
        format!("deform {}×{}", d.canvas[0], d.canvas[1]),
        d.vertices,
        d.boundary_vertices,
        d.frame_median_ms,
        d.frame_best_ms,
        d.frame_target_ms,
        d.deform_median_ms,
        d.solve_median_ms,
        d.raster_median_ms,
        d.switches_per_frame,
        d.hidden_max,
        d.restore_ms,
    );
}
