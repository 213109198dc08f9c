//! Subcommand definitions and dispatch. Each subcommand lives in its own file with its
//! argument struct; the library does the work, these files only translate arguments,
//! print results and map errors to exit codes.

use clap::{Parser, Subcommand};

pub mod check;
pub mod clone;
pub mod mesh;
pub mod mesh_args;
mod picture_out;
pub mod preview;
pub mod render;
pub mod render_args;
pub mod repl;
mod scene_open;
mod signals;
pub mod test;
pub mod test_args;
pub mod test_pending;
pub mod test_report;
pub mod track;
pub mod view;

/// An argument combination clap cannot reject by itself; exits with code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// `--jobs` above this is a usage error: it is far beyond any machine's cores, and each
/// thread costs a stack.
pub const MAX_JOBS: usize = 1024;

/// The one limit on worker threads, for every command's `--jobs`: 0 or more than
/// [`MAX_JOBS`] is a usage error; more than `useful` (the cores this process may use) is
/// lowered to it with a note on stderr, since more threads than cores only cost memory.
/// Without `--jobs`: `useful`.
pub fn jobs(asked: Option<usize>, useful: usize) -> Result<usize, UsageError> {
    let useful = useful.max(1);
    match asked {
        None => Ok(useful),
        Some(0) => Err(UsageError("--jobs must be at least 1".into())),
        Some(n) if n > MAX_JOBS => Err(UsageError(format!(
            "--jobs {n}: at most {MAX_JOBS} (this machine has {useful} cores to use)"
        ))),
        Some(n) if n > useful => {
            eprint_line!("note: --jobs {n} lowered to {useful}, the cores this process may use");
            Ok(useful)
        }
        Some(n) => Ok(n),
    }
}

/// Whether standard output is open, for data written to it (`-o -`). Rust's runtime reopens
/// a closed one (`>&-`) on `/dev/null`, read-write, so the data would vanish without an
/// error; a shell's `>/dev/null` opens it write-only, which stays a legitimate sink.
/// Python's `subprocess.DEVNULL` is read-write too and cannot be told from a closed one,
/// so summary lines ([`say`]) never ask: losing them is harmless, and a command that did
/// its work must not then fail.
pub fn stdout_is_open() -> bool {
    #[cfg(target_os = "linux")]
    {
        let on_null = std::fs::read_link("/proc/self/fd/1")
            .is_ok_and(|p| p == std::path::Path::new("/dev/null"));
        let read_write = std::fs::read_to_string("/proc/self/fdinfo/1").is_ok_and(|info| {
            info.lines()
                .find_map(|l| l.strip_prefix("flags:"))
                .and_then(|f| u32::from_str_radix(f.trim(), 8).ok())
                .is_some_and(|flags| flags & 0o3 == 0o2)
        });
        !(on_null && read_write)
    }
    #[cfg(not(target_os = "linux"))]
    {
        true
    }
}

/// `-` given for a file a command writes but never streams (`--junit`, the REPL's
/// `--preview`, `:save`): refused, where it made a file named `-` that looked like
/// standard output. `./-` still names such a file.
pub fn refuse_stdout_dash(what: &str, path: &std::path::Path) -> Result<(), UsageError> {
    match path.as_os_str() == "-" {
        true => Err(UsageError(format!(
            "{what} -: `-` means standard output, which {what} does not write; name a file (./- for one named -)"
        ))),
        false => Ok(()),
    }
}

/// For data written to standard output (`-o -`): an error when it is closed
/// ([`stdout_is_open`]), since the data would be lost without one.
pub fn check_stdout_for_data() -> anyhow::Result<()> {
    if !stdout_is_open() {
        anyhow::bail!(
            "-o -: standard output is closed (or /dev/null opened read-write): the data would be lost"
        );
    }
    Ok(())
}

/// Writes `line` and a newline to standard output; a failed write (closed, a full disk, a
/// broken pipe) is an error (exit 1), never a panic and never silently lost.
pub fn say(line: impl std::fmt::Display) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{line}")
        .and_then(|()| out.flush())
        .map_err(|e| anyhow::anyhow!("writing to standard output: {e}"))
}

