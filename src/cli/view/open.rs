//! `--open`: takes the view's URL and hands it to a browser — each program `$BROWSER` names
//! first (a `:`-separated list, as other tools read it; words split at spaces, and `%s` in
//! one stands for the URL, else the URL comes last), then the desktop's opener (`xdg-open`,
//! `open` on macOS, `explorer` on Windows). The first that starts is left running; when none
//! starts, or the one that started fails, that is a warning: the URL is printed anyway.

use std::ffi::OsString;
use std::process::{Command, Stdio};

/// Opens `url` in the user's browser (see the module's text); never fails the session.
pub fn open_in_browser(url: &str) {
    let mut tried = Vec::new();
    for (program, args) in candidates(std::env::var_os("BROWSER"), url) {
        let spawned = Command::new(&program)
            .args(&args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn();
        match spawned {
            Ok(mut child) => {
                // Waited for on the side so it leaves no zombie and a failure is reported.
                let _ = std::thread::Builder::new()
                    .name("view-open".into())
                    .spawn(move || match child.wait() {
                        Ok(status) if !status.success() => eprint_line!(
                            "warning: the browser program {program} ended with {status}; \
                             open the URL above"
                        ),
                        _ => {}
                    });
                return;
            }
            Err(error) => tried.push(format!("{program}: {error}")),
        }
    }
    eprint_line!(
        "warning: cannot open a browser ({}); open the URL above",
        tried.join("; ")
    );
}

/// The programs to try, in order, each with its arguments.
fn candidates(browser: Option<OsString>, url: &str) -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = browser
        .and_then(|b| b.into_string().ok())
        .iter()
        .flat_map(|b| b.split(':'))
        .filter_map(|entry| {
            let mut words = entry.split_whitespace().map(str::to_string);
            let program = words.next()?;
            let mut args: Vec<String> = words.collect();
            if args.iter().any(|a| a.contains("%s")) {
                args.iter_mut().for_each(|a| *a = a.replace("%s", url));
            } else {
                args.push(url.to_string());
            }
            Some((program, args))
        })
        .collect();
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(windows) {
        "explorer"
    } else {
        "xdg-open"
    };
    out.push((opener.to_string(), vec![url.to_string()]));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn browser_entries_come_first_with_the_url_where_percent_s_is() {
        let url = "http://127.0.0.1:1/?token=ab";
        let got = candidates(Some("firefox --new-window %s: :w3m".into()), url);
        assert_eq!(got.len(), 3);
        assert_eq!(
            got[0],
            ("firefox".into(), vec!["--new-window".into(), url.into()])
        );
        assert_eq!(got[1], ("w3m".into(), vec![url.into()]));
        assert_eq!(got[2].1, vec![url.to_string()]);
        assert_eq!(candidates(None, url).len(), 1);
    }
}
