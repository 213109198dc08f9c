//! `:save`: takes a path and writes the live scene there (see `repl/save.rs` for the two
//! forms the text takes).

use lapclone::util::ShowPath;
use std::path::Path;

use anyhow::Context as _;

use super::Session;
use crate::cli::repl::save::{saved_text, SaveForm};

impl Session {
    /// Writes the live scene (see `save.rs` for the two forms it takes).
    pub(super) fn save(&mut self, path: &Path) -> anyhow::Result<()> {
        let scene = self.current_scene()?;
        lapclone::output::check_output_folder(path)?;
        self.refuse_input(path, true)?;
        let (text, form) = saved_text(&scene, self.base_text.as_deref(), &self.edits, path);
        lapclone::util::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.shown()))?;
        if path.canonicalize().ok() == self.file {
            self.saved_revision = self.revision;
            self.file_text = Some(text);
        }
        match form {
            SaveForm::Script => self.say(format!("saved {}", path.shown())),
            SaveForm::Keys => self.say(format!(
                "saved {} (every key written out: the session's text does not rebuild this \
                 scene from that folder)",
                path.shown()
            )),
        }
        Ok(())
    }

    /// Refuses `output` when the live scene reads it or imports it, or when it is the loaded
    /// scene file, unless `scene_file_ok` (`:save` writes that file).
    pub fn refuse_input(&self, output: &Path, scene_file_ok: bool) -> anyhow::Result<()> {
        if let (Some(_), Some(loaded)) = (&self.renderer, &self.installed) {
            let imports = self.engine.module_files().files();
            lapclone::output::refuse_scene_reads(output, loaded, &imports)?;
        }
        let file = self.file.as_deref().filter(|_| !scene_file_ok);
        let own = self.session_inputs.iter().map(|p| p.as_path());
        let inputs: Vec<&Path> = file.into_iter().chain(own).collect();
        Ok(lapclone::output::refuse_input(output, &inputs)?)
    }

    /// Adds a file the session reads (its `--script`) to those no output may replace.
    pub fn protect(&mut self, input: &Path) {
        self.session_inputs.push(input.to_path_buf());
    }
}
