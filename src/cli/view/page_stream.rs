//! A page's connection as its WebSocket sees it: takes the accepted `TcpStream` and gives a
//! stream whose writes fail once a deadline the sender set has passed. tungstenite goes on
//! writing its buffer for as long as each write moves, and the socket's write timeout only
//! bounds one write, so a page reading a little now and then could hold a send, and its
//! thread, for as long as it liked; the deadline bounds the send as a whole.

use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::time::Instant;

/// A page's `TcpStream` with an optional deadline for writes.
pub struct PageStream {
    tcp: TcpStream,
    deadline: Option<Instant>,
}

impl PageStream {
    pub fn new(tcp: TcpStream) -> Self {
        PageStream {
            tcp,
            deadline: None,
        }
    }

    pub fn tcp(&self) -> &TcpStream {
        &self.tcp
    }

    pub fn tcp_mut(&mut self) -> &mut TcpStream {
        &mut self.tcp
    }

    /// Writes after `deadline` fail with [`io::ErrorKind::TimedOut`]; `None` lifts it.
    pub fn set_deadline(&mut self, deadline: Option<Instant>) {
        self.deadline = deadline;
    }
}

impl Read for PageStream {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.tcp.read(buf)
    }
}

impl Write for PageStream {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            return Err(io::Error::new(
                io::ErrorKind::TimedOut,
                "the page did not take what was sent in time",
            ));
        }
        self.tcp.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.tcp.flush()
    }
}
