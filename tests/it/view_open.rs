//! `lapclone repl --view --open`: the URL (token included) goes to the program `$BROWSER`
//! names — here a stand-in script that writes down its arguments — and a browser that
//! cannot be started is a warning while the session goes on and succeeds.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use super::view_ws::cat_scene;

/// Runs `lapclone repl SCENE --view --port 0 --open` with `env`, reading `:t 0.5` and then
/// the end of its input.
fn open_session(dir: &Path, env: &[(&str, &std::ffi::OsStr)]) -> Output {
    let scene = cat_scene(dir);
    let input = dir.join("input.txt");
    std::fs::write(&input, ":t 0.5\n").unwrap();
    let mut command = Command::new(env!("CARGO_BIN_EXE_lapclone"));
    command
        .args([
            "repl",
            scene.to_str().unwrap(),
            "--view",
            "--port",
            "0",
            "--open",
        ])
        .arg("--preview")
        .arg(dir.join("preview.png"))
        .current_dir(dir)
        .stdin(Stdio::from(std::fs::File::open(&input).unwrap()));
    for (key, value) in env {
        command.env(key, value);
    }
    command.output().unwrap()
}

fn printed_url(out: &Output) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("view: "))
        .unwrap_or_else(|| panic!("no URL printed: {stdout}"));
    line.trim_start_matches("view: ").to_string()
}

#[cfg(unix)]
#[test]
fn open_runs_the_browser_program_with_the_url_and_its_token() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = tempfile::tempdir().unwrap();
    let args = dir.path().join("args.txt");
    let stand_in = dir.path().join("stand-in browser");
    std::fs::write(
        &stand_in,
        format!(
            "#!/bin/sh\nprintf '%s\\n' \"$@\" > '{0}.part' && mv '{0}.part' '{0}'\n",
            args.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&stand_in, std::fs::Permissions::from_mode(0o755)).unwrap();
    // `$BROWSER` entries split at spaces: the stand-in is named through a link without one.
    let link = dir.path().join("browser");
    std::os::unix::fs::symlink(&stand_in, &link).unwrap();
    let out = open_session(dir.path(), &[("BROWSER", link.as_os_str())]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let url = printed_url(&out);
    let token = url.split_once("?token=").unwrap().1;
    assert_eq!(token.len(), 32, "{url}");
    assert!(token.chars().all(|c| c.is_ascii_hexdigit()), "{url}");
    // The stand-in runs on its own: wait for what it wrote.
    let started = Instant::now();
    while !args.exists() {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the browser program never ran"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(std::fs::read_to_string(&args).unwrap(), format!("{url}\n"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("cannot open a browser"), "{stderr}");
}

#[test]
fn a_missing_browser_is_a_warning_and_the_session_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    // No `$BROWSER` program and no desktop opener on an empty PATH.
    let empty = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-browser");
    let out = open_session(
        dir.path(),
        &[
            ("BROWSER", missing.as_os_str()),
            ("PATH", empty.path().as_os_str()),
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: cannot open a browser") && stderr.contains("no-such-browser"),
        "{stderr}"
    );
    assert!(printed_url(&out).contains("?token="));
    // The session went on after the warning: it loaded the scene.
    assert!(String::from_utf8_lossy(&out.stdout).contains("loaded "));
}
