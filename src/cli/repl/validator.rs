//! Telling finished input from unfinished: takes the text typed so far and says whether it
//! needs more lines (open brackets, a trailing operator, an unterminated string), using
//! Rhai's own parser. Used by the interactive editor (rustyline `Validator`) and by the
//! non-interactive reader alike, so both split input into entries the same way.

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
}
