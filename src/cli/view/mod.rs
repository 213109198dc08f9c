//! The REPL's live view (`lapclone repl --view`): takes the shared REPL session and gives a
//! page in the browser that shows its frame as it changes and turns pointer gestures into
//! structured edits, which the session writes as REPL lines (see docs/view.md). The server
//! knows the session and the renderer; nothing in the library knows the view.

mod admit;
mod edit;
mod http;
mod hub;
mod open;
mod page_stream;
mod scene;
mod server;
mod wake;
mod watch;

use std::collections::VecDeque;
use std::net::IpAddr;
use std::sync::{Arc, Mutex};

pub use edit::Edit;
pub use hub::{Hub, SceneText};
pub use open::open_in_browser;
pub use scene::Playhead;
pub use scene::{locate, scene_message};
pub use server::{start, LiveSession};
pub use watch::watch;

/// `--view` and its options, part of `lapclone repl`'s arguments.
#[derive(clap::Args, Debug, Clone)]
pub struct ViewArgs {
    /// Serve a live view of the session in the browser (prints its URL with its token).
    #[arg(long)]
    pub view: bool,
    /// Port for the live view (default: a free one).
    #[arg(long, requires = "view")]
    pub port: Option<u16>,
    /// Also open the live view in the default browser.
    #[arg(long, requires = "view")]
    pub open: bool,
    /// Listen on this address instead of 127.0.0.1 (the page then reaches the network).
    #[arg(long, value_name = "ADDR", requires = "view")]
    pub bind: Option<IpAddr>,
    /// Reload the scene when its file (or a module it imports) changes on disk, if the
    /// session has no unsaved edits.
    #[arg(long, requires = "view")]
    pub watch: bool,
}

pub(crate) use crate::util::lock;

/// The terminal's side of the view while a prompt is up: shared by the session (which
/// prints page lines and hands them over) and the prompt's loop.
pub type Printer = Arc<Terminal>;

/// Prints one line above the prompt.
pub type PrintFn = Box<dyn FnMut(String) + Send>;

/// Lines a page ran that wait for the prompt's history, at most this many.
const MAX_WAITING_LINES: usize = 1000;

/// Where lines printed for the view go while a prompt is up (rustyline's external
/// printer), and the lines pages ran, waiting to join the prompt's history (rustyline's
/// history cannot change under a prompt that is up, so they join before the next one).
#[derive(Default)]
pub struct Terminal {
    print: Mutex<Option<PrintFn>>,
    history: Mutex<VecDeque<String>>,
}

impl Terminal {
    pub fn set_print(&self, print: PrintFn) {
        *lock(&self.print) = Some(print);
    }

    /// Prints `text` above the prompt; gives it back when there is no printer.
    pub fn print(&self, text: String) -> Option<String> {
        match lock(&self.print).as_mut() {
            Some(print) => {
                print(text);
                None
            }
            None => Some(text),
        }
    }

    /// Keeps a line a page ran for the history (the oldest go past the bound).
    pub fn remember(&self, line: &str) {
        let mut waiting = lock(&self.history);
        if waiting.len() == MAX_WAITING_LINES {
            waiting.pop_front();
        }
        waiting.push_back(line.to_string());
    }

    /// The lines waiting for the history, oldest first; none wait afterwards.
    pub fn take_history(&self) -> Vec<String> {
        lock(&self.history).drain(..).collect()
    }
}

/// A JSON text message `{"type": "error", "message": …}` for a page.
pub fn error_message(message: &str) -> String {
    serde_json::json!({ "type": "error", "message": message }).to_string()
}
