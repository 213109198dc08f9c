//! The live view's server: takes the shared session, an address and a port, and gives a
//! listening server (its URL carries a fresh random token) that serves the page and one
//! WebSocket per page. Each page's messages are applied to the session in arrival order
//! (the session's lock orders pages and typed lines); replies and frames go back through
//! the [`Hub`]. Threads only: one accepting, one per connection.

use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::Context as _;
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::protocol::CloseFrame;
use tungstenite::{Message, WebSocket};

use super::admit::{Admission, ConnectionThreads};
use super::edit::{parse_request, Edit, Request};
use super::http::{accept, Accepted, Routes};
use super::hub::{Hub, Outgoing, PAGE_QUEUE};
use super::page_stream::PageStream;
use super::wake::{page_channel, PageQueue};
use super::{error_message, lock};

/// Where a page's thread cannot sleep on its socket and its queue at once (not Unix), how
/// long a socket read waits for input, which is how often frames are looked for there.
const POLL: Duration = Duration::from_millis(5);
/// The longest an idle page's thread sleeps before it looks again, woken or not.
const IDLE_WAIT: Duration = Duration::from_secs(1);
/// How long sending what is queued for a page may take before the page counts as gone.
const WRITE_TIMEOUT: Duration = Duration::from_secs(10);
/// The longest one write to a page's socket blocks before the deadline is looked at.
const WRITE_SLICE: Duration = Duration::from_millis(250);

const PAGE: &str = include_str!("page/index.html");
const SCRIPT: &str = include_str!("page/view.js");
const STYLE: &str = include_str!("page/view.css");

/// A running view server.
pub struct Server {
    pub url: String,
    pub addr: SocketAddr,
}

/// What a page may ask of the session it edits. The REPL's session implements it, so the view
/// never names the REPL that starts it.
pub trait LiveSession: Send {
    /// Publishes again (a page changed what it wants to be sent).
    fn view_publish(&mut self) -> Result<(), String>;
    /// Moves the playhead (no history).
    fn view_seek(&mut self, t: f64) -> Result<(), String>;
    /// The `located` reply for canvas point (x, y).
    fn view_locate(&self, x: f64, y: f64) -> String;
    /// Previews (`commit` false) or commits a page edit made against revision `rev`, keyed
    /// at `t` (the playhead the gesture began at) or, without it, at the session's playhead.
    fn view_edit(
        &mut self,
        rev: u64,
        commit: bool,
        edit: &Edit,
        t: Option<f64>,
    ) -> Result<(), String>;
    /// Escape: back to the committed scene's frame.
    fn view_cancel(&mut self) -> Result<(), String>;
    /// Ctrl+Z in a page.
    fn view_undo(&mut self) -> Result<(), String>;
    /// Ctrl+S in a page (confirmed there): `:save` to the loaded file.
    fn view_save(&mut self, rev: u64) -> Result<(), String>;
}

/// Binds `bind` (127.0.0.1 by default) on `port` (0: a free one) and serves the session.
pub fn start(
    bind: Option<IpAddr>,
    port: u16,
    session: Arc<Mutex<dyn LiveSession>>,
    hub: Arc<Hub>,
) -> anyhow::Result<Server> {
    let ip = bind.unwrap_or(IpAddr::V4(Ipv4Addr::LOCALHOST));
    let listener = TcpListener::bind((ip, port))
        .with_context(|| format!("cannot listen on {ip} port {port}"))?;
    let addr = listener
        .local_addr()
        .context("reading the view's address")?;
    let token = new_token()?;
    let mut hosts = vec![
        format!("127.0.0.1:{}", addr.port()),
        format!("localhost:{}", addr.port()),
        format!("[::1]:{}", addr.port()),
    ];
    // On every address the URL names the loopback one, which works here; another machine
    // puts one of this machine's addresses in its place.
    let shown = match ip {
        IpAddr::V6(v6) if v6.is_unspecified() => format!("[::1]:{}", addr.port()),
        IpAddr::V4(v4) if v4.is_unspecified() => format!("127.0.0.1:{}", addr.port()),
        IpAddr::V6(v6) => format!("[{v6}]:{}", addr.port()),
        IpAddr::V4(v4) => format!("{v4}:{}", addr.port()),
    };
    if !hosts.contains(&shown) {
        hosts.push(shown.clone());
    }
    let page = PAGE
        .replace("/*STYLE*/", STYLE)
        .replace("/*SCRIPT*/", SCRIPT);
    let routes = Arc::new(Routes {
        token: token.clone(),
        page,
        hosts,
        any_address_port: ip.is_unspecified().then_some(addr.port()),
    });
    let url = format!("http://{shown}/?token={token}");
    std::thread::Builder::new()
        .name("view-accept".into())
        .spawn(move || serve(listener, routes, session, hub))
        .context("starting the view server")?;
    Ok(Server { url, addr })
}

