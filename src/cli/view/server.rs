//! The live view's server: takes the shared session, an address and a port, and gives a
//! listening server (its URL carries a fresh random token) that serves the page and one
//! WebSocket per page. Each page's messages are applied to the session in arrival order
//! (the session's lock orders pages and typed lines); replies and frames go back through
//! the [`Hub`]. Threads only: one accepting, one per connection.

use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::Context as _;
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::protocol::CloseFrame;
use tungstenite::{Message, WebSocket};

use super::edit::{parse_request, Edit, Request};
use super::http::{accept, Accepted, Routes};
use super::hub::{Hub, Outgoing, PAGE_QUEUE};
use super::wake::{page_channel, PageQueue};
use super::{error_message, lock};

/// Connections served at once; more are closed unanswered.
const MAX_CONNECTIONS: usize = 32;
/// How long a page's socket read waits once input was seen (a message's rest may still be
/// on its way); where the wait cannot watch the queue, how often frames are looked for.
const POLL: Duration = Duration::from_millis(5);
/// The longest an idle page's thread sleeps before it looks again, woken or not.
const IDLE_WAIT: Duration = Duration::from_secs(1);
/// How long a write to a page may block before the page counts as gone.
const WRITE_TIMEOUT: Duration = Duration::from_secs(10);

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
    let shown = match ip {
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
    let open = Arc::new(AtomicUsize::new(0));
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        if open.load(Ordering::SeqCst) >= MAX_CONNECTIONS {
            super::http::refuse_busy(stream, MAX_CONNECTIONS);
            continue;
        }
        open.fetch_add(1, Ordering::SeqCst);
        let (routes, session, hub, slot) =
            (routes.clone(), session.clone(), hub.clone(), open.clone());
        let spawned = std::thread::Builder::new()
            .name("view-page".into())
            .spawn(move || {
                if let Ok(Accepted::Socket(socket)) = accept(stream, &routes) {
                    page_loop(*socket, &session, &hub);
                }
                slot.fetch_sub(1, Ordering::SeqCst);
            });
        if spawned.is_err() {
            // The thread never ran to give its slot back.
            open.fetch_sub(1, Ordering::SeqCst);
            eprint_line!("warning: the view cannot serve another page");
        }
    }
}

/// Serves one page until it closes: its messages in, frames and replies out. Its thread
/// sleeps until the page sends something or something is queued for it.
fn page_loop(mut socket: WebSocket<TcpStream>, session: &Mutex<dyn LiveSession>, hub: &Hub) {
    // A page that stops reading fails the write after a while, instead of blocking its
    // connection (one of MAX_CONNECTIONS) for good.
    let stream = socket.get_mut();
    if stream.set_read_timeout(Some(POLL)).is_err()
        || stream.set_write_timeout(Some(WRITE_TIMEOUT)).is_err()
    {
        return;
    }
    let _ = socket.get_mut().set_nodelay(true);
    let Ok((tx, queue)) = page_channel(PAGE_QUEUE) else {
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
        input = queue.wait(socket.get_ref(), IDLE_WAIT);
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
    socket: &mut WebSocket<TcpStream>,
    queue: &PageQueue<Outgoing>,
    id: u64,
    session: &Mutex<dyn LiveSession>,
    hub: &Hub,
    reply: &dyn Fn(String),
) -> bool {
    loop {
        match socket.read() {
            Ok(Message::Text(text)) => handle(text.as_str(), id, session, hub, reply),
            Ok(Message::Binary(_)) => reply(error_message("binary messages are not accepted")),
            Ok(Message::Close(_)) => {
                // Sends the close reply the protocol queued.
                let _ = socket.flush();
                return false;
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return true
            }
            Err(tungstenite::Error::Capacity(e)) => {
                refuse_oversized(socket, queue, &e.to_string(), reply);
                return false;
            }
            Err(_) => return false,
        }
        if !flush(socket, queue) {
            return false;
        }
    }
}

/// Answers a message over the size limit and closes the page's connection (1009): the
/// rest of an oversized frame, or of a fragmented message, cannot be told from what the
/// page sends next, so going on could apply part of a refused message.
fn refuse_oversized(
    socket: &mut WebSocket<TcpStream>,
    queue: &PageQueue<Outgoing>,
    problem: &str,
    reply: &dyn Fn(String),
) {
    reply(error_message(&format!(
        "refused: {problem}; the page disconnects (reload it)"
    )));
    if flush(socket, queue) {
        let frame = CloseFrame {
            code: CloseCode::Size,
            reason: "message too big".into(),
        };
        let _ = socket.close(Some(frame));
        let _ = socket.flush();
    }
    // The rest of the message is still arriving: closing on it would reset the answer away.
    super::http::close_gently(socket.get_mut(), super::http::LINGER);
}

/// Sends what is queued for this page; false once the page is gone.
fn flush(socket: &mut WebSocket<TcpStream>, queue: &PageQueue<Outgoing>) -> bool {
    let mut sent = false;
    while let Ok(message) = queue.try_recv() {
        let message = match message {
            Outgoing::Binary(bytes) => Message::Binary(bytes),
            Outgoing::Text(text) => Message::Text(text),
        };
        if socket.write(message).is_err() {
            return false;
        }
        sent = true;
    }
    !sent || socket.flush().is_ok()
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
