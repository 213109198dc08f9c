//! A helper thread kept for each thread that draws: takes two closures, runs one on the
//! helper thread and the other on the calling thread, and gives both results once both are
//! done — what `std::thread::scope` with one spawn does, without the spawn. One per drawing
//! thread (not per patch), so a scene's layers share one, and only one spins at a time.
//!
//! Why: a frame has two parallel sections (the preparation beside the membrane solve, then
//! the bands), and a replay one. On the 2-core machines a scoped spawn took 50–100 µs to
//! start running and its join 25–80 µs more, about 0.3 ms of a 4 ms deform frame (measured
//! with temporary timers; a standalone test: spawn 52–73 µs + join 23–36 µs, a sleeping
//! thread woken by a condition variable 40–48 µs, a spinning one 2 µs). So the helper spins
//! for [`AWAKE`] after each task, long enough to catch the next section and the next frame of
//! an interactive loop, and then sleeps on a condition variable.
//!
//! Soundness: the closure run on the helper borrows from the caller's stack, so its lifetime
//! is erased while it is posted. [`Helper::join`] does not return, or unwind, before the
//! helper has finished with it: a guard created before the caller's own closure runs waits
//! for the helper in its `drop`. A panic on the helper is caught there and resumed on the
//! caller after both are done. Whatever the helper's closure waits for must be released by
//! the caller's closure also when that one fails (the callers' `Abandon` and `CancelOnDrop`
//! guards), exactly as with a scoped thread.

use std::any::Any;
use std::cell::{RefCell, UnsafeCell};
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::util::{lock, SpinWait};

/// How long the helper keeps spinning for its next task before it sleeps. Covers the gap
/// between a frame's sections and, in an interactive loop, between frames (restoring the
/// canvas and a deformation step take well under a millisecond).
pub(crate) const AWAKE: Duration = Duration::from_millis(1);

/// Spins between two looks at the clock (and a `yield_now`).
const SPINS_PER_CHECK: u32 = 64;

const IDLE: u8 = 0;
const POSTED: u8 = 1;
const DONE: u8 = 2;
const STOP: u8 = 3;

/// A posted task, its lifetime erased (see the module doc).
type Task = dyn Fn() + Sync;

struct Shared {
    state: AtomicU8,
    /// Written by the owner only while the state is not `POSTED` (the helper does not read it
    /// then); read by the helper only after it saw `POSTED`, which the owner stores after it.
    task: UnsafeCell<Option<*const Task>>,
    panic: Mutex<Option<Box<dyn Any + Send>>>,
    /// Whether the helper sleeps (it holds this lock while it decides to).
    sleeping: Mutex<bool>,
    wake: Condvar,
}

// SAFETY: `task` is only accessed under the protocol documented on it; everything else is
// `Sync` already.
unsafe impl Sync for Shared {}
// SAFETY: the raw task pointer is only dereferenced by the helper while the owner keeps its
// target alive (see the module doc).
unsafe impl Send for Shared {}

struct Running {
    shared: Arc<Shared>,
    thread: JoinHandle<()>,
}

thread_local! {
    static HELPER: RefCell<Helper> = RefCell::new(Helper::default());
}

/// [`Helper::join`] with this thread's helper. A join inside another (or one during thread
/// teardown) runs `on_helper` on a scoped thread instead.
pub(crate) fn join<A, RA, B, RB>(on_helper: A, here: B) -> (RA, RB)
where
    A: FnOnce() -> RA + Send,
    RA: Send,
    B: FnOnce() -> RB,
{
    let mut pair = Some((on_helper, here));
    let pooled = HELPER.try_with(|cell| {
        let mut helper = cell.try_borrow_mut().ok()?;
        let (on_helper, here) = pair.take()?;
        Some(helper.join(on_helper, here))
    });
    if let Ok(Some(results)) = pooled {
        return results;
    }
    // invariant: the pair is only taken right before `Helper::join`, whose results returned.
    let (on_helper, here) = pair.take().expect("the closures were not run");
    std::thread::scope(|scope| {
        let helper = scope.spawn(on_helper);
        let rb = here();
        let ra = helper.join().unwrap_or_else(|e| resume_unwind(e));
        (ra, rb)
    })
}

