//! Which connections the live view serves: takes each accepted connection and gives it a
//! place while its request is read and answered (at most [`MAX_PENDING`]; a connection
//! past that ends the oldest one still waiting, so connections that send nothing cannot
//! lock a page out) and, once its token is checked, a page's place (at most [`MAX_PAGES`];
//! past that it is refused with why). The thread accepting connections never waits on a
//! client; it waits only for the threads of ended connections to finish, so that at most
//! [`MAX_THREADS`] connection threads run ([`ConnectionThreads`]).

use std::collections::VecDeque;
use std::net::{Shutdown, TcpStream};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use super::lock;

/// Pages served at once.
pub const MAX_PAGES: usize = 32;
/// Connections whose request is being read or answered at once.
pub const MAX_PENDING: usize = 32;
/// Connection threads at once: each waiting connection's and each page's, and a few whose
/// connection was ended and which are finishing.
const MAX_THREADS: usize = MAX_PENDING + MAX_PAGES + 8;
/// How long the accepting thread waits for a finishing connection thread before it looks
/// again.
const THREAD_WAIT: Duration = Duration::from_millis(1);
/// How long making room waits for the ended connection's thread to close it.
const ROOM_WAIT: Duration = Duration::from_millis(10);
/// How many times room is made for one thing that needs file descriptors.
const ROOM_TRIES: usize = 8;

/// The places the server gives out.
#[derive(Default)]
pub struct Admission {
    /// Connections not yet a page, oldest first: an id and a handle to end it by.
    pending: Mutex<VecDeque<(u64, TcpStream)>>,
    next: AtomicU64,
    pages: AtomicUsize,
}

/// A connection's place while its request is read and answered; given back when dropped.
pub struct Pending {
    admission: Arc<Admission>,
    id: u64,
}

/// A page's place; given back when dropped.
pub struct PagePlace(Arc<Admission>);

impl Admission {
    /// Gives `stream` a place, ending the oldest waiting connection when all are taken (a
    /// browser sends its request as soon as it connects; one that has sent nothing by the
    /// time [`MAX_PENDING`] more arrived is the one to go). `None`: `stream` cannot be
    /// watched and is not served.
    pub fn arrive(self: &Arc<Self>, stream: &TcpStream) -> Option<Pending> {
        let handle = stream.try_clone().ok()?;
        let id = self.next.fetch_add(1, Ordering::Relaxed);
        let mut pending = lock(&self.pending);
        while pending.len() >= MAX_PENDING {
            end(pending.pop_front());
        }
        pending.push_back((id, handle));
        Some(Pending {
            admission: self.clone(),
            id,
        })
    }

    /// Ends the oldest waiting connection, if one is, then waits [`ROOM_WAIT`] for its
    /// thread to close it: room when the process is out of file descriptors (accepting then
    /// fails until one closes, and would spin).
    pub fn make_room(&self) {
        end(lock(&self.pending).pop_front());
        std::thread::sleep(ROOM_WAIT);
    }

    /// Runs `open`, which needs file descriptors, until it gives something, making room
    /// after each failure, at most [`ROOM_TRIES`] times.
    pub fn with_room<T>(&self, mut open: impl FnMut() -> Option<T>) -> Option<T> {
        for _ in 0..ROOM_TRIES {
            if let Some(opened) = open() {
                return Some(opened);
            }
            self.make_room();
        }
        open()
    }

    /// Whether every page's place is taken.
    pub fn pages_full(&self) -> bool {
        self.pages.load(Ordering::SeqCst) >= MAX_PAGES
    }
}

/// The connection threads: each is joined once finished, so that at most [`MAX_THREADS`]
/// system threads run (a thread that has given back its places is still ending for a
/// moment, and a flood of connections would otherwise outrun them).
#[derive(Default)]
pub struct ConnectionThreads {
    running: Vec<JoinHandle<()>>,
}

