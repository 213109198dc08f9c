//! A REPL session: takes entries (Rhai source or `:commands`) one at a time and keeps the
//! live scene — the engine and its draft, a persistent `Scope`, the functions and imports of
//! earlier entries, an undo stack, and a renderer that re-renders and writes the preview
//! after every change. A failed entry leaves scene and variables as they were. This file
//! holds the state and dispatches entries; `eval`, `load`, `undo`, `save`, `render`,
//! `listing` and `live` (the live view's requests) each do one part.

mod eval;
mod listing;
mod live;
mod load;
mod render;
mod save;
mod undo;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::Context as _;
use lapclone::render::{Renderer, SceneUpdate};
use lapclone::scene::{frame_time, Scene};
use lapclone::script::{find_scripts_dir, LoadedScene, SceneEngine, ScriptOptions};
use rhai::{Scope, AST};

use super::commands::{help_text, parse_command, Command};
use super::completion::{function_names, SharedWords, Words};
use super::preview::Preview;
use crate::cli::render::OutputFormat;
use undo::Snapshot;

/// What an entry did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    Ok,
    Failed,
    Quit,
}

pub struct Session {
    cancel: Arc<AtomicBool>,
    /// The scene file (absolute), if one was loaded.
    file: Option<PathBuf>,
    /// Files the session itself reads (its `--script`): never an output.
    session_inputs: Vec<PathBuf>,
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
    /// Frames sent to the pages so far, so an entry knows whether it showed them one.
    published: std::cell::Cell<u64>,
    /// The scene's revision the loaded file holds (as loaded, or `:save`d over since).
    saved_revision: u64,
    /// The loaded file's text as this session last read or wrote it, so `--watch` knows its
    /// own `:save` from a change made elsewhere.
    file_text: Option<String>,
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
            session_inputs: Vec::new(),
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
            published: std::cell::Cell::new(0),
            saved_revision: 0,
            file_text: None,
        };
        session.refresh_words();
        session
    }

    /// Runs one entry: a `:command` or Rhai source (possibly several lines).
    pub fn entry(&mut self, text: &str) -> Step {
        match self.run_entry(text) {
            Ok(step) => step,
            Err(error) => {
                eprint_line!("{}", crate::cli::describe(&error));
                Step::Failed
            }
        }
    }

    /// Runs one entry and gives its error instead of printing it, on the scene's stack:
    /// the entry, and the snapshots, values shown and history it clones or drops, may hold
    /// values nested deeper than a thread's usual stack can walk.
    fn run_entry(&mut self, text: &str) -> anyhow::Result<Step> {
        lapclone::script::on_scene_stack(|| self.run_entry_here(text))
    }

    fn run_entry_here(&mut self, text: &str) -> anyhow::Result<Step> {
        let dropped = std::mem::take(&mut self.previewing);
        if dropped {
            // A page gesture left its preview in the renderer: the entry starts from the
            // committed scene.
            if let (Ok(scene), Some(renderer)) = (self.current_scene(), self.renderer.as_mut()) {
                let _ = renderer.set_scene(scene);
            }
        }
        let published = self.published.get();
        let step = self.run_entry_text(text);
        if dropped && self.published.get() == published {
            // The entry showed the pages nothing (`:list`, a failed line, an edit that
            // changed nothing): they still show the preview, so show them the scene.
            let _ = self.as_page(|s| s.show_frame());
        }
        step
    }

    fn run_entry_text(&mut self, text: &str) -> anyhow::Result<Step> {
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
                self.check_time(t).map_err(anyhow::Error::msg)?;
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
                self.render_to(OutputFormat::PngFolder, &output, range)?
            }
            Command::Gif(path) => self.render_to(OutputFormat::Gif, &path, None)?,
            Command::Stats => print!("{}", self.stats()?),
            Command::Quit => {}
        }
        Ok(())
    }

    /// Refuses a playhead past the scene's end (the rule `preview --t` follows); any time
    /// is taken before there is a scene.
    fn check_time(&self, t: f64) -> Result<(), String> {
        let Some(canvas) = self.renderer.as_ref().map(|r| &r.scene().canvas) else {
            return Ok(());
        };
        if !canvas.is_past_end(t) {
            return Ok(());
        }
        let number = lapclone::util::number_text;
        Err(format!(
            "t = {} s is past the scene's end: it lasts {} s",
            number(t),
            number(canvas.duration)
        ))
    }

    fn renderer(&self) -> anyhow::Result<&Renderer> {
        self.renderer
            .as_ref()
            .context("no scene yet: :load FILE, or call canvas(width, height) first")
    }

    fn current_scene(&self) -> anyhow::Result<Scene> {
        let file = self.file.clone().unwrap_or_else(|| PathBuf::from("<repl>"));
        let (scene, _) = self
            .engine
            .scene(&file)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(scene)
    }

    /// The variables entries see: the last binding of each name (a `let` shadows an earlier
    /// one of the same name, which the scope still holds), in the order they were bound.
    fn visible_variables(&self) -> Vec<(&str, &rhai::Dynamic)> {
        // `iter_raw` walks the scope from the newest binding back.
        let mut seen = std::collections::HashSet::new();
        let mut visible: Vec<(&str, &rhai::Dynamic)> = (self.scope.iter_raw())
            .filter(|(name, _, _)| seen.insert(*name))
            .map(|(name, _, value)| (name, value))
            .collect();
        visible.reverse();
        visible
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
                .visible_variables()
                .into_iter()
                .map(|(name, _)| name.to_string())
                .collect(),
            functions,
        };
        *crate::util::lock(&self.words) = words;
    }
}
