//! The scene being built by a running script: the canvas (once set), the patches, and where
//! in the source each was created (so later checks can point at the call that named a file).

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
}

/// A scene under construction; `canvas` is `None` until `canvas(...)` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Draft {
    /// Relative paths in the script resolve against this folder (the scene file's).
    pub base_dir: PathBuf,
    pub canvas: Option<Canvas>,
    pub patches: Vec<Patch>,
    pub origins: Origins,
    pub golden: Option<crate::golden::GoldenSettings>,
}

impl Draft {
    pub fn new(base_dir: &Path) -> Self {
        Draft {
            base_dir: base_dir.to_path_buf(),
            canvas: None,
            patches: Vec::new(),
            origins: Origins::default(),
            golden: None,
        }
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
