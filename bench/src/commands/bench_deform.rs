//! `lapclone-bench deform`: times the deform stage on hexagonal-disc fixtures (4 px edges):
//! rig build, a drag step with an unchanged constraint set (rotation + right-hand side + two
//! solves), a step that toggles one pin (2 rank-1 switches per frame), and a step that changes
//! the handle radius by 2% (a ring of far-field switches). Use a release build.

use crate::fixtures;
use glam::DVec2;
use lapclone::deform::{DeformRig, Deformed, Handle, Pin};
use lapclone::solve::LaplacianKind;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct DeformBenchArgs {
    /// Fixture sizes (approximate vertex counts).
    #[arg(long, value_delimiter = ',', default_values_t = vec![2_500usize, 10_000, 50_000])]
    pub vertices: Vec<usize>,
    /// Timed frames per measurement (median reported).
    #[arg(long, default_value_t = 200)]
    pub frames: usize,
    /// Use cotangent weights instead of the combinatorial Laplacian.
    #[arg(long)]
    pub cotangent: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(serde::Serialize)]
struct Row {
    vertices: usize,
    triangles: usize,
    build_ms: f64,
    first_frame_ms: f64,
    step_ms: f64,
    pin_toggle_ms: f64,
    pin_toggle_switches: f64,
    radius_change_ms: f64,
    radius_change_switches: f64,
    refactors: usize,
}

pub fn run(args: DeformBenchArgs) -> anyhow::Result<()> {
    if args.frames == 0 {
        return Err(super::UsageError("--frames must be positive".into()).into());
    }
    let kind = if args.cotangent {
        LaplacianKind::Cotangent
    } else {
        LaplacianKind::Combinatorial
    };
    let mut rows = Vec::new();
    for &n in &args.vertices {
        rows.push(bench_one(n, kind, args.frames)?);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    println!(
        "deform bench ({kind:?}), median of {} frames, ms",
        args.frames
    );
    println!(
        "{:>8} {:>9} {:>9} {:>9} {:>9} {:>16} {:>18} {:>6}",
        "verts", "tris", "build", "first", "step", "pin toggle (sw)", "radius chg (sw)", "refac"
    );
    for r in rows {
        println!(
            "{:>8} {:>9} {:>9.3} {:>9.3} {:>9.3} {:>9.3} ({:>4.1}) {:>9.3} ({:>6.1}) {:>6}",
            r.vertices,
            r.triangles,
            r.build_ms,
            r.first_frame_ms,
            r.step_ms,
            r.pin_toggle_ms,
            r.pin_toggle_switches,
            r.radius_change_ms,
            r.radius_change_switches,
            r.refactors
        );
    }
    Ok(())
}

fn bench_one(vertices: usize, kind: LaplacianKind, frames: usize) -> anyhow::Result<Row> {
    let mut mesh = fixtures::disc_with_vertices(vertices);
    let spacing = 4.0;
    mesh.positions.iter_mut().for_each(|p| *p *= spacing);
    let extent = mesh
        .positions
        .iter()
        .map(|p| p.length())
        .fold(0.0, f64::max);
    let start = Instant::now();
    let mut rig = DeformRig::new(&mesh, kind)?;
    let build_ms = ms(start);
    let p0 = DVec2::new(0.5 * extent, 0.0);
    let radius = 0.25 * extent;
    let drag = |k: usize| {
        let t = k as f64 / frames as f64;
        Handle::drag(p0, p0 + DVec2::new(0.0, 0.1 * radius * t), radius)
    };
    let mut out = Deformed::default();
    let start = Instant::now();
    rig.deform(&[drag(0)], &[], &mut out)?;
    let first_frame_ms = ms(start);
    let refactors_before = rig.factor().refactor_count();
    let step = time_frames(frames, |k| {
        Ok(rig.deform(&[drag(k)], &[], &mut out)?.switches())
    })?;
    // Inside the handle's free region, so toggling it really switches a constraint.
    let pin = [Pin(p0 + DVec2::new(0.5 * radius, 0.0))];
    let toggle = time_frames(frames, |k| {
        let pins: &[Pin] = if k % 2 == 0 { &pin } else { &[] };
        Ok(rig.deform(&[drag(frames)], pins, &mut out)?.switches())
    })?;
    let radius_change = time_frames(frames, |k| {
        let scale = if k % 2 == 0 { 1.02 } else { 1.0 };
        let h = Handle {
            radius: radius * scale,
            ..drag(frames)
        };
        Ok(rig.deform(&[h], &[], &mut out)?.switches())
    })?;
    Ok(Row {
        vertices: mesh.vertex_count(),
        triangles: mesh.triangles.len(),
        build_ms,
        first_frame_ms,
        step_ms: step.0,
        pin_toggle_ms: toggle.0,
        pin_toggle_switches: toggle.1,
        radius_change_ms: radius_change.0,
        radius_change_switches: radius_change.1,
        refactors: rig.factor().refactor_count() - refactors_before,
    })
}

/// Median frame time (ms) and mean switches per frame.
fn time_frames(
    frames: usize,
    mut frame: impl FnMut(usize) -> anyhow::Result<usize>,
) -> anyhow::Result<(f64, f64)> {
    let mut times = Vec::with_capacity(frames);
    let mut switches = 0;
    for k in 0..frames {
        let start = Instant::now();
        switches += frame(k)?;
        times.push(ms(start));
    }
    times.sort_by(f64::total_cmp);
    Ok((times[frames / 2], switches as f64 / frames as f64))
}

fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
