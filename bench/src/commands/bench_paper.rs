//! `lapclone-bench paper`: the paper's Table I and Fig. 5 measured on lapclone (use a release
//! build). It takes the assets folder and options and prints a table — per model: pixels,
//! vertices, pre-processing (MVC weights vs Cholesky factor), membrane time (MVC vs ours),
//! PSNR of the combinatorial, cotangent and MVC membranes against the pixel-grid reference,
//! seam steps and uncovered pixels — or JSON with `--json`; writes the Fig.-5-style picture
//! `fig5_spiral.png` into `--out`; with `--sweep`, sweeps the mesh density on the spiral and
//! writes the markdown table to `--sweep-out` (docs/quality.md).
//!
//! JSON keys (`--json`): `density`, `boundary_data` (`hat-average` or `vertex`), `repeats`, `models[]` with `model`, `width`, `height`,
//! `inside_pixels`, `vertices`, `triangles`, `boundary_vertices`, `mesh_ms`,
//! `reference_factor_ms`, `reference_solve_ms`, `uncovered`, and `combinatorial`,
//! `cotangent`, `mvc` objects with `psnr_db`, `seam_step`, `reference_seam_step`,
//! `preprocess_ms`, `membrane_ms` (MVC: `null` numbers and `not_run` = reason when it did not
//! run); `figure` (path or null); `sweep[]` (with `--sweep`) with `density`, `vertices`,
//! `mesh_ms`, `psnr_combinatorial_db`, `psnr_cotangent_db`, `uncovered`, `reclone_ms`,
//! `boundary`, `min_angle_deg`, `max_area` (null: none), `relax_sweeps`. With `--rings`, every model also has
//! `rings[]`: `first`, `last` (ring band; `last` null = and beyond), `combinatorial_db`,
//! `cotangent_db` — PSNR over the mask pixels that many 4-steps from the outside.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::reference::experiment::{
    reclone_ms, Experiment, MeshRun, MethodFigures, MvcOutcome, RunOptions,
};
use crate::reference::figure::comparison_figure;
use crate::reference::paper_models::{paper_model, MODEL_NAMES};
use crate::reference::{psnr_by_ring, GridMask};
use anyhow::Context;
use glam::DVec2;
use lapclone::mesh::{BoundaryPlacement, MeshOptions};
use lapclone::solve::LaplacianKind;
use lapclone::util::write_atomic;

/// Densities (max boundary edge, px) of the default sweep (centres: at most √2 px keeps every
/// centre, so 1 is the finest).
const SWEEP_DENSITIES: [f64; 4] = [4.0, 3.0, 2.0, 1.0];
/// Mesh configurations swept after the densities (boundary, density px, min angle °, max
/// area px², relaxation sweeps): the crack boundary (the earlier default), relaxation, grading
/// limits (docs/quality.md).
type SweepConfig = (BoundaryPlacement, f64, f64, Option<f64>, usize);
const SWEEP_QUALITY: [SweepConfig; 17] = [
    (BoundaryPlacement::Cracks, 4.0, 25.0, None, 2),
    (BoundaryPlacement::Cracks, 3.0, 25.0, None, 2),
    (BoundaryPlacement::Cracks, 2.0, 25.0, None, 2),
    (BoundaryPlacement::Cracks, 1.0, 25.0, None, 2),
    (BoundaryPlacement::Cracks, 0.5, 25.0, None, 2),
    (BoundaryPlacement::Cracks, 3.0, 25.0, None, 0),
    (BoundaryPlacement::OutsideCentres, 3.0, 25.0, None, 0),
    (BoundaryPlacement::OutsideCentres, 3.0, 27.0, None, 2),
    (BoundaryPlacement::OutsideCentres, 3.0, 28.0, None, 2),
    (BoundaryPlacement::OutsideCentres, 2.0, 28.0, None, 2),
    (BoundaryPlacement::OutsideCentres, 1.0, 28.0, None, 0),
    (BoundaryPlacement::OutsideCentres, 1.0, 30.0, None, 0),
    (BoundaryPlacement::OutsideCentres, 1.0, 30.0, Some(16.0), 0),
    (BoundaryPlacement::OutsideCentres, 1.0, 32.0, None, 0),
    (BoundaryPlacement::OutsideCentres, 1.0, 25.0, None, 5),
    (BoundaryPlacement::OutsideCentres, 1.0, 28.0, None, 5),
    (BoundaryPlacement::OutsideCentres, 1.0, 29.0, None, 5),
];
/// The one configuration `--quick` sweeps besides two densities: the crack boundary at 3 px.
const QUICK_QUALITY: std::ops::Range<usize> = 1..2;
/// Ring bands of `--rings` (inclusive; `u32::MAX`: and beyond).
const RING_BANDS: [(u32, u32); 6] = [(1, 1), (2, 2), (3, 3), (4, 7), (8, 15), (16, u32::MAX)];
/// Re-clones timed per sweep row at least (the best is reported): a shared machine's hiccups
/// made single rows of five read twice their neighbours.
const RECLONE_REPEATS: usize = 30;
/// Vertex counts of the Fig.-5 meshes (the paper's .5K, 1K, 3K).
const FIGURE_VERTICES: [usize; 3] = [500, 1000, 3000];

