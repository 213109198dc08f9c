//! `lapclone repl` in a pseudo-terminal (rexpect): the prompt, a Rhai line, tab completion
//! of a `:command` prefix and of a patch name, Ctrl-C clearing the line, Ctrl-D quitting
//! and the history file written.

use std::path::Path;
use std::process::Command;

use rexpect::session::spawn_command;

#[test]
fn prompt_line_completion_and_ctrl_d() {
    let dir = tempfile::tempdir().unwrap();
    let history = dir.path().join("history.txt");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cat_in_coffee.rhai");
    let command = repl_command(&scene, dir.path(), &history, &[]);
    let mut p = spawn_command(command, Some(20_000)).unwrap();
    p.exp_string("lapclone> ").unwrap();

    p.send_line("40 + 2").unwrap();
    p.exp_string("=> 42").unwrap();
    p.exp_string("lapclone> ").unwrap();

    // `:re` is ambiguous: the second Tab lists both candidates.
    p.send(":re\t\t").unwrap();
    p.flush().unwrap();
    p.exp_string(":reload").unwrap();
    p.exp_string(":render").unwrap();
    p.exp_string("lapclone> :re").unwrap();
    // Ctrl-C clears the line and keeps the session (wait for the fresh prompt: a new
    // prompt flushes input typed before it).
    p.send_control('c').unwrap();
    p.exp_string("\x1b[?2004l").unwrap();
    p.exp_string("lapclone> ").unwrap();

    // A unique patch-name prefix inside a string completes in place.
    p.send("get_patch(\"c\t").unwrap();
    p.flush().unwrap();
    p.exp_string("get_patch(\"cat").unwrap();
    p.send_line("\")").unwrap();
    p.exp_string("=> get_patch(\"cat\")").unwrap();
    p.exp_string("lapclone> ").unwrap();

    p.send_control('d').unwrap();
    p.exp_eof().unwrap();
    let saved = std::fs::read_to_string(&history).unwrap();
    assert!(saved.contains("40 + 2"), "{saved}");
}

#[test]
fn ctrl_c_cancels_a_running_render_and_keeps_the_session() {
    let dir = tempfile::tempdir().unwrap();
    // A long scene (2,880 frames): far more than can render before the Ctrl-C arrives.
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let scene = dir.path().join("long.rhai");
    std::fs::write(
        &scene,
        format!(
            "canvas(600, 400, #{{ fps: 24, duration: 120, background: \"{0}/coffee.png\" }});\n\
             let cat = patch(\"cat\", #{{ source: \"{0}/chelsea.png\", mask: \"{0}/masks/chelsea_face.png\" }});\n\
             cat.at(0, [100, 100]).at(120, [500, 300]);\n",
            assets.display()
        ),
    )
    .unwrap();
    let frames = dir.path().join("frames");
    let command = repl_command(&scene, dir.path(), &dir.path().join("history.txt"), &[]);
    let mut p = spawn_command(command, Some(60_000)).unwrap();
    p.exp_string("lapclone> ").unwrap();
    // Interrupt the render once its first frame file exists (in the temporary folder the
    // frames stay in until the last one is written).
    p.send_line(&format!(":render -o {}", frames.display()))
        .unwrap();
    let started = || {
        std::fs::read_dir(dir.path()).unwrap().flatten().any(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with(".frames.") && e.path().join("frame_0001.png").exists()
        })
    };
    while !started() {
        std::thread::yield_now();
    }
    p.send_control('c').unwrap();
    p.exp_string("cancelled").unwrap();
    p.exp_string("lapclone> ").unwrap();
    // A cancelled PNG sequence leaves nothing: no frame folder, no temporary folder.
    assert!(!frames.exists(), "the cancelled render left its frames");
    assert!(!started(), "the cancelled render left its temporary folder");
    // The session goes on.
    p.send_line("1 + 1").unwrap();
    p.exp_string("=> 2").unwrap();
    p.send_control('d').unwrap();
    p.exp_eof().unwrap();
}

