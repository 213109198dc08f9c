//! The live view's fixed routes: takes a connection's request head (bounded in size and
//! time) and gives either a response written back (the page, or an error status) or an
//! accepted WebSocket. Every request must carry the session token; the WebSocket's `Host`
//! and `Origin` must name this server, so another site open in the same browser can neither
//! read the page nor drive the session.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use tungstenite::handshake::derive_accept_key;
use tungstenite::protocol::{Role, WebSocketConfig};
use tungstenite::WebSocket;

use super::admit::{PagePlace, Pending, MAX_PAGES};
use super::edit::MAX_MESSAGE_BYTES;
use super::page_stream::PageStream;

/// Largest request head read, bytes.
const MAX_HEAD: usize = 8 * 1024;
/// How long a client may take to send its whole request head.
const HEAD_TIMEOUT: Duration = Duration::from_secs(5);
/// After an answer, how long and how much of what the client still sends is read and
/// dropped before the connection closes (see [`close_gently`]).
pub(super) const LINGER: Duration = Duration::from_secs(1);
const LINGER_BYTES: usize = 1 << 20;

/// What the server answers with: its token, the page, and the `host:port` names it goes by.
pub struct Routes {
    pub token: String,
    pub page: String,
    pub hosts: Vec<String>,
    /// Listening on every address (`--bind 0.0.0.0` or `::`), this port: any IP address
    /// with it names the server too. An address, unlike a name, cannot be rebound.
    pub any_address_port: Option<u16>,
}

impl Routes {
    /// Whether `host` (a `Host` header, or an `Origin` less its `http://`) names this server.
    fn names_this_server(&self, host: &str) -> bool {
        self.hosts.iter().any(|h| h.eq_ignore_ascii_case(host))
            || self.any_address_port.is_some_and(|port| {
                host.parse::<std::net::SocketAddr>()
                    .is_ok_and(|addr| addr.port() == port)
            })
    }
}

/// What a connection became.
pub enum Accepted {
    /// A response was written (the page, or an error); the connection is done.
    Answered,
    /// A page's WebSocket, and the place it holds until dropped.
    Socket(Box<WebSocket<PageStream>>, PagePlace),
}

/// A request refused: its status line and the reason shown in the body.
#[derive(Debug)]
struct Refusal(&'static str, String);

/// Reads one request from `stream` and answers it; a WebSocket takes a page's place, or
/// is refused when all are taken.
pub fn accept(mut stream: TcpStream, routes: &Routes, place: Pending) -> std::io::Result<Accepted> {
    stream.set_read_timeout(Some(HEAD_TIMEOUT))?;
    let routed = read_head(&mut stream).and_then(|(head, rest)| Ok((route(&head, routes)?, rest)));
    let refused = match routed {
        Err(refusal) => refusal,
        Ok((Route::Page, _)) if place.pages_full() => busy(),
        Ok((Route::Page, _)) => {
            serve_page(&mut stream, routes)?;
            // A request carrying a body would otherwise reset the page away.
            close_gently(&mut stream, LINGER);
            return Ok(Accepted::Answered);
        }
        Ok((Route::Socket { key }, rest)) => match place.into_page() {
            Ok(place) => return upgrade(stream, &key, rest, place),
            // Refused while still counted among the waiting connections.
            Err(Some(_waiting)) => return refuse(&mut stream, busy()),
            Err(None) => return Ok(Accepted::Answered),
        },
    };
    refuse(&mut stream, refused)
}

/// Answers `refusal` and closes the connection gently.
fn refuse(stream: &mut TcpStream, Refusal(status, body): Refusal) -> std::io::Result<Accepted> {
    let kind = "text/plain; charset=utf-8";
    respond(stream, status, kind, body.as_bytes(), &[])?;
    close_gently(stream, LINGER);
    Ok(Accepted::Answered)
}

/// The answer when every page's place is taken: why, instead of a connection closed
/// unanswered (the browser would say only that it was reset).
fn busy() -> Refusal {
    Refusal(
        "503 Service Unavailable",
        format!(
            "the live view serves at most {MAX_PAGES} pages at once: close a page of this \
             session, then reload this one"
        ),
    )
}

/// Closes a connection after its answer without resetting the answer away: closing with
/// unread input (a head past the limit, a request still arriving) sends a reset, and the
/// client's system may then drop the answer unread. So the answer is ended, and what the
/// client still sends is read and dropped until it closes, for at most `linger` and
/// [`LINGER_BYTES`].
pub(super) fn close_gently(stream: &mut TcpStream, linger: Duration) {
    let _ = stream.shutdown(std::net::Shutdown::Write);
    let deadline = Instant::now() + linger;
    let mut sink = [0u8; 8192];
    let mut read = 0;
    while read < LINGER_BYTES {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return;
        }
        match stream.read(&mut sink) {
            Ok(0) | Err(_) => return,
            Ok(n) => read += n,
        }
    }
}