/// A helper thread, started on first use and stopped when dropped.
pub(crate) struct Helper {
    running: Option<Running>,
    /// How long it spins after a task ([`AWAKE`]; tests use 0 to exercise the sleep).
    awake: Duration,
}

impl Default for Helper {
    fn default() -> Helper {
        Helper {
            running: None,
            awake: AWAKE,
        }
    }
}

impl Helper {
    /// Runs `on_helper` on the helper thread and `here` on this one; gives both results once
    /// both have finished. A panic in either resumes here once both are done (the helper's
    /// first). If no helper thread can be started, runs `here`, then `on_helper`, on this
    /// thread.
    pub fn join<A, RA, B, RB>(&mut self, on_helper: A, here: B) -> (RA, RB)
    where
        A: FnOnce() -> RA + Send,
        RA: Send,
        B: FnOnce() -> RB,
    {
        let Some(shared) = self.shared() else {
            let rb = here();
            return (on_helper(), rb);
        };
        let job = Mutex::new(Some(on_helper));
        let result = Mutex::new(None);
        let task = || {
            if let Some(job) = lock(&job).take() {
                *lock(&result) = Some(job());
            }
        };
        let task: &(dyn Fn() + Sync + '_) = &task;
        // SAFETY: only the lifetime changes; `finish` (dropped below, or while `here`
        // unwinds) waits until the helper is done with `task` and everything it borrows.
        let task = unsafe { std::mem::transmute::<&(dyn Fn() + Sync + '_), &'static Task>(task) };
        // SAFETY: the state is not POSTED (the last join waited for DONE), so the helper
        // does not read the slot now.
        unsafe { *shared.task.get() = Some(task as *const Task) };
        post(shared);
        let finish = Finish(shared);
        let rb = here();
        drop(finish);
        if let Some(payload) = lock(&shared.panic).take() {
            resume_unwind(payload);
        }
        let ra = result.into_inner().unwrap_or_else(PoisonError::into_inner);
        // invariant: the helper ran the job (DONE without a panic means `task` completed).
        (ra.expect("the helper ran the job"), rb)
    }

    /// The running helper's shared state, starting the thread if needed.
    fn shared(&mut self) -> Option<&Shared> {
        if self.running.is_none() {
            let shared = Arc::new(Shared {
                state: AtomicU8::new(IDLE),
                task: UnsafeCell::new(None),
                panic: Mutex::new(None),
                sleeping: Mutex::new(false),
                wake: Condvar::new(),
            });
            let served = Arc::clone(&shared);
            let awake = self.awake;
            let thread = std::thread::Builder::new()
                .name("lapclone-raster".into())
                .spawn(move || serve(&served, awake))
                .ok()?;
            self.running = Some(Running { shared, thread });
        }
        self.running.as_ref().map(|r| &*r.shared)
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        if let Some(running) = self.running.take() {
            running.shared.state.store(STOP, Ordering::Release);
            wake(&running.shared);
            // A helper panic was caught and resumed by its join already.
            let _ = running.thread.join();
        }
    }
}

/// Publishes the task in the slot and wakes the helper if it sleeps.
fn post(shared: &Shared) {
    shared.state.store(POSTED, Ordering::Release);
    wake(shared);
}

fn wake(shared: &Shared) {
    // Taking the lock orders this with the helper's decision to sleep: either it sees the
    // new state before it waits, or it is waiting and gets the notification.
    if *lock(&shared.sleeping) {
        shared.wake.notify_one();
    }
}

/// Waits, also while unwinding, until the helper has finished the posted task.
struct Finish<'a>(&'a Shared);

impl Drop for Finish<'_> {
    fn drop(&mut self) {
        let mut wait = SpinWait::default();
        while self.0.state.load(Ordering::Acquire) != DONE {
            wait.pause();
        }
        // SAFETY: DONE: the helper no longer reads the slot.
        unsafe { *self.0.task.get() = None };
    }
}

/// The helper thread: runs each posted task, then waits for the next.
fn serve(shared: &Shared, awake: Duration) {
    while next_post(shared, awake) == POSTED {
        // SAFETY: POSTED: the owner wrote the slot before, and keeps the task alive until it
        // sees DONE.
        let task = unsafe { *shared.task.get() };
        let ran = catch_unwind(AssertUnwindSafe(|| {
            if let Some(task) = task {
                // SAFETY: as above.
                unsafe { (*task)() }
            }
        }));
        if let Err(payload) = ran {
            *lock(&shared.panic) = Some(payload);
        }
        shared.state.store(DONE, Ordering::Release);
    }
}

