//! Running scene scripts: takes scene source text (a file, or REPL lines against a persistent
//! `Scope`) and gives the [`Scene`] it builds, or a positioned [`SceneError`].

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use rhai::{Dynamic, Engine, Scope, AST};

use super::draft::{Draft, Origin, Origins, SharedDraft};
use super::error::{ErrorKind, SceneError};
use super::budget::Budget;
use super::sandbox::{sandboxed_engine, Limits, ModuleFiles, SandboxResolver};
use super::{api, golden};
use crate::scene::Scene;

/// Where a script may import from, how far it may run, and how to stop it.
#[derive(Clone, Debug)]
pub struct ScriptOptions {
    /// Relative paths (images, imports) resolve against this folder.
    pub scene_dir: PathBuf,
    /// The project's `scripts/` folder; see [`find_scripts_dir`].
    pub scripts_dir: Option<PathBuf>,
    pub limits: Limits,
    /// Raise to stop a running evaluation (Ctrl-C); the caller lowers it again.
    pub cancel: Arc<AtomicBool>,
}

impl ScriptOptions {
    /// Options for a scene file: its folder, and the nearest `scripts/` folder above it.
    pub fn for_scene_file(path: &Path) -> Self {
        let scene_dir = scene_folder(path);
        ScriptOptions {
            scripts_dir: find_scripts_dir(&scene_dir),
            scene_dir,
            limits: Limits::default(),
            cancel: Arc::default(),
        }
    }
}

fn scene_folder(path: &Path) -> PathBuf {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The nearest `scripts/` folder in `start` or one of its ancestors.
pub fn find_scripts_dir(start: &Path) -> Option<PathBuf> {
    let start = start.canonicalize().ok()?;
    start
        .ancestors()
        .map(|dir| dir.join("scripts"))
        .find(|candidate| candidate.is_dir())
}

/// A sandboxed engine with the scene language registered, and the scene it is building.
pub struct SceneEngine {
    engine: Engine,
    draft: SharedDraft,
    modules: ModuleFiles,
    budget: Budget,
}

/// A parsed scene with the source positions of its objects.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene the file describes.
    pub scene: Scene,
    /// Where in the file each patch and handle was made (for positioned errors).
    pub(crate) origins: Origins,
    /// The scene file.
    pub file: PathBuf,
    /// The file's text.
    pub text: String,
}

impl LoadedScene {
    /// A validation error about the patch named `patch` (the patch a renderer's error
    /// names), positioned at the call that made that patch; at the scene file without a
    /// position when no patch is named or known.
    pub fn error_at_patch(&self, patch: Option<&str>, message: impl Into<String>) -> SceneError {
        let index = patch.and_then(|name| self.scene.patches.iter().position(|p| p.name == name));
        self.error_at(index.and_then(|i| self.origins.patches.get(i)), message)
    }

    /// A validation error at the `canvas(...)` call (about the background, the size).
    pub fn error_at_canvas(&self, message: impl Into<String>) -> SceneError {
        self.error_at(self.origins.canvas.as_ref(), message)
    }

    /// A validation error at `origin`: the scene file itself when there is none, or when the
    /// origin names the scene's folder (a call without a source).
    pub(super) fn error_at(&self, origin: Option<&Origin>, message: impl Into<String>) -> SceneError {
        let (file, position) = match origin {
            Some(o) if !o.file.is_dir() => (o.file.as_path(), o.position),
            Some(o) => (self.file.as_path(), o.position),
            None => (self.file.as_path(), rhai::Position::NONE),
        };
        let text = (file == self.file).then_some(self.text.as_str());
        SceneError::with_text(ErrorKind::Validation, file, position, message, text)
    }

    /// What `lapclone check` warns about: old spellings the file used and `canvas` calls that
    /// replaced an earlier one (positioned), then [`Scene::warnings`].
    pub fn warnings(&self) -> Vec<String> {
        let mut all = self.origins.warnings.clone();
        all.extend(self.scene.warnings());
        all
    }
}

impl SceneEngine {
    pub fn new(options: &ScriptOptions) -> Self {
        let resolver = SandboxResolver::new(&options.scene_dir, options.scripts_dir.as_deref());
        let modules = resolver.module_files();
        let seconds = std::time::Duration::from_secs(options.limits.max_seconds);
        let budget = Budget::new(options.limits.max_memory, seconds);
        let mut engine = sandboxed_engine(
            resolver,
            &options.limits,
            options.cancel.clone(),
            budget.clone(),
        );
        let draft = SharedDraft::new(Draft::new(&options.scene_dir));
        api::register(&mut engine, &draft);
        golden::register(&mut engine, &draft);
        SceneEngine {
            engine,
            draft,
            modules,
            budget,
        }
    }

