//! `lapclone mesh`: mask → mesh, with an optional picture, JSON stats and Laplacian export.

use lapclone::util::ShowPath;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use lapclone::mesh::{self, BitMask, Mesh, MeshOptions};
use lapclone::raster::overlay::{draw_mesh_overlay, OverlayStyle};
use lapclone::util::number_text;

use super::mesh_args::MeshQualityArgs;
use super::UsageError;

#[derive(clap::Args, Debug)]
pub struct MeshArgs {
    /// Mask image (any format the `image` crate reads).
    pub mask: PathBuf,
    /// Maximum boundary edge length in pixels (seam quality knob).
    #[arg(long, value_parser = super::finite_f64, allow_hyphen_values = true)]
    pub density: Option<f64>,
    /// Boundary placement, minimum angle, maximum area, relaxation, or the seam-quality
    /// preset (the same flags as `clone`).
    #[command(flatten)]
    pub quality: MeshQualityArgs,
    /// Vertex budget.
    #[arg(long = "max-vertices", allow_hyphen_values = true)]
    pub max_vertices: Option<usize>,
    /// Inside threshold in [0, 1] (alpha if the image has alpha, else luminance).
    #[arg(long, value_parser = super::finite_f64, allow_hyphen_values = true)]
    pub threshold: Option<f64>,
    /// Draw the mesh over the mask into this PNG.
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Print one JSON object with mesh statistics on stdout.
    #[arg(long)]
    pub stats: bool,
    /// Write the combinatorial Laplacian (Matrix Market) and `<file>.boundary`.
    #[arg(long = "laplacian-out")]
    pub laplacian_out: Option<PathBuf>,
}

pub fn run(args: MeshArgs) -> anyhow::Result<()> {
    let options = options_from(&args)?;
    let threshold = args
        .threshold
        .unwrap_or(f64::from(lapclone::mesh::MASK_THRESHOLD));
    if !(0.0..=1.0).contains(&threshold) {
        return Err(UsageError(format!(
            "--threshold must be in [0, 1], got {}",
            number_text(threshold)
        ))
        .into());
    }
    let outputs = output_files(&args);
    check_outputs(&outputs, &args.mask, args.laplacian_out.as_deref())?;
    let mask = BitMask::load(&args.mask, threshold as f32)?;
    let started = Instant::now();
    let mut result =
        mesh::mesh_mask(&mask, &options).with_context(|| format!("mask {}", args.mask.shown()))?;
    // The raw mask mesh (boundary on the pixel cracks unless `--boundary outside-centres`);
    // relaxation is the only finishing step that belongs to the mesh itself.
    if options.relax_sweeps > 0 {
        mesh::relax_interior(
            &mut result.mesh,
            options.relax_sweeps,
            options.min_angle_deg,
        );
        result.stats.min_angle_deg = mesh::min_angle_deg(&result.mesh);
    }
    let mesh_ms = started.elapsed().as_secs_f64() * 1e3;
    for warning in &result.warnings {
        eprint_line!("lapclone: warning: {warning}");
    }
    let mut contents = Vec::new();
    if args.output.is_some() {
        contents.push(picture(&result.mesh, &mask)?);
    }
    if args.laplacian_out.is_some() {
        contents.extend(laplacian(&result.mesh));
    }
    write_all(&outputs, &contents)?;
    let stats = &result.stats;
    if args.stats {
        let json = serde_json::json!({
            "vertices": stats.vertices,
            "triangles": stats.triangles,
            "boundary_vertices": stats.boundary_vertices,
            "pieces": stats.pieces,
            "holes": stats.holes,
            "min_angle_deg": stats.min_angle_deg,
            "uncovered_mask_pixels": mesh::uncovered_mask_pixels(&result.mesh, &mask),
            "max_boundary_deviation_px": stats.max_boundary_deviation_px,
            "boundary": stats.boundary.name(),
            "mesh_ms": mesh_ms,
        });
        super::say(json)?;
    } else {
        super::say(format_args!(
            "{} vertices, {} triangles, {} boundary vertices ({}), {} piece(s), {} hole(s), min angle {:.1}°, {:.2} ms",
            stats.vertices, stats.triangles, stats.boundary_vertices, stats.boundary.name(), stats.pieces, stats.holes, stats.min_angle_deg, mesh_ms
        ))?;
    }
    Ok(())
}

