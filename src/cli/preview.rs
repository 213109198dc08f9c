//! `lapclone preview`: takes a scene file and a time or frame number and writes that one
//! frame as a PNG.

use std::path::PathBuf;

use anyhow::Context;

use super::scene_open::{default_jobs, load_renderer, positioned};
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
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

pub fn run_preview(args: PreviewArgs) -> anyhow::Result<()> {
    if args.t.is_some_and(|t| t < 0.0) || args.frame == Some(0) {
        return Err(UsageError("--t must be ≥ 0 and --frame ≥ 1".into()).into());
    }
    lapclone::output::check_output_folder(&args.output)?;
    let (loaded, imports, mut renderer) = load_renderer(&args.scene)?;
    lapclone::output::refuse_scene_input(&args.output, &loaded, &imports)?;
    let format = renderer.output_format();
    let canvas = match (args.t, args.frame) {
        (Some(t), _) => renderer.render_time(t),
        (None, Some(frame)) => renderer.render_frame(frame - 1),
        (None, None) => renderer.render_frame(0),
    }
    .map_err(|e| positioned(&loaded, e))?;
    canvas
        .save_png_threaded(&args.output, format, default_jobs())
        .with_context(|| format!("writing {}", args.output.display()))?;
    Ok(())
}
