//! The rustyline helper: bundles the completer, hinter and validator of the REPL and dims
//! hints. Takes the session's shared [`Words`](super::completion::Words).

use std::borrow::Cow;

use rustyline::highlight::Highlighter;
use rustyline::{Completer, Helper, Hinter, Validator};

use super::completion::{ReplCompleter, SharedWords};
use super::hints::ReplHinter;
use super::validator::InputValidator;

#[derive(Helper, Completer, Hinter, Validator)]
pub struct ReplHelper {
    #[rustyline(Completer)]
    completer: ReplCompleter,
    #[rustyline(Hinter)]
    hinter: ReplHinter,
    #[rustyline(Validator)]
    validator: InputValidator,
}

impl ReplHelper {
    pub fn new(words: SharedWords) -> Self {
        ReplHelper {
            completer: ReplCompleter::new(words),
            hinter: ReplHinter::default(),
            validator: InputValidator::new(),
        }
    }
}

impl Highlighter for ReplHelper {
    fn highlight_hint<'h>(&self, hint: &'h str) -> Cow<'h, str> {
        Cow::Owned(format!("\x1b[2m{hint}\x1b[0m"))
    }
}