/// The page, with headers that keep it out of frames and caches and its scripts its own.
fn serve_page(stream: &mut TcpStream, routes: &Routes) -> std::io::Result<()> {
    let headers = [
        ("Cache-Control", "no-store"),
        ("Referrer-Policy", "no-referrer"),
        ("X-Content-Type-Options", "nosniff"),
        ("X-Frame-Options", "DENY"),
        (
            "Content-Security-Policy",
            "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; \
             connect-src 'self'; img-src 'self' data:; frame-ancestors 'none'",
        ),
    ];
    let kind = "text/html; charset=utf-8";
    respond(stream, "200 OK", kind, routes.page.as_bytes(), &headers)
}

/// Answers the WebSocket handshake and gives the socket, its messages bounded.
fn upgrade(
    mut stream: TcpStream,
    key: &str,
    rest: Vec<u8>,
    place: PagePlace,
) -> std::io::Result<Accepted> {
    let reply = format!(
        "HTTP/1.1 101 Switching Protocols\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n\
         Sec-WebSocket-Accept: {}\r\n\r\n",
        derive_accept_key(key.as_bytes())
    );
    stream.write_all(reply.as_bytes())?;
    let config = WebSocketConfig::default()
        .max_message_size(Some(MAX_MESSAGE_BYTES))
        .max_frame_size(Some(MAX_MESSAGE_BYTES));
    let stream = PageStream::new(stream);
    let socket = WebSocket::from_partially_read(stream, rest, Role::Server, Some(config));
    Ok(Accepted::Socket(Box::new(socket), place))
}

/// The parts of a request head the routes look at.
#[derive(Debug, Default)]
pub struct Head {
    pub method: String,
    /// The authority of an absolute-form target (`GET http://host:port/ws?…`), which must
    /// name this server as `Host` must.
    pub authority: Option<String>,
    pub path: String,
    pub query: String,
    pub headers: Vec<(String, String)>,
}

impl Head {
    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// Reads a request head within [`HEAD_TIMEOUT`] in all: a client sending a byte now and
/// then cannot keep its connection (one of the server's few) any longer.
fn read_head(stream: &mut TcpStream) -> Result<(Head, Vec<u8>), Refusal> {
    let deadline = Instant::now() + HEAD_TIMEOUT;
    let late = || {
        let seconds = HEAD_TIMEOUT.as_secs();
        Refusal(
            "408 Request Timeout",
            format!("the request head did not arrive within {seconds} s"),
        )
    };
    let mut buffer = Vec::with_capacity(1024);
    let mut chunk = [0u8; 1024];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return Err(late());
        }
        let n = stream.read(&mut chunk).map_err(|e| match e.kind() {
            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut => late(),
            _ => Refusal(
                "400 Bad Request",
                format!("reading the request failed: {e}"),
            ),
        })?;
        if n == 0 {
            return Err(Refusal("400 Bad Request", "connection closed".into()));
        }
        buffer.extend_from_slice(&chunk[..n]);
        if let Some(end) = head_end(&buffer) {
            if end > MAX_HEAD {
                return Err(too_large());
            }
            let head = parse_head(&buffer[..end])?;
            return Ok((head, buffer[end..].to_vec()));
        }
        if buffer.len() > MAX_HEAD {
            return Err(too_large());
        }
    }
}

/// Where the head in `buffer` ends: after its first empty line, which ends in CRLF or, as
/// HTTP lets a server accept, in a bare LF.
fn head_end(buffer: &[u8]) -> Option<usize> {
    let lf = buffer.iter().enumerate().filter(|&(_, &b)| b == b'\n');
    lf.map(|(i, _)| i).find_map(|i| match buffer.get(i + 1..) {
        Some([b'\n', ..]) => Some(i + 2),
        Some([b'\r', b'\n', ..]) => Some(i + 3),
        _ => None,
    })
}

fn too_large() -> Refusal {
    Refusal(
        "431 Request Header Fields Too Large",
        "request head too large".into(),
    )
}

/// Header fields a request may have: a browser sends about a dozen.
const MAX_HEADERS: usize = 32;

