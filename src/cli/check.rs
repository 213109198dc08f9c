//! `lapclone check`: takes a scene file, parses, evaluates, validates and builds it, and
//! prints a one-line summary (or the positioned error with a caret) and its warnings.

use lapclone::util::ShowPath;
use std::path::PathBuf;

use super::scene_open::{load_renderer, print_warnings};

#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Scene file (.rhai).
    pub scene: PathBuf,
}

pub fn run_check(args: CheckArgs) -> anyhow::Result<()> {
    let (loaded, _, renderer) = load_renderer(&args.scene)?;
    let c = &loaded.scene.canvas;
    let handles: usize = loaded.scene.patches.iter().map(|p| p.handles.len()).sum();
    let pins: usize = loaded.scene.patches.iter().map(|p| p.pins.len()).sum();
    let vertices: usize = renderer.vertex_counts().iter().sum();
    super::say(format_args!(
        "{}: ok — {}×{}, {} fps, {} s ({} frames), {} patches ({vertices} mesh vertices), {handles} handles, {pins} pins",
        args.scene.shown(),
        c.width,
        c.height,
        c.fps,
        c.duration,
        c.frame_count(),
        loaded.scene.patches.len(),
    ))?;
    print_warnings(&loaded, &renderer);
    Ok(())
}
