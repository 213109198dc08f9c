//! The REPL's live view (`lapclone repl --view`): takes the shared REPL session and gives a
//! page in the browser that shows its frame as it changes and turns pointer gestures into
//! structured edits, which the session writes as REPL lines (see docs/view.md). The server
//! knows the session and the renderer; nothing in the library knows the view.

mod edit;
mod http;
mod hub;
mod scene;
mod server;
mod watch;

use std::net::IpAddr;
use std::sync::{Arc, Mutex, MutexGuard};

pub use edit::{get_patch_call, Edit};
pub use hub::{Hub, SceneText};
pub use scene::Playhead;
pub use scene::{locate, scene_message};
pub use server::start;
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

/// A mutex whose holder panicked still guards consistent data here (each change is whole).
pub fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|p| p.into_inner())
}

/// Where lines printed for the view go while a prompt is up (rustyline's external printer).
pub type Printer = Arc<Mutex<Option<Box<dyn FnMut(String) + Send>>>>;

/// Opens `url` in the default browser with the desktop's opener program.
pub fn open_in_browser(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(windows) {
        "explorer"
    } else {
        "xdg-open"
    };
    let spawned = std::process::Command::new(opener)
        .arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn();
    if let Err(error) = spawned {
        eprintln!("warning: cannot open a browser ({opener}: {error}); open the URL above");
    }
}

/// A JSON text message `{"type": "error", "message": …}` for a page.
pub fn error_message(message: &str) -> String {
    serde_json::json!({ "type": "error", "message": message }).to_string()
}