/// Spins for `awake`, then sleeps, until a task is posted or the helper is stopped; gives
/// which.
fn next_post(shared: &Shared, awake: Duration) -> u8 {
    let posted = || match shared.state.load(Ordering::Acquire) {
        state @ (POSTED | STOP) => Some(state),
        _ => None,
    };
    let since = Instant::now();
    while since.elapsed() < awake {
        for _ in 0..SPINS_PER_CHECK {
            if let Some(state) = posted() {
                return state;
            }
            std::hint::spin_loop();
        }
        // Let a runnable thread of ours (or anyone's) have this core meanwhile.
        std::thread::yield_now();
    }
    let mut sleeping = lock(&shared.sleeping);
    loop {
        if let Some(state) = posted() {
            *sleeping = false;
            return state;
        }
        *sleeping = true;
        sleeping = shared
            .wake
            .wait(sleeping)
            .unwrap_or_else(PoisonError::into_inner);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    #[test]
    fn both_closures_run_and_give_their_results() {
        let mut helper = Helper::default();
        let mut data = vec![1, 2, 3];
        for round in 0..50 {
            let (left, right) = data.split_at_mut(1);
            let (a, b) = helper.join(
                || {
                    left[0] += round;
                    left[0]
                },
                || {
                    right[0] += 1;
                    right[0]
                },
            );
            assert_eq!((a, b), (data[0], data[1]));
        }
        assert_eq!(data, vec![1 + (0..50).sum::<i32>(), 52, 3]);
    }

    #[test]
    fn the_helper_runs_on_another_thread_and_both_overlap() {
        let mut helper = Helper::default();
        let here = std::thread::current().id();
        let arrived = AtomicUsize::new(0);
        // Each side waits for the other to arrive: this finishes only if both run at once.
        let meet = || {
            arrived.fetch_add(1, Ordering::SeqCst);
            while arrived.load(Ordering::SeqCst) < 2 {
                std::hint::spin_loop();
            }
            std::thread::current().id()
        };
        let (there, mine) = helper.join(meet, meet);
        assert_ne!(there, here);
        assert_eq!(mine, here);
    }

    #[test]
    fn a_join_inside_a_join_runs_on_a_scoped_thread() {
        let (outer, (inner_there, inner_here)) = join(
            || 1,
            || {
                join(
                    || std::thread::current().id(),
                    || std::thread::current().id(),
                )
            },
        );
        assert_eq!(outer, 1);
        assert_ne!(inner_there, inner_here);
    }

    #[test]
    fn a_helper_that_sleeps_after_every_task_still_wakes_for_each() {
        let mut helper = Helper {
            running: None,
            awake: Duration::ZERO,
        };
        for k in 0..200 {
            assert_eq!(helper.join(|| k, || k + 1), (k, k + 1));
        }
    }

    #[test]
    fn a_panic_on_either_side_resumes_after_both_are_done_and_the_helper_stays_usable() {
        let mut helper = Helper::default();
        let finished = AtomicUsize::new(0);
        let caught = catch_unwind(AssertUnwindSafe(|| {
            helper.join(
                || panic!("helper side"),
                || finished.fetch_add(1, Ordering::SeqCst),
            )
        }));
        assert!(caught.is_err());
        assert_eq!(finished.load(Ordering::SeqCst), 1);
        let panicking = AtomicUsize::new(0);
        let caught = catch_unwind(AssertUnwindSafe(|| {
            helper.join(
                || {
                    // Finish only once the caller is on its way out: its unwinding must
                    // still wait for this side before the borrowed counters go away.
                    while panicking.load(Ordering::SeqCst) == 0 {
                        std::hint::spin_loop();
                    }
                    finished.fetch_add(1, Ordering::SeqCst)
                },
                || {
                    panicking.store(1, Ordering::SeqCst);
                    panic!("caller side")
                },
            )
        }));
        assert!(caught.is_err());
        assert_eq!(finished.load(Ordering::SeqCst), 2);
        assert_eq!(helper.join(|| 5, || 6), (5, 6));
    }
}
