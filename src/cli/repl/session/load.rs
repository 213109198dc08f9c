//! `:load` and `:reload`: takes a scene file and gives the session its scene, engine,
//! scope, functions and imports, replacing the live scene (the undo history is cleared).

use lapclone::util::ShowPath;
use std::path::Path;

use anyhow::Context as _;
use lapclone::script::{read_scene_text, validate_scene, LoadedScene, SceneEngine, ScriptOptions};
use rhai::Scope;

use super::eval::import_statements;
use super::Session;

impl Session {
    /// Loads a scene file, replacing the live scene (the undo history is cleared).
    pub fn load(&mut self, path: &Path) -> anyhow::Result<()> {
        let file = path
            .canonicalize()
            .with_context(|| format!("cannot open scene {}", path.shown()))?;
        let text = read_scene_text(&file).map_err(|e| anyhow::anyhow!("{e}"))?;
        let options = ScriptOptions {
            cancel: self.cancel.clone(),
            ..ScriptOptions::for_scene_file(&file)
        };
        let engine = SceneEngine::new(&options);
        let mut scope = Scope::new();
        let scene_error = |e| anyhow::anyhow!("{e}");
        let ast = engine.compile(&text, &file).map_err(scene_error)?;
        let _ = engine
            .run_ast(&mut scope, &ast, &text, &file)
            .map_err(scene_error)?;
        let (scene, origins) = engine.scene(&file).map_err(scene_error)?;
        let loaded = LoadedScene {
            scene,
            origins,
            file: file.clone(),
            text: text.clone(),
        };
        validate_scene(&loaded).map_err(scene_error)?;
        self.install_scene(&loaded)?;
        self.engine = engine;
        self.scope = scope;
        self.functions = ast.clone_functions_only();
        self.imports = import_statements(&text);
        self.file_text = Some(text.clone());
        self.base_text = Some(text);
        self.edits.clear();
        self.saved_revision = self.revision;
        self.warned.clear();
        self.undo.clear();
        self.file = Some(file.clone());
        self.refresh_words();
        self.say(format!("loaded {}", file.shown()));
        self.warn();
        self.show_frame()
    }
}