impl ConnectionThreads {
    /// Starts `serve` on a thread of its own, once fewer than [`MAX_THREADS`] run (waiting
    /// for the threads of ended connections to finish).
    pub fn spawn(&mut self, serve: impl FnOnce() + Send + 'static) -> std::io::Result<()> {
        loop {
            let (done, running): (Vec<_>, Vec<_>) =
                self.running.drain(..).partition(|t| t.is_finished());
            self.running = running;
            // Each join returns once its system thread is gone.
            done.into_iter().for_each(|t| drop(t.join()));
            if self.running.len() < MAX_THREADS {
                break;
            }
            std::thread::sleep(THREAD_WAIT);
        }
        let thread = std::thread::Builder::new().name("view-page".into());
        self.running.push(thread.spawn(serve)?);
        Ok(())
    }
}

/// Ends a waiting connection: its thread's read or write then fails at once, and the thread
/// ends.
fn end(waiting: Option<(u64, TcpStream)>) {
    if let Some((_, stream)) = waiting {
        let _ = stream.shutdown(Shutdown::Both);
    }
}

impl Pending {
    /// Whether every page's place is taken (a page loaded now could not connect).
    pub fn pages_full(&self) -> bool {
        self.admission.pages_full()
    }

    /// Turns this connection's place into a page's. `Err(Some(self))`: every page's place
    /// is taken, and the connection keeps its waiting place while it is refused (so a flood
    /// of refused pages stays within [`MAX_PENDING`]); `Err(None)`: the connection was
    /// ended meanwhile (to make room).
    pub fn into_page(self) -> Result<PagePlace, Option<Pending>> {
        let pages = &self.admission.pages;
        let taken = pages.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
            (n < MAX_PAGES).then_some(n + 1)
        });
        if taken.is_err() {
            return Err(Some(self));
        }
        let place = PagePlace(self.admission.clone());
        match self.forget() {
            true => Ok(place),
            false => Err(None),
        }
    }

    /// Takes this connection off the waiting list; false when it was already taken off.
    fn forget(&self) -> bool {
        let mut pending = lock(&self.admission.pending);
        let at = pending.iter().position(|(id, _)| *id == self.id);
        at.and_then(|at| pending.remove(at)).is_some()
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        self.forget();
    }
}

impl Drop for PagePlace {
    fn drop(&mut self) {
        self.0.pages.fetch_sub(1, Ordering::SeqCst);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;
    use std::net::TcpListener;

    fn connection(listener: &TcpListener) -> (TcpStream, TcpStream) {
        let client = TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (server, _) = listener.accept().unwrap();
        (client, server)
    }

    #[test]
    fn a_new_connection_past_the_limit_ends_the_oldest_waiting_one() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let admission = Arc::new(Admission::default());
        let mut held = Vec::new();
        for _ in 0..MAX_PENDING + 3 {
            let (client, server) = connection(&listener);
            let place = admission.arrive(&server).unwrap();
            held.push((client, server, place));
        }
        assert_eq!(lock(&admission.pending).len(), MAX_PENDING);
        // The three oldest were ended: their reads see the end at once; the others wait.
        for (i, (_, server, _)) in held.iter_mut().enumerate() {
            server.set_nonblocking(true).unwrap();
            let read = server.read(&mut [0u8; 1]);
            assert_eq!(matches!(read, Ok(0)), i < 3, "connection {i}: {read:?}");
        }
        for (_, _, place) in held.drain(..3) {
            assert!(matches!(place.into_page(), Err(None)));
        }
        let pages: Vec<PagePlace> = held
            .drain(..)
            .map(|(_, _, place)| place.into_page().ok().unwrap())
            .collect();
        assert!(admission.pages_full());
        assert!(lock(&admission.pending).is_empty());
        let (_client, server) = connection(&listener);
        let late = admission.arrive(&server).unwrap();
        // Refused, it keeps its waiting place until it is dropped.
        let Err(Some(late)) = late.into_page() else {
            panic!("a 33rd page was given a place");
        };
        assert_eq!(lock(&admission.pending).len(), 1);
        drop(late);
        assert!(lock(&admission.pending).is_empty());
        drop(pages);
        assert!(!admission.pages_full());
    }
}