#[derive(clap::Args, Debug)]
pub struct PaperBenchArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Folder for the comparison picture.
    #[arg(long, default_value = "out/paper")]
    pub out: PathBuf,
    /// Folder holding the bundled photos and horse_mask.png.
    #[arg(long, default_value = "assets")]
    pub assets: PathBuf,
    /// Maximum boundary edge length in px for the table (default: the library default).
    #[arg(long, value_parser = super::finite_f64)]
    pub density: Option<f64>,
    /// Timed runs per figure (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Only models whose name contains this text.
    #[arg(long)]
    pub filter: Option<String>,
    /// Skip MVC on meshes whose dense weight table would exceed this many entries.
    #[arg(long, default_value_t = 40_000_000)]
    pub mvc_max_weights: usize,
    /// Tiny configuration (mouth only, one run, no picture; a small sweep): a smoke test.
    #[arg(long)]
    pub quick: bool,
    /// Do not write the comparison picture.
    #[arg(long)]
    pub no_figure: bool,
    /// Also sweep the mesh density on the spiral and write the markdown table.
    #[arg(long)]
    pub sweep: bool,
    /// Where `--sweep` writes its markdown.
    #[arg(long, default_value = "docs/quality.md")]
    pub sweep_out: PathBuf,
    /// Also write Table I and the picture into this file's "How good is it" block (between
    /// `<!-- bench paper: begin -->` and `<!-- bench paper: end -->`), e.g. README.md.
    #[arg(long)]
    pub readme: Option<PathBuf>,
    /// Also give PSNR by distance from the boundary (rings of 4-steps from the outside).
    #[arg(long)]
    pub rings: bool,
    /// The membrane's boundary values: `hat-average` (the default) or `vertex` (the paper's
    /// sample at the vertex).
    #[arg(long, default_value = "hat-average")]
    pub boundary_data: lapclone::clone::BoundaryData,
    #[command(flatten)]
    pub mesh: super::mesh_args::MeshQualityArgs,
}

#[derive(serde::Serialize)]
struct MethodJson {
    psnr_db: Option<f64>,
    seam_step: Option<f64>,
    reference_seam_step: Option<f64>,
    preprocess_ms: Option<f64>,
    membrane_ms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    not_run: Option<String>,
}

#[derive(serde::Serialize)]
struct ModelJson {
    model: String,
    width: usize,
    height: usize,
    inside_pixels: usize,
    vertices: usize,
    triangles: usize,
    boundary_vertices: usize,
    mesh_ms: f64,
    reference_factor_ms: f64,
    reference_solve_ms: f64,
    uncovered: usize,
    combinatorial: MethodJson,
    cotangent: MethodJson,
    mvc: MethodJson,
    #[serde(skip_serializing_if = "Option::is_none")]
    rings: Option<Vec<RingJson>>,
}

#[derive(serde::Serialize)]
struct RingJson {
    first: u32,
    last: Option<u32>,
    combinatorial_db: Option<f64>,
    cotangent_db: Option<f64>,
}

#[derive(serde::Serialize, Clone)]
struct SweepRow {
    density: f64,
    vertices: usize,
    mesh_ms: f64,
    psnr_combinatorial_db: f64,
    psnr_cotangent_db: f64,
    uncovered: usize,
    reclone_ms: f64,
    boundary: BoundaryPlacement,
    min_angle_deg: f64,
    max_area: Option<f64>,
    relax_sweeps: usize,
}

#[derive(serde::Serialize)]
struct Report {
    density: f64,
    boundary: &'static str,
    boundary_data: &'static str,
    repeats: usize,
    models: Vec<ModelJson>,
    figure: Option<String>,
    sweep: Vec<SweepRow>,
}

