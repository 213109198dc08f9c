//! Interrupted renders (docs/robustness.md): SIGINT (and SIGTERM, SIGHUP) during
//! `lapclone render` leaves no
//! frame and no temporary folder (a PNG sequence is all or nothing), and the render exits 1
//! saying it was interrupted; an interrupted GIF/APNG leaves no file at all, and an
//! interrupted MP4 neither a file nor an ffmpeg process, whether it comes while frames are
//! still going in (skipped without ffmpeg) or while ffmpeg finishes the file (a stand-in
//! ffmpeg that takes its time).
//!
//! No sleeps: the test polls for the first output with a bounded, yielding loop.

#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use crate::files;
use crate::processes::children_named;
use files::sorted_names;

/// A long scene (2 000 frames) so the render is still running when the signal comes.
fn write_scene(dir: &Path) -> PathBuf {
    let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets");
    let scene = dir.join("long.rhai");
    let text = format!(
        "canvas(64, 48, #{{ fps: 100, duration: 20, background: \"{}\" }});\n\
         let p = patch(\"p\", #{{ source: \"{}\", polygons: [[[10, 10], [60, 14], [30, 50]]] }});\n\
         p.at(0, [30, 24]).at(20, [40, 30]);\n\
         p.drag([40, 16], 12).key(0, [40, 16]).key(20, [46, 20]);\n",
        assets.join("coffee.png").display(),
        assets.join("chelsea.png").display()
    );
    std::fs::write(&scene, text).unwrap();
    scene
}

