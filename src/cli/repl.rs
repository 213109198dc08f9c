//! `lapclone repl [SCENE] [--script FILE] [--view]`: interactive scene editing. Takes lines from a
//! terminal (rustyline: history, completion, hints, multi-line input) or, when stdin is not
//! a terminal or with `--script`, from a stream; each entry is Rhai run against the live
//! scene or a `:command` (see docs/repl.md). Non-interactive sessions exit with code 1 when
//! any entry failed. With `--view` a page in the browser follows the session and edits it
//! too (see `crate::cli::view`).

mod commands;
mod completion;
mod helper;
mod hints;
mod keys;
mod preview;
mod save;
mod session;
mod sixel;
mod validator;

use lapclone::util::ShowPath;
use std::io::{BufRead, IsTerminal};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use anyhow::Context as _;
use rustyline::error::ReadlineError;
use rustyline::history::{FileHistory, History};
use rustyline::{Config, Editor};

use crate::util::lock;

use helper::ReplHelper;
pub(crate) use preview::show_picture;
use preview::{default_preview_path, Inline, Preview};
pub(crate) use session::Session;
use session::Step;
use validator::EntrySplitter;

#[derive(clap::Args, Debug)]
pub struct ReplArgs {
    /// Scene file to start from (.rhai).
    pub scene: Option<PathBuf>,
    /// Read entries from this file instead of the terminal (non-interactive).
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Where the live preview PNG goes (default: the system temp folder).
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// History file (default: DATA_DIR/lapclone/history.txt).
    #[arg(long)]
    pub history: Option<PathBuf>,
    #[command(flatten)]
    pub view: crate::cli::view::ViewArgs,
}

/// Set when a non-interactive entry fails: the process then exits with code 1.
#[derive(Debug, thiserror::Error)]
#[error("{0} failed entr{suffix}", suffix = if *.0 == 1 { "y" } else { "ies" })]
pub struct EntriesFailed(pub usize);

pub fn run(args: ReplArgs) -> anyhow::Result<()> {
    let interactive = args.script.is_none() && std::io::stdin().is_terminal();
    // The default preview's folder is this process's own: removed when the session ends.
    for (flag, path) in [("--preview", &args.preview), ("--history", &args.history)] {
        if let Some(path) = path {
            super::refuse_stdout_dash(flag, path)?;
        }
    }
    if let Some(path) = &args.preview {
        let what = format!("--preview {}: the REPL", path.shown());
        super::picture_out::png_name_only(&what, path)?;
    }
    let (preview_path, preview_folder) = match &args.preview {
        Some(path) => (path.clone(), None),
        None => default_preview_path().map(|(path, folder)| (path, Some(folder)))?,
    };
    lapclone::output::check_output_folder(&preview_path)?;
    // SIGTERM and SIGHUP (and, piped, SIGINT) end the session without the guard's drop: the
    // folder goes here.
    let folder = preview_folder.as_ref().map(|f| f.path().to_path_buf());
    let terminal = interactive
        .then(super::signals::SavedTerminal::capture)
        .flatten();
    let cleanup = move || {
        if let Some(terminal) = &terminal {
            terminal.restore();
        }
        if let Some(folder) = &folder {
            let _ = std::fs::remove_dir_all(folder);
        }
    };
    // Piped or scripted, Ctrl-C stops the session as SIGTERM does.
    super::signals::stop_on_terminate(cleanup, !interactive);
    let cancel = Arc::new(AtomicBool::new(false));
    // Ctrl-C also ends a wait for a FIFO's reader (`:save fifo` with nobody reading).
    lapclone::util::interrupt_waits_with(&cancel);
    let words = Arc::new(Mutex::new(completion::Words::default()));
    let preview = Preview::new(
        preview_path.clone(),
        interactive,
        Inline::detect(interactive),
    );
    let session = Arc::new(Mutex::new(Session::new(
        cancel.clone(),
        preview,
        words.clone(),
        interactive,
    )));
    let printer: crate::cli::view::Printer = Arc::default();
    if args.view.view {
        start_view(&args.view, &session, interactive.then(|| printer.clone()))?;
    }
    if let Some(script) = &args.script {
        lock(&session).protect(script);
        lock(&session)
            .refuse_input(&preview_path, false)
            .context("--preview")?;
    }
    let mut failures = 0;
    if let Some(scene) = &args.scene {
        let loaded = lock(&session).load(scene);
        // A preview that would replace what the scene reads ends the session before it
        // starts, instead of failing every entry.
        lock(&session)
            .refuse_input(&preview_path, false)
            .context("--preview")?;
        if let Err(error) = loaded {
            eprint_line!("{}", super::describe(&error));
            failures += 1;
        }
    }
    if args.view.watch {
        let (watched, reloaded) = (session.clone(), session.clone());
        crate::cli::view::watch(
            move || lock(&watched).watched_files(),
            move |changed| lock(&reloaded).watch_reload(changed),
        );
    }
    if interactive {
        interactive_loop(&session, &args, cancel, words, &printer)
    } else {
        let input: Box<dyn BufRead> = match &args.script {
            Some(path) => Box::new(std::io::BufReader::new(open_script(path)?)),
            None => Box::new(std::io::stdin().lock()),
        };
        failures += script_loop(&session, input)?;
        super::stdout_failure()?;
        if failures > 0 {
            return Err(EntriesFailed(failures).into());
        }
        Ok(())
    }
}

