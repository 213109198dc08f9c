//! The scene memory budget: takes a measure of the bytes the process has allocated (set
//! once by the program, [`set_allocation_probe`]) and a budget, and gives, for each script
//! evaluation, the message to stop it with once what it allocated exceeds the budget. Rhai
//! checks each string, array and map against its own size limit, but not everything a
//! script holds at once (a map grown by `m[k] = v`, many values each within its limit):
//! the budget bounds their total, checked as the script runs (at every operation).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

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

/// What an evaluation may allocate beyond what the process held when it started.
#[derive(Clone, Debug)]
pub(super) struct MemoryBudget {
    limit: usize,
    baseline: Arc<AtomicUsize>,
}

impl MemoryBudget {
    pub(super) fn new(limit: usize) -> Self {
        MemoryBudget {
            limit,
            baseline: Arc::new(AtomicUsize::new(allocated().unwrap_or(0))),
        }
    }

    /// Starts counting an evaluation from what the process holds now.
    pub(super) fn start(&self) {
        if let Some(now) = allocated() {
            self.baseline.store(now, Ordering::Relaxed);
        }
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
