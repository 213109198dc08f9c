//! The REPL's `:commands`: takes an input line starting with `:` and gives a parsed
//! [`Command`] (or a usage message); also the command table that `:help`, completion and
//! hints read.

use std::path::PathBuf;

use crate::cli::render::{frame_range, FrameRange};

/// One REPL command: its name (without the colon), argument usage and what it does.
pub struct CommandInfo {
    pub name: &'static str,
    pub usage: &'static str,
    pub help: &'static str,
}

impl CommandInfo {
    const fn new(name: &'static str, usage: &'static str, help: &'static str) -> Self {
        CommandInfo { name, usage, help }
    }
}

/// Every command, in the order `:help` lists them.
pub const COMMANDS: &[CommandInfo] = &[
    CommandInfo::new("help", "", "this list"),
    CommandInfo::new(
        "load",
        "FILE",
        "load a scene file (replaces the live scene)",
    ),
    CommandInfo::new(
        "reload",
        "",
        "load the current scene file again (drops REPL edits)",
    ),
    CommandInfo::new("save", "FILE", "write the live scene as a Rhai scene file"),
    CommandInfo::new("t", "SECONDS", "show the scene at a time"),
    CommandInfo::new("frame", "N", "show frame N (from 1)"),
    CommandInfo::new("show", "", "render and show the current frame again"),
    CommandInfo::new(
        "mesh",
        "",
        "toggle the deformed-mesh overlay on the preview",
    ),
    CommandInfo::new(
        "list",
        "",
        "canvas, patches, keys, handles, pins, layer order and variables",
    ),
    CommandInfo::new(
        "keys",
        "NAME",
        "a patch's keys as a table: track, time, value, easing (and its handles')",
    ),
    CommandInfo::new("undo", "", "undo the last change to the scene"),
    CommandInfo::new(
        "render",
        "[A..B] [-o DIR]",
        "render frames A..B (default all) to DIR/frame_NNNN.png (default frames)",
    ),
    CommandInfo::new("gif", "FILE", "render every frame into an animated GIF"),
    CommandInfo::new(
        "stats",
        "",
        "timings of the last frame and what the last edit rebuilt",
    ),
    CommandInfo::new("quit", "", "leave (Ctrl-D does too)"),
];

/// Commands that take a file path argument (completed with file names).
pub const PATH_COMMANDS: &[&str] = &["load", "save", "gif"];

#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    Help,
    Load(PathBuf),
    Reload,
    Save(PathBuf),
    Time(f64),
    Frame(u64),
    Show,
    Mesh,
    List,
    Keys(String),
    Undo,
    Render {
        range: Option<FrameRange>,
        output: PathBuf,
    },
    Gif(PathBuf),
    Stats,
    Quit,
}

/// Parses a `:command` line; the error is a message for the user.
pub fn parse_command(line: &str) -> Result<Command, String> {
    let body = line.trim().strip_prefix(':').unwrap_or(line.trim());
    let (name, rest) = match body.split_once(char::is_whitespace) {
        Some((name, rest)) => (name, rest.trim()),
        None => (body, ""),
    };
    let info = COMMANDS
        .iter()
        .find(|c| c.name == name)
        .ok_or_else(|| format!("unknown command `:{name}` (try :help)"))?;
    let usage = || format!("usage: :{} {}", info.name, info.usage);
    let no_args = |command: Command| {
        if rest.is_empty() {
            Ok(command)
        } else {
            Err(usage())
        }
    };
    // A FILE in quotes is one word, as `:render -o` takes it (an unclosed or trailing
    // quote is refused); unquoted, the rest of the line, spaces and all.
    let path = || {
        let file = match rest.starts_with(['"', '\'']) {
            true => match words(rest)
                .map_err(|e| format!("{}: {e}", usage()))?
                .as_slice()
            {
                [one] => one.clone(),
                _ => {
                    return Err(format!(
                        "{}: one FILE (in quotes if it has spaces)",
                        usage()
                    ))
                }
            },
            false => rest.to_string(),
        };
        match file.as_str() {
            "" if rest.is_empty() => Err(usage()),
            "" => Err(format!("{}: the FILE is empty", usage())),
            "-" => Err(format!(
                "{}: `-` means standard output, which :{} does not use; name a file (./- for one named -)",
                usage(),
                info.name
            )),
            _ => Ok(PathBuf::from(file)),
        }
    };
    match name {
        "help" => no_args(Command::Help),
        "load" => path().map(Command::Load),
        "reload" => no_args(Command::Reload),
        "save" => path().map(Command::Save),
        "t" => match rest.parse::<f64>() {
            Ok(t) if t.is_finite() && t >= 0.0 => Ok(Command::Time(t)),
            _ => Err(format!("{}: SECONDS must be a finite number ≥ 0", usage())),
        },
        "frame" => match rest.parse::<u64>() {
            Ok(n) if n >= 1 => Ok(Command::Frame(n)),
            _ => Err(format!("{}: N must be a frame number ≥ 1", usage())),
        },
        "show" => no_args(Command::Show),
        "mesh" => no_args(Command::Mesh),
        "list" => no_args(Command::List),
        "keys" if rest.is_empty() => Err(usage()),
        "keys" => Ok(Command::Keys(unquote(rest).to_string())),
        "undo" => no_args(Command::Undo),
        "render" => parse_render(rest).map_err(|e| format!("{}: {e}", usage())),
        "gif" => path().map(Command::Gif),
        "stats" => no_args(Command::Stats),
        "quit" => no_args(Command::Quit),
        _ => Err(format!("unknown command `:{name}`")),
    }
}