fn options_from(args: &MeshArgs) -> anyhow::Result<MeshOptions> {
    let mut options = args.quality.options(args.density)?;
    if let Some(max) = args.max_vertices {
        options.max_vertices = max;
        options.validate().map_err(|e| UsageError(e.to_string()))?;
    }
    Ok(options)
}

/// The files `mesh` writes, in order: the picture, the Laplacian and its `.boundary` list.
fn output_files(args: &MeshArgs) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = args.output.iter().cloned().collect();
    if let Some(path) = &args.laplacian_out {
        let mut boundary = path.as_os_str().to_os_string();
        boundary.push(".boundary");
        files.extend([path.clone(), PathBuf::from(boundary)]);
    }
    files
}

/// Refuses an output that is the mask, two outputs naming one file, `-` (mesh writes
/// files, not standard output), and a `--laplacian-out` that is not a regular file where one
/// exists (its `.boundary` list would be a new file beside a device or FIFO) — usage
/// errors, before anything is meshed.
fn check_outputs(outputs: &[PathBuf], mask: &Path, laplacian: Option<&Path>) -> anyhow::Result<()> {
    if let Some(path) = laplacian.filter(|p| p.exists()) {
        if let Some(kind) = lapclone::util::not_a_file(path) {
            let named = path.shown();
            return Err(UsageError(format!(
                "--laplacian-out {named} {kind}: it names two files, {named} and {named}.boundary"
            ))
            .into());
        }
    }
    for (index, output) in outputs.iter().enumerate() {
        if output.as_os_str() == "-" {
            return Err(UsageError(
                "mesh writes files: `-` (standard output) is not one of its outputs".into(),
            )
            .into());
        }
        lapclone::output::refuse_input(output, &[mask])?;
        if outputs[..index]
            .iter()
            .any(|o| lapclone::util::same_destination(o, output))
        {
            let named = output.shown();
            return Err(UsageError(format!("two outputs name the same file: {named}")).into());
        }
    }
    Ok(())
}

/// Writes every output to a temporary file first and renames them only once all are
/// written, so a failure leaves none of them.
fn write_all(outputs: &[PathBuf], contents: &[Vec<u8>]) -> anyhow::Result<()> {
    let mut staged = Vec::with_capacity(outputs.len());
    for (path, bytes) in outputs.iter().zip(contents) {
        let fill = |file: &mut std::fs::File| std::io::Write::write_all(file, bytes);
        let temp = lapclone::util::write_staged(path, fill)
            .with_context(|| format!("cannot write {}", path.shown()))?;
        staged.push((temp, path));
    }
    for (temp, path) in staged {
        temp.commit()
            .with_context(|| format!("cannot write {}", path.shown()))?;
    }
    Ok(())
}

/// The combinatorial Laplacian (Matrix Market) and the boundary vertices (0-based, one a
/// line).
fn laplacian(mesh: &Mesh) -> [Vec<u8>; 2] {
    let l = lapclone::solve::laplacian(mesh, lapclone::solve::LaplacianKind::Combinatorial);
    let comment = "combinatorial Laplacian of a lapclone mesh";
    let list: String = mesh.boundary_vertices().map(|v| format!("{v}\n")).collect();
    [
        lapclone::solve::matrix_market_text(&l, comment).into_bytes(),
        list.into_bytes(),
    ]
}

/// The mesh over the mask (light grey inside, dark grey outside), upscaled for viewing: PNG
/// bytes.
fn picture(mesh: &Mesh, mask: &BitMask) -> anyhow::Result<Vec<u8>> {
    let background = image::RgbaImage::from_fn(mask.width as u32, mask.height as u32, |x, y| {
        let v = if mask.get(x as i64, y as i64) {
            215
        } else {
            60
        };
        image::Rgba([v, v, v, 255])
    });
    let style = OverlayStyle {
        scale: OverlayStyle::auto_scale(background.width(), background.height()),
        ..OverlayStyle::default()
    };
    let picture = draw_mesh_overlay(
        &background,
        &mesh.positions,
        &mesh.triangles,
        &mesh.loops,
        &[],
        &style,
    )?;
    Ok(lapclone::golden::encode_rgba_png(&picture))
}