pub fn run(args: PaperBenchArgs) -> anyhow::Result<()> {
    let mesh_options = args.mesh.options(args.density)?;
    if args.repeat == 0 {
        return Err(super::UsageError("--repeat must be at least 1".into()).into());
    }
    let run_options = RunOptions {
        repeats: if args.quick { 1 } else { args.repeat },
        mvc_max_weights: args.mvc_max_weights,
        keep_membranes: false,
        boundary_data: args.boundary_data,
    };
    let names: Vec<&str> = MODEL_NAMES
        .into_iter()
        .filter(|n| !args.quick || *n == "mouth")
        .filter(|n| args.filter.as_ref().is_none_or(|f| n.contains(f.as_str())))
        .collect();
    let mut models = Vec::new();
    for name in names {
        let experiment = load_experiment(&args.assets, name)?;
        let table_options = RunOptions {
            keep_membranes: args.rings,
            ..run_options
        };
        let run = experiment
            .run(&mesh_options, &table_options)
            .with_context(|| format!("model {name}"))?;
        if !args.json {
            eprintln!("measured {name}");
        }
        let mut json = model_json(name, &experiment, &run);
        if args.rings {
            json.rings = Some(rings_json(&experiment, &run)?);
        }
        models.push(json);
    }
    let figure = if args.quick || args.no_figure {
        None
    } else {
        Some(write_figure(&args, &run_options)?)
    };
    let sweep = if args.sweep {
        run_sweep(&args, &run_options)?
    } else {
        Vec::new()
    };
    let report = Report {
        density: mesh_options.density,
        boundary: mesh_options.boundary.name(),
        boundary_data: args.boundary_data.name(),
        repeats: run_options.repeats,
        models,
        figure: figure.map(|p| p.display().to_string()),
        sweep,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", table_text(&report));
    }
    if let Some(readme) = &args.readme {
        write_readme_block(readme, &report)?;
    }
    Ok(())
}

const README_BEGIN: &str = "<!-- bench paper: begin -->";
const README_END: &str = "<!-- bench paper: end -->";

/// Replaces the README's generated block with this run's Table I and picture.
fn write_readme_block(readme: &Path, report: &Report) -> anyhow::Result<()> {
    let old =
        std::fs::read_to_string(readme).with_context(|| format!("reading {}", readme.display()))?;
    let (Some(begin), Some(end)) = (old.find(README_BEGIN), old.find(README_END)) else {
        anyhow::bail!(
            "{}: no `{README_BEGIN}` … `{README_END}` block",
            readme.display()
        );
    };
    let picture = report
        .figure
        .as_ref()
        .map(|p| format!("\n![Fig. 5 style comparison]({p})\n"))
        .unwrap_or_default();
    let block = format!(
        "{README_BEGIN}\nGenerated by `lapclone-bench paper --readme {}` (release build).\n\n\
         ```text\n{}```\n{picture}{README_END}",
        readme.display(),
        table_text(report)
    );
    let text = format!("{}{block}{}", &old[..begin], &old[end + README_END.len()..]);
    write_atomic(readme, text.as_bytes()).with_context(|| format!("writing {}", readme.display()))
}

fn load_experiment(assets: &Path, name: &str) -> anyhow::Result<Experiment> {
    let model = paper_model(assets, name)
        .with_context(|| format!("loading model {name} from {}", assets.display()))?
        .with_context(|| format!("unknown model {name}"))?;
    let mask = GridMask::new(model.width, model.height, &model.inside)?;
    Ok(Experiment::new(mask, model.source, model.target)?)
}

fn method_json(figures: &MethodFigures) -> MethodJson {
    MethodJson {
        psnr_db: Some(figures.comparison.psnr_db),
        seam_step: Some(figures.comparison.seam_step.mean_abs),
        reference_seam_step: Some(figures.comparison.reference_seam_step.mean_abs),
        preprocess_ms: Some(figures.preprocess_ms),
        membrane_ms: Some(figures.membrane_ms),
        not_run: None,
    }
}

fn mvc_json(outcome: &MvcOutcome) -> MethodJson {
    match outcome.figures() {
        Some(f) => method_json(f),
        None => MethodJson {
            psnr_db: None,
            seam_step: None,
            reference_seam_step: None,
            preprocess_ms: None,
            membrane_ms: None,
            not_run: outcome.not_run_reason(),
        },
    }
}

