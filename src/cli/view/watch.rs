//! `--watch`: takes two callbacks, one giving the files to watch (the loaded scene file and
//! the modules its `import` lines name) and one reloading the scene, and gives a thread
//! that polls those files (twice a second, by modification time and size) and calls the
//! reload with the files that changed. What a reload does (refuse over unsaved edits, keep the
//! playhead) is the caller's: this file knows no session.

use std::path::PathBuf;
use std::time::{Duration, SystemTime};

const POLL: Duration = Duration::from_millis(500);

type Stamp = Vec<(PathBuf, Option<(SystemTime, u64)>)>;

/// Starts the watching thread; the files as they are now are the baseline.
pub fn watch(
    files: impl Fn() -> Vec<PathBuf> + Send + 'static,
    reload: impl Fn(&[PathBuf]) + Send + 'static,
) {
    let mut last = stamp(&files);
    let spawned = std::thread::Builder::new()
        .name("view-watch".into())
        .spawn(move || loop {
            std::thread::sleep(POLL);
            let now = stamp(&files);
            let changed: Vec<PathBuf> = match same_files(&last, &now) {
                true => (last.iter().zip(&now))
                    .filter(|(a, b)| a.1 != b.1)
                    .map(|(_, b)| b.0.clone())
                    .collect(),
                false => Vec::new(),
            };
            last = now;
            if !changed.is_empty() {
                reload(&changed);
                last = stamp(&files);
            }
        });
    if let Err(error) = spawned {
        eprint_line!("warning: --watch is off: {error}");
    }
}

fn stamp(files: &impl Fn() -> Vec<PathBuf>) -> Stamp {
    files()
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
