//! The live view against clients that misbehave: connections that never send a request
//! cannot lock a page out, a request carrying a body still gets its whole answer, and a
//! WebSocket frame that breaks the protocol is answered with an error and a close with the
//! fitting code (1002, 1007), changing nothing.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use serde_json::json;
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::Message;

use super::view_ws::{cat_scene, Page, ViewRepl};

#[test]
fn connections_that_send_nothing_cannot_lock_a_page_out() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    // More silent connections than the server has places for, all kept open.
    let silent: Vec<TcpStream> = (0..40)
        .map(|_| TcpStream::connect(repl.host()).unwrap())
        .collect();
    let mut page = repl.page();
    page.send(&json!({"type": "seek", "t": 0.5}));
    page.until(|v| v["type"] == "scene" && v["t"] == 0.5);
    // The oldest silent ones were ended to make room; the newest still wait their turn.
    let ended = silent
        .iter()
        .filter(|s| {
            s.set_read_timeout(Some(Duration::from_millis(200)))
                .unwrap();
            matches!((&**s).read(&mut [0u8; 1]), Ok(0))
        })
        .count();
    assert!(ended >= 9, "{ended} of 40 silent connections ended");
    drop((silent, page));
    assert!(repl.finish().success());
}

#[test]
fn a_request_carrying_a_body_gets_the_whole_page() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let mut stream = TcpStream::connect(repl.host()).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(60)))
        .unwrap();
    let path = repl.url.split_once(&repl.host()).unwrap().1.to_string();
    let body = vec![b'x'; 900_000];
    let head = format!(
        "GET {path} HTTP/1.1\r\nHost: {}\r\nContent-Length: {}\r\n\r\n",
        repl.host(),
        body.len()
    );
    let mut writer = stream.try_clone().unwrap();
    let sending = std::thread::spawn(move || {
        let _ = writer.write_all(head.as_bytes());
        let _ = writer.write_all(&body);
    });
    let mut answer = Vec::new();
    let read = stream.read_to_end(&mut answer);
    sending.join().unwrap();
    read.expect("the answer is read to its end, not reset away");
    let answer = String::from_utf8(answer).unwrap();
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer:.200}");
    let (head, page) = answer.split_once("\r\n\r\n").unwrap();
    let length = head
        .lines()
        .find_map(|l| l.strip_prefix("Content-Length: "))
        .unwrap();
    assert_eq!(page.len(), length.parse::<usize>().unwrap());
    assert!(page.trim_end().ends_with("</html>"));
    assert!(repl.finish().success());
}

/// Sends one raw client frame: `first` is its first byte (FIN, reserved bits, opcode);
/// masked with a zero mask (which leaves the payload as it is) unless `unmasked`.
fn send_frame(page: &mut Page, first: u8, payload: &[u8], unmasked: bool) {
    let MaybeTlsStream::Plain(stream) = page.socket.get_mut() else {
        panic!("not a plain stream")
    };
    assert!(payload.len() < 126);
    let mut frame = vec![first];
    if unmasked {
        frame.push(payload.len() as u8);
    } else {
        frame.push(0x80 | payload.len() as u8);
        frame.extend_from_slice(&[0; 4]);
    }
    frame.extend_from_slice(payload);
    stream.write_all(&frame).unwrap();
}

#[test]
fn frames_that_break_the_protocol_are_closed_with_their_code_and_change_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let seek = br#"{"type":"seek","t":0.9}"#;
    let mut not_utf8 = seek.to_vec();
    not_utf8[9] = 0xff;
    let cases: [(&str, u8, &[u8], bool, CloseCode); 4] = [
        ("unmasked", 0x81, seek, true, CloseCode::Protocol),
        (
            "reserved bits",
            0x81 | 0x40,
            seek,
            false,
            CloseCode::Protocol,
        ),
        ("unknown opcode", 0x83, seek, false, CloseCode::Protocol),
        ("not UTF-8", 0x81, &not_utf8, false, CloseCode::Invalid),
    ];
    for (what, first, payload, unmasked, code) in cases {
        let mut page = repl.page();
        let t = page.scene["t"].clone();
        send_frame(&mut page, first, payload, unmasked);
        let error = page.until(|v| v["type"] == "error");
        let message = error["message"].as_str().unwrap();
        assert!(message.contains("refused"), "{what}: {error}");
        let close = match page.socket.read() {
            Ok(Message::Close(frame)) => frame,
            Ok(other) => panic!("{what}: after the refusal: {other:?}"),
            Err(e) => panic!("{what}: no close frame: {e:?}"),
        };
        assert_eq!(close.map(|f| f.code), Some(code), "{what}");
        let other = repl.page();
        assert_eq!(other.scene["t"], t, "{what}: applied");
    }
    assert!(repl.finish().success());
}

