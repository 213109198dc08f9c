//! The scene being built by a running script: the canvas (once set), the patches, and where
//! in the source each was created (so later checks can point at the call that named a file),
//! and stable ids for the script's references to patches and handles.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};

use rhai::Position;

use crate::scene::{Canvas, Patch};

/// Where a scene object was created: the file (main scene or module) and the call position.
#[derive(Clone, Debug, PartialEq)]
pub struct Origin {
    pub file: PathBuf,
    pub position: Position,
}

/// Source positions of the calls that made the canvas and each patch (`patches[i]` for
/// `scene.patches[i]`).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Origins {
    pub canvas: Option<Origin>,
    pub patches: Vec<Origin>,
    /// `file:line:col: …` for each old spelling the script used, and each `canvas` call
    /// that replaced an earlier one.
    pub warnings: Vec<String>,
    /// Track files the script read (`follow`, `track_keys`): inputs of every render, also
    /// when a later call replaced the keys one of them gave.
    pub read: Vec<PathBuf>,
}

/// Stable identities of the draft's patches and handles, so a script's `Patch` and `Handle`
/// values keep naming the same object when others are removed or reordered.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Ids {
    /// `patches[i]` is the id of `Draft::patches[i]`.
    pub patches: Vec<u64>,
    /// `handles[i][j]` is the id of `Draft::patches[i].handles[j]`.
    pub handles: Vec<Vec<u64>>,
    next: u64,
}

impl Ids {
    fn fresh(&mut self) -> u64 {
        self.next += 1;
        self.next
    }
}

/// A scene under construction; `canvas` is `None` until `canvas(...)` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Draft {
    /// Relative paths in the script resolve against this folder (the scene file's).
    pub base_dir: PathBuf,
    pub canvas: Option<Canvas>,
    pub patches: Vec<Patch>,
    pub origins: Origins,
    pub ids: Ids,
    pub golden: Option<crate::golden::GoldenSettings>,
}

impl Draft {
    pub fn new(base_dir: &Path) -> Self {
        Draft {
            base_dir: base_dir.to_path_buf(),
            canvas: None,
            patches: Vec::new(),
            origins: Origins::default(),
            ids: Ids::default(),
            golden: None,
        }
    }

    /// Adds a patch (with handles already in it) last in scene order; gives its id.
    pub fn push_patch(&mut self, patch: Patch, origin: Origin) -> u64 {
        let id = self.ids.fresh();
        let handles = (0..patch.handles.len()).map(|_| self.ids.fresh()).collect();
        self.patches.push(patch);
        self.origins.patches.push(origin);
        self.ids.patches.push(id);
        self.ids.handles.push(handles);
        id
    }

    /// The scene-order index of the patch with this id.
    pub fn patch_index(&self, id: u64) -> Option<usize> {
        self.ids.patches.iter().position(|&p| p == id)
    }

    /// The index of a patch's handle with this id.
    pub fn handle_index(&self, patch: usize, id: u64) -> Option<usize> {
        self.ids.handles.get(patch)?.iter().position(|&h| h == id)
    }

    /// A new id for a handle just pushed onto `patches[patch].handles`.
    pub fn register_handle(&mut self, patch: usize) -> u64 {
        let id = self.ids.fresh();
        self.ids.handles[patch].push(id);
        id
    }

    /// Removes the patch at `index` with its origin and ids.
    pub fn remove_patch(&mut self, index: usize) -> Patch {
        self.origins.patches.remove(index);
        self.ids.patches.remove(index);
        self.ids.handles.remove(index);
        self.patches.remove(index)
    }

    /// Moves the patch at `from` to scene-order position `to` (after removing it).
    pub fn move_patch(&mut self, from: usize, to: usize) {
        let origin = self.origins.patches.remove(from);
        let id = self.ids.patches.remove(from);
        let handles = self.ids.handles.remove(from);
        let patch = self.patches.remove(from);
        self.origins.patches.insert(to, origin);
        self.ids.patches.insert(to, id);
        self.ids.handles.insert(to, handles);
        self.patches.insert(to, patch);
    }

    /// `no patch "dog"; patches: cat, horse` (or `there are no patches`).
    pub fn no_patch_message(&self, name: &str) -> String {
        if self.patches.is_empty() {
            return format!("no patch {name:?}; there are no patches");
        }
        let names: Vec<&str> = self.patches.iter().map(|p| p.name.as_str()).collect();
        format!("no patch {name:?}; patches: {}", names.join(", "))
    }
}

/// The draft shared between the engine's registered functions and its owner.
#[derive(Clone, Debug)]
pub struct SharedDraft(Arc<Mutex<Draft>>);

impl SharedDraft {
    pub fn new(draft: Draft) -> Self {
        SharedDraft(Arc::new(Mutex::new(draft)))
    }

    /// Locks the draft; a panic elsewhere while holding the lock cannot leave it half-edited
    /// (every edit is computed first and committed in one assignment), so poison is ignored.
    pub fn lock(&self) -> MutexGuard<'_, Draft> {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}