fn model_json(name: &str, experiment: &Experiment, run: &MeshRun) -> ModelJson {
    let (reference_factor_ms, reference_solve_ms) = experiment.reference_ms();
    ModelJson {
        model: name.to_string(),
        width: experiment.width(),
        height: experiment.height(),
        inside_pixels: experiment.mask().inside_count(),
        vertices: run.mesh.vertex_count(),
        triangles: run.mesh.triangles.len(),
        boundary_vertices: run.mesh.boundary_vertices().count(),
        mesh_ms: run.mesh_ms,
        reference_factor_ms,
        reference_solve_ms,
        uncovered: run.uncovered,
        combinatorial: method_json(&run.combinatorial),
        cotangent: method_json(&run.cotangent),
        mvc: mvc_json(&run.mvc),
        rings: None,
    }
}

/// PSNR per ring band of both Laplacian membranes (kept in `run`).
fn rings_json(experiment: &Experiment, run: &MeshRun) -> anyhow::Result<Vec<RingJson>> {
    let by_ring = |membrane: &Option<Vec<f64>>| -> anyhow::Result<Vec<Option<f64>>> {
        let membrane = membrane.as_ref().context("membrane not kept")?;
        Ok(psnr_by_ring(
            membrane,
            experiment.reference(),
            crate::reference::experiment::CHANNELS,
            experiment.mask(),
            &RING_BANDS,
        )?)
    };
    let combinatorial = by_ring(&run.combinatorial.membrane)?;
    let cotangent = by_ring(&run.cotangent.membrane)?;
    Ok(RING_BANDS
        .iter()
        .enumerate()
        .map(|(i, &(first, last))| RingJson {
            first,
            last: (last != u32::MAX).then_some(last),
            combinatorial_db: combinatorial[i],
            cotangent_db: cotangent[i],
        })
        .collect())
}

fn rings_text(out: &mut String, report: &Report) {
    for m in &report.models {
        let Some(rings) = &m.rings else { continue };
        let _ = writeln!(
            out,
            "{}: PSNR (dB) by ring, combinatorial / cotangent",
            m.model
        );
        for r in rings {
            let band = match r.last {
                Some(last) if last == r.first => format!("{}", r.first),
                Some(last) => format!("{}-{last}", r.first),
                None => format!("{}+", r.first),
            };
            let _ = writeln!(
                out,
                "  ring {band:>5}  {:>6} / {:>6}",
                number(r.combinatorial_db, 2),
                number(r.cotangent_db, 2)
            );
        }
    }
}

fn number(value: Option<f64>, decimals: usize) -> String {
    match value {
        Some(v) => format!("{v:.decimals$}"),
        None => "n/a".into(),
    }
}

fn table_text(report: &Report) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Table I ({} boundary, density {} px, {} boundary data, best of {}; times in ms; PSNR \
         in dB against the pixel-grid reference)",
        report.boundary, report.density, report.boundary_data, report.repeats
    );
    let _ = writeln!(
        out,
        "{:<7} {:>9} {:>8} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8} {:>16} {:>8} {:>8} {:>9}",
        "model",
        "pixels",
        "vertices",
        "pre MVC",
        "pre ours",
        "mem MVC",
        "mem ours",
        "PSNR cmb",
        "PSNR cot",
        "PSNR MVC",
        "seam cmb",
        "seam ref",
        "uncovered"
    );
    for m in &report.models {
        let mvc = &m.mvc;
        let mvc_psnr = match &mvc.not_run {
            Some(reason) => reason.clone(),
            None => number(mvc.psnr_db, 2),
        };
        let _ = writeln!(
            out,
            "{:<7} {:>9} {:>8} {:>9} {:>9.2} {:>9} {:>9.3} {:>8.2} {:>8.2} {:>16} {:>8.4} {:>8.4} {:>9}",
            m.model,
            format!("{}x{}", m.width, m.height),
            m.vertices,
            number(mvc.preprocess_ms, 1),
            m.combinatorial.preprocess_ms.unwrap_or(f64::NAN),
            number(mvc.membrane_ms, 3),
            m.combinatorial.membrane_ms.unwrap_or(f64::NAN),
            m.combinatorial.psnr_db.unwrap_or(f64::NAN),
            m.cotangent.psnr_db.unwrap_or(f64::NAN),
            mvc_psnr,
            m.combinatorial.seam_step.unwrap_or(f64::NAN),
            m.combinatorial.reference_seam_step.unwrap_or(f64::NAN),
            m.uncovered,
        );
    }
    rings_text(&mut out, report);
    if let Some(path) = &report.figure {
        let _ = writeln!(out, "comparison picture: {path}");
    }
    if !report.sweep.is_empty() {
        out.push('\n');
        out.push_str(&sweep_markdown(&report.sweep));
    }
    out
}

