//! Times the raster alone: a ~2,500-vertex patch covering ~400×400 px drawn into a
//! 1920×1080 canvas, per frame (reset of the previous frame's rectangle by `copy_rect_from` + `draw_patch`). Run with
//! `cargo run --release --example raster_timing`.

use std::time::Instant;

use glam::{DAffine2, DVec2};
use lapclone::mesh::{BoundaryLoop, LoopKind};
use lapclone::pixels::{Canvas, FloatImage, PixelFormat};
use lapclone::raster::{
    covered_boundary_vertices, draw_patch, CoverageGrid, Patch, PixelRect, RasterOptions,
    RasterScratch,
};

/// CPU time of this thread in seconds (Linux; 0 elsewhere): robust when the machine is busy.
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|text| text.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}

fn main() {
    let side = 50u32; // 51×51 = 2,601 vertices, 5,000 triangles
    let cell = 8.0;
    let index = |i: u32, j: u32| j * (side + 1) + i;
    let mut rest = Vec::new();
    for j in 0..=side {
        for i in 0..=side {
            rest.push(DVec2::new(
                40.0 + f64::from(i) * cell,
                40.0 + f64::from(j) * cell,
            ));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..side {
        for i in 0..side {
            triangles.push([index(i, j), index(i + 1, j), index(i, j + 1)]);
            triangles.push([index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)]);
        }
    }
    let mut boundary = Vec::new();
    boundary.extend((0..side).map(|i| index(i, 0)));
    boundary.extend((0..side).map(|j| index(side, j)));
    boundary.extend((1..=side).rev().map(|i| index(i, side)));
    boundary.extend((1..=side).rev().map(|j| index(0, j)));
    let loops = vec![BoundaryLoop {
        kind: LoopKind::Outer,
        piece: 0,
        vertices: boundary.clone(),
    }];
    let source = FloatImage::from_fn(480, 480, PixelFormat::RGBA8, |i, j| {
        [i as f32 / 480.0, j as f32 / 480.0, 0.5, 1.0]
    })
    .expect("non-empty");
    let background = Canvas::from_image(
        &FloatImage::from_fn(1920, 1080, PixelFormat::RGBA8, |i, j| {
            [0.2, (i ^ j) as f32 / 4096.0, 0.4, 1.0]
        })
        .expect("non-empty"),
    );
    let membrane: Vec<[f32; 3]> = rest
        .iter()
        .map(|p| [(p.x * 0.001) as f32, -0.05, (p.y * 0.0005) as f32])
        .collect();
    let depth: Vec<f32> = rest.iter().map(|p| (p.x * 0.01) as f32).collect();
    let mut canvas = background.clone();
    let mut scratch = RasterScratch::new();
    let mut grid = CoverageGrid::new();
    let mut covered = Vec::new();
    let mut dirty = PixelRect::default();
    // LAPCLONE_THREADS: threads per draw (default 1, so CPU time measures the work).
    let threads: usize = std::env::var("LAPCLONE_THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    for (label, feather, with_depth) in [
        ("plain", 0.0f32, false),
        ("depth", 0.0, true),
        ("depth+feather 4", 4.0, true),
    ] {
        // LAPCLONE_TIMING_FRAMES shortens the run (e.g. under callgrind).
        let frames: u32 = std::env::var("LAPCLONE_TIMING_FRAMES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(300)
            .max(21);
        let mut raster_total = 0.0;
        let mut reset_total = 0.0;
        let mut query_total = 0.0;
        let mut raster_cpu = 0.0;
        for frame in 0..frames {
            let angle = 0.1 + 0.002 * f64::from(frame);
            let place =
                DAffine2::from_translation(DVec2::new(900.0 + f64::from(frame % 50), 500.0))
                    * DAffine2::from_angle(angle)
                    * DAffine2::from_translation(-DVec2::new(240.0, 240.0));
            let placed: Vec<DVec2> = rest.iter().map(|&p| place.transform_point2(p)).collect();
            let t0 = Instant::now();
            // Restore only what the previous frame drew (the renderer's cheap reset).
            canvas
                .copy_rect_from(&background, dirty)
                .expect("same canvas");
            let t1 = Instant::now();
            let cpu1 = thread_cpu_seconds();
            let patch = Patch {
                rest: &rest,
                placed: &placed,
                triangles: &triangles,
                membrane: &membrane,
                depth: with_depth.then_some(&depth[..]),
                loops: &loops,
                source: &source,
            };
            let options = RasterOptions {
                feather,
                threads,
                // LAPCLONE_RASTER_SCALAR: the scalar shading path, for comparisons.
                simd: std::env::var_os("LAPCLONE_RASTER_SCALAR").is_none(),
                ..RasterOptions::default()
            };
            dirty = draw_patch(&mut canvas, &patch, &options, &mut scratch)
                .expect("valid patch")
                .work;
            let cpu2 = thread_cpu_seconds();
            let t2 = Instant::now();
            covered_boundary_vertices(
                &placed,
                &triangles,
                &depth,
                &boundary,
                &mut grid,
                &mut covered,
            )
            .expect("valid");
            let t3 = Instant::now();
            if frame >= 20 {
                reset_total += (t1 - t0).as_secs_f64();
                raster_total += (t2 - t1).as_secs_f64();
                raster_cpu += cpu2 - cpu1;
                query_total += (t3 - t2).as_secs_f64();
            }
        }
        let n = f64::from(frames - 20);
        println!(
            "{label:>16}: draw_patch {:.3} ms/frame wall, {:.3} ms CPU; dirty-rect reset {:.3} ms, coverage query {:.3} ms ({} verts, {} tris)",
            raster_total / n * 1e3,
            raster_cpu / n * 1e3,
            reset_total / n * 1e3,
            query_total / n * 1e3,
            rest.len(),
            triangles.len()
        );
    }
}
