//! `lapclone-bench mesh`: meshes synthetic masks from 128² to 2000² (the spiral family and
//! the other shapes of `mesh::synth`) at default settings and prints a table of vertex
//! counts and timings (median and best of `--repeat` runs), or JSON with `--json`.

use std::path::PathBuf;
use std::time::Instant;

use crate::synth;
use anyhow::Context;
use lapclone::mesh::{self, BitMask, MeshOptions};

#[derive(clap::Args, Debug)]
pub struct MeshBenchArgs {
    /// Runs per mask (the median and best are reported).
    #[arg(long, default_value_t = 5)]
    pub repeat: usize,
    /// Maximum boundary edge length in pixels (default: the library default).
    #[arg(long, value_parser = super::finite_f64)]
    pub density: Option<f64>,
    /// Only masks whose name contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// Also save every synthetic mask as `<dir>/<name>.png`.
    #[arg(long = "save-masks")]
    pub save_masks: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

#[derive(serde::Serialize)]
struct Row {
    name: String,
    width: usize,
    height: usize,
    inside_pixels: usize,
    vertices: usize,
    triangles: usize,
    boundary_vertices: usize,
    median_ms: f64,
    best_ms: f64,
}

fn cases() -> Vec<(String, BitMask)> {
    let mut cases: Vec<(String, BitMask)> = [128, 256, 512]
        .into_iter()
        .map(|s| (format!("spiral-{s}"), synth::spiral(s, s)))
        .collect();
    cases.push(("spiral-770x743".into(), synth::spiral_default()));
    cases.push(("spiral-1000".into(), synth::spiral(1000, 1000)));
    cases.push(("spiral-2000".into(), synth::spiral(2000, 2000)));
    cases.push(("disc-2000".into(), synth::disc(2000, 2000, 900.0)));
    cases.push((
        "annulus-1000".into(),
        synth::annulus(1000, 1000, 200.0, 450.0),
    ));
    cases.push(("two-holes-1000".into(), synth::two_holes(1000, 700)));
    cases.push(("comb-1000".into(), synth::comb(1000, 600, 8, 2)));
    cases.push(("nested-1000".into(), synth::nested(1000, 1000)));
    cases.push(("blobs-1000".into(), synth::blobs(1000, 1000, 3)));
    cases.push(("speckle-256".into(), synth::speckle(256, 256, 0.35, 5)));
    cases
}

pub fn run(args: MeshBenchArgs) -> anyhow::Result<()> {
    let mut options = MeshOptions::default();
    if let Some(density) = args.density {
        options.density = density;
    }
    options
        .validate()
        .map_err(|e| super::UsageError(e.to_string()))?;
    let repeat = args.repeat.max(1);
    let mut rows = Vec::new();
    for (name, mask) in cases() {
        if args
            .filter
            .as_ref()
            .is_some_and(|f| !name.contains(f.as_str()))
        {
            continue;
        }
        if let Some(dir) = &args.save_masks {
            let path = dir.join(format!("{name}.png"));
            let mut bytes = Vec::new();
            mask.to_image()
                .write_to(
                    &mut std::io::Cursor::new(&mut bytes),
                    image::ImageFormat::Png,
                )
                .with_context(|| format!("encoding {}", path.display()))?;
            lapclone::util::write_atomic(&path, &bytes)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        let mut times = Vec::with_capacity(repeat);
        let mut last = None;
        for _ in 0..repeat {
            let started = Instant::now();
            let result =
                mesh::mesh_mask(&mask, &options).with_context(|| format!("meshing {name}"))?;
            times.push(started.elapsed().as_secs_f64() * 1e3);
            last = Some(result);
        }
        let stats = last.expect("at least one run").stats; // invariant: repeat ≥ 1, so the loop ran and set `last`.
        times.sort_by(f64::total_cmp);
        rows.push(Row {
            name,
            width: mask.width,
            height: mask.height,
            inside_pixels: mask.count_inside(),
            vertices: stats.vertices,
            triangles: stats.triangles,
            boundary_vertices: stats.boundary_vertices,
            median_ms: times[times.len() / 2],
            best_ms: times[0],
        });
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        print_table(&rows, &options);
    }
    Ok(())
}

fn print_table(rows: &[Row], options: &MeshOptions) {
    println!(
        "mesh bench (boundary {}, density {} px, min angle {}°){}",
        options.boundary.name(),
        options.density,
        options.min_angle_deg,
        if cfg!(debug_assertions) {
            "  [DEBUG BUILD: timings meaningless]"
        } else {
            ""
        }
    );
    println!(
        "{:<16} {:>11} {:>10} {:>9} {:>9} {:>9} {:>10} {:>9}",
        "mask", "size", "inside px", "vertices", "triangles", "boundary", "median ms", "best ms"
    );
    for r in rows {
        println!(
            "{:<16} {:>11} {:>10} {:>9} {:>9} {:>9} {:>10.2} {:>9.2}",
            r.name,
            format!("{}x{}", r.width, r.height),
            r.inside_pixels,
            r.vertices,
            r.triangles,
            r.boundary_vertices,
            r.median_ms,
            r.best_ms
        );
    }
}
