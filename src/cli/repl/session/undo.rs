//! The undo stack: takes the session's state before an entry (a [`Snapshot`]) and gives it
//! back on `:undo` or after a failed entry. Functions and imports are kept: they only add
//! names.

use std::path::Path;

use anyhow::Context as _;
use lapclone::script::Draft;
use rhai::Scope;

use super::eval::session_renderer;
use super::Session;

/// The state an `:undo` (or a failed entry) goes back to. Functions and imports are kept:
/// they only add names.
pub(super) struct Snapshot {
    pub(super) draft: Draft,
    pub(super) scope: Scope<'static>,
    /// How many entries `edits` had.
    pub(super) edits: usize,
}

impl Session {
    pub(super) fn snapshot(&self) -> Snapshot {
        Snapshot {
            draft: self.engine.draft(),
            scope: self.scope.clone(),
            edits: self.edits.len(),
        }
    }

    /// Puts scene and scope back; the renderer follows (its layers are still there).
    pub(super) fn restore(&mut self, snapshot: Snapshot) {
        self.engine.restore(snapshot.draft);
        self.scope = snapshot.scope;
        self.edits.truncate(snapshot.edits);
        if let (Some(renderer), Ok((scene, _))) = (
            self.renderer.as_mut(),
            self.engine.scene(Path::new("<undo>")),
        ) {
            if renderer.scene() != &scene && renderer.set_scene(scene).is_err() {
                self.renderer = None;
            }
        }
        self.refresh_words();
    }

    pub(super) fn undo(&mut self) -> anyhow::Result<()> {
        let snapshot = self.undo.pop().context("nothing to undo")?;
        self.restore(snapshot);
        self.revision += 1;
        self.say(format!("undone ({} more)", self.undo.len()));
        if self.engine.draft().canvas.is_none() {
            self.renderer = None;
            return Ok(());
        }
        if self.renderer.is_none() {
            let (scene, _) = self
                .engine
                .scene(Path::new("<undo>"))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            self.renderer = Some(session_renderer(scene).map_err(|e| anyhow::anyhow!("{e}"))?);
        }
        self.show_frame()
    }
}
