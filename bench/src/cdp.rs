//! A small Chrome DevTools Protocol client: takes a chromium program and a URL, launches it
//! headless and gives a connection to that one page (calls, script evaluation, dispatched
//! mouse events). Spoken over a WebSocket with tungstenite, so no browser-driving crate. The
//! live view's browser test (`tests/it/view_browser.rs`, which includes this file) and the
//! `lapclone-bench browser` benchmark share it; it uses only crates both have.

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// Why talking to the browser failed.
#[derive(Debug, thiserror::Error)]
pub enum CdpError {
    #[error("cannot start {program}: {source}")]
    Launch {
        program: PathBuf,
        source: std::io::Error,
    },
    #[error("chromium printed no DevTools address within {0:?}")]
    NoEndpoint(Duration),
    #[error("DevTools connection: {0}")]
    Socket(#[from] tungstenite::Error),
    #[error("DevTools sent bad JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("{method} failed: {reply}")]
    Call { method: String, reply: String },
    #[error("the page never had `{0}` within {1:?}")]
    Timeout(String, Duration),
}

/// `chromium` (or `chromium-browser`) on `PATH`, if installed.
pub fn find_chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser"].iter().find_map(|name| {
        std::env::split_paths(&path)
            .map(|d| d.join(name))
            .find(|p| p.is_file())
    })
}

/// How long chromium may take to start and print its DevTools address.
const START_TIMEOUT: Duration = Duration::from_secs(60);

/// A headless chromium and a DevTools connection to one page of it; dropping it closes the
/// browser.
pub struct Browser {
    child: Child,
    socket: WebSocket<MaybeTlsStream<TcpStream>>,
    session: Option<String>,
    next_id: u64,
}

impl Browser {
    /// Starts `program` headless (no sandbox: the benchmark and CI run as root) with its
    /// profile in `profile` and a `width`×`height` window, and opens `url` in a new page.
    pub fn launch(
        program: &Path,
        profile: &Path,
        (width, height): (u32, u32),
        url: &str,
    ) -> Result<Browser, CdpError> {
        let mut child = Command::new(program)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--window-size={width},{height}"))
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| CdpError::Launch {
                program: program.to_path_buf(),
                source,
            })?;
        let endpoint = match child.stderr.take().map(devtools_endpoint) {
            Some(Ok(endpoint)) => endpoint,
            Some(Err(e)) => return Err(stop(child, e)),
            None => return Err(stop(child, CdpError::NoEndpoint(START_TIMEOUT))),
        };
        let socket = match tungstenite::connect(endpoint.as_str()) {
            Ok((socket, _)) => socket,
            Err(e) => return Err(stop(child, e.into())),
        };
        let mut browser = Browser {
            child,
            socket,
            session: None,
            next_id: 0,
        };
        let target = browser.call("Target.createTarget", json!({ "url": url }))?;
        let attached = browser.call(
            "Target.attachToTarget",
            json!({ "targetId": target["targetId"], "flatten": true }),
        )?;
        browser.session = attached["sessionId"].as_str().map(str::to_string);
        Ok(browser)
    }

    /// Sends `method` (on the page once attached) without waiting for its reply; gives the
    /// call's id.
    fn send(&mut self, method: &str, params: Value) -> Result<u64, CdpError> {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if let Some(session) = &self.session {
            message["sessionId"] = json!(session);
        }
        self.socket
            .send(Message::Text(message.to_string().into()))?;
        Ok(id)
    }

    /// Calls `method` (on the page once attached) and returns its result.
    pub fn call(&mut self, method: &str, params: Value) -> Result<Value, CdpError> {
        let id = self.send(method, params)?;
        loop {
            if let Message::Text(text) = self.socket.read()? {
                let reply: Value = serde_json::from_str(text.as_str())?;
                if reply["id"] == id {
                    if reply.get("error").is_some() {
                        return Err(CdpError::Call {
                            method: method.to_string(),
                            reply: reply.to_string(),
                        });
                    }
                    return Ok(reply["result"].clone());
                }
            }
        }
    }

    /// The value of `expression` evaluated in the page (promises awaited).
    pub fn eval(&mut self, expression: &str) -> Result<Value, CdpError> {
        let result = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true, "awaitPromise": true }),
        )?;
        if let Some(exception) = result.get("exceptionDetails") {
            return Err(CdpError::Call {
                method: format!("Runtime.evaluate({expression})"),
                reply: exception.to_string(),
            });
        }
        Ok(result["result"]["value"].clone())
    }

    /// Waits until `expression` is true in the page, polling every 20 ms.
    pub fn wait_for(&mut self, expression: &str, timeout: Duration) -> Result<(), CdpError> {
        let started = Instant::now();
        while self.eval(expression)? != json!(true) {
            if started.elapsed() > timeout {
                return Err(CdpError::Timeout(expression.to_string(), timeout));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        Ok(())
    }

    /// Dispatches a left-button mouse event (`mouseMoved`, `mousePressed`, `mouseReleased`)
    /// at page point (`x`, `y`); moves carry the button held, as in a drag.
    pub fn mouse(&mut self, kind: &str, x: f64, y: f64) -> Result<(), CdpError> {
        self.call("Input.dispatchMouseEvent", mouse_event(kind, x, y))
            .map(drop)
    }

    /// Dispatches the same event without waiting for chromium's reply, as a mouse hands the
    /// browser its reports whether or not the page has taken the last one: chromium answers a
    /// move only once the page has handled it, so waiting would pace the moves by the page's
    /// frames. The next `call` passes over the replies (a refused move is not reported).
    pub fn mouse_unacked(&mut self, kind: &str, x: f64, y: f64) -> Result<(), CdpError> {
        self.send("Input.dispatchMouseEvent", mouse_event(kind, x, y))
            .map(drop)
    }

    /// Presses and releases `key` (its DOM name, and its Windows virtual key code).
    pub fn key(&mut self, key: &str, code: u32) -> Result<(), CdpError> {
        for kind in ["keyDown", "keyUp"] {
            self.call(
                "Input.dispatchKeyEvent",
                json!({ "type": kind, "key": key, "code": key, "windowsVirtualKeyCode": code }),
            )?;
        }
        Ok(())
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        // Closing through the protocol lets chromium end its helper processes too.
        self.session = None;
        let _ = self.call("Browser.close", json!({}));
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A left-button mouse event at page point (`x`, `y`), the button held but on release.
fn mouse_event(kind: &str, x: f64, y: f64) -> Value {
    let buttons = if kind == "mouseReleased" { 0 } else { 1 };
    json!({ "type": kind, "x": x, "y": y, "button": "left", "buttons": buttons, "clickCount": 1 })
}

/// The `ws://` address chromium prints on stderr; a thread keeps draining stderr afterwards so
/// chromium never blocks on a full pipe.
fn devtools_endpoint(stderr: std::process::ChildStderr) -> Result<String, CdpError> {
    let (found, endpoint) = mpsc::channel();
    std::thread::spawn(move || {
        let mut found = Some(found);
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if let Some((_, address)) = line.split_once("DevTools listening on ") {
                if let Some(found) = found.take() {
                    let _ = found.send(address.trim().to_string());
                }
            }
        }
    });
    endpoint
        .recv_timeout(START_TIMEOUT)
        .map_err(|_| CdpError::NoEndpoint(START_TIMEOUT))
}

/// Ends a browser that failed to start properly and passes its error on.
fn stop(mut child: Child, error: CdpError) -> CdpError {
    let _ = child.kill();
    let _ = child.wait();
    error
}
