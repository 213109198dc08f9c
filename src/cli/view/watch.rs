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
            // Stamped before the reload reads the files: a write while it runs is either read
            // by it or seen by the next poll, never taken for the state just loaded.
            last = now;
            if !changed.is_empty() {
                reload(&changed);
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

#[cfg(test)]
mod tests {
    use std::sync::mpsc;

    use super::*;

    /// A file written again while its reload runs (an editor saving twice, a build step)
    /// is reloaded once more: the second write is not lost.
    #[test]
    fn a_write_during_a_reload_is_reloaded_too() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("scene.rhai");
        std::fs::write(&file, "one").unwrap();
        let (tx, calls) = mpsc::channel();
        let (watched, written) = (file.clone(), file.clone());
        watch(
            move || vec![watched.clone()],
            move |changed| {
                let text = std::fs::read_to_string(&written).unwrap();
                if text == "two" {
                    std::fs::write(&written, "three!").unwrap();
                }
                let _ = tx.send((changed.to_vec(), text));
            },
        );
        std::thread::sleep(POLL / 2);
        std::fs::write(&file, "two").unwrap();
        let wait = Duration::from_secs(10);
        let first = calls
            .recv_timeout(wait)
            .expect("the first write is reloaded");
        assert_eq!(first, (vec![file.clone()], "two".to_string()));
        let second = calls
            .recv_timeout(wait)
            .expect("the write during the reload is reloaded");
        assert_eq!(second, (vec![file], "three!".to_string()));
    }
}