/// Parses a complete request head.
fn parse_head(bytes: &[u8]) -> Result<Head, Refusal> {
    let bad = |m: &str| Refusal("400 Bad Request", m.to_string());
    let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut request = httparse::Request::new(&mut headers);
    match request.parse(bytes) {
        Ok(httparse::Status::Complete(_)) => {}
        Err(httparse::Error::TooManyHeaders) => {
            return Err(Refusal(
                "431 Request Header Fields Too Large",
                format!("more than {MAX_HEADERS} header fields"),
            ))
        }
        _ => return Err(bad("malformed request")),
    }
    let target = request.path.unwrap_or("");
    // An origin server takes the absolute form too (RFC 9112, 3.2.2).
    let (authority, target) = match after_http_scheme(target) {
        Some(rest) => {
            let (authority, tail) = rest.split_at(rest.find(['/', '?']).unwrap_or(rest.len()));
            let slash = if tail.starts_with('/') { "" } else { "/" };
            (Some(authority.to_string()), format!("{slash}{tail}"))
        }
        None => (None, target.to_string()),
    };
    let (path, query) = target.split_once('?').unwrap_or((&target, ""));
    Ok(Head {
        method: request.method.unwrap_or("").to_string(),
        authority,
        path: path.to_string(),
        query: query.to_string(),
        headers: request
            .headers
            .iter()
            .map(|h| {
                (
                    h.name.to_string(),
                    String::from_utf8_lossy(h.value).into_owned(),
                )
            })
            .collect(),
    })
}

#[derive(Debug, PartialEq)]
enum Route {
    Page,
    Socket { key: String },
}

fn route(head: &Head, routes: &Routes) -> Result<Route, Refusal> {
    if head.method != "GET" {
        return Err(Refusal("405 Method Not Allowed", "only GET".into()));
    }
    let host = single_header(head, "Host")?;
    for named in std::iter::once(host).chain(head.authority.as_deref()) {
        if !routes.names_this_server(named) {
            return Err(Refusal(
                "403 Forbidden",
                format!("unexpected Host {named:?}"),
            ));
        }
    }
    if !matches!(head.path.as_str(), "/" | "/ws") {
        return Err(Refusal("404 Not Found", "no such page".into()));
    }
    let token = head
        .query
        .split('&')
        .find_map(|pair| pair.strip_prefix("token="))
        .unwrap_or("");
    if !same_token(token, &routes.token) {
        return Err(Refusal("403 Forbidden", "missing or wrong token".into()));
    }
    if head.path == "/" {
        return Ok(Route::Page);
    }
    // The page's own origin is the address it was loaded from, which is this request's
    // `Host`: on a wildcard bind another machine's address names the server too, but a
    // page from there is not this one.
    let origin = single_header(head, "Origin")?;
    let same = |from: &str| from.eq_ignore_ascii_case(host) && routes.names_this_server(from);
    if !after_http_scheme(origin).is_some_and(same) {
        return Err(Refusal(
            "403 Forbidden",
            format!("foreign Origin {origin:?}"),
        ));
    }
    // `Upgrade` may list several protocols (`h2c, websocket`).
    let upgrade = head.header("Upgrade").is_some_and(|v| {
        v.split(',')
            .any(|p| p.trim().eq_ignore_ascii_case("websocket"))
    });
    let key = head.header("Sec-WebSocket-Key").unwrap_or("");
    if !upgrade || head.header("Sec-WebSocket-Version") != Some("13") {
        return Err(Refusal("400 Bad Request", "not a WebSocket request".into()));
    }
    if !is_websocket_key(key) {
        return Err(Refusal(
            "400 Bad Request",
            "Sec-WebSocket-Key is not 16 bytes in base64".into(),
        ));
    }
    Ok(Route::Socket {
        key: key.to_string(),
    })
}

/// The value of header `name`, empty when absent; refused when given twice (which of two
/// would be checked, and which a proxy would pass on, is anyone's guess).
fn single_header<'a>(head: &'a Head, name: &str) -> Result<&'a str, Refusal> {
    let mut values = head
        .headers
        .iter()
        .filter(|(n, _)| n.eq_ignore_ascii_case(name));
    let first = values.next().map_or("", |(_, v)| v.as_str());
    match values.next() {
        Some(_) => Err(Refusal("400 Bad Request", format!("more than one {name}"))),
        None => Ok(first),
    }
}

/// What follows `http://` (in any case) at the start of `text`: the host of an `Origin`, or
/// an absolute-form target's authority and path.
fn after_http_scheme(text: &str) -> Option<&str> {
    let scheme = text.get(..7)?;
    scheme.eq_ignore_ascii_case("http://").then(|| &text[7..])
}

