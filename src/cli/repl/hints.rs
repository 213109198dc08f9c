//! Hints shown greyed after the cursor: takes the line being edited and gives the rest of a
//! `:command` with its usage (`:ren` → `der [A..B] [-o DIR]`), or else the most recent
//! history entry that starts with the line.

use rustyline::hint::{Hinter, HistoryHinter};
use rustyline::Context;

use super::commands::COMMANDS;

/// The rest of the single command `line` (cursor at its end) can still become, plus usage.
pub fn command_hint(line: &str) -> Option<String> {
    let typed = line.strip_prefix(':')?;
    if typed.contains(char::is_whitespace) {
        return None;
    }
    let mut matches = COMMANDS.iter().filter(|c| c.name.starts_with(typed));
    let only = matches.next()?;
    if matches.next().is_some() && only.name != typed {
        return None;
    }
    let rest = &only.name[typed.len()..];
    Some(if only.usage.is_empty() {
        rest.to_string()
    } else {
        format!("{rest} {}", only.usage)
    })
    .filter(|h| !h.is_empty())
}

pub struct ReplHinter {
    history: HistoryHinter,
}

impl Default for ReplHinter {
    fn default() -> Self {
        ReplHinter {
            history: HistoryHinter::new(),
        }
    }
}

impl Hinter for ReplHinter {
    type Hint = String;

    fn hint(&self, line: &str, pos: usize, ctx: &Context<'_>) -> Option<String> {
        if pos < line.len() {
            return None;
        }
        command_hint(line).or_else(|| self.history.hint(line, pos, ctx))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_hints_finish_a_unique_prefix_with_usage() {
        assert_eq!(command_hint(":ren").as_deref(), Some("der [A..B] [-o DIR]"));
        assert_eq!(command_hint(":sa").as_deref(), Some("ve FILE"));
        assert_eq!(command_hint(":t").as_deref(), Some(" SECONDS"));
        assert_eq!(command_hint(":qu").as_deref(), Some("it"));
        assert_eq!(command_hint(":re"), None, "ambiguous: reload, render");
        assert_eq!(command_hint(":quit"), None, "nothing left to add");
        assert_eq!(command_hint(":save x"), None);
        assert_eq!(command_hint("cat"), None);
    }
}
