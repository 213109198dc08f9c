//! One page's queue of outgoing messages, with a wake-up: takes a bound and gives a sender
//! (kept by the [`Hub`](super::hub::Hub)) whose every message also wakes the page's thread,
//! and the queue that thread drains, which waits until the page's socket has input or a
//! message is queued. An idle page's thread so sleeps until there is something to do,
//! instead of looking every few milliseconds, and a frame for it leaves at once.
//!
//! On Unix the wake-up is one end of a socket pair, polled beside the page's socket; on
//! other systems the wait returns at once and the thread looks again after its socket's
//! read timeout, as a plain polling loop would.

use std::net::TcpStream;
use std::ops::Deref;
use std::sync::mpsc::{Receiver, SyncSender, TrySendError};
use std::time::Duration;

/// The sending half: queues a message for the page and wakes its thread.
pub struct PageSender<T> {
    tx: SyncSender<T>,
    wake: platform::Waker,
}

// Derived, it would ask `T: Clone`, which a sender does not need.
impl<T> Clone for PageSender<T> {
    fn clone(&self) -> Self {
        PageSender {
            tx: self.tx.clone(),
            wake: self.wake.clone(),
        }
    }
}

impl<T> PageSender<T> {
    /// Queues `message` unless the queue is full, then wakes the page.
    pub fn try_send(&self, message: T) -> Result<(), TrySendError<T>> {
        self.tx.try_send(message)?;
        self.wake.wake();
        Ok(())
    }
}

/// The receiving half: the page's queue, and a wait for the page's socket or the queue.
pub struct PageQueue<T> {
    rx: Receiver<T>,
    wait: platform::Waiter,
}

impl<T> Deref for PageQueue<T> {
    type Target = Receiver<T>;

    fn deref(&self) -> &Receiver<T> {
        &self.rx
    }
}

impl<T> PageQueue<T> {
    /// Sleeps until `socket` has input (or closed), a message was queued, or `limit` passed;
    /// whether the socket may have input (always true where the wait cannot tell).
    pub fn wait(&self, socket: &TcpStream, limit: Duration) -> bool {
        self.wait.wait(socket, limit)
    }
}

/// A page's queue of at most `bound` messages.
pub fn page_channel<T>(bound: usize) -> std::io::Result<(PageSender<T>, PageQueue<T>)> {
    let (tx, rx) = std::sync::mpsc::sync_channel(bound);
    let (wake, wait) = platform::pair()?;
    Ok((PageSender { tx, wake }, PageQueue { rx, wait }))
}

#[cfg(unix)]
mod platform {
    use std::io::{Read, Write};
    use std::net::TcpStream;
    use std::os::unix::net::UnixStream;
    use std::sync::Arc;
    use std::time::Duration;

    use rustix::event::{poll, PollFd, PollFlags, Timespec};

    /// The writing end: a byte written makes the reading end readable. Writes never block
    /// (a full pair already holds a wake-up).
    #[derive(Clone)]
    pub struct Waker(Arc<UnixStream>);

    pub struct Waiter(UnixStream);

    pub fn pair() -> std::io::Result<(Waker, Waiter)> {
        let (write, read) = UnixStream::pair()?;
        write.set_nonblocking(true)?;
        read.set_nonblocking(true)?;
        Ok((Waker(Arc::new(write)), Waiter(read)))
    }

    impl Waker {
        pub fn wake(&self) {
            let _ = (&*self.0).write(&[1]);
        }
    }

    impl Waiter {
        pub fn wait(&self, socket: &TcpStream, limit: Duration) -> bool {
            let timeout = Timespec::try_from(limit).ok();
            let mut fds = [
                PollFd::new(socket, PollFlags::IN),
                PollFd::new(&self.0, PollFlags::IN),
            ];
            if poll(&mut fds, timeout.as_ref()).is_err() {
                // Interrupted or failed: the caller reads (with its timeout) and comes back.
                return true;
            }
            let input = !fds[0].revents().is_empty();
            // Every wake-up so far is seen: the queue is drained after this returns.
            let mut sink = [0u8; 64];
            while matches!((&self.0).read(&mut sink), Ok(n) if n > 0) {}
            input
        }
    }
}

#[cfg(not(unix))]
mod platform {
    use std::net::TcpStream;
    use std::time::Duration;

    #[derive(Clone)]
    pub struct Waker;

    pub struct Waiter;

    pub fn pair() -> std::io::Result<(Waker, Waiter)> {
        Ok((Waker, Waiter))
    }

    impl Waker {
        pub fn wake(&self) {}
    }

    impl Waiter {
        pub fn wait(&self, _socket: &TcpStream, _limit: Duration) -> bool {
            true
        }
    }
}
