//! `--watch`: takes the shared session and gives a thread that polls the loaded scene file
//! and the modules its `import` lines name (twice a second, by modification time and size)
//! and reloads the scene when one changes — only when the session has no unsaved edits;
//! otherwise it says why not. The playhead is kept.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime};

use super::lock;
use crate::cli::repl::Session;

const POLL: Duration = Duration::from_millis(500);

type Stamp = Vec<(PathBuf, Option<(SystemTime, u64)>)>;

/// Starts the watching thread; the files as they are now are the baseline.
pub fn watch(session: Arc<Mutex<Session>>) {
    let mut last = stamp(&session);
    let spawned = std::thread::Builder::new()
        .name("view-watch".into())
        .spawn(move || loop {
            std::thread::sleep(POLL);
            let now = stamp(&session);
            let changed = last != now && same_files(&last, &now);
            last = now;
            if changed {
                lock(&session).watch_reload();
                last = stamp(&session);
            }
        });
    if let Err(error) = spawned {
        eprintln!("warning: --watch is off: {error}");
    }
}

fn stamp(session: &Mutex<Session>) -> Stamp {
    let files = lock(session).watched_files();
    files
        .into_iter()
        .map(|f| {
            let meta = std::fs::metadata(&f).ok();
            let stamp = meta.and_then(|m| Some((m.modified().ok()?, m.len())));
            (f, stamp)
        })
        .collect()
}

/// Whether two stamps list the same files (a `:load` of another file is no change on disk).
fn same_files(a: &Stamp, b: &Stamp) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.0 == y.0)
}
