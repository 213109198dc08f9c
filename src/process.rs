//! External programs (ffmpeg, ffprobe) as child processes: takes a `Command` and gives a
//! running [`Child`] whose standard error is collected by a thread of its own (so a chatty
//! program never stalls on a full pipe), its last lines for an error message, a wait that a
//! cancel flag cuts short, and a kill when it is dropped unfinished.

use std::io::Read;
use std::process::{ChildStdin, ChildStdout, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// A started program; dropped, it is killed (if still running) and reaped.
pub struct Child {
    child: std::process::Child,
    stderr: Option<JoinHandle<String>>,
}

impl Child {
    /// Starts `command` with its standard error piped to a collecting thread; standard
    /// input and output are as `command` sets them.
    pub fn spawn(command: &mut Command) -> std::io::Result<Child> {
        let mut child = command.stderr(Stdio::piped()).spawn()?;
        // invariant: requested as a pipe just above.
        let mut pipe = child.stderr.take().expect("piped stderr");
        let stderr = std::thread::spawn(move || {
            let mut text = String::new();
            let _ = pipe.read_to_string(&mut text);
            text
        });
        Ok(Child {
            child,
            stderr: Some(stderr),
        })
    }

    /// The input pipe, once, if `command` asked for one.
    pub fn take_stdin(&mut self) -> Option<ChildStdin> {
        self.child.stdin.take()
    }

    /// The output pipe, once, if `command` asked for one.
    pub fn take_stdout(&mut self) -> Option<ChildStdout> {
        self.child.stdout.take()
    }

    /// Waits for the program to exit; `Ok(None)` as soon as `cancel` is set instead.
    pub fn wait(&mut self, cancel: Option<&AtomicBool>) -> std::io::Result<Option<ExitStatus>> {
        let Some(cancel) = cancel else {
            return self.child.wait().map(Some);
        };
        loop {
            if let Some(status) = self.child.try_wait()? {
                return Ok(Some(status));
            }
            if cancel.load(Ordering::Relaxed) {
                return Ok(None);
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    /// Kills the program if it still runs, and reaps it.
    pub fn stop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// The last `n` non-empty lines the program printed on standard error. Call it once the
    /// program has exited or been stopped: it waits for the pipe to close. Empty after the
    /// first call.
    pub fn last_lines(&mut self, n: usize) -> Vec<String> {
        let text = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
        lines[lines.len().saturating_sub(n)..]
            .iter()
            .map(|l| l.to_string())
            .collect()
    }
}

impl Drop for Child {
    fn drop(&mut self) {
        self.stop();
    }
}
