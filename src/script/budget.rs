//! The evaluation budget: takes a measure of the bytes the process has allocated (set once
//! by the program, [`set_allocation_probe`]), a memory budget and a time limit, and gives,
//! for each script evaluation, the message to stop it with once what it allocated exceeds
//! the budget or it has run past the limit. Rhai checks each string, array and map against
//! its own size limit, but not everything a script holds at once (a map grown by
//! `m[k] = v`, many values each within its limit): the budget bounds their total, checked
//! as the script runs (at every operation). Rhai's operation limit bounds the operations,
//! but not the size check after each one that changes a value, which walks the whole
//! value: growing a list by `push` in a loop takes time in the square of its length
//! (40,000 pairs: 5 s), so the time limit bounds that.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

static PROBE: OnceLock<fn() -> usize> = OnceLock::new();

/// Lets scene evaluation measure its memory: `probe` gives the bytes the process has
/// allocated now (a counting global allocator's figure). Without a probe only Rhai's
/// per-value size limits apply. The first call wins.
pub fn set_allocation_probe(probe: fn() -> usize) {
    let _ = PROBE.set(probe);
}

fn allocated() -> Option<usize> {
    PROBE.get().map(|probe| probe())
}

/// What an evaluation may allocate beyond what the process held when it started, and how
/// long it may run.
#[derive(Clone, Debug)]
pub(super) struct Budget {
    limit: usize,
    baseline: Arc<AtomicUsize>,
    time_limit: Duration,
    started: Arc<Mutex<Instant>>,
}

impl Budget {
    pub(super) fn new(limit: usize, time_limit: Duration) -> Self {
        Budget {
            limit,
            baseline: Arc::new(AtomicUsize::new(allocated().unwrap_or(0))),
            time_limit,
            started: Arc::new(Mutex::new(Instant::now())),
        }
    }

    /// Starts counting an evaluation from what the process holds now, and from now.
    pub(super) fn start(&self) {
        if let Some(now) = allocated() {
            self.baseline.store(now, Ordering::Relaxed);
        }
        *crate::util::lock(&self.started) = Instant::now();
    }

    /// The error message once the evaluation has run past the time limit; `operations` is
    /// Rhai's count so far, the clock being read every few thousand of them.
    pub(super) fn late(&self, operations: u64) -> Option<String> {
        if operations % 4096 != 0 || crate::util::lock(&self.started).elapsed() < self.time_limit {
            return None;
        }
        Some(format!(
            "the scene's evaluation ran for over {} s and is stopped (a list grown by `push` \
             in a loop takes time in the square of its length: make it at once, e.g. \
             `let a = []; a.pad(n, 0); a.map(|v, i| …)`)",
            self.time_limit.as_secs()
        ))
    }

    /// The error message once the evaluation holds more than the budget.
    pub(super) fn exceeded(&self) -> Option<String> {
        let now = allocated()?;
        let used = now.saturating_sub(self.baseline.load(Ordering::Relaxed));
        (used > self.limit).then(|| {
            format!(
                "the scene's data (strings, arrays, maps) exceeds the scene memory budget of {} MiB",
                self.limit >> 20
            )
        })
    }
}
