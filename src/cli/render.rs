//! `lapclone render`, `preview` and `check`: scene files to frames. `check` parses, evaluates
//! and validates a scene and prints positioned errors with a caret; `render` and `preview`
//! take their final flags here and are wired to the renderer by the pipeline integration.

use std::path::PathBuf;

use clap::ValueEnum;

use crate::cli::UsageError;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    Png,
    Gif,
    Apng,
}

/// An inclusive frame range `A..B` (frame numbers as in the file names, from 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub first: u64,
    pub last: u64,
}

pub fn frame_range(text: &str) -> Result<FrameRange, String> {
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| format!("`{text}` is not a frame range A..B"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<u64>()
            .map_err(|_| format!("`{s}` is not a frame number"))
    };
    let (first, last) = (parse(a)?, parse(b)?);
    if first == 0 || last < first {
        return Err(format!("frame range `{text}` must have 1 ≤ A ≤ B"));
    }
    Ok(FrameRange { first, last })
}

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (.rhai).
    pub scene: PathBuf,
    /// Output folder for frame_NNNN.png, or the output file for --format gif|apng.
    #[arg(short = 'o', long = "output", default_value = "frames")]
    pub output: PathBuf,
    /// Inclusive frame numbers to render, e.g. 1..24 (default: all).
    #[arg(long, value_parser = frame_range)]
    pub frames: Option<FrameRange>,
    #[arg(long, value_enum, default_value = "png")]
    pub format: OutputFormat,
    /// PNG encoder threads (default: available cores).
    #[arg(long)]
    pub jobs: Option<usize>,
}

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("when").args(["t", "frame"]).multiple(false)))]
pub struct PreviewArgs {
    pub scene: PathBuf,
    /// Time in seconds.
    #[arg(long = "t", value_parser = crate::cli::finite_f64)]
    pub t: Option<f64>,
    /// Frame number (from 1).
    #[arg(long)]
    pub frame: Option<u64>,
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Scene file (.rhai).
    pub scene: PathBuf,
}

pub fn run_render(args: RenderArgs) -> anyhow::Result<()> {
    if args.jobs == Some(0) {
        return Err(UsageError("--jobs must be at least 1".into()).into());
    }
    anyhow::bail!("`lapclone render` is not implemented yet")
}

pub fn run_preview(args: PreviewArgs) -> anyhow::Result<()> {
    if args.t.is_some_and(|t| t < 0.0) || args.frame == Some(0) {
        return Err(UsageError("--t must be ≥ 0 and --frame ≥ 1".into()).into());
    }
    anyhow::bail!("`lapclone preview` is not implemented yet")
}

pub fn run_check(args: CheckArgs) -> anyhow::Result<()> {
    let loaded = lapclone::script::load_scene(&args.scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    let summary = lapclone::script::validate_scene(&loaded).map_err(|e| anyhow::anyhow!("{e}"))?;
    let c = &loaded.scene.canvas;
    println!(
        "{}: ok — {}×{}, {} fps, {} s ({} frames), {} patches, {} handles, {} pins",
        args.scene.display(),
        c.width,
        c.height,
        c.fps,
        c.duration,
        summary.frames,
        summary.patches,
        summary.handles,
        summary.pins
    );
    Ok(())
}
