//! Telling finished input from unfinished: takes the text typed so far and says whether it
//! needs more lines (open brackets, a trailing operator, an unterminated string), using
//! Rhai's own parser. Used by the interactive editor (rustyline `Validator`) and by the
//! non-interactive reader alike, so both split input into entries the same way. The reader
//! goes through [`EntrySplitter`], which keeps a long entry's reading linear: while a
//! bracket is surely still open it parses again only now and then. Also whether an entry
//! ends in `;` ([`ends_in_semicolon`]): a statement, whose value the REPL does not show.

use rhai::{Engine, LexError, ParseErrorType, Position};
use rustyline::validate::{ValidationContext, ValidationResult, Validator};

/// Parses input only (never runs it).
pub struct InputValidator {
    parser: Engine,
}

impl Default for InputValidator {
    fn default() -> Self {
        Self::new()
    }
}

impl InputValidator {
    pub fn new() -> Self {
        InputValidator {
            parser: Engine::new_raw(),
        }
    }

    /// Whether `text` is unfinished Rhai: the parser ran out of input while it still
    /// expected something. `:commands` and blank input are always finished.
    pub fn is_incomplete(&self, text: &str) -> bool {
        let trimmed = text.trim();
        if trimmed.is_empty() || trimmed.starts_with(':') {
            return false;
        }
        match self.parser.compile(text) {
            Ok(_) => false,
            Err(error) => {
                let (kind, position) = (error.err_type(), error.position());
                match kind {
                    ParseErrorType::UnexpectedEOF => true,
                    ParseErrorType::BadInput(LexError::UnterminatedString) => true,
                    ParseErrorType::MissingToken(..)
                    | ParseErrorType::MissingSymbol(..)
                    | ParseErrorType::ExprExpected(..) => at_end(text, position),
                    _ => false,
                }
            }
        }
    }
}

/// Whether `position` lies at or after the last non-blank character of `text` (the parser
/// reached the end of the input).
fn at_end(text: &str, position: Position) -> bool {
    let (Some(line), column) = (position.line(), position.position()) else {
        return true;
    };
    let content = text.trim_end();
    let last_line = content.lines().count().max(1);
    if line != last_line {
        return line > last_line;
    }
    let last_len = content.lines().last().map_or(0, |l| l.chars().count());
    column.is_none_or(|c| c > last_len)
}

/// Whether the last thing in `text` other than blanks and comments is a `;` outside any
/// string: the entry ends as a statement, as in Rust or Julia, so its value is not shown.
/// Comments are `//` to the line's end and `/* */`, which nest as in Rhai.
pub fn ends_in_semicolon(text: &str) -> bool {
    let mut chars = text.chars().peekable();
    let mut last = None;
    let mut quote = None;
    while let Some(c) = chars.next() {
        if let Some(q) = quote {
            match c {
                '\\' if q != '`' => {
                    chars.next();
                }
                c if c == q => quote = None,
                _ => {}
            }
            continue;
        }
        match (c, chars.peek()) {
            ('/', Some('/')) => {
                chars.by_ref().find(|&c| c == '\n');
                continue;
            }
            ('/', Some('*')) => {
                chars.next();
                skip_block_comment(&mut chars);
                continue;
            }
            ('"' | '\'' | '`', _) => quote = Some(c),
            (c, _) if c.is_whitespace() => continue,
            _ => {}
        }
        last = Some(c);
    }
    last == Some(';')
}

/// Skips a block comment's text after its `/*`, nested ones included.
fn skip_block_comment(chars: &mut std::iter::Peekable<std::str::Chars>) {
    let mut depth = 1usize;
    while let Some(c) = chars.next() {
        match (c, chars.peek()) {
            ('*', Some('/')) => {
                chars.next();
                depth -= 1;
                if depth == 0 {
                    return;
                }
            }
            ('/', Some('*')) => {
                chars.next();
                depth += 1;
            }
            _ => {}
        }
    }
}

/// Splits piped input into entries line by line, as [`InputValidator`] would. Parsing the
/// whole entry after every line is quadratic: a 20,000-line array literal took 34 s. So once
/// an entry is [`EXACT_LINES`] long and a bracket in it is surely still open, it is parsed
/// again only after it has grown by an eighth. A correct entry ends on the same line as
/// with a parse per line; a wrong one may be reported a few lines later than its error (its
/// message still names the error's own line).
#[derive(Default)]
pub struct EntrySplitter {
    validator: InputValidator,
    brackets: Brackets,
    /// The entry read so far, its lines joined by `\n`.
    entry: String,
    lines: usize,
    parsed_at: usize,
    parses: usize,
}

/// Entries shorter than this are parsed after every line, as the interactive editor does.
const EXACT_LINES: usize = 64;

impl EntrySplitter {
    /// Adds the next line; gives the entry it finishes. Blank lines between entries are
    /// skipped.
    pub fn push(&mut self, line: &str) -> Option<String> {
        if self.entry.is_empty() && line.trim().is_empty() {
            return None;
        }
        if !self.entry.is_empty() {
            self.entry.push('\n');
        }
        self.entry.push_str(line);
        self.lines += 1;
        self.brackets.feed(line);
        if self.needs_more() {
            return None;
        }
        let entry = std::mem::take(&mut self.entry);
        self.drop_entry();
        Some(entry)
    }