/// The CPU time `pid` has used, in clock ticks (user and system).
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .unwrap()
        .1
        .split_whitespace()
        .collect();
    fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap()
}

/// Out of file descriptors, accepting fails until one closes: the server neither spins on
/// the failure nor lets the connections holding them lock a page out.
#[test]
fn out_of_file_descriptors_the_server_neither_spins_nor_locks_pages_out() {
    let Some(prlimit) = lapclone::util::find_program("prlimit") else {
        eprintln!("skipped: prlimit (util-linux) is not installed");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let mut command = std::process::Command::new(prlimit);
    command
        .arg("--nofile=24")
        .arg(env!("CARGO_BIN_EXE_lapclone"));
    let repl = ViewRepl::start_in(command, dir.path(), &scene, &[]);
    let silent: Vec<TcpStream> = (0..40)
        .filter_map(|_| TcpStream::connect(repl.host()).ok())
        .collect();
    std::thread::sleep(Duration::from_millis(300));
    let pid = repl.pid();
    let before = cpu_ticks(pid);
    std::thread::sleep(Duration::from_secs(1));
    let used = cpu_ticks(pid) - before;
    // A spinning accept loop uses the whole second (100 ticks); waiting, next to none.
    assert!(used < 30, "{used} ticks of CPU in 1 s with nothing to do");
    let mut page = repl.page();
    page.send(&json!({"type": "seek", "t": 0.5}));
    page.until(|v| v["type"] == "scene" && v["t"] == 0.5);
    drop((silent, page));
    assert!(repl.finish().success());
}

/// How many threads process `pid` runs.
fn threads(pid: u32) -> usize {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let line = status.lines().find(|l| l.starts_with("Threads:")).unwrap();
    line["Threads:".len()..].trim().parse().unwrap()
}

/// With every page's place taken, a flood of WebSocket requests (with the token) that are
/// refused and never closed stays within the server's bound on connection threads: each is
/// counted among the waiting connections while it is answered, and the accepting thread
/// waits for ended ones to finish before it starts another.
#[test]
fn a_flood_of_refused_pages_keeps_the_threads_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let scene = cat_scene(dir.path());
    let repl = ViewRepl::start(dir.path(), &scene);
    let pages: Vec<Page> = (0..32).map(|_| repl.page()).collect();
    let pid = repl.pid();
    let before = threads(pid);
    let watching = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
    let watcher = {
        let watching = watching.clone();
        std::thread::spawn(move || {
            let mut most = 0;
            while watching.load(std::sync::atomic::Ordering::Relaxed) {
                most = most.max(threads(pid));
                std::thread::sleep(Duration::from_millis(2));
            }
            most
        })
    };
    let path = repl
        .socket_url()
        .replacen(&format!("ws://{}", repl.host()), "", 1);
    let request = format!(
        "GET {path} HTTP/1.1\r\nHost: {0}\r\nOrigin: http://{0}\r\nUpgrade: websocket\r\n\
         Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
         Sec-WebSocket-Version: 13\r\n\r\n",
        repl.host()
    );
    let held: Vec<TcpStream> = (0..400)
        .filter_map(|_| {
            let mut stream = TcpStream::connect(repl.host()).ok()?;
            stream.write_all(request.as_bytes()).ok()?;
            Some(stream)
        })
        .collect();
    std::thread::sleep(Duration::from_millis(300));
    watching.store(false, std::sync::atomic::Ordering::Relaxed);
    let most = watcher.join().unwrap();
    // 32 waiting connections and 8 finishing, over the threads the 32 pages already run,
    // and a few more: a thread whose join has returned is still counted for a moment while
    // the kernel finishes its exit (CI once saw one). Unbounded, the flood would make 400.
    assert!(
        most <= before + 44,
        "{most} threads at most, {before} with the 32 pages"
    );
    drop((held, pages));
    assert!(repl.finish().success());
}
