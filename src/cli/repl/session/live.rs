//! The session's side of the live view: takes the page's requests (seek, locate, an edit
//! previewed or committed, cancel, undo, save) and gives the frames and scene messages the
//! [`Hub`] sends to every page. A committed edit becomes one REPL line run through the
//! session's own entry path, so it is printed, undoable and saved like a typed one; a
//! previewed edit only renders (no history), and cancel renders the committed scene again.

use lapclone::util::ShowPath;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec2;
use lapclone::scene::get_patch_call;
use lapclone::script::ScriptOptions;
use rhai::Scope;

use super::{Session, Step};
use crate::cli::view::{locate, scene_message, Edit, Hub, LiveSession, Printer, SceneText};

impl Session {
    /// Sends every frame and scene change to `hub`; lines printed for page edits go to
    /// `printer` while a prompt is up, and the lines pages run join its history.
    pub fn attach_view(&mut self, hub: Arc<Hub>, printer: Option<Printer>) {
        self.view = Some(hub);
        self.printer = printer;
    }

    /// Prints a line of the session's own: through the prompt's printer while a page's
    /// request runs, so the prompt stays intact.
    pub(super) fn say(&self, text: String) {
        if let Some(text) = self.above_prompt(text) {
            crate::cli::print_line(&text);
        }
    }

    /// Prints a warning as [`say`](Self::say) prints a line: above the prompt while a page's
    /// request runs, else to standard error.
    pub(super) fn say_warning(&self, text: String) {
        if let Some(text) = self.above_prompt(text) {
            eprint_line!("{text}");
        }
    }

    /// Prints `text` above the prompt while a page's request runs; else gives it back.
    fn above_prompt(&self, text: String) -> Option<String> {
        match (&self.printer, self.from_view) {
            (Some(printer), true) => printer.print(text),
            _ => Some(text),
        }
    }

    /// Sends the current frame and scene message to the pages, if a view is attached.
    pub(super) fn publish(&self) {
        let (Some(hub), Some(renderer)) = (&self.view, &self.renderer) else {
            return;
        };
        let file = self
            .file
            .as_deref()
            .and_then(Path::file_name)
            .and_then(|n| n.to_str());
        let head = crate::cli::view::Playhead {
            time: self.time,
            revision: self.revision,
            file,
        };
        let scene = SceneText {
            plain: scene_message(renderer, &head, false),
            with_mesh: hub
                .wants_mesh()
                .then(|| scene_message(renderer, &head, true)),
        };
        hub.publish(renderer.frame(), renderer.drawn_region(), scene);
        self.published.set(self.published.get() + 1);
    }

    /// Runs `line` as an entry, printing it first as the page's.
    fn view_line(&mut self, line: &str) -> Result<(), String> {
        self.say_from_view(format!("(view) {line}"));
        self.from_view = true;
        let result = self.run_entry(line);
        self.from_view = false;
        match result {
            Ok(Step::Ok | Step::Quit) => {
                if let Some(printer) = &self.printer {
                    printer.remember(line);
                }
                self.tell_pages(line);
                Ok(())
            }
            Ok(Step::Failed) => Err(format!("{line} failed")),
            Err(error) => {
                let message = crate::cli::describe(&error);
                self.say_from_view(message.clone());
                Err(message)
            }
        }
    }

    /// Shows a page's line, done, in every page's log.
    fn tell_pages(&self, line: &str) {
        if let Some(hub) = &self.view {
            hub.broadcast(serde_json::json!({ "type": "line", "text": line }).to_string());
        }
    }

    fn say_from_view(&mut self, text: String) {
        self.from_view = true;
        self.say(text);
        self.from_view = false;
    }

    pub(super) fn as_page(
        &mut self,
        run: impl FnOnce(&mut Self) -> anyhow::Result<()>,
    ) -> Result<(), String> {
        self.from_view = true;
        let result = run(self);
        self.from_view = false;
        result.map_err(|e| crate::cli::describe(&e))
    }

    /// How a line names patch `name`: a variable entries see holding it (one spelled like
    /// the patch first), else `get_patch("name")`.
    fn receiver(&self, name: &str) -> String {
        let mut holders: Vec<String> = Vec::new();
        for (var, value) in self.visible_variables() {
            if value.type_name().ends_with("PatchRef") || value.type_name() == "Patch" {
                let mut scope = Scope::new();
                scope.push(var, value.clone());
                let named = self
                    .engine
                    .engine()
                    .eval_with_scope::<String>(&mut scope, &format!("{var}.name"));
                if named.ok().as_deref() == Some(name) {
                    holders.push(var.to_string());
                }
            }
        }
        holders.sort_by_key(|v| v != name);
        holders
            .into_iter()
            .next()
            .unwrap_or_else(|| get_patch_call(name))
    }

    /// The files `--watch` polls: the loaded scene and the modules it imports.
    pub fn watched_files(&self) -> Vec<PathBuf> {
        let Some(file) = &self.file else {
            return Vec::new();
        };
        let options = ScriptOptions::for_scene_file(file);
        let mut files = vec![file.clone()];
        for statement in &self.imports {
            let Some(name) = statement.split('"').nth(1) else {
                continue;
            };
            let module = format!("{name}.rhai");
            let candidates = std::iter::once(options.scene_dir.join(&module))
                .chain(options.scripts_dir.iter().map(|d| d.join(&module)));
            if let Some(found) = candidates.into_iter().find(|p| p.is_file()) {
                files.push(found);
            }
        }
        files
    }