/// Starts the live view's server and prints its URL (with the token) before the prompt.
fn start_view(
    args: &crate::cli::view::ViewArgs,
    session: &Arc<Mutex<Session>>,
    printer: Option<crate::cli::view::Printer>,
) -> anyhow::Result<()> {
    let hub = Arc::new(crate::cli::view::Hub::default());
    lock(session).attach_view(hub.clone(), printer);
    let server = crate::cli::view::start(args.bind, args.port.unwrap_or(0), session.clone(), hub)?;
    if args.bind.is_some_and(|ip| !ip.is_loopback()) {
        eprint_line!(
            "warning: the live view listens on {}: anyone who can reach it and has the URL's \
             token can edit this session",
            server.addr
        );
    }
    if args.bind.is_some_and(|ip| ip.is_unspecified()) {
        eprint_line!(
            "note: on every address, the URL names this machine's loopback one; from another \
             machine, put one of this machine's addresses in its place"
        );
    }
    super::print_line(format_args!("view: {}", server.url));
    if args.open {
        crate::cli::view::open_in_browser(&server.url);
    }
    Ok(())
}

/// Splits `input` into entries as the interactive validator would (unfinished Rhai goes on
/// on the next line) and runs them; gives the number of failed entries.
fn script_loop(session: &Mutex<Session>, mut input: Box<dyn BufRead>) -> anyhow::Result<usize> {
    let mut splitter = EntrySplitter::default();
    let mut failures = 0;
    let mut number = 0;
    while let Some(line) = next_line(&mut input, &mut number)? {
        let Ok(line) = line else {
            // The entry this line was part of cannot be run: it is dropped with it.
            eprint_line!("input line {number}: not valid UTF-8; this entry is skipped");
            failures += 1;
            splitter.drop_entry();
            continue;
        };
        if splitter.len() + line.len() > MAX_ENTRY_BYTES {
            anyhow::bail!("input line {number}: the entry is over {MAX_ENTRY_BYTES} bytes");
        }
        let Some(entry) = splitter.push(&line) else {
            continue;
        };
        super::stdout_failure()?;
        match lock(session).entry(&entry) {
            Step::Ok => {}
            Step::Failed => failures += 1,
            Step::Quit => return Ok(failures),
        }
    }
    if let Some(rest) = splitter.finish() {
        if lock(session).entry(&rest) == Step::Failed {
            failures += 1;
        }
    }
    Ok(failures)
}

/// Opens a `--script`: a regular file or a FIFO (commands piped through one are a normal
/// use), not a folder or a device (`/dev/zero` never ends a line).
fn open_script(path: &std::path::Path) -> anyhow::Result<std::fs::File> {
    let what = lapclone::util::not_a_file(path);
    if let Some(what) = what.filter(|w| !w.contains("FIFO")) {
        anyhow::bail!("cannot open script {}: it {what}", path.shown());
    }
    std::fs::File::open(path).with_context(|| format!("cannot open script {}", path.shown()))
}

/// Longest entry a piped session reads, as long as a scene file may be.
const MAX_ENTRY_BYTES: usize = lapclone::limits::MAX_SCENE_BYTES as usize;

/// The next line of `input` without its line ending (`Err` inside: not UTF-8), counting
/// lines in `number`; `None` at the end. A line over [`MAX_ENTRY_BYTES`] is an error: the
/// reading stops there rather than hold it or look for its end (`/dev/zero` has none).
fn next_line(
    input: &mut dyn BufRead,
    number: &mut usize,
) -> anyhow::Result<Option<Result<String, std::string::FromUtf8Error>>> {
    use std::io::Read as _;
    let mut bytes = Vec::new();
    let limit = MAX_ENTRY_BYTES as u64 + 1;
    let read = input
        .take(limit)
        .read_until(b'\n', &mut bytes)
        .context("reading input")?;
    if read == 0 {
        return Ok(None);
    }
    *number += 1;
    if bytes.len() > MAX_ENTRY_BYTES {
        anyhow::bail!("input line {number} is over {MAX_ENTRY_BYTES} bytes");
    }
    for end in [b'\n', b'\r'] {
        if bytes.last() == Some(&end) {
            bytes.pop();
        }
    }
    Ok(Some(String::from_utf8(bytes)))
}

