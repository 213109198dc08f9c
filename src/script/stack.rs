//! The stack scene code runs on: takes a closure that evaluates a scene (or clones, shows
//! or drops the values a REPL holds) and gives its result, run on a thread whose stack
//! holds the deepest value a scene can build within its limits.
//!
//! Rhai prints, compares, clones and drops a value by recursion, one frame per level of
//! nesting (about 1.7 kB to print one). A loop of `m = [m]` nests without bound but for
//! the time limit: Rhai's size check walks the whole value after each step, so a scene
//! reaches about 37,000 levels in its 60 s here, which printed would need some 60 MB of
//! stack where a main thread has 8 MB and a spawned one 2 MB. [`SCENE_STACK`] gives four
//! times that depth; the memory is only reserved, and touched as deep as a scene goes.

use std::cell::Cell;

/// Bytes of stack a scene's thread has.
pub const SCENE_STACK: usize = 256 << 20;

thread_local! {
    /// Whether this thread was started with [`SCENE_STACK`].
    static ON_SCENE_STACK: Cell<bool> = const { Cell::new(false) };
}

/// Runs `work` on a thread with [`SCENE_STACK`] (this one when it has it), waiting for it;
/// a panic in `work` goes on in the caller. Where no such thread can be started (no
/// address space left), `work` runs here.
pub fn on_scene_stack<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    if ON_SCENE_STACK.with(Cell::get) {
        return work();
    }
    let mut work = Some(work);
    let joined = std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .name("lapclone-scene".into())
            .stack_size(SCENE_STACK)
            .spawn_scoped(scope, || {
                ON_SCENE_STACK.with(|on| on.set(true));
                // invariant: taken once, by this thread only.
                (work.take().expect("work not yet run"))()
            });
        spawned.ok().map(|thread| thread.join())
    });
    match joined {
        Some(Ok(result)) => result,
        Some(Err(panic)) => std::panic::resume_unwind(panic),
        // invariant: the spawn failed, so the closure never ran and is still here.
        None => (work.take().expect("work not run by a thread"))(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn work_runs_once_on_a_big_stack_and_nested_calls_stay_on_it() {
        let outer = std::thread::current().id();
        let (inner, nested) = on_scene_stack(|| {
            let inner = std::thread::current().id();
            (inner, on_scene_stack(|| std::thread::current().id()))
        });
        assert_ne!(inner, outer);
        assert_eq!(nested, inner);
        // Deeper recursion than a spawned thread's 2 MB stack allows.
        fn depth(n: u64) -> u64 {
            // A frame of half a kilobyte the optimiser cannot drop.
            let pad = std::hint::black_box([n; 64]);
            if n == 0 {
                0
            } else {
                1 + depth(n - 1) + pad[63] - n
            }
        }
        assert_eq!(on_scene_stack(|| depth(50_000)), 50_000);
    }
}