fn parse_render(rest: &str) -> Result<Command, String> {
    let mut range = None;
    let mut output = PathBuf::from("frames");
    let words = words(rest)?;
    let mut words = words.iter().map(String::as_str);
    while let Some(word) = words.next() {
        if word == "-o" {
            match words.next() {
                None => return Err("-o needs a folder".into()),
                Some("") => return Err("the -o folder is empty".into()),
                Some(dir) => output = PathBuf::from(dir),
            }
        } else if range.is_none() && word.contains("..") {
            range = Some(frame_range(word)?);
        } else {
            return Err(format!("unexpected `{word}`"));
        }
    }
    Ok(Command::Render { range, output })
}

/// Splits arguments at blanks; a word in double or single quotes keeps its blanks
/// (`-o "my frames"`). No backslash escapes, so Windows paths read as typed.
fn words(text: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut rest = text.trim_start();
    while let Some(first) = rest.chars().next() {
        let (word, after) = if first == '"' || first == '\'' {
            let end = rest[1..]
                .find(first)
                .ok_or_else(|| format!("unclosed {first} in `{rest}`"))?;
            (&rest[1..1 + end], &rest[2 + end..])
        } else {
            rest.split_at(rest.find(char::is_whitespace).unwrap_or(rest.len()))
        };
        if after.starts_with(|c: char| !c.is_whitespace()) {
            return Err(format!("a quoted word runs into `{after}`"));
        }
        words.push(word.to_string());
        rest = after.trim_start();
    }
    Ok(words)
}

/// Strips one pair of surrounding quotes, so `:save "my scene.rhai"` works.
fn unquote(text: &str) -> &str {
    let text = text.trim();
    for quote in ['"', '\''] {
        if let Some(inner) = text.strip_prefix(quote).and_then(|t| t.strip_suffix(quote)) {
            return inner;
        }
    }
    text
}

/// The `:help` text.
pub fn help_text() -> String {
    let mut out = String::from(
        "Lines are Rhai run against the live scene (see docs/scene-language.md); unfinished\n\
         input (open brackets, a trailing operator) continues on the next line.\n\
         Ctrl-C cancels a running evaluation or render (or clears the line); Ctrl-D quits.\n",
    );
    for c in COMMANDS {
        let head = format!(":{} {}", c.name, c.usage);
        out.push_str(&format!("  {head:<24} {}\n", c.help));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_command_shape() {
        assert_eq!(parse_command(":t 1.5"), Ok(Command::Time(1.5)));
        assert_eq!(parse_command(":frame 3"), Ok(Command::Frame(3)));
        assert_eq!(
            parse_command(":save \"a b.rhai\""),
            Ok(Command::Save(PathBuf::from("a b.rhai")))
        );
        assert_eq!(
            parse_command(":render 2..4 -o out"),
            Ok(Command::Render {
                range: Some(FrameRange { first: 2, last: 4 }),
                output: PathBuf::from("out")
            })
        );
        assert_eq!(
            parse_command(":render"),
            Ok(Command::Render {
                range: None,
                output: PathBuf::from("frames")
            })
        );
        assert_eq!(parse_command("  :quit  "), Ok(Command::Quit));
        assert_eq!(
            parse_command(":keys \"big cat\""),
            Ok(Command::Keys("big cat".into()))
        );
        assert!(parse_command(":keys").is_err());
    }

    #[test]
    fn refuses_bad_arguments_with_usage() {
        assert!(parse_command(":nope")
            .unwrap_err()
            .contains("unknown command"));
        assert!(parse_command(":t -1")
            .unwrap_err()
            .contains("usage: :t SECONDS"));
        assert!(parse_command(":t NaN").is_err());
        assert!(parse_command(":frame 0").is_err());
        assert!(parse_command(":save")
            .unwrap_err()
            .contains("usage: :save FILE"));
        // Quotes make one word, as `:render -o` reads them; `-` is no file.
        for bad in [
            ":save \"c d.rhai\" e",
            ":save \"",
            ":gif \"x.gif",
            ":save -",
            ":gif -",
        ] {
            assert!(
                parse_command(bad).unwrap_err().contains("usage: :"),
                "{bad}"
            );
        }
        assert_eq!(
            parse_command(":save my scene.rhai"),
            Ok(Command::Save(PathBuf::from("my scene.rhai")))
        );
        assert_eq!(
            parse_command(":save ./-"),
            Ok(Command::Save(PathBuf::from("./-")))
        );
        assert!(parse_command(":list extra").is_err());
        assert!(parse_command(":render 3..1").is_err());
        assert!(parse_command(":render -o").is_err());
        for (line, message) in [
            (":render -o \"my frames", "unclosed \""),
            (":render -o \"a\"b", "runs into `b`"),
            (":render -o ''", "the -o folder is empty"),
            (":gif \"\"", "usage: :gif FILE: the FILE is empty"),
            (":save ''", "the FILE is empty"),
        ] {
            let error = parse_command(line).unwrap_err();
            assert!(error.contains(message), "{line}: {error}");
        }
    }

    #[test]
    fn quoted_words_keep_their_blanks() {
        assert_eq!(
            parse_command(":render -o \"my frames\" 1..2"),
            Ok(Command::Render {
                range: Some(FrameRange { first: 1, last: 2 }),
                output: PathBuf::from("my frames")
            })
        );
        assert_eq!(
            parse_command(":render  'a \"b' "),
            Err("usage: :render [A..B] [-o DIR]: unexpected `a \"b`".into())
        );
        assert_eq!(
            words(r"-o C:\out\x 'it is'"),
            Ok(vec!["-o".into(), r"C:\out\x".into(), "it is".into()])
        );
    }

    #[test]
    fn help_lists_every_command() {
        let help = help_text();
        for c in COMMANDS {
            assert!(help.contains(&format!(":{}", c.name)), "{}", c.name);
        }
    }
}