/// Meshes the spiral at the Fig.-5 vertex counts and writes the picture.
fn write_figure(args: &PaperBenchArgs, run_options: &RunOptions) -> anyhow::Result<PathBuf> {
    let experiment = load_experiment(&args.assets, "spiral")?;
    let run_options = RunOptions {
        repeats: 1,
        keep_membranes: true,
        ..*run_options
    };
    let mut runs = Vec::new();
    for wanted in FIGURE_VERTICES {
        let options = density_for_vertices(&experiment, wanted)?;
        runs.push(experiment.run(&options, &run_options)?);
    }
    let picture = comparison_figure(&experiment, &runs, 2)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let path = args.out.join("fig5_spiral.png");
    // The figure is opaque, so its premultiplied pixels are its straight RGBA ones.
    let mut bytes = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut bytes),
        picture.data(),
        picture.width(),
        picture.height(),
        image::ExtendedColorType::Rgba8,
    )
    .context("encoding the picture")?;
    write_atomic(&path, &bytes).with_context(|| format!("writing {}", path.display()))?;
    if !args.json {
        for (wanted, run) in FIGURE_VERTICES.iter().zip(&runs) {
            let mvc = run
                .mvc
                .figures()
                .map(|f| format!("{:.2}", f.comparison.psnr_db))
                .unwrap_or_else(|| run.mvc.not_run_reason().unwrap_or_default());
            eprintln!(
                "fig5 ~{wanted} vertices: {} vertices, PSNR combinatorial {:.2} dB, cotangent \
                 {:.2} dB, MVC {mvc} dB",
                run.mesh.vertex_count(),
                run.combinatorial.comparison.psnr_db,
                run.cotangent.comparison.psnr_db,
            );
        }
    }
    Ok(path)
}

/// The mesh options whose vertex count on the experiment's mask comes closest to `wanted`:
/// a geometric bisection on the density, with the simplification tolerance following it
/// (coarse meshes need coarse boundaries).
fn density_for_vertices(experiment: &Experiment, wanted: usize) -> anyhow::Result<MeshOptions> {
    let options_for = |density: f64| MeshOptions {
        density,
        simplify_tolerance: (0.5 * density).clamp(0.9, 3.0),
        ..MeshOptions::default()
    };
    let count = |density: f64| -> anyhow::Result<usize> {
        let mask = experiment.mask();
        let bits = lapclone::mesh::BitMask::from_fn(mask.width(), mask.height(), |x, y| {
            mask.is_inside(y * mask.width() + x)
        });
        Ok(lapclone::mesh::mesh_mask(&bits, &options_for(density))?
            .mesh
            .vertex_count())
    };
    let (mut fine, mut coarse) = (0.5_f64, 200.0_f64);
    let mut best = (usize::MAX, fine);
    for _ in 0..14 {
        let middle = (fine * coarse).sqrt();
        let n = count(middle)?;
        if n.abs_diff(wanted) < best.0 {
            best = (n.abs_diff(wanted), middle);
        }
        if n > wanted {
            fine = middle;
        } else {
            coarse = middle;
        }
    }
    Ok(options_for(best.1))
}

fn run_sweep(args: &PaperBenchArgs, run_options: &RunOptions) -> anyhow::Result<Vec<SweepRow>> {
    let experiment = load_experiment(&args.assets, if args.quick { "mouth" } else { "spiral" })?;
    let run_options = RunOptions {
        mvc_max_weights: 0,
        ..*run_options
    };
    let mut rows = Vec::new();
    for options in sweep_configurations(args.quick) {
        let density = options.density;
        let run = experiment.run(&options, &run_options)?;
        let reclone = reclone_ms(
            experiment.source(),
            experiment.target(),
            run.mesh.clone(),
            LaplacianKind::Combinatorial,
            run_options.boundary_data,
            DVec2::new(0.6, 0.3),
            run_options.repeats.max(RECLONE_REPEATS),
        )?;
        if !args.json {
            eprintln!("swept {:?} density {density}", options.boundary);
        }
        rows.push(SweepRow {
            density,
            vertices: run.mesh.vertex_count(),
            mesh_ms: run.mesh_ms,
            psnr_combinatorial_db: run.combinatorial.comparison.psnr_db,
            psnr_cotangent_db: run.cotangent.comparison.psnr_db,
            uncovered: run.uncovered,
            reclone_ms: reclone,
            boundary: options.boundary,
            min_angle_deg: options.min_angle_deg,
            max_area: options.max_area,
            relax_sweeps: options.relax_sweeps,
        });
    }
    if !args.quick {
        let old = std::fs::read_to_string(&args.sweep_out).unwrap_or_default();
        let text = splice_generated(&old, &sweep_document(&experiment, &rows));
        if let Some(parent) = args.sweep_out.parent() {
            std::fs::create_dir_all(parent).ok();
        }
        write_atomic(&args.sweep_out, text.as_bytes())
            .with_context(|| format!("writing {}", args.sweep_out.display()))?;
    }
    Ok(rows)
}

