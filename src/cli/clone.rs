//! `lapclone clone`: one seamless clone of a source patch into a target image, optionally
//! deformed by drags and pins, with JSON timings and a mesh overlay on request.

use lapclone::util::ShowPath;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use glam::DVec2;
use lapclone::clone::{
    mesh_from_mask, Anchor, BoundaryData, CloneMode, CloneOptions, CloneStats, PatchCloner,
    PatchMesh, Placement,
};
use lapclone::deform::{DeformRig, Deformed, Handle, Pin};
use lapclone::mesh::{BitMask, MeshOptions};
use lapclone::pixels::{Canvas, FloatImage, PixelFormat};
use lapclone::raster::overlay::{draw_mesh_overlay, HandleMarker, OverlayStyle};
use lapclone::solve::LaplacianKind;
use lapclone::util::number_text;

use super::picture_out::PictureOut;
use super::{finite_f64, point, UsageError};

#[derive(clap::Args, Debug)]
pub struct CloneArgs {
    /// Source image the patch is taken from.
    #[arg(long)]
    pub source: PathBuf,
    /// Mask selecting the patch (white/opaque = inside), the source's size unless offset.
    #[arg(long)]
    pub mask: PathBuf,
    /// Where the mask's pixel (0,0) lies in the source, when the sizes differ.
    #[arg(long = "mask-offset", value_parser = point, allow_hyphen_values = true)]
    pub mask_offset: Option<[f64; 2]>,
    /// Target image the patch is cloned into.
    #[arg(long)]
    pub target: PathBuf,
    /// Target position of the anchor (by default the centre of the mask's bounding box).
    #[arg(long, value_parser = point, allow_hyphen_values = true)]
    pub at: [f64; 2],
    /// Uniform scale of the patch.
    #[arg(long, default_value_t = 1.0, value_parser = finite_f64, allow_hyphen_values = true)]
    pub scale: f64,
    /// Rotation in degrees (positive turns x towards y: clockwise on screen).
    #[arg(long, default_value_t = 0.0, value_parser = finite_f64, allow_hyphen_values = true)]
    pub rotate: f64,
    /// Which point of the mask's bounding box `--at` refers to.
    #[arg(long, value_enum, default_value_t = AnchorArg::Centre)]
    pub anchor: AnchorArg,
    /// Maximum boundary edge length in pixels.
    #[arg(long, value_parser = finite_f64, allow_hyphen_values = true)]
    pub density: Option<f64>,
    #[command(flatten)]
    pub mesh: super::mesh_args::MeshQualityArgs,
    /// Inside threshold of the mask in [0, 1].
    #[arg(long, default_value_t = f64::from(lapclone::mesh::MASK_THRESHOLD), value_parser = finite_f64, allow_hyphen_values = true)]
    pub threshold: f64,
    #[arg(long, value_enum, default_value_t = LaplacianArg::Combinatorial)]
    pub laplacian: LaplacianArg,
    #[arg(long, value_enum, default_value_t = ModeArg::Normal)]
    pub mode: ModeArg,
    /// The membrane's boundary values: `hat-average` (target − source averaged along each
    /// boundary vertex's edges) or `vertex` (sampled at the vertex, as in the paper).
    #[arg(long, default_value = "hat-average")]
    pub boundary_data: BoundaryData,
    /// Soften the patch's outer edge over this many pixels.
    #[arg(long, default_value_t = 0.0, value_parser = finite_f64, allow_hyphen_values = true)]
    pub feather: f64,
    /// Drag X0,Y0:X1,Y1[:R] in the source's frame (repeatable); R defaults to a quarter of
    /// the mask's larger bounding-box side.
    #[arg(long, value_parser = parse_drag, allow_hyphen_values = true)]
    pub drag: Vec<DragArg>,
    /// Hold the point X,Y of the source's frame still (repeatable).
    #[arg(long, value_parser = point, allow_hyphen_values = true)]
    pub pin: Vec<[f64; 2]>,
    /// Draw the (deformed) mesh and the handles over the result (8-bit RGBA output).
    #[arg(long = "show-mesh")]
    pub show_mesh: bool,
    /// Print one JSON object with sizes and timings on stdout.
    #[arg(long)]
    pub stats: bool,
    /// Output PNG (written in the target's bit depth and colour type); `-` writes it to
    /// standard output.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum AnchorArg {
    #[value(alias = "center")]
    Centre,
    #[value(alias = "top-left")]
    Topleft,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum LaplacianArg {
    Combinatorial,
    Cotangent,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum ModeArg {
    Normal,
    Monochrome,
}

#[derive(Clone, Copy, Debug)]
pub struct DragArg {
    pub from: DVec2,
    pub to: DVec2,
    pub radius: Option<f64>,
}

fn parse_drag(text: &str) -> Result<DragArg, String> {
    let parts: Vec<&str> = text.split(':').collect();
    if !(2..=3).contains(&parts.len()) {
        return Err(format!("`{text}` is not a drag X0,Y0:X1,Y1[:R]"));
    }
    let radius = match parts.get(2) {
        Some(r) => {
            let r = finite_f64(r)?;
            if r <= 0.0 {
                return Err(format!(
                    "drag radius must be positive, not {}",
                    number_text(r)
                ));
            }
            Some(r)
        }
        None => None,
    };
    Ok(DragArg {
        from: DVec2::from(point(parts[0])?),
        to: DVec2::from(point(parts[1])?),
        radius,
    })
}

pub fn run(args: CloneArgs) -> anyhow::Result<()> {
    let out = check_arguments(&args)?;
    let mesh_options = args.mesh.options(args.density)?;
    let load_started = Instant::now();
    // The source and the mask (then the mesh and the factor) load on two threads while the
    // target decodes here, straight to the canvas.
    let (prepared, target) = std::thread::scope(|scope| {
        let source = scope.spawn(|| FloatImage::load(&args.source));
        let prepared = scope.spawn(|| prepare(&args, &mesh_options, source));
        let target = load_target(&args.target);
        (join(prepared), target)
    });
    // Errors in the order source, target, mask and the rest.
    let prepared = match prepared {
        Err(PrepareError::Source(error)) => return Err(error.into()),
        Err(PrepareError::Other(error)) => Err(error),
        Ok(prepared) => Ok(prepared),
    };
    let (mut canvas, target_format) = target?;
    let Prepared {
        mut cloner,
        mut deformation,
        placement,
        handles,
        mesh_ms,
        factor_ms,
    } = prepared?;
    // Kept only to time a re-clone for --stats.
    let background = args.stats.then(|| canvas.clone());
    let load_ms = millis_since(load_started);

    let stats = clone_once(&mut cloner, &mut canvas, &placement, deformation.as_mut())?;
    let total_ms = mesh_ms + factor_ms + stats.solve_ms + stats.raster_ms;
    report_clone_warnings(&stats);

    let picture = Picture {
        canvas: &canvas,
        format: target_format,
        cloner: &cloner,
        handles: &handles,
        placement: &placement,
    };
    write_output(&args, &out, picture)?;
    if let Some(background) = &background {
        let reclone_ms = time_reclone(&mut cloner, background, &placement, deformation.as_mut())?;
        let json = serde_json::json!({
            "vertices": cloner.mesh().vertex_count(),
            "boundary_vertices": cloner.membrane().boundary_vertices().len(),
            "constrained": stats.membrane.constrained,
            "outside": stats.membrane.outside,
            "hidden": stats.membrane.hidden,
            "glued_vertices": stats.membrane.glued,
            "glue_iterations": stats.membrane.glue_iterations,
            "switched": stats.membrane.switches.updates + stats.membrane.switches.downdates,
            "mesh_ms": mesh_ms,
            "factor_ms": factor_ms,
            "solve_ms": stats.solve_ms,
            "raster_ms": stats.raster_ms,
            "total_ms": total_ms,
            "reclone_ms": reclone_ms,
            "load_ms": load_ms,
        });
        super::say(json)?;
    }
    Ok(())
}

/// The patch ready to clone: its cloner (mesh factored, source sampled), deformation and
/// placement, with the meshing and factoring times.
struct Prepared {
    cloner: PatchCloner,
    deformation: Option<Deformed>,
    placement: Placement,
    handles: Vec<Handle>,
    mesh_ms: f64,
    factor_ms: f64,
}

/// Why [`prepare`] failed: the source's error is told before the target's, the rest after.
enum PrepareError {
    Source(lapclone::pixels::PixelError),
    Other(anyhow::Error),
}

/// Loads the mask and meshes it (the source's size read from its header, so meshing
/// overlaps the source's decoding), then waits for the source and builds the cloner.
fn prepare(
    args: &CloneArgs,
    mesh_options: &MeshOptions,
    source: std::thread::ScopedJoinHandle<'_, Result<FloatImage, lapclone::pixels::PixelError>>,
) -> Result<Prepared, PrepareError> {
    let header_size = lapclone::limits::image_dimensions(&args.source).ok();
    let mut mesh_ms = 0.0;
    let meshed = BitMask::load(&args.mask, args.threshold as f32)
        .map_err(anyhow::Error::from)
        .map(|mask| {
            let started = Instant::now();
            let patch = mesh_patch(args, &mask, header_size.unwrap_or_default(), mesh_options);
            mesh_ms = millis_since(started);
            (patch, mask)
        });
    let source = join(source).map_err(PrepareError::Source)?;
    let (mut patch, mask) = meshed.map_err(PrepareError::Other)?;
    let size = (source.width(), source.height());
    if header_size != Some(size) {
        // Only if the header disagrees with the decoder: mesh again with the decoded size.
        let started = Instant::now();
        patch = mesh_patch(args, &mask, size, mesh_options);
        mesh_ms += millis_since(started);
    }
    build_cloner(args, source, patch.map_err(PrepareError::Other)?, mesh_ms)
        .map_err(PrepareError::Other)
}

fn mesh_patch(
    args: &CloneArgs,
    mask: &BitMask,
    source_size: (u32, u32),
    options: &MeshOptions,
) -> anyhow::Result<PatchMesh> {
    mesh_from_mask(
        mask,
        args.mask_offset.map(DVec2::from),
        source_size,
        options,
    )
    .with_context(|| format!("mask {}", args.mask.shown()))
}

/// The cloner on the patch's mesh (the factor), and the deformation of the drags and pins.
fn build_cloner(
    args: &CloneArgs,
    source: FloatImage,
    patch: PatchMesh,
    mesh_ms: f64,
) -> anyhow::Result<Prepared> {
    for warning in &patch.result.warnings {
        eprint_line!("lapclone: warning: {warning}");
    }
    let anchor = match args.anchor {
        AnchorArg::Centre => Anchor::Centre,
        AnchorArg::Topleft => Anchor::TopLeft,
    };
    let placement = Placement {
        pivot: anchor.point(patch.bbox_min, patch.bbox_max),
        at: DVec2::from(args.at),
        scale: args.scale,
        rotation_deg: args.rotate,
    };
    let handles = handles_from(&args.drag, patch.default_drag_radius());
    let pins: Vec<Pin> = args.pin.iter().map(|&p| Pin(DVec2::from(p))).collect();

    let factor_started = Instant::now();
    let options = CloneOptions {
        laplacian: laplacian_kind(args.laplacian),
        mode: match args.mode {
            ModeArg::Normal => CloneMode::Normal,
            ModeArg::Monochrome => CloneMode::Monochrome,
        },
        feather: args.feather as f32,
        boundary_data: args.boundary_data,
    };
    let mut cloner = PatchCloner::new(source, patch.result.mesh, &options)?;
    // One clone, nothing to overlap it with: shade on every core.
    cloner.set_raster_threads(lapclone::util::available_cores());
    let deformation = if handles.is_empty() && pins.is_empty() {
        None
    } else {
        let mut rig = DeformRig::new(cloner.mesh(), options.laplacian)?;
        let mut deformed = Deformed::default();
        rig.deform(&handles, &pins, &mut deformed)?;
        Some(deformed)
    };
    Ok(Prepared {
        cloner,
        deformation,
        placement,
        handles,
        mesh_ms,
        factor_ms: millis_since(factor_started),
    })
}

/// A scoped thread's result; a panic on it continues on this thread.
fn join<T>(handle: std::thread::ScopedJoinHandle<'_, T>) -> T {
    handle
        .join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

fn check_arguments(args: &CloneArgs) -> anyhow::Result<PictureOut> {
    if let Some(error) = lapclone::limits::scale_error(args.scale) {
        return Err(UsageError(format!("--scale: {error}")).into());
    }
    if !(0.0..=1.0).contains(&args.threshold) {
        return Err(UsageError(format!(
            "--threshold must lie in [0, 1], not {}",
            number_text(args.threshold)
        ))
        .into());
    }
    if !lapclone::limits::feather_in_range(args.feather) {
        return Err(UsageError(format!(
            "--feather must lie in [0, {}], not {:?}",
            lapclone::limits::MAX_FEATHER,
            args.feather
        ))
        .into());
    }
    if let Some(density) = args.density {
        if density <= 0.0 {
            return Err(UsageError("--density must be positive".into()).into());
        }
        let options = MeshOptions {
            density,
            ..MeshOptions::default()
        };
        options
            .validate()
            .map_err(|e| UsageError(format!("--density: {e}")))?;
    }
    if args.stats && args.output.as_os_str() == "-" {
        return Err(UsageError(
            "--stats prints on standard output, which -o - already holds the picture on".into(),
        )
        .into());
    }
    PictureOut::check(
        "clone",
        &args.output,
        &[&args.source, &args.mask, &args.target],
    )
}

fn laplacian_kind(arg: LaplacianArg) -> LaplacianKind {
    match arg {
        LaplacianArg::Combinatorial => LaplacianKind::Combinatorial,
        LaplacianArg::Cotangent => LaplacianKind::Cotangent,
    }
}

fn handles_from(drags: &[DragArg], default_radius: f64) -> Vec<Handle> {
    drags
        .iter()
        .map(|d| Handle::drag(d.from, d.to, d.radius.unwrap_or(default_radius)))
        .collect()
}

fn clone_once(
    cloner: &mut PatchCloner,
    canvas: &mut Canvas,
    placement: &Placement,
    deformed: Option<&mut Deformed>,
) -> anyhow::Result<CloneStats> {
    Ok(match deformed {
        None => cloner.clone_onto(canvas, placement)?,
        Some(d) => cloner.clone_deformed(canvas, placement, &d.positions, Some(&d.depth))?,
    })
}

/// One more clone after moving the patch by a few pixels: mesh and factor reused.
fn time_reclone(
    cloner: &mut PatchCloner,
    background: &Canvas,
    placement: &Placement,
    deformed: Option<&mut Deformed>,
) -> anyhow::Result<f64> {
    let mut scratch = background.clone();
    let moved = Placement {
        at: placement.at + DVec2::new(3.0, 2.0),
        ..*placement
    };
    let started = Instant::now();
    clone_once(cloner, &mut scratch, &moved, deformed)?;
    Ok(millis_since(started))
}

fn report_clone_warnings(stats: &CloneStats) {
    if stats.membrane.constrained == 0 && stats.raster.written == 0 {
        eprint_line!("lapclone: warning: the patch lies entirely outside the target; the output is the target");
    } else if stats.membrane.constrained == 0 {
        eprint_line!("lapclone: warning: no boundary vertex lies inside the target; the patch is pasted without blending");
    }
}

/// What `--output` shows: the cloned canvas, or with `--show-mesh` the mesh over it.
struct Picture<'a> {
    canvas: &'a Canvas,
    format: PixelFormat,
    cloner: &'a PatchCloner,
    handles: &'a [Handle],
    placement: &'a Placement,
}

fn write_output(args: &CloneArgs, out: &PictureOut, picture: Picture) -> anyhow::Result<()> {
    let Picture {
        canvas,
        format,
        cloner,
        handles,
        placement,
    } = picture;
    if !args.show_mesh {
        return out.write_canvas(canvas, format, lapclone::util::available_cores());
    }
    let map = placement.to_affine();
    let markers: Vec<HandleMarker> = handles
        .iter()
        .map(|h| HandleMarker {
            at: map.transform_point2(h.from),
            target: Some(map.transform_point2(h.to)),
        })
        .collect();
    let background = canvas.to_rgba8_image();
    let style = OverlayStyle {
        scale: 1.0,
        ..OverlayStyle::default()
    };
    let mesh = cloner.mesh();
    let picture = draw_mesh_overlay(
        &background,
        cloner.placed(),
        &mesh.triangles,
        &mesh.loops,
        &markers,
        &style,
    )?;
    out.write_bytes(&lapclone::golden::encode_rgba_png(&picture))
}

/// The target as the canvas to clone onto (8-bit images without a float copy; 8-bit PNGs
/// decoded row by row straight into it), and the format the output is written in.
fn load_target(path: &Path) -> anyhow::Result<(Canvas, PixelFormat)> {
    use lapclone::pixels::{decode_png_levels, open_error};
    if let Some(png) = decode_png_levels(path).map_err(|error| open_error(path, error))? {
        return Ok((
            Canvas::from_rgba8(png.width, png.height, png.levels)?,
            png.format,
        ));
    }
    let decoded = FloatImage::decode(path)?;
    let format = PixelFormat::of(&decoded);
    Ok((Canvas::from_dynamic(&decoded)?, format))
}

fn millis_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
