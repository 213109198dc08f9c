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
    let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
    command
        .arg("repl")
        .arg(&scene)
        .arg("--preview")
        .arg(dir.path().join("preview.png"))
        .arg("--history")
        .arg(&history)
        .env("TERM", "xterm")
        .env("LAPCLONE_INLINE", "off");
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
    p.exp_string("=> patch(\"cat\")").unwrap();
    p.exp_string("lapclone> ").unwrap();

    p.send_control('d').unwrap();
    p.exp_eof().unwrap();
    let saved = std::fs::read_to_string(&history).unwrap();
    assert!(saved.contains("40 + 2"), "{saved}");
}