/// SIGTERM at the prompt ends the session (exit 1, "interrupted") and gives the terminal
/// back as the session found it: the line editor's raw mode and bracketed paste are undone,
/// so the shell's `stty -g` reads the same before and after.
#[test]
fn sigterm_at_the_prompt_gives_the_terminal_back() {
    let dir = tempfile::tempdir().unwrap();
    let mut command = Command::new("sh");
    command
        .arg("-c")
        .arg("echo \"shell $$\"; stty -g; echo =; \"$0\" repl --preview \"$1\" --history \"$2\"; echo \"exit $?\"; stty -g; echo =")
        .arg(env!("CARGO_BIN_EXE_lapclone"))
        .arg(dir.path().join("preview.png"))
        .arg(dir.path().join("history.txt"))
        .env("TERM", "xterm")
        .env("LAPCLONE_INLINE", "off");
    let mut p = spawn_command(command, Some(20_000)).unwrap();
    p.exp_string("shell ").unwrap();
    let shell: u32 = p.read_line().unwrap().trim().parse().unwrap();
    let before = p.exp_string("=").unwrap();
    p.exp_string("lapclone> ").unwrap();
    let repl = crate::processes::children_named(shell, "lapclone");
    assert_eq!(repl.len(), 1, "the session under the shell: {repl:?}");
    let status = Command::new("kill")
        .args(["-TERM", &repl[0].to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let ended = p.exp_string("exit 1").unwrap();
    assert!(ended.contains("interrupted"), "{ended:?}");
    assert!(
        ended.contains("\x1b[?2004l"),
        "bracketed paste left on: {ended:?}"
    );
    let after = p.exp_string("=").unwrap();
    assert_eq!(after.trim(), before.trim(), "the terminal's settings");
    p.exp_eof().unwrap();
}

/// What a page's line prints (its value, a warning) goes above the prompt with the line
/// itself, so the prompt and the half-typed entry under it stay whole; typing ahead with a
/// view attached reaches the prompt whole.
#[test]
fn a_page_lines_output_goes_above_a_prompt_in_use() {
    use tungstenite::client::IntoClientRequest;
    let dir = tempfile::tempdir().unwrap();
    let scene = crate::view_ws::cat_scene(dir.path());
    let history = dir.path().join("history.txt");
    let command = repl_command(&scene, dir.path(), &history, &["--view", "--port", "0"]);
    let mut p = spawn_command(command, Some(20_000)).unwrap();
    p.exp_string("view: http://").unwrap();
    let rest = p.read_line().unwrap();
    let (host, token) = rest.trim().split_once("/?token=").unwrap();
    p.exp_string("lapclone> ").unwrap();
    // Typed ahead at once, as a paste without bracketed paste comes: every character is
    // read (the line editor once kept all but the first until the next key).
    p.send("cat.na").unwrap();
    p.flush().unwrap();
    p.exp_string("cat.na").unwrap();
    let mut request = format!("ws://{host}/ws?token={token}")
        .into_client_request()
        .unwrap();
    let origin = format!("http://{host}").parse().unwrap();
    request.headers_mut().insert("Origin", origin);
    let (mut socket, _) = tungstenite::connect(request).unwrap();
    let rev = loop {
        if let tungstenite::Message::Text(text) = socket.read().unwrap() {
            let value: serde_json::Value = serde_json::from_str(text.as_str()).unwrap();
            if value["type"] == "scene" {
                break value["rev"].as_u64().unwrap();
            }
        }
    };
    // A key removed where there is none: the line and its error, several lines with the
    // caret, are both printed.
    let edit = serde_json::json!({"type": "edit", "rev": rev, "commit": true,
        "edit": {"op": "remove_key", "patch": "cat", "track": "at", "t": 1.5}});
    let text = edit.to_string();
    socket
        .send(tungstenite::Message::Text(text.into()))
        .unwrap();
    p.exp_string("(view) cat.remove_key(1.5, \"at\");").unwrap();
    p.exp_string("^").unwrap();
    // The prompt comes back, with the half-typed entry, after everything the line printed.
    p.exp_string("lapclone> cat.na").unwrap();
    p.send_control('c').unwrap();
    p.exp_string("lapclone> ").unwrap();
    p.send_control('d').unwrap();
    p.exp_eof().unwrap();
}

/// `:save` into a FIFO nobody reads waits for a reader, as a shell's `>` does, and Ctrl-C
/// ends the wait with an error; the session goes on (a blocking open hung it for good).
#[cfg(unix)]
#[test]
fn ctrl_c_ends_a_save_waiting_for_a_fifo_reader() {
    let dir = tempfile::tempdir().unwrap();
    let scene = crate::view_ws::cat_scene(dir.path());
    let fifo = dir.path().join("saved.rhai");
    crate::files::make_fifo(&fifo);
    let command = repl_command(&scene, dir.path(), &dir.path().join("history.txt"), &[]);
    let mut p = spawn_command(command, Some(60_000)).unwrap();
    p.exp_string("lapclone> ").unwrap();
    p.send_line(&format!(":save {}", fifo.display())).unwrap();
    // The Ctrl-C comes once the entry waits for the reader (asleep between its looks):
    // earlier, the prompt would clear the line, or the entry's start lower the flag.
    let pid = process_with_argument(&fifo.with_file_name("preview.png"));
    let waiting = (0..6000).any(|_| {
        std::thread::sleep(std::time::Duration::from_millis(10));
        // Entries run on a thread of their own (the scene's stack): any of the threads.
        let tasks = std::fs::read_dir(format!("/proc/{pid}/task"))
            .into_iter()
            .flatten();
        tasks.flatten().any(|task| {
            std::fs::read_to_string(task.path().join("wchan"))
                .is_ok_and(|w| w.contains("nanosleep"))
        })
    });
    assert!(
        waiting,
        "the save never waited interruptibly for its reader"
    );
    p.send_control('c').unwrap();
    p.exp_string("interrupted while waiting for a program to read the FIFO")
        .unwrap();
    p.exp_string("lapclone> ").unwrap();
    p.send_line("1 + 1").unwrap();
    p.exp_string("=> 2").unwrap();
    p.send_control('d').unwrap();
    p.exp_eof().unwrap();
}

/// The process whose command line holds `argument` (a path unique to one test).
#[cfg(unix)]
fn process_with_argument(argument: &Path) -> u32 {
    let wanted = argument.as_os_str().as_encoded_bytes();
    let found = std::fs::read_dir("/proc")
        .unwrap()
        .flatten()
        .find_map(|entry| {
            let pid: u32 = entry.file_name().to_str()?.parse().ok()?;
            let line = std::fs::read(entry.path().join("cmdline")).ok()?;
            line.split(|&b| b == 0)
                .any(|part| part == wanted)
                .then_some(pid)
        });
    found.expect("the REPL's process")
}

/// `lapclone repl SCENE` with `extra` arguments, its preview in `dir` and its history at
/// `history`, for a terminal that shows no inline pictures.
fn repl_command(scene: &Path, dir: &Path, history: &Path, extra: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
    command
        .arg("repl")
        .arg(scene)
        .args(extra)
        .arg("--preview")
        .arg(dir.join("preview.png"))
        .arg("--history")
        .arg(history)
        .env("TERM", "xterm")
        .env("LAPCLONE_INLINE", "off");
    command
}