/// 128 random bits from the operating system, as 32 hex digits.
fn new_token() -> anyhow::Result<String> {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).map_err(|e| anyhow::anyhow!("no random token: {e}"))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

fn serve(
    listener: TcpListener,
    routes: Arc<Routes>,
    session: Arc<Mutex<dyn LiveSession>>,
    hub: Arc<Hub>,
) {
    let admission = Arc::new(Admission::default());
    let mut threads = ConnectionThreads::default();
    for stream in listener.incoming() {
        let stream = match stream {
            Ok(stream) => stream,
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionAborted => continue,
            Err(_) => {
                // Out of file descriptors, most likely: the error stays until one closes.
                admission.make_room();
                continue;
            }
        };
        let Some(place) = admission.with_room(|| admission.arrive(&stream)) else {
            continue;
        };
        let (routes, session, hub) = (routes.clone(), session.clone(), hub.clone());
        let admission = admission.clone();
        let spawned = threads.spawn(move || {
            if let Ok(Accepted::Socket(socket, _place)) = accept(stream, &routes, place) {
                page_loop(*socket, &session, &hub, &admission);
            }
        });
        if spawned.is_err() {
            eprint_line!("warning: the view cannot serve another page");
        }
    }
}

/// Serves one page until it closes: its messages in, frames and replies out. Its thread
/// sleeps until the page sends something or something is queued for it.
fn page_loop(
    mut socket: WebSocket<PageStream>,
    session: &Mutex<dyn LiveSession>,
    hub: &Hub,
    admission: &Admission,
) {
    // A page that stops reading fails the write after a while, instead of blocking its
    // connection (one of the server's few) for good.
    let stream = socket.get_ref().tcp();
    if stream.set_read_timeout(Some(POLL)).is_err()
        || stream.set_write_timeout(Some(WRITE_SLICE)).is_err()
    {
        return;
    }
    let _ = socket.get_ref().tcp().set_nodelay(true);
    let Some((tx, queue)) = admission.with_room(|| page_channel(PAGE_QUEUE).ok()) else {
        return;
    };
    let id = hub.connect(tx.clone());
    let reply = |m: String| {
        let _ = tx.try_send(Outgoing::Text(m.into()));
    };
    // Bytes that came with the handshake are already read from the socket, so the first
    // look for messages does not wait for the socket.
    let mut input = true;
    loop {
        if input && !read_messages(&mut socket, &queue, id, session, hub, &reply) {
            break;
        }
        if !flush(&mut socket, &queue) {
            break;
        }
        hub.catch_up(id);
        input = queue.wait(socket.get_ref().tcp(), IDLE_WAIT);
    }
    // A gesture never finished (the page closed mid-drag) is cancelled as Escape would be;
    // without a preview in progress the cancel changes nothing.
    if hub.disconnect(id) {
        let _ = lock(session).view_cancel();
    }
}

/// Reads and applies the page's messages until none is waiting, sending each one's
/// answers before the next is read; false once the page is gone.
fn read_messages(
    socket: &mut WebSocket<PageStream>,
    queue: &PageQueue<Outgoing>,
    id: u64,
    session: &Mutex<dyn LiveSession>,
    hub: &Hub,
    reply: &dyn Fn(String),
) -> bool {
    loop {
        match read_now(socket) {
            Ok(Message::Text(text)) => handle(text.as_str(), id, session, hub, reply),
            Ok(Message::Binary(_)) => reply(error_message("binary messages are not accepted")),
            Ok(Message::Close(_)) => {
                // Sends the close reply the protocol queued.
                let _ = socket.flush();
                return false;
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e)) if blocked(&e) => return true,
            Err(fault) => {
                if let Some((code, reason)) = close_code(&fault) {
                    let problem = format!("refused: {fault}; the page disconnects (reload it)");
                    close_for(socket, queue, (code, reason), &problem, reply);
                }
                return false;
            }
        }
        if !flush(socket, queue) {
            return false;
        }
    }
}