    fn needs_more(&mut self) -> bool {
        let lines_since = self.lines - self.parsed_at;
        if self.brackets.surely_open() && self.lines >= EXACT_LINES && lines_since * 8 < self.lines
        {
            return true;
        }
        self.parsed_at = self.lines;
        self.parses += 1;
        self.validator.is_incomplete(&self.entry)
    }

    /// Bytes of the entry read so far.
    pub fn len(&self) -> usize {
        self.entry.len()
    }

    /// Forgets the entry read so far (one of its lines could not be read).
    pub fn drop_entry(&mut self) {
        self.entry.clear();
        self.brackets = Brackets::default();
        (self.lines, self.parsed_at) = (0, 0);
    }

    /// At the end of the input: the unfinished entry, unless it is blank.
    pub fn finish(&mut self) -> Option<String> {
        let entry = std::mem::take(&mut self.entry);
        self.drop_entry();
        Some(entry).filter(|e| !e.trim().is_empty())
    }

    /// Parses run so far, over all entries.
    #[cfg(test)]
    fn parses(&self) -> usize {
        self.parses
    }
}

/// Rhai's brackets as far as a lexer one line at a time can tell: strings, characters,
/// comments (block comments nest) and backtick strings with `${…}` in them are skipped.
/// Anything it does not follow (a closer that does not match, a line ending inside a
/// string) makes it unsure for the rest of the entry, and then the parser decides.
#[derive(Default)]
struct Brackets {
    /// Open brackets; a backtick marks an open `${` inside a backtick string.
    stack: Vec<char>,
    mode: Mode,
    unsure: bool,
}

#[derive(Default, Clone, Copy, PartialEq)]
enum Mode {
    #[default]
    Code,
    /// Inside a quoted string or character; the quote.
    Quoted(char),
    Backtick,
    /// Inside a `//` comment, which ends with its line.
    LineComment,
    /// Inside block comments, this many deep.
    Comment(usize),
}

impl Brackets {
    fn surely_open(&self) -> bool {
        !self.unsure && !self.stack.is_empty() && matches!(self.mode, Mode::Code | Mode::Comment(_))
    }

    fn feed(&mut self, line: &str) {
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            if self.unsure {
                return;
            }
            let next = chars.peek().copied();
            let skip_next = match self.mode {
                Mode::Code => self.code(c, next),
                Mode::Quoted(quote) => {
                    if c == quote {
                        self.mode = Mode::Code;
                    }
                    c == '\\'
                }
                Mode::Backtick => self.backtick(c, next),
                Mode::LineComment => break,
                Mode::Comment(depth) => self.comment(depth, c, next),
            };
            if skip_next {
                chars.next();
            }
        }
        // A string may not run on to the next line without a `\`: left to the parser.
        match self.mode {
            Mode::LineComment => self.mode = Mode::Code,
            Mode::Quoted(_) => self.unsure = true,
            _ => {}
        }
    }

    /// One character of code; whether the next one is taken with it.
    fn code(&mut self, c: char, next: Option<char>) -> bool {
        match (c, next) {
            ('/', Some('/')) => {
                self.mode = Mode::LineComment;
                return true;
            }
            ('/', Some('*')) => {
                self.mode = Mode::Comment(1);
                return true;
            }
            ('"' | '\'', _) => self.mode = Mode::Quoted(c),
            ('`', _) => self.mode = Mode::Backtick,
            ('(' | '[' | '{', _) => self.stack.push(c),
            (')' | ']' | '}', _) => match (self.stack.pop(), c) {
                (Some('('), ')') | (Some('['), ']') | (Some('{'), '}') => {}
                (Some('`'), '}') => self.mode = Mode::Backtick,
                _ => self.unsure = true,
            },
            _ => {}
        }
        false
    }

    fn backtick(&mut self, c: char, next: Option<char>) -> bool {
        match (c, next) {
            ('`', _) => self.mode = Mode::Code,
            ('$', Some('{')) => {
                self.stack.push('`');
                self.mode = Mode::Code;
                return true;
            }
            _ => {}
        }
        false
    }

    fn comment(&mut self, depth: usize, c: char, next: Option<char>) -> bool {
        match (c, next) {
            ('/', Some('*')) => self.mode = Mode::Comment(depth + 1),
            ('*', Some('/')) if depth == 1 => self.mode = Mode::Code,
            ('*', Some('/')) => self.mode = Mode::Comment(depth - 1),
            _ => return false,
        }
        true
    }
}