fn interactive_loop(
    session: &Mutex<Session>,
    args: &ReplArgs,
    cancel: Arc<AtomicBool>,
    words: completion::SharedWords,
    printer: &crate::cli::view::Printer,
) -> anyhow::Result<()> {
    let mut editor = line_editor(args, cancel, words, printer)?;
    let history = args.history.clone().or_else(default_history_path);
    if let Some(path) = &history {
        let _ = editor.load_history(path);
    }
    super::print_line(format_args!(
        "lapclone repl — :help for commands, Ctrl-D to quit"
    ));
    loop {
        add_page_lines(printer, editor.history_mut());
        match editor.readline("lapclone> ") {
            Ok(line) => {
                if !line.trim().is_empty() {
                    let _ = editor.add_history_entry(line.as_str());
                }
                if lock(session).entry(&line) == Step::Quit {
                    break;
                }
                super::stdout_failure()?;
            }
            Err(ReadlineError::Interrupted) => continue,
            Err(ReadlineError::Eof) => break,
            Err(error) => return Err(error).context("reading input"),
        }
    }
    add_page_lines(printer, editor.history_mut());
    if let Some(path) = &history {
        match lock(session).refuse_input(path, false) {
            Ok(()) => save_history(&mut editor, path),
            Err(error) => eprint_line!("warning: history not written: {}", super::describe(&error)),
        }
    }
    Ok(())
}

/// The prompt's line editor: completion from `words`, Ctrl-C raising `cancel` while an entry
/// runs, and (with a view) page lines printed above the prompt.
fn line_editor(
    args: &ReplArgs,
    cancel: Arc<AtomicBool>,
    words: completion::SharedWords,
    printer: &crate::cli::view::Printer,
) -> anyhow::Result<Editor<ReplHelper, FileHistory>> {
    let config = Config::builder()
        .auto_add_history(false)
        .completion_type(rustyline::CompletionType::List)
        .build();
    let mut editor: Editor<ReplHelper, FileHistory> =
        Editor::with_config(config).context("starting the line editor")?;
    // Ctrl-C while an entry runs raises the cancel flag (the engine and render loops check
    // it); at the prompt rustyline reads it as a key and we clear the line. Installed after
    // the editor: rustyline takes SIGINT for itself when it is created.
    let flag = cancel.clone();
    if ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed)).is_err() {
        eprint_line!("warning: Ctrl-C cannot cancel evaluations in this session");
    }
    editor.set_helper(Some(ReplHelper::new(words)));
    if args.view.view {
        // Lines a page's edits print go above the prompt instead of through it.
        match editor.create_external_printer() {
            Ok(mut external) => {
                printer.set_print(Box::new(move |text: String| {
                    use rustyline::ExternalPrinter as _;
                    // A page's text may carry a scene's own strings: no control reaches
                    // the terminal raw, as on standard error.
                    let shown = lapclone::util::visible_controls(&text);
                    let _ = external.print(format!("{shown}\n"));
                }));
            }
            Err(error) => eprint_line!("warning: page edits print through the prompt: {error}"),
        }
    }
    Ok(editor)
}

/// The lines pages ran since the last prompt join the history, as typed lines do.
fn add_page_lines(printer: &crate::cli::view::Printer, history: &mut impl History) {
    for line in printer.take_history() {
        let _ = history.add_owned(line);
    }
}

/// DATA_DIR/lapclone/history.txt, creating the folder (none if there is no data folder).
fn default_history_path() -> Option<PathBuf> {
    let dir = dirs::data_dir()?.join("lapclone");
    if let Err(error) = std::fs::create_dir_all(&dir) {
        eprint_line!(
            "warning: no history: cannot create {}: {error}",
            dir.shown()
        );
        return None;
    }
    Some(dir.join("history.txt"))
}

fn save_history(editor: &mut Editor<ReplHelper, FileHistory>, path: &std::path::Path) {
    if let Err(error) = editor.save_history(path) {
        eprint_line!("warning: cannot write history {}: {error}", path.shown());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustyline::history::SearchDirection;

    #[test]
    fn lines_pages_ran_join_the_history_in_order_once() {
        let printer: crate::cli::view::Printer = Arc::default();
        let mut history = FileHistory::new();
        history.add("cat.at(0, [1, 2]);").unwrap();
        printer.remember("cat.rotate(0.5, 10);");
        printer.remember(":undo");
        add_page_lines(&printer, &mut history);
        add_page_lines(&printer, &mut history);
        let entries: Vec<String> = (0..history.len())
            .map(|i| {
                let found = history.get(i, SearchDirection::Forward).unwrap().unwrap();
                found.entry.into_owned()
            })
            .collect();
        assert_eq!(
            entries,
            ["cat.at(0, [1, 2]);", "cat.rotate(0.5, 10);", ":undo"]
        );
    }
}