/// Reads the page's next message if it has come whole, never waiting for the rest of one
/// (tungstenite keeps the part read for the next call), so that what is queued for the
/// page goes out while it is still sending: the thread then sleeps on the socket and its
/// queue together. Where it cannot ([`PageQueue::wait`] returns at once), the read waits
/// up to [`POLL`] for input instead.
fn read_now(socket: &mut WebSocket<PageStream>) -> tungstenite::Result<Message> {
    if !cfg!(unix) {
        return socket.read();
    }
    // Writes keep blocking (up to their timeout): only this read must not wait.
    socket.get_ref().tcp().set_nonblocking(true)?;
    let read = socket.read();
    socket.get_ref().tcp().set_nonblocking(false)?;
    read
}

/// The close code and reason a page's fault is answered with; `None` when the page is
/// gone and there is no one to answer.
fn close_code(fault: &tungstenite::Error) -> Option<(CloseCode, &'static str)> {
    use tungstenite::error::ProtocolError;
    match fault {
        tungstenite::Error::Capacity(_) => Some((CloseCode::Size, "message too big")),
        tungstenite::Error::Utf8(_) => Some((CloseCode::Invalid, "text not UTF-8")),
        tungstenite::Error::Protocol(ProtocolError::ResetWithoutClosingHandshake) => None,
        tungstenite::Error::Protocol(_) => Some((CloseCode::Protocol, "protocol error")),
        _ => None,
    }
}

/// Answers a fault in what the page sent and closes its connection with `close`: the
/// rest of an oversized frame, or of a fragmented message, cannot be told from what the
/// page sends next, and a frame that breaks the protocol leaves nothing after it to trust,
/// so going on could apply part of a refused message.
fn close_for(
    socket: &mut WebSocket<PageStream>,
    queue: &PageQueue<Outgoing>,
    (code, reason): (CloseCode, &'static str),
    problem: &str,
    reply: &dyn Fn(String),
) {
    reply(error_message(problem));
    if flush(socket, queue) {
        let frame = CloseFrame {
            code,
            reason: reason.into(),
        };
        let _ = socket.close(Some(frame));
        let _ = socket.flush();
    }
    // The rest of the message may still be arriving: closing on it would reset the answer
    // away.
    super::http::close_gently(socket.get_mut().tcp_mut(), super::http::LINGER);
}

/// Sends what is queued for this page; false once the page is gone, or has not taken it
/// within [`WRITE_TIMEOUT`].
fn flush(socket: &mut WebSocket<PageStream>, queue: &PageQueue<Outgoing>) -> bool {
    flush_within(socket, queue, WRITE_TIMEOUT)
}

/// [`flush`] with its deadline. Each write to the socket blocks at most [`WRITE_SLICE`]
/// (its write timeout) and none starts after the deadline, so a page reading a little now
/// and then is still dropped once `limit` has passed in all.
fn flush_within(
    socket: &mut WebSocket<PageStream>,
    queue: &PageQueue<Outgoing>,
    limit: Duration,
) -> bool {
    let deadline = Instant::now() + limit;
    socket.get_mut().set_deadline(Some(deadline));
    let sent = send_queued(socket, queue, deadline);
    socket.get_mut().set_deadline(None);
    sent
}

/// Writes what is queued and flushes everything buffered; false once the page is gone or
/// `deadline` passed.
fn send_queued(
    socket: &mut WebSocket<PageStream>,
    queue: &PageQueue<Outgoing>,
    deadline: Instant,
) -> bool {
    let late = || Instant::now() >= deadline;
    while let Ok(message) = queue.try_recv() {
        let message = match message {
            Outgoing::Binary(bytes) => Message::Binary(bytes),
            Outgoing::Text(text) => Message::Text(text),
        };
        // A write that timed out keeps its message buffered for the next write or flush.
        match socket.write(message) {
            Ok(()) => {}
            Err(tungstenite::Error::Io(e)) if blocked(&e) && !late() => {}
            Err(_) => return false,
        }
    }
    // Flushed even with nothing queued: the replies tungstenite owes (a pong for each ping
    // read) wait in its buffer, which a page that never reads would grow without bound.
    loop {
        match socket.flush() {
            Ok(()) => return true,
            Err(tungstenite::Error::Io(e)) if blocked(&e) && !late() => {}
            Err(_) => return false,
        }
    }
}

/// Whether a socket call failed only for its timeout.
fn blocked(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
    )
}

