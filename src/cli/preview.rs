//! `lapclone preview`: takes a scene file and a time or frame number and writes that one
//! frame as a PNG (a file, or standard output for `-o -`).

use std::path::PathBuf;

use super::picture_out::PictureOut;
use super::scene_open::{default_jobs, load_renderer, positioned, print_warnings};
use crate::cli::UsageError;

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("when").args(["t", "frame"]).multiple(false)))]
pub struct PreviewArgs {
    pub scene: PathBuf,
    /// Time in seconds.
    #[arg(long = "t", value_parser = crate::cli::finite_f64, allow_hyphen_values = true)]
    pub t: Option<f64>,
    /// Frame number (from 1).
    #[arg(long, allow_hyphen_values = true)]
    pub frame: Option<u64>,
    /// Output PNG; `-` writes it to standard output.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

pub fn run_preview(args: PreviewArgs) -> anyhow::Result<()> {
    if args.t.is_some_and(|t| t < 0.0) || args.frame == Some(0) {
        return Err(UsageError("--t must be ≥ 0 and --frame ≥ 1".into()).into());
    }
    let out = PictureOut::check("preview", &args.output, &[])?;
    let (loaded, imports, mut renderer) = load_renderer(&args.scene)?;
    lapclone::output::refuse_scene_input(&args.output, &loaded, &imports)?;
    check_inside(&args, &renderer.scene().canvas)?;
    print_warnings(&loaded, &renderer);
    let format = renderer.output_format();
    let canvas = match (args.t, args.frame) {
        (Some(t), _) => renderer.render_time(t),
        (None, Some(frame)) => renderer.render_frame(frame - 1),
        (None, None) => renderer.render_frame(0),
    }
    .map_err(|e| positioned(&loaded, e))?;
    out.write_canvas(canvas, format, default_jobs())
}

/// A time past the scene's end or a frame past its last is a usage error, as `render
/// --frames` past the end is: the picture would be of no frame the scene renders.
fn check_inside(
    args: &PreviewArgs,
    canvas: &lapclone::animation::SceneCanvas,
) -> Result<(), UsageError> {
    let number = lapclone::util::number_text;
    let frames = canvas.frame_count();
    match (args.t, args.frame) {
        (Some(t), _) if canvas.is_past_end(t) => Err(UsageError(format!(
            "--t {}: the scene lasts {} s",
            number(t),
            number(canvas.duration)
        ))),
        (_, Some(frame)) if frame > frames => Err(UsageError(format!(
            "--frame {frame}: the scene has {frames} frames"
        ))),
        _ => Ok(()),
    }
}
