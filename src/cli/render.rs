//! `lapclone render`: takes [`RenderArgs`] and writes the scene's frames through the
//! library's output stage (`lapclone::output`), with Ctrl-C, a progress bar and a summary
//! line. The arguments are in `render_args`, the scene loading in `scene_open`.

use lapclone::util::ShowPath;
use std::time::Instant;

use lapclone::output::{refuse_render_input, render_frames, OutputError, Rendered, SinkPlan};
use lapclone::script::LoadedScene;

pub use super::render_args::{frame_range, OutputFormat, RenderArgs};
pub(crate) use super::scene_open::{default_jobs, positioned, progress_bar};
use super::scene_open::{load_renderer, print_warnings, TerminalProgress};
pub use lapclone::FrameRange;

pub fn run_render(args: RenderArgs) -> anyhow::Result<()> {
    let jobs = super::jobs(args.jobs, default_jobs())?;
    // Before any output exists, so that Ctrl-C always goes through the clean-up below.
    let cancel = super::signals::cancel_flag();
    let kind = args.output_kind()?;
    for warning in args.unused_flags(kind) {
        eprint_line!("lapclone: warning: {warning}");
    }
    // Before the scene: a video's ffmpeg starts up while the scene loads.
    let plan = SinkPlan::new(kind, &args.output, args.sink_settings())?;
    let (loaded, imports, mut renderer) = load_renderer(&args.scene)?;
    print_warnings(&loaded, &renderer);
    refuse_render_input(kind, &args.output, &loaded, &imports)?;
    let range = args.range(renderer.frame_count())?;
    let started = Instant::now();
    let sink = plan.open(&renderer, range, jobs, cancel.clone())?;
    let mut progress = TerminalProgress(progress_bar(range.len()));
    let rendered = render_frames(&mut renderer, sink, range, &cancel, &mut progress)
        .map_err(|error| render_failure(&loaded, error))?;
    progress.0.finish_and_clear();
    let summary = summary(&rendered, started, renderer.factorisations());
    // Standard output may be the video stream itself.
    if args.output.as_os_str() == "-" {
        eprint_line!("{summary}");
    } else {
        super::say(summary)?;
    }
    Ok(())
}

/// A failed render's error: a renderer's positioned at its scene call.
fn render_failure(loaded: &LoadedScene, error: OutputError) -> anyhow::Error {
    match error {
        OutputError::Render(error) => positioned(loaded, error),
        other => other.into(),
    }
}

fn summary(rendered: &Rendered, started: Instant, factorisations: usize) -> String {
    let frames = rendered.frames;
    let seconds = started.elapsed().as_secs_f64();
    format!(
        "rendered {frames} frames to {} in {seconds:.2} s ({:.1} fps; {:.2} ms/frame compute; {factorisations} factorisation{})",
        rendered.path.shown(),
        frames as f64 / seconds,
        rendered.compute_ms / frames as f64,
        if factorisations == 1 { "" } else { "s" }
    )
}
