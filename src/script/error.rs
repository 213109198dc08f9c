//! Scene errors with positions: takes Rhai parse/eval errors (or our own validation failures)
//! and gives a [`SceneError`] naming the file, line and column, printed as
//! `file:line:col: message`, the source line, and a caret under the column.

use crate::util::ShowPath;
use std::fmt;
use std::path::{Path, PathBuf};

use rhai::{EvalAltResult, ParseError, Position};

/// What kind of failure a [`SceneError`] reports (the REPL treats cancellation differently).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file does not parse.
    Syntax,
    /// A failure while running the script: bad values, unknown functions, missing files.
    Runtime,
    /// A sandbox limit (operations, call depth, sizes) was hit.
    Limit,
    /// The cancel flag was raised.
    Cancelled,
    /// The scene was complete but invalid (e.g. no canvas), or a referenced file is unusable.
    Validation,
    /// A file cannot be read.
    Io,
}

/// A scene file's error, positioned: `file:line:col: message`, with the source line and a caret when printed.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// The scene file (or module) the error is in.
    pub file: PathBuf,
    /// Rhai position (1-based line and column); `Position::NONE` when there is none.
    pub position: Position,
    /// The message, without position.
    pub message: String,
    /// The offending source line, when known.
    pub source_line: Option<String>,
}

impl std::error::Error for SceneError {}

impl SceneError {
    /// An error of `kind` at `position` in `file`.
    pub fn new(
        kind: ErrorKind,
        file: &Path,
        position: Position,
        message: impl Into<String>,
    ) -> Self {
        Self::with_text(kind, file, position, message, None)
    }

    /// An error of `kind` about `file` as a whole (no position).
    pub(super) fn in_file(kind: ErrorKind, file: &Path, message: impl Into<String>) -> Self {
        Self::new(kind, file, Position::NONE, message)
    }

    /// [`SceneError::new`] with its source line taken from `text` (the file's contents), or
    /// read from disk for `None`.
    pub(super) fn with_text(
        kind: ErrorKind,
        file: &Path,
        position: Position,
        message: impl Into<String>,
        text: Option<&str>,
    ) -> Self {
        let mut error = SceneError {
            kind,
            file: file.to_path_buf(),
            position,
            message: message.into(),
            source_line: None,
        };
        error.load_source_line(text);
        error
    }

    /// The 1-based line, if known (not past line 65,534, as far as Rhai counts).
    pub fn line(&self) -> Option<usize> {
        line_and_column(self.position).0
    }

    /// The 1-based column, if known (not past column 65,534, as far as Rhai counts).
    pub fn column(&self) -> Option<usize> {
        line_and_column(self.position).1
    }

    /// Fills `source_line` from `text` (the file's contents) or, failing that, from disk.
    pub fn load_source_line(&mut self, text: Option<&str>) {
        let Some(line) = self.line() else {
            return;
        };
        let from_disk;
        let text = match text {
            Some(t) => t,
            None => {
                let Ok(t) = super::source::read_source(&self.file) else {
                    return;
                };
                from_disk = t;
                &from_disk
            }
        };
        self.source_line = text.lines().nth(line.saturating_sub(1)).map(str::to_string);
    }

    /// A syntax error from Rhai's parser.
    pub fn from_parse(error: &ParseError, file: &Path, text: &str) -> Self {
        let message = format!("syntax error: {}", error.err_type());
        Self::with_text(ErrorKind::Syntax, file, error.position(), message, Some(text))
    }

    /// An evaluation error: unwraps function-call and module wrappers down to the innermost
    /// error so the position points at the offending call, in the file where it is.
    /// `module_file` maps an import path to the file it resolved to.
    pub fn from_eval(
        error: Box<EvalAltResult>,
        file: &Path,
        text: &str,
        module_file: &dyn Fn(&str) -> Option<PathBuf>,
    ) -> Self {
        let mut current_file = file.to_path_buf();
        let mut error = error;
        // Where the scene file called into what failed: named when the failure is in a
        // module, whose line alone does not say which of the scene's calls gave the bad value.
        let mut scene_call = None;
        // The innermost call with a position: where a positionless error (Rhai's own
        // `range` with step 0) is reported.
        let mut last_call = None;
        loop {
            match *error {
                EvalAltResult::ErrorInFunctionCall(_, source, inner, call) => {
                    if current_file == file && !call.is_none() {
                        scene_call = Some(call);
                    }
                    if !call.is_none() {
                        last_call = Some((current_file.clone(), call));
                    }
                    if !source.is_empty() {
                        current_file = PathBuf::from(source);
                    }
                    error = inner;
                }
                EvalAltResult::ErrorInModule(name, inner, _) => {
                    if let Some(path) = module_file(&name) {
                        current_file = path;
                    }
                    error = inner;
                }
                _ => break,
            }
        }
        let mut error = error;
        let mut position = error.take_position();
        if let Some((call_file, call)) = last_call.filter(|_| position.is_none()) {
            (current_file, position) = (call_file, call);
        }
        let (kind, mut message) = classify(&error);
        if let Some(call) = scene_call.filter(|_| current_file != file) {
            message = format!("{message} (called at {})", location(file, call));
        }
        let text = (current_file == file).then_some(text);
        Self::with_text(kind, &current_file, position, message, text)
    }
}