/// The sweep's mesh options: each density alone, then the quality configurations (fewer of
/// both with `quick`).
fn sweep_configurations(quick: bool) -> impl Iterator<Item = MeshOptions> {
    let densities: &[f64] = if quick {
        &SWEEP_DENSITIES[..2]
    } else {
        &SWEEP_DENSITIES
    };
    let quality: &[SweepConfig] = if quick {
        &SWEEP_QUALITY[QUICK_QUALITY]
    } else {
        &SWEEP_QUALITY
    };
    densities
        .iter()
        .map(|&density| MeshOptions {
            density,
            ..MeshOptions::default()
        })
        .chain(quality.iter().map(
            |&(boundary, density, min_angle_deg, max_area, relax_sweeps)| MeshOptions {
                density,
                boundary,
                min_angle_deg,
                max_area,
                relax_sweeps,
                ..MeshOptions::default()
            },
        ))
}

fn sweep_markdown(rows: &[SweepRow]) -> String {
    let mut out = String::from(
        "| boundary | density (px) | min angle (°) | max area (px²) | relax | vertices \
         | mesh (ms) | PSNR combinatorial (dB) | PSNR cotangent (dB) | uncovered px \
         | re-clone (ms) |\n|:---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let boundary = match r.boundary {
            BoundaryPlacement::Cracks => "cracks",
            BoundaryPlacement::OutsideCentres => "outside centres",
        };
        let _ = writeln!(
            out,
            "| {boundary} | {} | {} | {} | {} | {} | {:.1} | {:.2} | {:.2} | {} | {:.2} |",
            r.density,
            r.min_angle_deg,
            r.max_area.map_or("–".into(), |a| a.to_string()),
            r.relax_sweeps,
            r.vertices,
            r.mesh_ms,
            r.psnr_combinatorial_db,
            r.psnr_cotangent_db,
            r.uncovered,
            r.reclone_ms
        );
    }
    out
}

const BEGIN: &str = "<!-- bench paper --sweep: begin -->";
const END: &str = "<!-- bench paper --sweep: end -->";

/// Replaces the text between the markers in `old` with `generated` (keeping the hand-written
/// rest of the document); a document without markers becomes just the generated part.
fn splice_generated(old: &str, generated: &str) -> String {
    let block = format!("{BEGIN}\n{generated}{END}\n");
    match (old.find(BEGIN), old.find(END)) {
        (Some(begin), Some(end)) if begin < end => {
            format!(
                "{}{block}{}",
                &old[..begin],
                old[end + END.len()..].trim_start_matches('\n')
            )
        }
        _ => format!("# Mesh density vs quality\n\n{block}"),
    }
}

fn sweep_document(experiment: &Experiment, rows: &[SweepRow]) -> String {
    format!(
        "Generated by `lapclone-bench paper --sweep` (release build); do not edit by hand.\n\n\
         Spiral model, {}×{} px, {} mask pixels, other mesh options at their defaults \
         (`outside centres`: boundary vertices exactly on the outside pixel centres; at \
         density 1 every one of them, coarser densities drop centres on straight runs). \
         PSNR of source + membrane against source + pixel-grid reference membrane over the \
         mask pixels (peak 1); uncovered = mask pixels whose centre is in no triangle; \
         re-clone = constraint switches + solve + raster via `PatchCloner` at a placement \
         nudged by (0.6, 0.3) px, best of {RECLONE_REPEATS} or more, combinatorial Laplacian; \
         boundary data hat-averaged unless `--boundary-data vertex`.\n\n{}",
        experiment.width(),
        experiment.height(),
        experiment.mask().inside_count(),
        sweep_markdown(rows)
    )
}
