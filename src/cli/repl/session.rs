//! A REPL session: takes entries (Rhai source or `:commands`) one at a time and keeps the
//! live scene — the engine and its draft, a persistent `Scope`, the functions and imports of
//! earlier entries, an undo stack, and a renderer that re-renders and writes the preview
//! after every change. A failed entry leaves scene and variables as they were.

mod live;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context as _;
use lapclone::render::{RenderError, Renderer, SceneUpdate};
use lapclone::scene::{frame_time, Background, Scene, Shape};
use lapclone::script::{
    find_scripts_dir, validate_scene, Draft, LoadedScene, SceneEngine, ScriptOptions,
};
use rhai::{Dynamic, Scope, AST};

use super::commands::{help_text, parse_command, Command};
use super::completion::{function_names, SharedWords, Words};
use super::keys::key_table;
use super::preview::Preview;
use super::save::{saved_text, SaveForm};
use crate::cli::render::{default_jobs, positioned, FrameRange, OutputFormat, SinkPlan};

/// What an entry did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    Ok,
    Failed,
    Quit,
}

/// The state an `:undo` (or a failed entry) goes back to. Functions and imports are kept:
/// they only add names.
struct Snapshot {
    draft: Draft,
    scope: Scope<'static>,
    /// How many entries `edits` had.
    edits: usize,
}

pub struct Session {
    cancel: Arc<AtomicBool>,
    /// The scene file (absolute), if one was loaded.
    file: Option<PathBuf>,
    engine: SceneEngine,
    scope: Scope<'static>,
    /// Function definitions of every successful entry (and of the loaded file).
    functions: AST,
    /// `import` statements of every successful entry, re-run before each entry.
    imports: Vec<String>,
    /// The loaded scene file's text, the start of what `:save` writes.
    base_text: Option<String>,
    /// Every successful Rhai entry since the load, in order (undo drops its share).
    edits: Vec<String>,
    /// The warnings already printed, so each is printed once while it holds.
    warned: Vec<String>,
    undo: Vec<Snapshot>,
    renderer: Option<Renderer>,
    last_update: Option<SceneUpdate>,
    /// The scene last handed to the renderer, to position render errors at their calls.
    installed: Option<LoadedScene>,
    time: f64,
    preview: Preview,
    entries: u64,
    words: SharedWords,
    interactive: bool,
    /// The live view's pages, when `--view` is on.
    view: Option<Arc<crate::cli::view::Hub>>,
    /// Prints above the prompt while a page's request runs.
    printer: Option<crate::cli::view::Printer>,
    /// Whether the entry running came from a page (its output goes through `printer` and
    /// the preview file is left alone: the page is the preview).
    from_view: bool,
    /// Counts scene changes, so a page's edit made against an older scene is refused.
    revision: u64,
    /// Whether the renderer holds a page gesture's uncommitted preview.
    previewing: bool,
    /// How many of `edits` the loaded file holds (it was `:save`d over since the load).
    saved_edits: usize,
}

impl Session {
    /// An empty session whose relative paths resolve against the current folder.
    pub fn new(
        cancel: Arc<AtomicBool>,
        preview: Preview,
        words: SharedWords,
        interactive: bool,
    ) -> Self {
        let dir = std::env::current_dir()
            .and_then(|d| d.canonicalize())
            .unwrap_or_else(|_| PathBuf::from("."));
        let options = ScriptOptions {
            scripts_dir: find_scripts_dir(&dir),
            scene_dir: dir,
            limits: Default::default(),
            cancel: cancel.clone(),
        };
        let session = Session {
            engine: SceneEngine::new(&options),
            cancel,
            file: None,
            scope: Scope::new(),
            functions: AST::empty(),
            imports: Vec::new(),
            base_text: None,
            edits: Vec::new(),
            warned: Vec::new(),
            undo: Vec::new(),
            renderer: None,
            last_update: None,
            installed: None,
            time: 0.0,
            preview,
            entries: 0,
            words,
            interactive,
            view: None,
            printer: None,
            from_view: false,
            revision: 0,
            previewing: false,
            saved_edits: 0,
        };
        session.refresh_words();
        session
    }

    /// Runs one entry: a `:command` or Rhai source (possibly several lines).
    pub fn entry(&mut self, text: &str) -> Step {
        match self.run_entry(text) {
            Ok(step) => step,
            Err(error) => {
                eprintln!("{}", crate::cli::describe(&error));
                Step::Failed
            }
        }
    }