fn classify(error: &EvalAltResult) -> (ErrorKind, String) {
    use EvalAltResult as E;
    match error {
        E::ErrorRuntime(value, _) => (ErrorKind::Runtime, value.to_string()),
        E::ErrorParsing(p, _) => (ErrorKind::Syntax, format!("syntax error: {p}")),
        E::ErrorTerminated(value, _) if value.to_string() != super::sandbox::CANCELLED => {
            (ErrorKind::Limit, value.to_string())
        }
        E::ErrorTerminated(..) => (ErrorKind::Cancelled, "evaluation cancelled".into()),
        E::ErrorTooManyOperations(_) => (
            ErrorKind::Limit,
            "too many operations: the script runs too long (a runaway loop?)".into(),
        ),
        E::ErrorStackOverflow(_) => (
            ErrorKind::Limit,
            "call stack overflow: functions nest too deep (runaway recursion?)".into(),
        ),
        E::ErrorDataTooLarge(..) | E::ErrorTooManyModules(_) | E::ErrorTooManyVariables(_) => {
            (ErrorKind::Limit, error.to_string())
        }
        E::ErrorFunctionNotFound(signature, _) => (
            ErrorKind::Runtime,
            format!("unknown function or wrong argument types: {signature}"),
        ),
        E::ErrorModuleNotFound(name, _) => (
            ErrorKind::Runtime,
            format!(
                "module `{name}` not found in the scene's folder or the project's scripts/ folder"
            ),
        ),
        _ => (ErrorKind::Runtime, error.to_string()),
    }
}

/// Rhai counts lines and columns in 16 bits and stops at 65,535, so a position there may lie
/// anywhere past it: it is never shown as if it were exact.
const POSITION_CEILING: usize = u16::MAX as usize;

/// `position`'s 1-based line and column, each `None` when unknown or past what Rhai counts.
fn line_and_column(position: Position) -> (Option<usize>, Option<usize>) {
    let line = position.line().filter(|&l| l < POSITION_CEILING);
    let column = line
        .and(position.position())
        .filter(|&c| c < POSITION_CEILING);
    (line, column)
}

/// Where `position` is in `file`, as messages print it: `file:line:col`, `file:line` or
/// `file`, with a word when the line or column lies past what Rhai counts.
pub(crate) fn location(file: &Path, position: Position) -> String {
    let file = file.shown();
    let past = |what| format!("{what} {POSITION_CEILING} or later");
    match (line_and_column(position), position.line(), position.position()) {
        ((Some(line), Some(col)), ..) => format!("{file}:{line}:{col}"),
        ((Some(line), None), _, Some(_)) => format!("{file}:{line}: {}", past("column")),
        ((Some(line), None), ..) => format!("{file}:{line}"),
        ((None, _), Some(_), _) => format!("{file}: {}", past("line")),
        _ => format!("{file}"),
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", location(&self.file, self.position), self.message)?;
        // A column past what Rhai counts says nothing of where in a long line to look.
        let column_lost = self.column().is_none() && self.position.position().is_some();
        if let Some(source) = self.source_line.as_ref().filter(|_| !column_lost) {
            let (shown, col) = excerpt(source, self.column());
            write!(f, "\n{}", crate::util::visible_controls(&shown))?;
            if let Some(col) = col {
                write!(f, "\n{}^", caret_indent(&shown, col))?;
            }
        }
        Ok(())
    }
}

/// Characters of a source line shown on each side of the column: a scene line can be
/// megabytes long, and the message must stay readable.
const EXCERPT_SIDE: usize = 60;

/// `source` as printed under a message, with the column the caret goes under: the whole line
/// when it is short, else the characters around `col` between `…` marks.
fn excerpt(source: &str, col: Option<usize>) -> (String, Option<usize>) {
    let length = source.chars().count();
    if length <= 4 * EXCERPT_SIDE {
        return (source.to_string(), col);
    }
    let centre = col.unwrap_or(1).saturating_sub(1).min(length);
    let first = centre.saturating_sub(EXCERPT_SIDE);
    let last = (centre + EXCERPT_SIDE).min(length);
    let mut shown: String = if first > 0 { "…".into() } else { String::new() };
    shown.extend(source.chars().skip(first).take(last - first));
    if last < length {
        shown.push('…');
    }
    let col = col.map(|c| c - first + usize::from(first > 0));
    (shown, col)
}