/// Prints what clap gave instead of arguments (the help, the version, or a usage error) and
/// gives the exit code: help and version that cannot be written (a full disk, a closed
/// output) are a failure, not a silent 0.
pub fn clap_exit(error: &clap::Error) -> i32 {
    use std::io::Write as _;
    let printed = error.print().and_then(|()| std::io::stdout().flush());
    if !error.use_stderr() {
        if let Err(e) = printed {
            eprint_line!("lapclone: error: writing to standard output: {e}");
            return 1;
        }
    }
    error.exit_code()
}

/// The first failed write to standard output (closed, a full disk, a broken pipe).
static STDOUT_FAILED: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Prints a line to standard output where a command goes on after a failed write (the
/// REPL, a review): the failure never panics, it is kept, and the command ends with it
/// (exit 1) at its next check, so nothing is silently lost.
pub(crate) fn print_line(line: impl std::fmt::Display) {
    if let Err(error) = say(line) {
        let _ = STDOUT_FAILED.set(describe(&error));
    }
}

/// The kept failed write, as an error.
pub(crate) fn stdout_failure() -> anyhow::Result<()> {
    match STDOUT_FAILED.get() {
        Some(message) => Err(anyhow::anyhow!("{message}")),
        None => Ok(()),
    }
}

/// The error and its causes as one line, `outer: cause: …`. The library's errors already
/// end their message with their cause's, so a cause whose text the line holds is not
/// repeated (anyhow's `{:#}` would print it twice).
pub fn describe(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if !line.contains(&text) {
            if !line.is_empty() {
                line.push_str(": ");
            }
            line.push_str(&text);
        }
    }
    line
}

#[derive(Parser, Debug)]
#[command(
    name = "lapclone",
    version,
    about = "Seamless image cloning and deformation with the combinatorial Laplacian"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Mesh a mask into an adaptive, boundary-conforming triangle mesh.
    Mesh(mesh::MeshArgs),
    /// Clone a source patch seamlessly into a target image (optionally deformed).
    Clone(clone::CloneArgs),
    /// Render a Rhai scene into frames (PNG sequence, GIF, APNG, Y4M, or MP4/WebM/MOV through ffmpeg).
    Render(render::RenderArgs),
    /// Render one frame of a scene.
    Preview(preview::PreviewArgs),
    /// Parse, evaluate and validate a scene without rendering it.
    Check(check::CheckArgs),
    /// Edit a scene interactively.
    Repl(repl::ReplArgs),
    /// Compare scenes' frames with their golden frames (accept, reject, review changes).
    Test(test_args::TestArgs),
    /// Follow points through footage and write their track as CSV (for a scene's `follow`).
    Track(track::TrackArgs),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    // `render` checks a cancel flag between frames; the REPL takes Ctrl-C for itself.
    if !matches!(cli.command, Command::Render(_) | Command::Repl(_)) {
        signals::stop_on_signals();
    }
    match cli.command {
        Command::Mesh(args) => mesh::run(args),
        Command::Clone(args) => clone::run(args),
        Command::Render(args) => render::run_render(args),
        Command::Preview(args) => preview::run_preview(args),
        Command::Check(args) => check::run_check(args),
        Command::Repl(args) => repl::run(args),
        Command::Test(args) => test::run(args),
        Command::Track(args) => track::run(args),
    }
}

/// Rejects NaN and infinities in numeric arguments (clap's f64 parser accepts them).
pub fn finite_f64(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!("`{text}` is not a finite number"))
    }
}

/// Parses `X,Y` into two finite numbers within the positions' bound
/// ([`lapclone::limits::MAX_POSITION`], as a scene's positions are).
pub fn point(text: &str) -> Result<[f64; 2], String> {
    let (x, y) = text
        .split_once(',')
        .ok_or_else(|| format!("`{text}` is not a point X,Y"))?;
    let point = [finite_f64(x)?, finite_f64(y)?];
    match point.into_iter().find_map(lapclone::limits::position_error) {
        Some(error) => Err(error),
        None => Ok(point),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn describe_names_every_cause_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let typed = lapclone::pixels::PixelError::Read {
            path: "in/a.png".into(),
            source: io,
        };
        let error = anyhow::Error::new(typed).context("loading the source");
        assert_eq!(
            describe(&error),
            "loading the source: cannot read image in/a.png: no such file"
        );
        let plain = anyhow::anyhow!("first").context("second");
        assert_eq!(describe(&plain), "second: first");
    }
}
