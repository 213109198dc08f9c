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
    /// About how many bytes `scope` holds ([`scope_bytes`]).
    bytes: usize,
}

/// Most entries `:undo` goes back.
pub(super) const MAX_UNDO: usize = 500;
/// Most bytes the kept scopes may hold together (estimated, see [`scope_bytes`]): each
/// snapshot copies every variable, so a session holding large arrays keeps fewer steps.
const MAX_UNDO_SCOPE_BYTES: usize = 512 << 20;

impl Session {
    /// Keeps `before` as the newest undo step, dropping the oldest past the bounds.
    pub(super) fn remember(&mut self, before: Snapshot) {
        self.undo.push(before);
        let mut bytes: usize = self.undo.iter().map(|s| s.bytes).sum();
        while self.undo.len() > MAX_UNDO || (bytes > MAX_UNDO_SCOPE_BYTES && self.undo.len() > 1) {
            bytes -= self.undo.remove(0).bytes;
        }
    }

    pub(super) fn snapshot(&self) -> Snapshot {
        Snapshot {
            draft: self.engine.draft(),
            scope: self.scope.clone(),
            edits: self.edits.len(),
            bytes: scope_bytes(&self.scope),
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

/// About how many bytes a scope's values hold: strings and blobs by length, arrays and maps
/// by their items, 16 bytes for anything else.
fn scope_bytes(scope: &Scope) -> usize {
    scope.iter_raw().map(|(_, _, v)| value_bytes(v)).sum()
}

fn value_bytes(value: &rhai::Dynamic) -> usize {
    if let Some(text) = value.read_lock::<rhai::ImmutableString>() {
        return 16 + text.len();
    }
    if let Some(array) = value.read_lock::<rhai::Array>() {
        return 16 + array.iter().map(value_bytes).sum::<usize>();
    }
    if let Some(map) = value.read_lock::<rhai::Map>() {
        return 16
            + map
                .iter()
                .map(|(k, v)| k.len() + value_bytes(v))
                .sum::<usize>();
    }
    if let Some(blob) = value.read_lock::<rhai::Blob>() {
        return 16 + blob.len();
    }
    16
}