/// Whitespace that lines a caret up under column `col` (1-based) of `source` as shown:
/// tabs kept as tabs, each other character as wide as the terminal shows it (a hidden one
/// as its `\u{..}` escape, a CJK character or an emoji two columns).
fn caret_indent(source: &str, col: usize) -> String {
    use unicode_width::UnicodeWidthStr as _;
    let mut indent = String::new();
    for c in source.chars().chain(std::iter::repeat(' ')).take(col.saturating_sub(1)) {
        match c {
            '\t' => indent.push('\t'),
            c => {
                let mut one = [0u8; 4];
                let width = crate::util::visible_controls(c.encode_utf8(&mut one)).width();
                indent.extend(std::iter::repeat_n(' ', width));
            }
        }
    }
    indent
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn caret_sits_under_the_column() {
        let mut e = SceneError::new(
            ErrorKind::Runtime,
            Path::new("s.rhai"),
            Position::new(2, 5),
            "bad",
        );
        e.load_source_line(Some("first\n\tab(cd);\n"));
        assert_eq!(e.to_string(), "s.rhai:2:5: bad\n\tab(cd);\n\t   ^");
    }

    /// Before the column, a control character is shown as its escape, a character that
    /// turns the text's direction too, and a wide one takes two columns: the caret still
    /// sits under the column as the terminal shows the line.
    #[test]
    fn caret_counts_escapes_and_wide_characters() {
        let at = |line: &str, col: u16| {
            let mut e = SceneError::new(ErrorKind::Runtime, Path::new("s.rhai"), Position::new(1, col), "bad");
            e.load_source_line(Some(line));
            let text = e.to_string();
            let lines: Vec<&str> = text.lines().collect();
            (lines[1].to_string(), lines[2].len() - 1)
        };
        let (shown, caret) = at("let s = \"\u{1b}[2J\"; 1/0;", 18);
        assert_eq!(shown, "let s = \"\\u{1b}[2J\"; 1/0;");
        assert_eq!(&shown[caret..caret + 1], "/");
        let (shown, caret) = at("\"猫猫\"; 1/0;", 8);
        assert_eq!(caret, 9, "{shown}");
        let (shown, _) = at("\"\u{202e}abc\"; 1/0;", 10);
        assert_eq!(shown, "\"\\u{202e}abc\"; 1/0;");
    }

    /// Rhai stops counting lines and columns at 65,535: a position there is said to be at or
    /// past it, never given as exact, and no caret points into a line it cannot place.
    #[test]
    fn positions_past_what_rhai_counts_are_not_shown_as_exact() {
        let text = "canvas(1, 1);\nbad();\n";
        let cases = [
            (Position::new(2, 1), "s.rhai:2:1: bad\nbad();\n^", Some(2), Some(1)),
            (Position::new(65_534, 7), "s.rhai:65534:7: bad", Some(65_534), Some(7)),
            (Position::new(65_535, 7), "s.rhai: line 65535 or later: bad", None, None),
            (Position::new(2, 65_535), "s.rhai:2: column 65535 or later: bad", Some(2), None),
            (Position::NONE, "s.rhai: bad", None, None),
        ];
        for (position, shown, line, column) in cases {
            let mut e = SceneError::new(ErrorKind::Runtime, Path::new("s.rhai"), position, "bad");
            e.load_source_line(Some(text));
            assert_eq!(e.to_string(), shown, "{position:?}");
            assert_eq!((e.line(), e.column()), (line, column), "{position:?}");
        }
    }

    /// A line of megabytes is shown as the characters around the column, and the caret
    /// still sits under the column's character.
    #[test]
    fn a_long_line_is_shown_around_the_column() {
        // Rhai's columns are 16-bit, so the line is as long as they reach.
        let line = format!("{}@{}", "a".repeat(30_000), "b".repeat(30_000));
        for (col, marks) in [(30_001u16, 2), (5, 1), (60_001, 1)] {
            let mut e = SceneError::new(
                ErrorKind::Syntax,
                Path::new("s.rhai"),
                Position::new(1, col),
                "bad",
            );
            e.load_source_line(Some(&line));
            let text = e.to_string();
            assert!(text.len() < 400, "{} bytes", text.len());
            let lines: Vec<&str> = text.lines().collect();
            assert_eq!(lines[1].matches('…').count(), marks, "{}", lines[1]);
            let under = lines[2].chars().count() - 1;
            let expected = line.chars().nth(usize::from(col) - 1).unwrap();
            assert_eq!(lines[1].chars().nth(under), Some(expected), "col {col}");
        }
    }
}
