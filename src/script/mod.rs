//! The scene language: a sandboxed Rhai engine that runs scene files (or REPL lines) and
//! builds a [`crate::scene::Scene`]. Takes source text and folders, gives a scene or a
//! [`SceneError`] with file, line, column and a caret-marked source line. The language is
//! documented in docs/scene-language.md.

mod api;
mod refs;
mod draft;
mod edit_api;
mod engine;
mod error;
mod golden;
mod follow_api;
mod budget;
mod footage_options;
mod sandbox;
mod source;
mod stack;
mod validate;
mod values;

pub use refs::{HandleRef, PatchRef, PinRef};
pub use draft::{Draft, Ids, Origin, Origins};
pub use engine::{
    find_scripts_dir, load_scene, load_scene_and_imports, load_scene_cancellable, parse_scene, read_scene_text, LoadedScene, SceneEngine,
    ScriptOptions,
};
pub use error::{ErrorKind, SceneError};
pub use budget::set_allocation_probe;
pub use stack::{on_scene_stack, SCENE_STACK};
pub use sandbox::{Limits, ModuleFiles, SandboxResolver};
pub use api::{OTHER_OPTION_KEYS, PATCH_OPTIONS};
pub use validate::{validate_scene, CheckSummary};
