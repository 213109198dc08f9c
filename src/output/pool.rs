//! The worker threads of the frame writers: takes jobs and, per thread, a handler built on
//! that thread; gives each job to whichever worker is free, keeps the first error a handler
//! returns and skips the jobs after it (the queue still drains, so a sender never blocks on
//! a failed pool). Results come back in whatever order the workers finish: a writer that
//! needs them in order puts them back in order itself.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use crate::util::lock;

/// The first error any worker reported, and whether there was one (kept once it is taken).
struct Failure<E> {
    error: Mutex<Option<E>>,
    failed: AtomicBool,
}

impl<E> Failure<E> {
    fn record(&self, error: E) {
        lock(&self.error).get_or_insert(error);
        self.failed.store(true, Ordering::Relaxed);
    }
}

pub(super) struct WorkerPool<J, E> {
    sender: Option<SyncSender<J>>,
    workers: Vec<JoinHandle<()>>,
    failure: Arc<Failure<E>>,
}

impl<J: Send + 'static, E: Send + 'static> WorkerPool<J, E> {
    /// Starts `threads` workers (at least 1); each calls `make` once, on its own thread, for
    /// its handler. At most `threads` jobs wait in the queue.
    pub(super) fn new<M, H>(threads: usize, make: M) -> Self
    where
        M: Fn() -> H + Clone + Send + 'static,
        H: FnMut(J) -> Result<(), E>,
    {
        let (sender, receiver) = sync_channel::<J>(threads.max(1));
        let receiver = Arc::new(Mutex::new(receiver));
        let failure = Arc::new(Failure {
            error: Mutex::new(None),
            failed: AtomicBool::new(false),
        });
        let workers = (0..threads.max(1))
            .map(|_| {
                let (receiver, failure, make) = (receiver.clone(), failure.clone(), make.clone());
                std::thread::spawn(move || work(&receiver, &failure, make()))
            })
            .collect();
        WorkerPool {
            sender: Some(sender),
            workers,
            failure,
        }
    }
}

impl<J, E> WorkerPool<J, E> {
    /// Queues a job, blocking while the queue is full; gives it back once the pool is
    /// stopped or every worker has ended.
    pub(super) fn send(&self, job: J) -> Result<(), J> {
        match &self.sender {
            Some(sender) => sender.send(job).map_err(|e| e.0),
            None => Err(job),
        }
    }

    /// Whether a worker failed (also after its error was taken).
    pub(super) fn failed(&self) -> bool {
        self.failure.failed.load(Ordering::Relaxed)
    }

    /// The first error, once.
    pub(super) fn take_error(&self) -> Option<E> {
        lock(&self.failure.error).take()
    }

    /// Closes the queue and waits until the workers have finished it; a worker that
    /// panicked counts as the error `panicked()` (unless an error came first).
    pub(super) fn stop(&mut self, panicked: impl Fn() -> E) {
        self.sender = None;
        for worker in self.workers.drain(..) {
            if worker.join().is_err() {
                self.failure.record(panicked());
            }
        }
    }
}

impl<J, E> Drop for WorkerPool<J, E> {
    fn drop(&mut self) {
        self.sender = None;
        self.workers.drain(..).for_each(|w| drop(w.join()));
    }
}

fn work<J, E>(queue: &Mutex<Receiver<J>>, failure: &Failure<E>, mut handle: impl FnMut(J) -> Result<(), E>) {
    loop {
        // The queue's lock is released before the job runs, so the workers run at once.
        let job = lock(queue).recv();
        let Ok(job) = job else { return };
        if failure.failed.load(Ordering::Relaxed) {
            continue; // drain the queue without running it
        }
        if let Err(error) = handle(job) {
            failure.record(error);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::WorkerPool;
    use std::sync::mpsc::channel;

    #[test]
    fn every_job_runs_once_on_any_thread_count() {
        for threads in [1, 2, 5] {
            let (done, results) = channel::<u32>();
            let mut pool = WorkerPool::<u32, ()>::new(threads, move || {
                let done = done.clone();
                move |job| done.send(job).map_err(|_| ())
            });
            (0..50).for_each(|job| pool.send(job).unwrap());
            pool.stop(|| ());
            let mut seen: Vec<u32> = results.try_iter().collect();
            seen.sort();
            assert_eq!(seen, (0..50).collect::<Vec<_>>(), "{threads} threads");
            assert!(!pool.failed());
            assert_eq!(pool.send(7), Err(7), "a stopped pool refuses jobs");
        }
    }

    #[test]
    fn first_error_wins_and_later_jobs_are_skipped() {
        let (ran, runs) = channel::<u32>();
        let mut pool = WorkerPool::<u32, String>::new(1, move || {
            let ran = ran.clone();
            move |job| {
                ran.send(job).unwrap();
                (job < 3).then_some(()).ok_or(format!("job {job} failed"))
            }
        });
        (0..10).for_each(|job| pool.send(job).unwrap());
        pool.stop(|| "panicked".into());
        assert_eq!(runs.try_iter().collect::<Vec<_>>(), vec![0, 1, 2, 3]);
        assert_eq!(pool.take_error().as_deref(), Some("job 3 failed"));
        assert_eq!(pool.take_error(), None, "the error is given once");
        assert!(pool.failed(), "the pool stays failed after the error is taken");
    }

    #[test]
    fn a_panicking_worker_is_reported() {
        let mut pool = WorkerPool::<u32, String>::new(2, || {
            |job| {
                assert!(job != 1, "worker panics on job 1");
                Ok(())
            }
        });
        for job in 0..4 {
            let _ = pool.send(job);
        }
        pool.stop(|| "a worker panicked".into());
        assert_eq!(pool.take_error().as_deref(), Some("a worker panicked"));
    }
}
