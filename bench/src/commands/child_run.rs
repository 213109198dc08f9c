//! One command timed from outside, as a user waits for it: takes a program, its arguments,
//! a working folder and a folder for its output streams, and gives the wall time from spawn
//! to reap, the child's peak resident set and what it printed on stdout. The peak is the
//! kernel's own high-water mark of that one process (`wait4`'s `ru_maxrss`), exact however
//! briefly the peak lasted, which polling `/proc` cannot promise, and it needs no external
//! `time` program.

use std::ffi::OsString;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::Instant;

use anyhow::Context;

/// A command line to run, from `cwd`.
#[derive(Clone, Debug)]
pub struct Invocation {
    /// Short name used for the log files and in messages.
    pub name: &'static str,
    pub program: PathBuf,
    pub args: Vec<OsString>,
    pub cwd: PathBuf,
}

impl Invocation {
    /// The command as a shell would show it (for reports; not re-parsed).
    pub fn display(&self) -> String {
        let mut line = self.program.display().to_string();
        for arg in &self.args {
            line.push(' ');
            line.push_str(&arg.to_string_lossy());
        }
        line
    }
}

/// One finished run.
#[derive(Clone, Debug)]
pub struct Measured {
    /// Spawn to reap, seconds.
    pub wall_s: f64,
    /// Peak resident set of the child itself (not of its own children), bytes; `None` where
    /// the platform does not report it.
    pub peak_rss_bytes: Option<u64>,
    /// Everything the command wrote on stdout.
    pub stdout: String,
}

/// Runs `invocation` to completion with an empty stdin and its output streams in files under
/// `logs` (a pipe nobody reads could stall it). A non-zero exit is an error carrying the last
/// lines of its stderr.
pub fn run(invocation: &Invocation, logs: &Path) -> anyhow::Result<Measured> {
    let out_path = logs.join(format!("{}.stdout", invocation.name));
    let err_path = logs.join(format!("{}.stderr", invocation.name));
    let stdout =
        File::create(&out_path).with_context(|| format!("cannot create {}", out_path.display()))?;
    let stderr =
        File::create(&err_path).with_context(|| format!("cannot create {}", err_path.display()))?;
    let started = Instant::now();
    let child = Command::new(&invocation.program)
        .args(&invocation.args)
        .current_dir(&invocation.cwd)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .with_context(|| format!("cannot start `{}`", invocation.display()))?;
    let (status, peak_rss_bytes) = reap(child)?;
    let wall_s = started.elapsed().as_secs_f64();
    if !status.success() {
        let tail = last_lines(&std::fs::read_to_string(&err_path).unwrap_or_default(), 8);
        anyhow::bail!("`{}` failed ({status}): {tail}", invocation.display());
    }
    let stdout = std::fs::read_to_string(&out_path)
        .with_context(|| format!("cannot read {}", out_path.display()))?;
    Ok(Measured {
        wall_s,
        peak_rss_bytes,
        stdout,
    })
}

/// Whether `program args…` starts and exits 0 (output discarded); `Err` says why not.
pub fn probe(program: &Path, args: &[&str]) -> Result<(), String> {
    let output = Command::new(program)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", program.display()))?;
    if output.status.success() {
        Ok(())
    } else {
        let stderr = String::from_utf8_lossy(&output.stderr);
        Err(format!(
            "`{} {}` failed ({}): {}",
            program.display(),
            args.join(" "),
            output.status,
            last_lines(&stderr, 1)
        ))
    }
}

fn last_lines(text: &str, count: usize) -> String {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    lines[lines.len().saturating_sub(count)..].join(" | ")
}

/// Waits for `child` with `wait4`, which also gives the child's resource usage.
#[cfg(unix)]
fn reap(child: Child) -> anyhow::Result<(ExitStatus, Option<u64>)> {
    use std::os::unix::process::ExitStatusExt;
    // invariant: a process id always fits pid_t on Unix (std reads it from one).
    let pid = libc::pid_t::try_from(child.id()).expect("pid fits pid_t");
    let mut status: libc::c_int = 0;
    // SAFETY: `rusage` is plain integers, for which all-zero bytes are a valid value.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    loop {
        // SAFETY: `pid` is our own child, not yet reaped (std never waited on it), and both
        // pointers are to live locals of the right types.
        let reaped = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
        if reaped == pid {
            break;
        }
        let error = std::io::Error::last_os_error();
        if error.kind() != std::io::ErrorKind::Interrupted {
            return Err(error).context("wait4 on the benchmarked command");
        }
    }
    // `child` is reaped: dropping it only closes its (null or file) handles.
    drop(child);
    let maxrss = u64::try_from(usage.ru_maxrss).unwrap_or(0);
    // Linux and the BSDs report kibibytes, macOS bytes.
    let bytes = if cfg!(target_os = "macos") {
        maxrss
    } else {
        maxrss * 1024
    };
    Ok((ExitStatus::from_raw(status), Some(bytes)))
}

#[cfg(not(unix))]
fn reap(mut child: Child) -> anyhow::Result<(ExitStatus, Option<u64>)> {
    Ok((child.wait()?, None))
}

#[cfg(test)]
mod tests {
    use super::last_lines;

    #[test]
    fn last_lines_keeps_the_tail_without_blank_lines() {
        assert_eq!(last_lines("a\n\nb\nc\n\n", 2), "b | c");
        assert_eq!(last_lines("only", 5), "only");
        assert_eq!(last_lines("", 3), "");
    }
}