    /// A watched file changed: reloads unless the session has edits not saved to it.
    pub fn watch_reload(&mut self, changed: &[PathBuf]) {
        // The old scope is dropped here: on the scene's stack, as an entry's would be.
        lapclone::script::on_scene_stack(|| self.watch_reload_here(changed));
    }

    fn watch_reload_here(&mut self, changed: &[PathBuf]) {
        let Some(file) = self.file.clone() else {
            return;
        };
        let own_write = changed == [file.clone()]
            && lapclone::script::read_scene_text(&file).ok() == self.file_text;
        if own_write {
            return; // this session's `:save`: what it holds is what the file says
        }
        self.from_view = true;
        if self.revision != self.saved_revision {
            self.say(format!(
                "{} changed on disk; not reloaded: the session has unsaved edits (:save it, or \
                 :reload to drop them)",
                file.shown()
            ));
        } else if let Err(error) = self.load(&file) {
            self.say(crate::cli::describe(&error));
        }
        self.from_view = false;
    }

    /// A variable name for a new handle no variable has yet: `h`, `h2`, `h3`, …
    fn new_handle_name(&self) -> String {
        let taken = |n: &str| self.scope.iter_raw().any(|(v, _, _)| v == n);
        (1..)
            .map(|i| {
                if i == 1 {
                    "h".to_string()
                } else {
                    format!("h{i}")
                }
            })
            .find(|n| !taken(n))
            .unwrap_or_else(|| "h".into())
    }

    /// Refuses a page's `what` made against revision `rev` unless it is the session's: a
    /// past one is stale (the page is sent the scene again, to redo it against), a future
    /// one never existed.
    fn check_revision(&mut self, rev: u64, what: &str) -> Result<(), String> {
        let now = self.revision;
        if rev > now {
            return Err(format!(
                "{what} against revision {rev}: the scene is at revision {now}"
            ));
        }
        if rev < now {
            self.publish();
            return Err(format!(
                "stale {what}: the scene changed since (revision {rev}, now {now}); try again"
            ));
        }
        Ok(())
    }
}

impl LiveSession for Session {
    /// Publishes again (a page changed what it wants to be sent).
    fn view_publish(&mut self) -> Result<(), String> {
        self.publish();
        Ok(())
    }

    /// Moves the playhead (no history).
    fn view_seek(&mut self, t: f64) -> Result<(), String> {
        self.check_time(t)?;
        self.time = t;
        self.as_page(|s| s.show_frame())
    }

    /// The `located` reply for canvas point (x, y).
    fn view_locate(&self, x: f64, y: f64) -> String {
        let found = self
            .renderer
            .as_ref()
            .and_then(|r| locate(r, self.time, DVec2::new(x, y)));
        let (patch, source) = match found {
            Some((name, p)) => (Some(name), Some([p.x, p.y])),
            None => (None, None),
        };
        serde_json::json!({ "type": "located", "x": x, "y": y, "patch": patch, "source": source })
            .to_string()
    }

    /// Previews (`commit` false) or commits a page edit made against revision `rev`, keyed
    /// at `t` (the playhead the gesture began at) or, without it, at the session's playhead.
    fn view_edit(
        &mut self,
        rev: u64,
        commit: bool,
        edit: &Edit,
        t: Option<f64>,
    ) -> Result<(), String> {
        let t = t.unwrap_or(self.time);
        for keyed in std::iter::once(t).chain(edit.keys_elsewhere()) {
            self.check_time(keyed)?;
        }
        self.check_revision(rev, "edit")?;
        if self
            .engine
            .draft()
            .patches
            .iter()
            .all(|p| p.name != edit.patch())
        {
            return Err(format!("no patch {:?}", edit.patch()));
        }
        if commit {
            let line = edit.line(t, &self.receiver(edit.patch()), &self.new_handle_name());
            return self.view_line(&line);
        }
        if !edit.previews() {
            return Err("this edit has no preview".into());
        }
        let mut scene = self.current_scene().map_err(|e| e.to_string())?;
        edit.apply_key(&mut scene, t)?;
        let renderer = self.renderer.as_mut().ok_or("no scene to preview")?;
        renderer.set_scene(scene).map_err(|e| e.to_string())?;
        self.previewing = true;
        self.as_page(|s| s.show_frame())
    }

    /// Escape: back to the committed scene's frame.
    fn view_cancel(&mut self) -> Result<(), String> {
        if !std::mem::take(&mut self.previewing) {
            return Ok(());
        }
        let scene = self.current_scene().map_err(|e| e.to_string())?;
        if let Some(renderer) = self.renderer.as_mut() {
            renderer.set_scene(scene).map_err(|e| e.to_string())?;
        }
        self.as_page(|s| s.show_frame())
    }

    /// Ctrl+Z in a page.
    fn view_undo(&mut self) -> Result<(), String> {
        self.view_cancel()?;
        self.view_line(":undo")
    }

    /// Ctrl+S in a page (confirmed there): `:save` to the loaded file.
    fn view_save(&mut self, rev: u64) -> Result<(), String> {
        self.check_revision(rev, "save")?;
        let file = self
            .file
            .clone()
            .ok_or("no scene file loaded: use :save FILE in the terminal")?;
        let line = format!(":save {}", file.shown());
        self.say_from_view(format!("(view) {line}"));
        self.as_page(|s| s.save(&file))?;
        self.tell_pages(&line);
        Ok(())
    }
}