    /// Runs one entry and gives its error instead of printing it.
    fn run_entry(&mut self, text: &str) -> anyhow::Result<Step> {
        if std::mem::take(&mut self.previewing) {
            // A page gesture left its preview in the renderer: the entry starts from the
            // committed scene.
            if let (Ok(scene), Some(renderer)) = (self.current_scene(), self.renderer.as_mut()) {
                let _ = renderer.set_scene(scene);
            }
        }
        self.cancel.store(false, Ordering::Relaxed);
        let trimmed = text.trim();
        if trimmed.is_empty() {
            return Ok(Step::Ok);
        }
        let result = if trimmed.starts_with(':') {
            match parse_command(trimmed) {
                Ok(Command::Quit) => return Ok(Step::Quit),
                Ok(command) => self.command(command),
                Err(usage) => Err(anyhow::anyhow!(usage)),
            }
        } else {
            self.eval(text)
        };
        self.cancel.store(false, Ordering::Relaxed);
        result.map(|()| Step::Ok)
    }

    /// Loads a scene file, replacing the live scene (the undo history is cleared).
    pub fn load(&mut self, path: &Path) -> anyhow::Result<()> {
        let file = path
            .canonicalize()
            .with_context(|| format!("cannot open scene {}", path.display()))?;
        let text = std::fs::read_to_string(&file)
            .with_context(|| format!("cannot read scene {}", file.display()))?;
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
        self.base_text = Some(text);
        self.edits.clear();
        self.saved_edits = 0;
        self.warned.clear();
        self.undo.clear();
        self.file = Some(file.clone());
        self.refresh_words();
        self.say(format!("loaded {}", file.display()));
        self.warn();
        self.show_frame()
    }

    fn command(&mut self, command: Command) -> anyhow::Result<()> {
        match command {
            Command::Help => print!("{}", help_text()),
            Command::Load(path) => self.load(&path)?,
            Command::Reload => {
                let file = self
                    .file
                    .clone()
                    .context("no scene file loaded (:load FILE)")?;
                self.load(&file)?;
            }
            Command::Save(path) => self.save(&path)?,
            Command::Time(t) => {
                self.time = t;
                self.show_frame()?;
            }
            Command::Frame(n) => {
                let renderer = self.renderer()?;
                let count = renderer.frame_count();
                if n > count {
                    anyhow::bail!("frame {n}: the scene has {count} frames");
                }
                self.time = frame_time(n - 1, renderer.scene().canvas.fps);
                self.show_frame()?;
            }
            Command::Show => self.show_frame()?,
            Command::Mesh => {
                self.preview.overlay = !self.preview.overlay;
                let state = if self.preview.overlay { "on" } else { "off" };
                crate::cli::print_line(format_args!("mesh overlay {state}"));
                if self.renderer.is_some() {
                    self.show_frame()?;
                }
            }
            Command::List => print!("{}", self.listing()),
            Command::Keys(name) => print!("{}", self.keys(&name)?),
            Command::Undo => self.undo()?,
            Command::Render { range, output } => {
                self.render_to(OutputFormat::Png, &output, range)?
            }
            Command::Gif(path) => self.render_to(OutputFormat::Gif, &path, None)?,
            Command::Stats => print!("{}", self.stats()?),
            Command::Quit => {}
        }
        Ok(())
    }

