//! Rhai entries against the live scene: takes an entry's source, runs it with the session's
//! scope, functions and imports, and gives the rebuilt scene to the renderer (only changed
//! layers are rebuilt) and the preview; a failure restores scene and scope. Also the
//! scene's warnings, printed once each.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use lapclone::render::{RenderError, Renderer, SceneUpdate};
use lapclone::scene::Scene;
use lapclone::script::LoadedScene;
use rhai::{Dynamic, Scope, AST};

use super::Session;
use crate::cli::render::positioned;
use crate::cli::repl::validator::ends_in_semicolon;

impl Session {
    /// Runs Rhai source against the live scene; on any failure restores scene and scope.
    pub(super) fn eval(&mut self, text: &str) -> anyhow::Result<()> {
        self.entries += 1;
        let name = PathBuf::from(format!("<entry {}>", self.entries));
        let before = self.snapshot();
        let (value, ast) = match self.run(text, &name) {
            Ok(done) => done,
            Err(error) => {
                self.restore(before);
                return Err(error);
            }
        };
        if self.engine.draft() != before.draft {
            if let Err(error) = self.rebuild(&name, text) {
                self.restore(before);
                return Err(error);
            }
            self.remember(before);
            self.warn();
        }
        self.edits.push(text.to_string());
        self.functions = self.functions.merge(&ast.clone_functions_only());
        self.imports.extend(import_statements(text));
        self.refresh_words();
        // A page's edit is shown as its `(view)` line, a statement like any entry that ends
        // in `;`: the patch or handle the call gives back would be a line of noise.
        if !value.is_unit() && !ends_in_semicolon(text) {
            let shown = self.display(value);
            self.say(if self.interactive {
                format!("=> {shown}")
            } else {
                shown
            });
        }
        Ok(())
    }

    /// A value as the script's own `to_string` shows it (scene types register theirs).
    pub(super) fn display(&self, value: Dynamic) -> String {
        let mut scope = Scope::new();
        scope.push("value", value.clone());
        self.engine
            .engine()
            .eval_with_scope::<String>(&mut scope, "to_string(value)")
            .unwrap_or_else(|_| value.to_string())
    }

    pub(super) fn run(&mut self, text: &str, name: &Path) -> anyhow::Result<(Dynamic, AST)> {
        let scene_error = |e| anyhow::anyhow!("{e}");
        let ast = self.engine.compile(text, name).map_err(scene_error)?;
        let imports = self
            .engine
            .compile(&self.imports.join("\n"), name)
            .unwrap_or_default();
        let program = imports.merge(&self.functions).merge(&ast);
        let value = self
            .engine
            .run_ast(&mut self.scope, &program, text, name)
            .map_err(scene_error)?;
        Ok((value, ast))
    }

    /// Hands the edited scene to the renderer (reusing unchanged layers) and shows it.
    pub(super) fn rebuild(&mut self, name: &Path, text: &str) -> anyhow::Result<()> {
        if self.engine.draft().canvas.is_none() {
            self.renderer = None;
            return Ok(());
        }
        let (scene, origins) = self
            .engine
            .scene(name)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let loaded = LoadedScene {
            scene,
            origins,
            file: name.to_path_buf(),
            text: text.to_string(),
        };
        self.install_scene(&loaded)?;
        self.show_frame()
    }

    pub(super) fn install_scene(&mut self, loaded: &LoadedScene) -> anyhow::Result<()> {
        let started = Instant::now();
        let update = match self.renderer.as_mut() {
            Some(renderer) => renderer.set_scene(loaded.scene.clone()),
            None => session_renderer(loaded.scene.clone()).map(|renderer| {
                let update = SceneUpdate {
                    rebuilt: loaded.scene.patches.len(),
                    ..SceneUpdate::default()
                };
                self.renderer = Some(renderer);
                update
            }),
        }
        .map_err(|e| positioned(loaded, e))?;
        if self.interactive && update.rebuilt + update.rigs_built > 0 {
            self.say(format!(
                "built {} layer(s), kept {} ({:.0} ms)",
                update.rebuilt + update.rigs_built,
                update.reused,
                started.elapsed().as_secs_f64() * 1e3
            ));
        }
        self.revision += 1;
        self.last_update = Some(update);
        self.installed = Some(loaded.clone());
        Ok(())
    }

    /// Renders the frame at the current time and updates the preview.
    pub(super) fn show_frame(&mut self) -> anyhow::Result<()> {
        let renderer = self
            .renderer
            .as_mut()
            .context("no scene yet: :load FILE, or call canvas(width, height) first")?;
        if let Err(error) = renderer.render_time(self.time) {
            return Err(match &self.installed {
                Some(loaded) => positioned(loaded, error),
                None => render_error(error),
            });
        }
        self.publish();
        if self.from_view {
            return Ok(());
        }
        let renderer = self.renderer.as_ref().context("no scene yet")?;
        self.refuse_input(&self.preview.path, false)?;
        self.preview.update(renderer)
    }

    /// Prints the scene's new warnings (old spellings, a replaced canvas, keys no frame
    /// shows) to stderr, as `lapclone check` lists them.
    pub(super) fn warn(&mut self) {
        let Ok((scene, origins)) = self.engine.scene(Path::new("<repl>")) else {
            return;
        };
        let mut warnings = origins.warnings;
        warnings.extend(scene.warnings());
        for warning in warnings.iter().filter(|w| !self.warned.contains(w)) {
            self.say_warning(format!("warning: {warning}"));
        }
        self.warned = warnings;
    }
}

/// The session's renderer for `scene`: someone waits on each of its frames (the live view,
/// the preview file), and nothing encodes beside it, so every core shades.
pub(super) fn session_renderer(scene: Scene) -> Result<Renderer, RenderError> {
    let mut renderer = Renderer::new(scene)?;
    renderer.set_raster_threads(lapclone::util::available_cores());
    Ok(renderer)
}

/// A render error (it names its patch; no source position, as the scene may come from many
/// entries).
pub(super) fn render_error(error: RenderError) -> anyhow::Error {
    anyhow::anyhow!("render failed: {error}")
}

/// The top-level `import "…" as name;` statements of `text`, one per line, so later entries
/// see the same modules.
pub fn import_statements(text: &str) -> Vec<String> {
    text.lines()
        .map(|line| line.split("//").next().unwrap_or("").trim())
        .filter(|line| line.starts_with("import ") && line.contains(" as "))
        .map(|line| match line.find(';') {
            Some(end) => line[..=end].to_string(),
            None => format!("{line};"),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn import_statements_are_collected_with_semicolons() {
        let text = "import \"motion\" as m;\nlet a = 1;\n  import \"shapes\" as s // c\n";
        assert_eq!(
            import_statements(text),
            ["import \"motion\" as m;", "import \"shapes\" as s;"]
        );
    }
}
