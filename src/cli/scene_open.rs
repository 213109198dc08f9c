//! Scene files opened for the commands that render them (`render`, `preview`, `check`,
//! `test`): takes a path and gives the loaded scene, its imported modules and a built
//! renderer, every error positioned at the scene call it is about, and their warnings; also the shared
//! pieces of a render's terminal side (cancel on Ctrl-C, the progress bar, default jobs).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use lapclone::render::{RenderError, Renderer};
use lapclone::script::{load_scene_and_imports, LoadedScene};
use lapclone::RenderProgress;

/// Parses, validates and builds the renderer (meshes and factors every patch); every error
/// comes back positioned at the scene call it is about.
pub(crate) fn load_renderer(scene: &Path) -> anyhow::Result<(LoadedScene, Vec<PathBuf>, Renderer)> {
    let (loaded, imports) = load_scene_and_imports(scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    let renderer = lapclone::build_renderer(&loaded).map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok((loaded, imports, renderer))
}

/// Prints what the scene warns about (old option names, a second `canvas`, keys past the
/// end), then what its renderer does, one `warning:` line each: what `check`, `render` and
/// `preview` say about a scene, so a user who only renders hears it too.
pub(crate) fn print_warnings(loaded: &LoadedScene, renderer: &Renderer) {
    for warning in loaded.warnings().into_iter().chain(renderer.warnings()) {
        eprint_line!("warning: {warning}");
    }
}

pub(crate) fn positioned(loaded: &LoadedScene, error: RenderError) -> anyhow::Error {
    anyhow::anyhow!("{}", lapclone::output::render_error_at_call(loaded, &error))
}

pub(crate) fn default_jobs() -> usize {
    lapclone::util::available_cores()
}

/// A frame counter on stderr when it is a terminal (hidden otherwise).
pub(crate) fn progress_bar(frames: u64) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(frames);
    if let Ok(style) =
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  eta {eta}")
    {
        bar.set_style(style);
    }
    bar
}

/// A render's progress on the terminal: notes on stderr, frames on the bar.
pub(crate) struct TerminalProgress(pub ProgressBar);

impl RenderProgress for TerminalProgress {
    fn note(&mut self, message: &str) {
        eprint_line!("note: {message}");
    }

    fn frame_done(&mut self, _number: u64) {
        self.0.inc(1);
    }
}

/// The REPL's renders: notes on stderr, no bar.
pub(crate) struct NotesOnly;

impl RenderProgress for NotesOnly {
    fn note(&mut self, message: &str) {
        eprint_line!("note: {message}");
    }
}