fn spawn_render(scene: &Path, out: &Path, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Polls (yielding, bounded) until `ready` holds or the child has exited.
fn wait_until(child: &mut Child, mut ready: impl FnMut() -> bool) -> bool {
    for _ in 0..50_000_000u64 {
        if ready() {
            return true;
        }
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::yield_now();
    }
    false
}

fn interrupt(child: &Child) {
    signal(child, "-INT");
}

/// Sends `child` the signal `name` (as `kill` spells it: `-TERM`).
fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([name, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// Sends `child` the signal `name` and checks it stopped as an interrupted command does:
/// exit 1, saying "interrupted" (`what` names the case in failures).
fn stop(child: Child, name: &str, what: &str) {
    signal(&child, name);
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{what}: {stderr}");
    assert!(stderr.contains("interrupted"), "{what}: {stderr}");
}

/// SIGTERM (`kill`, `timeout`, a container stopping) and SIGHUP (a closed terminal) stop a
/// render as Ctrl-C does: exit 1, "interrupted", nothing left beside the scene.
#[test]
fn sigterm_and_sighup_stop_a_render_as_ctrl_c_does() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    for (name, out) in [
        ("-TERM", "movie.gif"),
        ("-HUP", "frames"),
        ("-TERM", "frames"),
    ] {
        let mut child = spawn_render(&scene, &dir.path().join(out), &[]);
        let started = wait_until(&mut child, || {
            sorted_names(dir.path()).iter().any(|n| n.ends_with(".tmp"))
        });
        assert!(started, "{name} {out}: the render ended before writing");
        stop(child, name, &format!("{name} {out}"));
        assert_eq!(
            sorted_names(dir.path()),
            ["long.rhai"],
            "{name} {out}: files left"
        );
    }
}

/// A stop signal during `lapclone test --update` leaves the goldens it finished and no
/// temporary file among them, and exits 1 saying so.
#[test]
fn a_stopped_golden_update_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let goldens = dir.path().join("goldens").join("long");
    for name in ["-TERM", "-INT"] {
        let _ = std::fs::remove_dir_all(dir.path().join("goldens"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .arg("test")
            .arg(&scene)
            .args(["--update", "--jobs", "1", "--frames", "1..2000"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let started = wait_until(&mut child, || goldens.join("frame_0002.png").exists());
        assert!(started, "{name}: the update ended before its second golden");
        stop(child, name, name);
        let names = sorted_names(&goldens);
        assert!(
            names
                .iter()
                .all(|n| n.starts_with("frame_") && n.ends_with(".png")),
            "{names:?}"
        );
    }
}

#[test]
fn sigint_during_a_png_sequence_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let frames = dir.path().join("frames");
    let mut child = spawn_render(&scene, &frames, &["--jobs", "2"]);
    // The frames go into a temporary folder beside `frames` until the last one is written.
    let started = wait_until(&mut child, || {
        sorted_names(dir.path())
            .iter()
            .filter(|n| n.starts_with(".frames.") && n.ends_with(".tmp"))
            .any(|n| dir.path().join(n).join("frame_0001.png").exists())
    });
    assert!(started, "the render ended before its first frame appeared");
    stop(child, "-INT", "png sequence");
    assert_eq!(
        sorted_names(dir.path()),
        ["long.rhai"],
        "the interrupted render left files"
    );
}

#[test]
fn sigint_during_an_animation_file_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    for format in ["apng", "gif"] {
        let out = dir.path().join(format!("movie.{format}"));
        let mut child = spawn_render(&scene, &out, &["--format", format]);
        // The writer's temporary file appears once the first frame is being written.
        let started = wait_until(&mut child, || {
            sorted_names(dir.path()).iter().any(|n| n.ends_with(".tmp"))
        });
        assert!(started, "{format}: the render ended before writing");
        stop(child, "-INT", format);
        assert_eq!(
            sorted_names(dir.path()),
            ["long.rhai"],
            "{format}: the interrupted render left files"
        );
    }
}

/// Whether any process is left in process group `group`.
fn group_alive(group: u32) -> bool {
    Command::new("kill")
        .args(["-0", "--", &format!("-{group}")])
        .stderr(Stdio::null())
        .status()
        .unwrap()
        .success()
}

#[test]
fn sigint_during_a_video_stops_ffmpeg_and_leaves_no_file() {
    if lapclone::util::find_program("ffmpeg").is_none() {
        eprintln!("skipped: ffmpeg not on PATH (apt-get install ffmpeg to run this test)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let out = dir.path().join("movie.mp4");
    let mut child = spawn_render(&scene, &out, &[]);
    let id = child.id();
    // The temporary file exists once the render has started ffmpeg.
    let started = wait_until(&mut child, || {
        sorted_names(dir.path()).iter().any(|n| n.ends_with(".tmp"))
            && children_named(id, "ffmpeg").len() == 1
    });
    assert!(started, "the render ended before ffmpeg wrote anything");
    let ffmpeg = children_named(child.id(), "ffmpeg");
    assert_eq!(ffmpeg.len(), 1, "ffmpeg processes: {ffmpeg:?}");
    interrupt_video(child, dir.path(), ffmpeg[0]);
}

/// Interrupts a video render whose encoder leads process group `ffmpeg` and checks that it
/// exits 1 saying so, leaving nothing in `dir` but the scene and no encoder process.
fn interrupt_video(child: Child, dir: &Path, ffmpeg: u32) {
    // The encoder leads a process group of its own, so the signal reaches only lapclone.
    assert!(group_alive(ffmpeg));
    interrupt(&child);
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    assert_eq!(
        sorted_names(dir),
        ["long.rhai"],
        "the interrupted video render left files"
    );
    assert!(
        !group_alive(ffmpeg),
        "ffmpeg (process group {ffmpeg}) still runs"
    );
}

/// A stand-in for ffmpeg that takes the whole stream, starts the file, says that its input
/// has ended (writing its process id into `$FAKE_FFMPEG_FLUSHING`), then takes its time
/// finishing, as x264 does draining its lookahead. `exec` keeps it one process, as ffmpeg is.
const SLOW_FINISHING_FFMPEG: &str = "#!/bin/sh
for output; do :; done
printf 'not a video yet' > \"$output\"
cat > /dev/null
echo $$ > \"$FAKE_FFMPEG_FLUSHING.part\"
mv \"$FAKE_FFMPEG_FLUSHING.part\" \"$FAKE_FFMPEG_FLUSHING\"
exec sleep 60
";

#[test]
fn sigint_while_ffmpeg_finishes_the_video_stops_it_and_leaves_no_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let tools = tempfile::tempdir().unwrap();
    let fake = tools.path().join("ffmpeg");
    std::fs::write(&fake, SLOW_FINISHING_FFMPEG).unwrap();
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let flushing = tools.path().join("flushing");
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut search = vec![tools.path().to_path_buf()];
    search.extend(std::env::split_paths(&path));
    let out = dir.path().join("movie.mp4");
    let mut child = Command::new(env!("CARGO_BIN_EXE_lapclone"))
        .args([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .args(["--frames", "1..3"])
        .env("PATH", std::env::join_paths(search).unwrap())
        .env("FAKE_FFMPEG_FLUSHING", &flushing)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Every frame is in and the pipe closed: lapclone now waits for ffmpeg to finish.
    assert!(
        wait_until(&mut child, || flushing.exists()),
        "the render ended before its encoder read the whole stream"
    );
    let pid = std::fs::read_to_string(&flushing).unwrap();
    interrupt_video(child, dir.path(), pid.trim().parse().unwrap());
}

/// SIGTERM and SIGHUP end a REPL session (exit 1, "interrupted") and take its private
/// preview folder with it, as `:quit` does, and a `:render` in progress with its temporary
/// folder; so does Ctrl-C in a piped session, which has no prompt to give it to.
#[test]
fn sigterm_and_sighup_end_a_repl_and_remove_its_preview_folder() {
    use std::io::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let temp = dir.path().join("temp");
    for name in ["-TERM", "-HUP", "-INT"] {
        std::fs::create_dir(&temp).unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_lapclone"))
            .arg("repl")
            .arg(&scene)
            .env("TMPDIR", &temp)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The first preview is drawn once the session (and its signal handler) is up.
        let drawn = wait_until(&mut child, || {
            sorted_names(&temp)
                .iter()
                .any(|folder| temp.join(folder).join("preview.png").exists())
        });
        assert!(drawn, "{name}: the session ended before its first preview");
        // Its input stays open: only the signal may end the session.
        let mut input = child.stdin.take().unwrap();
        let frames = dir.path().join("frames");
        writeln!(input, ":render -o {}", frames.display()).unwrap();
        let rendering = wait_until(&mut child, || {
            sorted_names(dir.path()).iter().any(|n| n.ends_with(".tmp"))
        });
        assert!(rendering, "{name}: the session ended before its render");
        stop(child, name, &format!("repl {name}"));
        drop(input);
        assert_eq!(
            sorted_names(&temp),
            Vec::<String>::new(),
            "{name}: left in the temp folder"
        );
        std::fs::remove_dir(&temp).unwrap();
        assert_eq!(sorted_names(dir.path()), ["long.rhai"], "{name}: left");
    }
}

/// Whether process `pid`'s main thread is asleep (in `nanosleep`): a render waiting for its
/// FIFO's reader sleeps between looks; one stuck in a blocking open never does.
fn sleeping(pid: u32) -> bool {
    let wchan = std::fs::read_to_string(format!("/proc/{pid}/wchan"));
    wchan.is_ok_and(|w| w.contains("nanosleep"))
}

/// A render into a FIFO nobody reads waits for a reader, and one Ctrl-C ends the wait: exit
/// 1, "interrupted", the FIFO left as it was (a blocking open could not be interrupted).
#[test]
fn ctrl_c_ends_a_wait_for_a_fifo_reader() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let fifo = dir.path().join("out.y4m");
    files::make_fifo(&fifo);
    let child = spawn_render(&scene, &fifo, &[]);
    // Looked at for at most a minute: a blocking open never sleeps.
    let waiting = (0..6000).any(|_| {
        std::thread::sleep(std::time::Duration::from_millis(10));
        sleeping(child.id())
    });
    if !waiting {
        let mut child = child;
        let _ = child.kill();
        panic!("the render never waited interruptibly for its reader");
    }
    stop(child, "-INT", "a FIFO with no reader");
    let kind = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(kind.is_fifo());
    assert_eq!(sorted_names(dir.path()), ["long.rhai", "out.y4m"]);
}

/// A second signal ends a render at once (the first asks it to stop after the frame in
/// progress): a PNG sequence's temporary folder goes too, however the two fall against the
/// render's own cleanup.
#[test]
fn a_second_signal_during_a_png_render_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    for name in ["-INT", "-TERM", "-INT", "-TERM"] {
        let mut child = spawn_render(&scene, &dir.path().join("frames"), &[]);
        let started = wait_until(&mut child, || {
            sorted_names(dir.path()).iter().any(|n| n.ends_with(".tmp"))
        });
        assert!(started, "{name}: the render ended before writing");
        signal(&child, name);
        stop(child, name, &format!("{name} twice"));
        assert_eq!(
            sorted_names(dir.path()),
            ["long.rhai"],
            "{name} twice: files left"
        );
    }
}