    /// Runs Rhai source against the live scene; on any failure restores scene and scope.
    fn eval(&mut self, text: &str) -> anyhow::Result<()> {
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
            self.undo.push(before);
            self.warn();
        }
        self.edits.push(text.to_string());
        self.functions = self.functions.merge(&ast.clone_functions_only());
        self.imports.extend(import_statements(text));
        self.refresh_words();
        if !value.is_unit() {
            let shown = self.display(value);
            if self.interactive {
                crate::cli::print_line(format_args!("=> {shown}"));
            } else {
                crate::cli::print_line(&shown);
            }
        }
        Ok(())
    }

    /// A value as the script's own `to_string` shows it (scene types register theirs).
    fn display(&self, value: Dynamic) -> String {
        let mut scope = Scope::new();
        scope.push("value", value.clone());
        self.engine
            .engine()
            .eval_with_scope::<String>(&mut scope, "to_string(value)")
            .unwrap_or_else(|_| value.to_string())
    }

    fn run(&mut self, text: &str, name: &Path) -> anyhow::Result<(Dynamic, AST)> {
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
    fn rebuild(&mut self, name: &Path, text: &str) -> anyhow::Result<()> {
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

    fn install_scene(&mut self, loaded: &LoadedScene) -> anyhow::Result<()> {
        let started = Instant::now();
        let update = match self.renderer.as_mut() {
            Some(renderer) => renderer.set_scene(loaded.scene.clone()),
            None => Renderer::new(loaded.scene.clone()).map(|renderer| {
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

    fn renderer(&self) -> anyhow::Result<&Renderer> {
        self.renderer
            .as_ref()
            .context("no scene yet: :load FILE, or call canvas(width, height) first")
    }

    /// Renders the frame at the current time and updates the preview.
    fn show_frame(&mut self) -> anyhow::Result<()> {
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
        self.preview.update(renderer)
    }

    fn snapshot(&self) -> Snapshot {
        Snapshot {
            draft: self.engine.draft(),
            scope: self.scope.clone(),
            edits: self.edits.len(),
        }
    }

    /// Puts scene and scope back; the renderer follows (its layers are still there).
    fn restore(&mut self, snapshot: Snapshot) {
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

    fn undo(&mut self) -> anyhow::Result<()> {
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
            self.renderer = Some(Renderer::new(scene).map_err(|e| anyhow::anyhow!("{e}"))?);
        }
        self.show_frame()
    }

    fn current_scene(&self) -> anyhow::Result<Scene> {
        let file = self.file.clone().unwrap_or_else(|| PathBuf::from("<repl>"));
        let (scene, _) = self
            .engine
            .scene(&file)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(scene)
    }

    /// Writes the live scene (see `save.rs` for the two forms it takes).
    fn save(&mut self, path: &Path) -> anyhow::Result<()> {
        let scene = self.current_scene()?;
        crate::cli::clone::check_output_folder(path)?;
        let (text, form) = saved_text(&scene, self.base_text.as_deref(), &self.edits, path);
        lapclone::util::write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        if path.canonicalize().ok() == self.file {
            self.saved_edits = self.edits.len();
        }
        match form {
            SaveForm::Script => self.say(format!("saved {}", path.display())),
            SaveForm::Keys => self.say(format!(
                "saved {} (every key written out: the session's text does not rebuild this \
                 scene from that folder)",
                path.display()
            )),
        }
        Ok(())
    }

    /// Prints the scene's new warnings (keys no frame shows) to stderr.
    fn warn(&mut self) {
        let Ok((scene, _)) = self.engine.scene(Path::new("<repl>")) else {
            return;
        };
        let warnings = scene.warnings();
        for warning in warnings.iter().filter(|w| !self.warned.contains(w)) {
            eprintln!("warning: {warning}");
        }
        self.warned = warnings;
    }

    /// The `:keys NAME` table.
    fn keys(&self, name: &str) -> anyhow::Result<String> {
        let draft = self.engine.draft();
        let patch = draft
            .patches
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| anyhow::anyhow!(draft.no_patch_message(name)))?;
        Ok(key_table(patch))
    }

    /// Renders frames with a fresh renderer, so the files are byte-identical to
    /// `lapclone render` of the `:save`d scene.
    fn render_to(
        &mut self,
        format: OutputFormat,
        output: &Path,
        range: Option<FrameRange>,
    ) -> anyhow::Result<()> {
        let scene = self.current_scene()?;
        if let Some(loaded) = &self.installed {
            let imports = self.engine.module_files().files();
            crate::cli::inputs::refuse_render_input(format.kind(), output, loaded, &imports)?;
        }
        let started = Instant::now();
        let plan = SinkPlan::new(format.kind(), output, Default::default())?;
        let mut renderer = Renderer::new(scene).map_err(|e| anyhow::anyhow!("{e}"))?;
        let total = renderer.frame_count();
        let range = range.unwrap_or(FrameRange {
            first: 1,
            last: total,
        });
        if range.last > total {
            anyhow::bail!(
                "frames {}..{}: the scene has {total} frames",
                range.first,
                range.last
            );
        }
        let mut sink = plan.open(&renderer, range, default_jobs(), self.cancel.clone())?;
        for number in range.first..=range.last {
            if self.cancel.load(Ordering::Relaxed) {
                sink.abandon();
                anyhow::bail!("render cancelled after frame {}", number - 1);
            }
            if let Err(error) = renderer.render_frame(number - 1) {
                sink.abandon();
                return Err(render_error(error));
            }
            sink.push(number, renderer.frame())?;
        }
        let written = sink.finish()?;
        crate::cli::print_line(format_args!(
            "rendered {} frames to {} in {:.2} s",
            range.last - range.first + 1,
            written.display(),
            started.elapsed().as_secs_f64()
        ));
        Ok(())
    }

    fn stats(&self) -> anyhow::Result<String> {
        let renderer = self.renderer()?;
        let s = renderer.last_stats();
        let mut out = format!(
            "t = {} s: {:.2} ms total (deform {:.2}, solve {:.2}, raster {:.2}); \
             switches: {} deform, {} clone; boundary hidden {}, outside {}, glued {}\n",
            s.time,
            s.total_ms,
            s.deform_ms,
            s.solve_ms,
            s.raster_ms,
            s.deform_switches,
            s.clone_switches,
            s.hidden,
            s.outside,
            s.glued
        );
        let vertices = renderer.vertex_counts();
        out.push_str(&format!("mesh vertices per patch: {vertices:?}\n"));
        if let Some(u) = self.last_update {
            out.push_str(&format!(
                "last edit: {} layer(s) kept, {} rebuilt, {} dropped, {} rig(s) built\n",
                u.reused, u.rebuilt, u.dropped, u.rigs_built
            ));
        }
        Ok(out)
    }

    /// The `:list` text: canvas, patches with their keys, handles and pins, and variables.
    pub fn listing(&self) -> String {
        let draft = self.engine.draft();
        let mut out = String::new();
        match &draft.canvas {
            Some(c) => {
                let background = match &c.background {
                    Background::Image(path) => short(path),
                    Background::Colour(rgba) => format!("colour {rgba:?}"),
                    Background::Footage(f) => format!("footage {}", f.describe()),
                };
                out.push_str(&format!(
                    "canvas {}×{}, {} fps, {} s ({} frames), background {background}\n",
                    c.width,
                    c.height,
                    c.fps,
                    c.duration,
                    c.frame_count()
                ));
            }
            None => out.push_str("no canvas yet\n"),
        }
        for patch in &draft.patches {
            let shape = match &patch.shape {
                Shape::Mask(path) => format!("mask {}", short(path)),
                Shape::Polygons(p) => format!("{} polygon(s)", p.len()),
            };
            out.push_str(&format!(
                "patch \"{}\": source {}, {shape}, {:?}, {:?}, feather {}, boundary data {}, \
                 boundary {}\n",
                patch.name,
                short(&patch.source),
                patch.laplacian,
                patch.mode,
                patch.feather,
                patch.boundary_data.name(),
                patch.boundary.name()
            ));
            let p = &patch.placement;
            out.push_str(&format!(
                "  keys: position {}, scale {}, rotation {}, depth {}, opacity {}\n",
                p.position.keys().len(),
                p.scale.keys().len(),
                p.rotation.keys().len(),
                p.depth.keys().len(),
                p.opacity.keys().len()
            ));
            for (i, h) in patch.handles.iter().enumerate() {
                out.push_str(&format!(
                    "  handle {i}: from [{}, {}], radius {}, {} key(s)\n",
                    h.from.x,
                    h.from.y,
                    h.radius,
                    h.to.keys().len()
                ));
            }
            for (i, pin) in patch.pins.iter().enumerate() {
                let end = pin.end.map_or("end".to_string(), |e| format!("{e} s"));
                out.push_str(&format!(
                    "  pin {i}: at [{}, {}], {} s to {end}\n",
                    pin.at.x, pin.at.y, pin.start
                ));
            }
        }
        out.push_str(&layer_order(&draft, self.time));
        let names: Vec<&str> = self.scope.iter_raw().map(|(name, _, _)| name).collect();
        if !names.is_empty() {
            out.push_str(&format!("variables: {}\n", names.join(", ")));
        }
        out
    }

    fn refresh_words(&self) {
        let mut functions = function_names(self.engine.engine());
        functions.extend(self.functions.iter_functions().map(|f| f.name.to_string()));
        functions.sort();
        functions.dedup();
        let words = Words {
            patches: self
                .engine
                .draft()
                .patches
                .iter()
                .map(|p| p.name.clone())
                .collect(),
            variables: self
                .scope
                .iter_raw()
                .map(|(name, _, _)| name.to_string())
                .collect(),
            functions,
        };
        *self.words.lock().unwrap_or_else(|p| p.into_inner()) = words;
    }
}

/// `layers at t = 1.5 s, back to front: horse, cat (opacity 0.5)`.
fn layer_order(draft: &Draft, t: f64) -> String {
    let Some(canvas) = draft.canvas.clone() else {
        return String::new();
    };
    if draft.patches.is_empty() {
        return String::new();
    }
    let scene = Scene {
        canvas,
        patches: draft.patches.clone(),
        golden: None,
    };
    let state = scene.evaluate(t);
    let layers: Vec<String> = state
        .draw_order
        .iter()
        .map(|&i| {
            let (patch, s) = (&scene.patches[i], &state.patches[i]);
            let mut text = format!("{:?} (depth {}", patch.name, s.depth);
            if s.opacity < 1.0 {
                text.push_str(&format!(", opacity {}", s.opacity));
            }
            text + ")"
        })
        .collect();
    format!(
        "layers at t = {t} s, back to front: {}\n",
        layers.join(", ")
    )
}

/// A render error (it names its patch; no source position, as the scene may come from many
/// entries).
fn render_error(error: RenderError) -> anyhow::Error {
    anyhow::anyhow!("render failed: {error}")
}

fn short(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
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