impl Validator for InputValidator {
    fn validate(&self, ctx: &mut ValidationContext) -> rustyline::Result<ValidationResult> {
        Ok(if self.is_incomplete(ctx.input()) {
            ValidationResult::Incomplete
        } else {
            ValidationResult::Valid(None)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unfinished_input_continues() {
        let v = InputValidator::new();
        for text in [
            "let a = [1, 2,",
            "fn f(x) {",
            "f(1,",
            "let x = 1 +",
            "let s = \"abc",
            "if true {\n  let a = 1;",
            "cat.key(0, #{ at: [1, 2],",
            "let m = #{",
        ] {
            assert!(v.is_incomplete(text), "should continue: {text:?}");
        }
    }

    #[test]
    fn finished_or_wrong_input_runs() {
        let v = InputValidator::new();
        for text in [
            "let a = [1, 2];",
            "1 + 2",
            "fn f(x) { x }",
            "let a = 1; a",
            "let a = [1, 2]]",
            "1 +* 2",
            ":save x.rhai",
            "",
            "   ",
        ] {
            assert!(!v.is_incomplete(text), "should run: {text:?}");
        }
    }

    /// Entries as the piped reader splits `text`, and the parses it took.
    fn split(text: &str) -> (Vec<String>, usize) {
        let mut splitter = EntrySplitter::default();
        let mut entries: Vec<String> = text.lines().filter_map(|l| splitter.push(l)).collect();
        entries.extend(splitter.finish());
        (entries, splitter.parses())
    }

    #[test]
    fn a_long_literal_is_one_entry_read_in_linear_time() {
        let lines = 20_000;
        let body: Vec<String> = (0..lines)
            .map(|i| format!("  [{i}, \"]\", '(', `${{[i][0]}}`],"))
            .collect();
        let text = format!("let a = [\n{}\n];\nlet b = 1;", body.join("\n"));
        let (entries, parses) = split(&text);
        assert_eq!(entries.len(), 2, "{:?}", entries.last());
        assert_eq!(entries[1], "let b = 1;");
        // A parse per line up to EXACT_LINES, then one per eighth of growth: about 140.
        assert!(parses < 200, "{parses} parses for {lines} lines");
    }

    #[test]
    fn an_error_in_a_long_entry_ends_it_soon_after() {
        let mut lines: Vec<String> = vec!["let a = [".into()];
        lines.extend((0..99).map(|i| {
            if i == 70 {
                "1 2,".into()
            } else {
                format!("{i},")
            }
        }));
        lines.push("];".into());
        let (entries, _) = split(&lines.join("\n"));
        let first = entries[0].lines().count();
        assert!(
            (72..=90).contains(&first),
            "the first entry ran {first} lines"
        );
    }

    /// A line of a long entry. Each holds brackets that only open, in a string, a
    /// character, a comment or a backtick string: counted by mistake, they would hold the
    /// entry open past its end.
    fn filler(kind: u8, i: usize) -> String {
        match kind % 6 {
            0 => format!("{i},"),
            1 => format!("\"\\\"[(\", {i}, // [ ({{ ["),
            2 => format!("'(', '[', '\\'', {i},"),
            3 => format!("`( ${{[{i}, [0]][1][0]}} [`,"),
            4 => format!("/* ( /* [ */ [ */ {i}, #{{ a: [{i}] }},"),
            _ => format!("[[{i}], (1 + 2)],"),
        }
    }

    #[test]
    fn brackets_in_strings_characters_and_comments_do_not_count() {
        for kind in 0..6 {
            let line = filler(kind, 7);
            let mut brackets = Brackets::default();
            brackets.feed(&line);
            assert!(brackets.stack.is_empty() && !brackets.unsure, "{line}");
            assert!(brackets.mode == Mode::Code, "{line}");
            brackets.feed("[");
            assert!(brackets.surely_open(), "{line}");
        }
        let mut comment = Brackets::default();
        comment.feed("[ /* ] /* ] */");
        comment.feed("] */ (");
        assert_eq!(comment.stack, ['[', '(']);
        let mut string = Brackets::default();
        string.feed("[\"(");
        assert!(
            !string.surely_open(),
            "a line ending in a string is the parser's to judge"
        );
    }

    fn entry(kind: u8, length: usize, i: usize) -> String {
        let body: Vec<String> = (0..length)
            .map(|j| filler((kind >> 3).wrapping_add(j as u8), j))
            .collect();
        match kind % 3 {
            0 => format!("let v{i} = {i};"),
            1 => format!("let v{i} = [\n{}\n];", body.join("\n")),
            _ => format!(
                "fn f{i}(x) {{\n  let w = [\n{}\n  ];\n  x\n}}",
                body.join("\n")
            ),
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 64,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x11_5e5),
            ..Default::default()
        })]

        /// Correct entries, short and long, end on their own last line.
        #[test]
        fn entries_end_where_they_end(shapes in proptest::collection::vec((0u8..255, 0usize..300), 1..8)) {
            let entries: Vec<String> = shapes.iter().enumerate().map(|(i, &(k, n))| entry(k, n, i)).collect();
            let (split, _) = split(&entries.join("\n"));
            let v = InputValidator::new();
            for e in &entries {
                proptest::prop_assert!(!v.is_incomplete(e) && v.parser.compile(e).is_ok(), "not Rhai: {e}");
            }
            proptest::prop_assert_eq!(split, entries);
        }
    }
}