    pub fn engine(&self) -> &Engine {
        &self.engine
    }

    pub fn module_files(&self) -> &ModuleFiles {
        &self.modules
    }

    /// Parses `text` (named `file` in errors).
    pub fn compile(&self, text: &str, file: &Path) -> Result<AST, SceneError> {
        let mut ast = self
            .engine
            .compile(text)
            .map_err(|e| SceneError::from_parse(&e, file, text))?;
        ast.set_source(file.to_string_lossy().as_ref());
        Ok(ast)
    }

    /// Runs `text` against `scope`, adding to the scene being built. On error the scene is
    /// left as the calls before the failing one made it (the REPL snapshots around a line).
    pub fn run(&self, scope: &mut Scope, text: &str, file: &Path) -> Result<Dynamic, SceneError> {
        let ast = self.compile(text, file)?;
        self.run_ast(scope, &ast, text, file)
    }

    /// Runs a compiled script; `text` and `file` are for error messages.
    pub fn run_ast(
        &self,
        scope: &mut Scope,
        ast: &AST,
        text: &str,
        file: &Path,
    ) -> Result<Dynamic, SceneError> {
        super::on_scene_stack(|| {
            self.budget.start();
            self.engine
                .eval_ast_with_scope::<Dynamic>(scope, ast)
                .map_err(|e| SceneError::from_eval(e, file, text, &|name| self.modules.file_of(name)))
        })
    }

    /// A copy of the scene under construction.
    pub fn draft(&self) -> Draft {
        self.draft.lock().clone()
    }

    /// Replaces the scene under construction (undo).
    pub fn restore(&self, draft: Draft) {
        *self.draft.lock() = draft;
    }

    /// The finished scene: it must have a canvas. `file` names the scene in errors.
    pub fn scene(&self, file: &Path) -> Result<(Scene, Origins), SceneError> {
        let draft = self.draft();
        let Some(canvas) = draft.canvas else {
            return Err(SceneError::in_file(
                ErrorKind::Validation,
                file,
                "the scene has no canvas: add canvas(width, height, #{ fps: 24, duration: 2 })",
            ));
        };
        let scene = Scene {
            canvas,
            patches: draft.patches,
            golden: draft.golden,
        };
        scene
            .sanity_check()
            .map_err(|e| SceneError::in_file(ErrorKind::Validation, file, e.to_string()))?;
        Ok((scene, draft.origins))
    }
}

/// Reads, runs and finishes the scene file at `path`.
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    load_scene_and_imports(path).map(|(loaded, _)| loaded)
}

/// [`load_scene`], also giving the module files the scene imported (directly or through
/// other modules): with the scene and its images, what a render reads.
pub fn load_scene_and_imports(path: &Path) -> Result<(LoadedScene, Vec<PathBuf>), SceneError> {
    load_scene_cancellable(path, Arc::default())
}

/// [`load_scene_and_imports`], stopped as soon as another thread (or a signal handler)
/// raises `cancel`, as Ctrl-C stops `lapclone render`: the error is then
/// [`ErrorKind::Cancelled`].
pub fn load_scene_cancellable(
    path: &Path,
    cancel: Arc<AtomicBool>,
) -> Result<(LoadedScene, Vec<PathBuf>), SceneError> {
    let text = read_scene_text(path)?;
    let mut options = ScriptOptions::for_scene_file(path);
    options.cancel = cancel;
    run_scene(&text, path, &options)
}

/// The text of the scene file at `path`, which must be a regular file (a FIFO or a device
/// would be read until it ends, which may be never) of at most
/// [`MAX_SCENE_BYTES`](crate::limits::MAX_SCENE_BYTES).
pub fn read_scene_text(path: &Path) -> Result<String, SceneError> {
    super::source::read_source(path)
        .map_err(|e| SceneError::in_file(ErrorKind::Io, path, format!("cannot read scene: {e}")))
}

/// Runs scene source `text` (named `file`) with `options` and finishes the scene.
pub fn parse_scene(
    text: &str,
    file: &Path,
    options: &ScriptOptions,
) -> Result<LoadedScene, SceneError> {
    run_scene(text, file, options).map(|(loaded, _)| loaded)
}

fn run_scene(
    text: &str,
    file: &Path,
    options: &ScriptOptions,
) -> Result<(LoadedScene, Vec<PathBuf>), SceneError> {
    // The scope (and every value the scene built) is dropped on the scene's stack too.
    super::on_scene_stack(|| {
    let engine = SceneEngine::new(options);
    let _ = engine.run(&mut Scope::new(), text, file)?;
    let (scene, origins) = engine.scene(file)?;
    let loaded = LoadedScene {
        scene,
        origins,
        file: file.to_path_buf(),
        text: text.to_string(),
    };
    Ok((loaded, engine.module_files().files()))
    })
}
