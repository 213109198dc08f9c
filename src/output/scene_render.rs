//! A scene rendered to a path: takes a loaded scene, its renderer, an output path and
//! [`RenderOptions`] (format, frames, threads, settings, cancel flag), and gives the written
//! output ([`Rendered`]) or an [`OutputError`]. [`render_frames`] is the frame loop alone, for
//! callers that check and open the output themselves (the CLI starts ffmpeg before the
//! scene loads); progress goes to a [`RenderProgress`] the caller picks.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use super::inputs::refuse_render_input;
use super::request::{FrameRange, SinkSettings};
use super::sink::{FrameSink, SinkPlan};
use super::{OutputError, OutputKind};
use crate::render::{RenderError, Renderer};
use crate::script::{LoadedScene, SceneError};

/// What a render reports as it goes. Both methods do nothing by default; `()` is the
/// silent reporter.
pub trait RenderProgress {
    /// A note for the user about the output (e.g. a video padded to even sides).
    fn note(&mut self, _message: &str) {}
    /// Frame `number` (from 1) was rendered and handed to the writer.
    fn frame_done(&mut self, _number: u64) {}
}

impl RenderProgress for () {}

/// How [`render_scene`] writes.
#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// The format; `None` takes the one the path's extension names (no extension, or
    /// `.png`: a folder of `frame_NNNN.png`).
    pub format: Option<OutputKind>,
    /// The frames to write (default: all).
    pub frames: Option<FrameRange>,
    /// Encoder threads (PNG frames, video conversion); 0 means the available cores.
    pub jobs: usize,
    /// Force, PNG compression, video quality.
    pub settings: SinkSettings,
    /// Raised by another thread to stop the render; the output then does not appear.
    pub cancel: Option<Arc<AtomicBool>>,
}

/// What a finished render wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// The output (file, folder, or `-`).
    pub path: PathBuf,
    /// Frames written.
    pub frames: u64,
    /// Milliseconds the renderer spent computing them (not encoding).
    pub compute_ms: f64,
}

/// Renders `loaded`'s scene through `renderer` (built from it, e.g. by
/// [`open_scene`](crate::open_scene)) to `path`, as `lapclone render` does: the same files,
/// byte for byte. `imports` are the module files the scene imported; an output that is the
/// scene, an import or any file the scene reads is refused. The output appears whole or
/// not at all. A renderer's error comes back positioned ([`OutputError::Scene`]).
pub fn render_scene(
    loaded: &LoadedScene,
    imports: &[PathBuf],
    renderer: &mut Renderer,
    path: &Path,
    options: &RenderOptions,
    progress: &mut dyn RenderProgress,
) -> Result<Rendered, OutputError> {
    let kind = OutputKind::resolve(path, options.format)?;
    if kind.needs_ffmpeg() && crate::util::find_program("ffmpeg").is_none() {
        return Err(OutputError::NoFfmpeg);
    }
    refuse_render_input(kind, path, loaded, imports)?;
    let plan = SinkPlan::new(kind, path, options.settings)?;
    let total = renderer.frame_count();
    let range = options.frames.unwrap_or(FrameRange::all(total));
    range.check(total)?;
    let jobs = match options.jobs {
        0 => crate::util::available_cores(),
        jobs => jobs,
    };
    let cancel = options.cancel.clone().unwrap_or_default();
    let sink = plan.open(renderer, range, jobs, cancel.clone())?;
    render_frames(renderer, sink, range, &cancel, progress).map_err(|error| match error {
        OutputError::Render(e) => render_error_at_call(loaded, &e).into(),
        other => other,
    })
}

/// Renders the frames of `range` (which must lie in the scene, [`FrameRange::check`]) into
/// an opened sink and finishes it; a failure or a raised `cancel` abandons the sink, so
/// nothing appears. Renderer errors come back as
/// [`OutputError::Render`], a cancel as [`OutputError::Interrupted`] (also when a writer
/// refused because it saw the cancel) or [`OutputError::InterruptedFinishing`].
pub fn render_frames(
    renderer: &mut Renderer,
    mut sink: FrameSink,
    range: FrameRange,
    cancel: &AtomicBool,
    progress: &mut dyn RenderProgress,
) -> Result<Rendered, OutputError> {
    if let Err(error) = range.check(renderer.frame_count()) {
        sink.abandon();
        return Err(error);
    }
    if let Some(note) = sink.note() {
        progress.note(note);
    }
    let cancelled = || cancel.load(Ordering::Relaxed);
    let mut compute_ms = 0.0;
    for number in range.first..=range.last {
        let pushed = if cancelled() {
            Err(OutputError::Interrupted { after: number - 1 })
        } else {
            match renderer.render_frame(number - 1) {
                Err(error) => Err(OutputError::Render(error)),
                // The writers see the cancel too: report it, not their refusal.
                Ok(canvas) => sink.push(number, canvas).map_err(|error| match error {
                    _ if cancelled() => OutputError::Interrupted { after: number - 1 },
                    error => error,
                }),
            }
        };
        if let Err(error) = pushed {
            sink.abandon();
            return Err(error);
        }
        compute_ms += renderer.last_stats().total_ms;
        progress.frame_done(number);
    }
    // A cancel that came while the last frame rendered stops the render as one during
    // any other frame does, before the output is finished and named.
    if cancelled() {
        sink.abandon();
        return Err(OutputError::Interrupted { after: range.last });
    }
    let path = match sink.finish() {
        Err(_) if cancelled() => return Err(OutputError::InterruptedFinishing),
        result => result?,
    };
    Ok(Rendered {
        path,
        frames: range.len(),
        compute_ms,
    })
}

/// A renderer's error as a [`SceneError`] positioned at the scene call it is about: the
/// call that made its patch, or `canvas(...)` for the background's footage.
pub fn render_error_at_call(loaded: &LoadedScene, error: &RenderError) -> SceneError {
    if error.is_about_background() {
        return loaded.error_at_canvas(error.to_string());
    }
    loaded.error_at_patch(error.patch_name(), error.to_string())
}