/// Applies one page message to the session; `reply` answers this page only.
fn handle(
    text: &str,
    id: u64,
    session: &Mutex<dyn LiveSession>,
    hub: &Hub,
    reply: &dyn Fn(String),
) {
    let request = match parse_request(text) {
        Ok(request) => request,
        Err(message) => return reply(error_message(&message)),
    };
    let previews = matches!(request, Request::Edit { commit: false, .. });
    let mut session = lock(session);
    let result = match request {
        Request::Seek { t } => session.view_seek(t),
        Request::Locate { x, y } => {
            reply(session.view_locate(x, y));
            Ok(())
        }
        Request::Edit {
            rev,
            commit,
            edit,
            t,
        } => session.view_edit(rev, commit, &edit, t),
        Request::Cancel {} => session.view_cancel(),
        Request::Undo {} => session.view_undo(),
        Request::Save { rev } => session.view_save(rev),
        Request::Mesh { on } => {
            hub.set_mesh(id, on);
            session.view_publish()
        }
    };
    match result {
        Ok(()) if previews => hub.set_previewer(id),
        Ok(()) => {}
        Err(message) => reply(error_message(&message)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::{TcpListener, TcpStream};
    use tungstenite::protocol::Role;

    /// A connected pair: the page's end, and the server's, whose writes time out after 50 ms.
    fn connection() -> (TcpStream, TcpStream) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let client = TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (server, _) = listener.accept().unwrap();
        server
            .set_write_timeout(Some(Duration::from_millis(50)))
            .unwrap();
        (client, server)
    }

    /// Queues 64 MiB for the page on `server` and checks that sending it gives up once a
    /// 400 ms deadline has passed, one write's timeout past it at most (with room for a
    /// loaded machine); gives the socket.
    fn send_until_the_deadline(server: TcpStream) -> WebSocket<PageStream> {
        let mut socket = WebSocket::from_raw_socket(PageStream::new(server), Role::Server, None);
        let (tx, queue) = page_channel(PAGE_QUEUE).unwrap();
        let frame = tungstenite::Bytes::from(vec![7u8; 1 << 20]);
        for _ in 0..PAGE_QUEUE {
            tx.try_send(Outgoing::Binary(frame.clone())).unwrap();
        }
        let limit = Duration::from_millis(400);
        let started = Instant::now();
        assert!(!flush_within(&mut socket, &queue, limit));
        let took = started.elapsed();
        assert!(took >= limit, "gave up after {took:?}");
        assert!(took < limit + Duration::from_secs(3), "took {took:?}");
        socket
    }

    /// A page that stops reading is given up on once the whole deadline has passed, not
    /// after a timeout per write (each of which may move a little and start again).
    #[test]
    fn sending_to_a_page_that_stops_reading_ends_at_the_deadline() {
        let (client, server) = connection();
        send_until_the_deadline(server);
        drop(client);
    }

    /// A page that reads a little now and then, so that every write moves a little, is
    /// given up on at the deadline too: tungstenite goes on writing a buffer while each
    /// write moves, so the deadline is kept by the stream it writes to.
    #[test]
    fn sending_to_a_page_that_reads_slowly_ends_at_the_deadline() {
        use std::io::Read as _;
        let (mut client, server) = connection();
        // About 3 MB/s, for at most 30 s: 64 MiB would take 20 s.
        let reader = std::thread::spawn(move || {
            let mut chunk = vec![0u8; 64 << 10];
            let started = Instant::now();
            while started.elapsed() < Duration::from_secs(30) {
                match client.read(&mut chunk) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => std::thread::sleep(Duration::from_millis(20)),
                }
            }
        });
        let socket = send_until_the_deadline(server);
        let _ = socket.get_ref().tcp().shutdown(std::net::Shutdown::Both);
        reader.join().unwrap();
    }
}
