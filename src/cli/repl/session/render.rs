//! `:render` and `:gif`: takes a format, an output path and a frame range and writes the
//! live scene's frames through the library's output stage, with a fresh renderer, so the
//! files are byte-identical to `lapclone render` of the `:save`d scene.

use lapclone::util::ShowPath;
use std::path::Path;
use std::time::Instant;

use lapclone::output::{refuse_render_input, render_frames, OutputError, SinkPlan};
use lapclone::render::Renderer;

use super::eval::render_error;
use super::Session;
use crate::cli::render::{default_jobs, FrameRange, OutputFormat};
use crate::cli::scene_open::NotesOnly;

impl Session {
    /// Renders frames with a fresh renderer, so the files are byte-identical to
    /// `lapclone render` of the `:save`d scene.
    pub(super) fn render_to(
        &mut self,
        format: OutputFormat,
        output: &Path,
        range: Option<FrameRange>,
    ) -> anyhow::Result<()> {
        let scene = self.current_scene()?;
        if let Some(loaded) = &self.installed {
            let imports = self.engine.module_files().files();
            refuse_render_input(format, output, loaded, &imports)?;
        }
        self.refuse_input(output, false)?;
        let started = Instant::now();
        let plan = SinkPlan::new(format, output, Default::default())?;
        let mut renderer = Renderer::new(scene).map_err(|e| anyhow::anyhow!("{e}"))?;
        let total = renderer.frame_count();
        let range = range.unwrap_or(FrameRange::all(total));
        if range.last > total {
            anyhow::bail!(
                "frames {}..{}: the scene has {total} frames",
                range.first,
                range.last
            );
        }
        let sink = plan.open(&renderer, range, default_jobs(), self.cancel.clone())?;
        let rendered = render_frames(&mut renderer, sink, range, &self.cancel, &mut NotesOnly)
            .map_err(|error| match error {
                OutputError::Interrupted { after } => {
                    anyhow::anyhow!("render cancelled after frame {after}")
                }
                OutputError::InterruptedFinishing => {
                    anyhow::anyhow!("render cancelled while writing the last frames")
                }
                OutputError::Render(error) => render_error(error),
                other => other.into(),
            })?;
        crate::cli::print_line(format_args!(
            "rendered {} frames to {} in {:.2} s",
            rendered.frames,
            rendered.path.shown(),
            started.elapsed().as_secs_f64()
        ));
        Ok(())
    }
}
