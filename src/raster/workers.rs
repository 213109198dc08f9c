//! The raster's worker threads: takes a draw's parallel parts (closures over the draw's
//! borrowed buffers) and runs them on a pool of long-lived threads, one per core, started on
//! the first draw that asks for more than one thread; gives their results back to the draw.
//!
//! Why a pool rather than threads started per draw: a started thread costs 50–120 µs before
//! it runs, and when another program holds the other core (the browser painting the live
//! view) it waited a median 0.7 ms for it, while the caller could only wait at the join for
//! a thread that had not even begun. Here a part no worker has taken yet is run by the
//! thread that offered it ([`rayon_core::join`]), so a draw never waits for a thread that
//! has not started: with no free core it runs on one thread, as fast as a one-thread draw.

use std::sync::OnceLock;

use rayon_core::{ThreadPool, ThreadPoolBuilder};

/// The most threads one draw shades on, whatever a caller asks for, and the most the worker
/// pool starts: well above the cores shading can use.
pub const MAX_RASTER_THREADS: usize = 64;

/// The pool, started on first use; `None` when its threads could not be started, or in a
/// process forked after they were (it has none of them: Python's `multiprocessing` forks).
/// Every draw then runs on its caller's thread alone, with the same pixels.
fn pool() -> Option<&'static ThreadPool> {
    static POOL: OnceLock<(u32, Option<ThreadPool>)> = OnceLock::new();
    let start = || {
        let pool = ThreadPoolBuilder::new()
            .num_threads(crate::util::available_cores().clamp(1, MAX_RASTER_THREADS))
            .thread_name(|index| format!("lapclone-raster-{index}"))
            .build();
        (std::process::id(), pool.ok())
    };
    let (started_in, pool) = POOL.get_or_init(start);
    pool.as_ref().filter(|_| *started_in == std::process::id())
}

/// Runs `work` on a worker (inline when already on one, or when there is no pool), so the
/// parts it offers through [`both`] and [`copies`] can be taken back by the thread running
/// it. The calling thread waits meanwhile.
pub(crate) fn on_pool<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    match pool() {
        Some(pool) => pool.install(work),
        None => work(),
    }
}

/// Runs `a` here and offers `b` to a free worker, running `b` here too when none took it.
pub(crate) fn both<A, B>(a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B + Send) -> (A, B)
where
    A: Send,
    B: Send,
{
    match on_a_worker() {
        true => rayon_core::join(a, b),
        false => (a(), b()),
    }
}

/// Runs `task` `count` times, at once where workers are free (each copy offered as in
/// [`both`]), and sums what the copies give. The copies share their work through a queue
/// (`Bands`), so a copy nobody took in time finds it done.
pub(crate) fn copies(count: usize, task: &(impl Fn() -> (usize, usize) + Sync)) -> (usize, usize) {
    if count <= 1 || !on_a_worker() {
        return task();
    }
    let half = count / 2;
    let (a, b) = rayon_core::join(|| copies(half, task), || copies(count - half, task));
    (a.0 + b.0, a.1 + b.1)
}

/// Whether this thread is one of the pool's, whose offered parts other workers can take.
fn on_a_worker() -> bool {
    pool().is_some_and(|pool| pool.current_thread_index().is_some())
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;

    #[test]
    fn every_copy_runs_once_and_their_results_add_up() {
        for count in [1, 2, 3, 7, 64] {
            let runs = AtomicUsize::new(0);
            let task = || {
                let n = runs.fetch_add(1, Ordering::Relaxed);
                (1, n)
            };
            let (ones, _) = on_pool(|| copies(count, &task));
            assert_eq!((ones, runs.load(Ordering::Relaxed)), (count, count));
        }
    }

    #[test]
    fn both_parts_run_on_and_off_the_pool() {
        let on = on_pool(|| both(on_a_worker, || 2));
        assert_eq!(on, (pool().is_some(), 2));
        assert_eq!(both(|| 1, || 2), (1, 2));
    }
}