/// Whether `key` is 16 bytes in base64 (RFC 6455, 4.2.1): 22 base64 digits, the last
/// holding 2 bits (so one of `AQgw`), then `==`.
fn is_websocket_key(key: &str) -> bool {
    let digit = |b: &u8| b.is_ascii_alphanumeric() || *b == b'+' || *b == b'/';
    let bytes = key.as_bytes();
    bytes.len() == 24
        && bytes.ends_with(b"==")
        && bytes[..22].iter().all(digit)
        && b"AQgw".contains(&bytes[21])
}

/// Compares tokens in time independent of where they first differ.
fn same_token(given: &str, token: &str) -> bool {
    given.len() == token.len()
        && given
            .bytes()
            .zip(token.bytes())
            .fold(0u8, |acc, (a, b)| acc | (a ^ b))
            == 0
}

fn respond(
    stream: &mut TcpStream,
    status: &str,
    content_type: &str,
    body: &[u8],
    headers: &[(&str, &str)],
) -> std::io::Result<()> {
    let mut head = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\nConnection: close\r\n",
        body.len()
    );
    for (name, value) in headers {
        head.push_str(&format!("{name}: {value}\r\n"));
    }
    head.push_str("\r\n");
    stream.write_all(head.as_bytes())?;
    stream.write_all(body)?;
    stream.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn routes() -> Routes {
        Routes {
            token: "abc123".into(),
            page: String::new(),
            hosts: vec!["127.0.0.1:8000".into(), "localhost:8000".into()],
            any_address_port: None,
        }
    }

    fn head(text: &str) -> Head {
        parse_head(text.replace('\n', "\r\n").as_bytes()).unwrap()
    }

    #[test]
    fn more_header_fields_than_the_limit_are_refused_as_too_large() {
        let many: String = (0..33).map(|i| format!("X-{i}: {i}\r\n")).collect();
        let text = format!("GET / HTTP/1.1\r\nHost: 127.0.0.1:8000\r\n{many}\r\n");
        let refused = parse_head(text.as_bytes()).map(|_| ()).unwrap_err();
        assert_eq!(refused.0, "431 Request Header Fields Too Large");
        assert!(
            refused.1.contains("more than 32 header fields"),
            "{}",
            refused.1
        );
    }

    const WS: &str = "Upgrade: websocket\nConnection: Upgrade\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\nSec-WebSocket-Version: 13\n";

    #[test]
    fn page_and_socket_need_token_host_and_origin() {
        let r = routes();
        assert_eq!(
            route(
                &head("GET /?token=abc123 HTTP/1.1\nHost: 127.0.0.1:8000\n\n"),
                &r
            )
            .unwrap(),
            Route::Page
        );
        for bad in [
            "GET / HTTP/1.1\nHost: 127.0.0.1:8000\n\n",
            "GET /?token=abc124 HTTP/1.1\nHost: 127.0.0.1:8000\n\n",
            "GET /?token=abc12 HTTP/1.1\nHost: 127.0.0.1:8000\n\n",
            "GET /?token=abc123 HTTP/1.1\nHost: evil.example:8000\n\n",
            "POST /?token=abc123 HTTP/1.1\nHost: 127.0.0.1:8000\n\n",
            "GET /etc/passwd?token=abc123 HTTP/1.1\nHost: 127.0.0.1:8000\n\n",
        ] {
            assert!(route(&head(bad), &r).is_err(), "{bad}");
        }
        let ok = format!("GET /ws?token=abc123 HTTP/1.1\nHost: localhost:8000\nOrigin: http://localhost:8000\n{WS}\n");
        assert!(matches!(route(&head(&ok), &r), Ok(Route::Socket { .. })));
        let foreign = ok.replace(
            "Origin: http://localhost:8000",
            "Origin: http://evil.example",
        );
        assert!(route(&head(&foreign), &r).unwrap_err().1.contains("Origin"));
        let no_origin = ok.replace("Origin: http://localhost:8000\n", "");
        assert!(route(&head(&no_origin), &r).is_err());
    }

    /// One `Host` only: with two, which one a proxy or cache read is anyone's guess.
    #[test]
    fn a_second_host_is_refused() {
        let two = "GET /?token=abc123 HTTP/1.1\nHost: 127.0.0.1:8000\nHost: evil.example\n\n";
        let refusal = route(&head(two), &routes()).unwrap_err();
        assert_eq!(refusal.0, "400 Bad Request");
    }

    /// Listening on every address, any IP address with the port names the server (so
    /// another machine can open the page), but never a name, which could be rebound.
    #[test]
    fn on_every_address_any_ip_with_the_port_is_this_server() {
        let r = Routes {
            any_address_port: Some(8000),
            ..routes()
        };
        let page = |host: &str| format!("GET /?token=abc123 HTTP/1.1\nHost: {host}\n\n");
        for host in ["192.0.2.7:8000", "[2001:db8::1]:8000", "127.0.0.1:8000"] {
            assert_eq!(
                route(&head(&page(host)), &r).unwrap(),
                Route::Page,
                "{host}"
            );
            assert!(route(&head(&page(host)), &routes()).is_err() || host.starts_with("127"));
        }
        for host in [
            "192.0.2.7:8001",
            "192.0.2.7",
            "evil.example:8000",
            "1.2.3.4.nip.io:8000",
        ] {
            assert!(route(&head(&page(host)), &r).is_err(), "{host}");
        }
        let socket = |origin: &str| {
            format!("GET /ws?token=abc123 HTTP/1.1\nHost: 192.0.2.7:8000\nOrigin: {origin}\n{WS}\n")
        };
        assert!(route(&head(&socket("http://192.0.2.7:8000")), &r).is_ok());
        assert!(route(&head(&socket("http://evil.example:8000")), &r).is_err());
        assert!(route(&head(&socket("https://192.0.2.7:8000")), &r).is_err());
        // Another address with the port names the server, but a page from there is not
        // the one this request's Host says it was loaded from.
        for foreign in [
            "http://203.0.113.5:8000",
            "http://[2001:db8::1]:8000",
            "http://0.0.0.0:8000",
        ] {
            let refused = route(&head(&socket(foreign)), &r).map(|_| ());
            assert!(
                refused.is_err_and(|e| e.1.contains("foreign Origin")),
                "{foreign}"
            );
        }
        let two = socket("http://192.0.2.7:8000")
            .replace("Origin:", "Origin: http://evil.example\nOrigin:");
        assert!(route(&head(&two), &r).is_err_and(|e| e.1.contains("more than one Origin")));
    }

    /// An absolute-form target is taken as its path, when its authority names this server
    /// as `Host` must; `Upgrade` may list several protocols; the key must be 16 bytes.
    #[test]
    fn absolute_targets_upgrade_lists_and_keys() {
        let r = routes();
        let page = |target: &str| format!("GET {target} HTTP/1.1\nHost: 127.0.0.1:8000\n\n");
        for target in [
            "http://127.0.0.1:8000/?token=abc123",
            "HTTP://localhost:8000?token=abc123",
        ] {
            assert_eq!(
                route(&head(&page(target)), &r).unwrap(),
                Route::Page,
                "{target}"
            );
        }
        for target in [
            "http://evil.example:8000/?token=abc123",
            "http://127.0.0.1:8000/?token=abc124",
            "http://127.0.0.1:8000/etc?token=abc123",
        ] {
            assert!(route(&head(&page(target)), &r).is_err(), "{target}");
        }
        let socket = |upgrade: &str, key: &str| {
            format!(
                "GET /ws?token=abc123 HTTP/1.1\nHost: 127.0.0.1:8000\nOrigin: http://127.0.0.1:8000\n\
                 Upgrade: {upgrade}\nConnection: Upgrade\nSec-WebSocket-Key: {key}\n\
                 Sec-WebSocket-Version: 13\n\n"
            )
        };
        let key = "dGhlIHNhbXBsZSBub25jZQ==";
        for upgrade in ["websocket", "h2c, websocket", "WebSocket ,foo"] {
            assert!(route(&head(&socket(upgrade, key)), &r).is_ok(), "{upgrade}");
        }
        assert!(route(&head(&socket("h2c", key)), &r).is_err());
        for bad in [
            "",
            "abc",
            "dGhlIHNhbXBsZSBub25jZR==",
            "dGhlIHNhbXBsZSBub25jZQ=",
            "dGhlIHNhbXBsZSBub25j*Q==",
        ] {
            let refusal = route(&head(&socket("websocket", bad)), &r).unwrap_err();
            assert_eq!(refusal.0, "400 Bad Request", "{bad}");
        }
    }

    /// A head may end in bare LFs: it is read at once, not waited on until the timeout.
    #[test]
    fn a_head_ends_at_its_first_empty_line_in_crlf_or_lf() {
        assert_eq!(head_end(b"GET / HTTP/1.1\r\nHost: a\r\n\r\nrest"), Some(27));
        assert_eq!(head_end(b"GET / HTTP/1.1\nHost: a\n\nrest"), Some(24));
        assert_eq!(head_end(b"GET / HTTP/1.1\nHost: a\n\r\nrest"), Some(25));
        assert_eq!(head_end(b"GET / HTTP/1.1\r\nHost: a\r\n"), None);
        assert_eq!(head_end(b""), None);
    }
}
