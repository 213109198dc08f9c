//! Stop signals for the batch commands: takes Ctrl-C, SIGTERM and SIGHUP (`kill`, `timeout`,
//! a container stopping, a closed terminal) and gives either a cancel flag that a command's
//! own loop checks (`render`: its outputs removed, "interrupted", exit 1), or, for a command
//! without such a loop, its temporary outputs removed and exit 1 at once. A second signal
//! always ends the program at once, its temporary outputs removed. The REPL, which keeps
//! Ctrl-C for itself, ends on the other two after removing its private preview folder and
//! giving the terminal back its settings.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A flag the first stop signal raises; the next one ends the program.
pub(crate) fn cancel_flag() -> Arc<AtomicBool> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    on_signals(move || {
        if flag.swap(true, Ordering::SeqCst) {
            stop_now();
        }
    });
    cancel
}

/// Any stop signal ends the program at once, its temporary outputs removed.
pub(crate) fn stop_on_signals() {
    on_signals(stop_now);
}

/// SIGTERM and SIGHUP end the program at once, after `cleanup` and with its temporary
/// outputs removed; so does SIGINT with `ctrl_c` (a REPL fed by a pipe or a script, which
/// has no prompt to give Ctrl-C to). Without it SIGINT is left to the caller (the
/// interactive REPL, whose line editor and cancel flag own it).
pub(crate) fn stop_on_terminate(cleanup: impl Fn() + Send + 'static, ctrl_c: bool) {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let stops: &[i32] = if ctrl_c {
            &[SIGTERM, SIGHUP, SIGINT]
        } else {
            &[SIGTERM, SIGHUP]
        };
        let Ok(mut signals) = signal_hook::iterator::Signals::new(stops) else {
            return;
        };
        let _ = std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                if signals.forever().next().is_some() {
                    cleanup();
                    stop_now();
                }
            });
    }
    #[cfg(not(unix))]
    drop((cleanup, ctrl_c));
}

/// The terminal's settings as the REPL found them. A signal that ends the session while the
/// line editor holds the terminal raw puts them back, so the shell it returns to echoes and
/// takes lines again.
pub(crate) struct SavedTerminal {
    #[cfg(unix)]
    settings: rustix::termios::Termios,
}

impl SavedTerminal {
    /// Standard input's settings, when it is a terminal.
    pub fn capture() -> Option<Self> {
        #[cfg(unix)]
        {
            let settings = rustix::termios::tcgetattr(std::io::stdin()).ok()?;
            Some(Self { settings })
        }
        #[cfg(not(unix))]
        None
    }

    /// Puts the settings back, turns off the bracketed paste the line editor turned on, and
    /// ends the prompt's line.
    pub fn restore(&self) {
        #[cfg(unix)]
        {
            use rustix::termios::{tcsetattr, OptionalActions};
            use std::io::{IsTerminal, Write};
            let _ = tcsetattr(std::io::stdin(), OptionalActions::Now, &self.settings);
            let mut out = std::io::stdout();
            if out.is_terminal() {
                let _ = out.write_all(b"\x1b[?2004l\r\n");
                let _ = out.flush();
            }
        }
    }
}

fn stop_now() {
    lapclone::util::remove_pending_outputs();
    eprint_line!("lapclone: interrupted");
    std::process::exit(1);
}

/// Runs `action` on a thread of its own for each stop signal. If the handler or its thread
/// cannot be set up, the signals keep their default action (the program ends).
fn on_signals(action: impl Fn() + Send + 'static) {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        let _ = std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || signals.forever().for_each(|_| action()));
    }
    #[cfg(not(unix))]
    {
        let _ = ctrlc::set_handler(action);
    }
}
