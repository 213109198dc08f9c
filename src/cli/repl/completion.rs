//! Tab completion: takes the line being edited, the cursor and the words the session knows
//! (patch names, variables, registered Rhai functions) and gives the candidates — `:commands`
//! at the start, file paths after `:load`/`:save`/`:gif`/`-o`, patch names inside a string
//! literal, and variables, functions, keywords and scene option keys elsewhere.

use std::sync::{Arc, Mutex};

use rhai::Engine;
use rustyline::completion::{Completer, FilenameCompleter, Pair};
use rustyline::Context;

use super::commands::{COMMANDS, PATH_COMMANDS};

/// Words the completer offers, kept up to date by the session after every entry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Words {
    pub patches: Vec<String>,
    pub variables: Vec<String>,
    /// Registered and built-in function names (sorted, unique).
    pub functions: Vec<String>,
}

pub type SharedWords = Arc<Mutex<Words>>;

const KEYWORDS: &[&str] = &[
    "let", "const", "fn", "if", "else", "for", "in", "while", "loop", "return", "true", "false",
    "import", "as", "break", "continue",
];

/// Every function name `engine` knows (scene API and Rhai's packages), without operators
/// and property accessors.
pub fn function_names(engine: &Engine) -> Vec<String> {
    let mut names: Vec<String> = engine
        .gen_fn_signatures(true)
        .iter()
        .filter_map(|signature| {
            let head = signature.split('(').next()?;
            let name = head.rsplit([' ', '.', ':']).next()?;
            let is_identifier = name
                .chars()
                .next()
                .is_some_and(|c| c.is_alphabetic() || c == '_')
                && name.chars().all(|c| c.is_alphanumeric() || c == '_');
            (is_identifier && !name.contains('$')).then(|| name.to_string())
        })
        .collect();
    names.sort();
    names.dedup();
    names
}

/// What the text before the cursor asks to complete.
#[derive(Debug, PartialEq)]
pub enum Completion {
    /// `:commands` starting with this prefix (whole word from 0).
    Command,
    /// A file path starting at this byte offset.
    Path,
    /// Words from [`Words`] (`in_string`: patch names only) for the word at `start`.
    Word { start: usize, in_string: bool },
}

/// Decides what kind of completion the text before the cursor wants.
pub fn classify(before: &str) -> Completion {
    if let Some(body) = before.strip_prefix(':') {
        let mut words = body.split_whitespace();
        let ends_in_space = body.ends_with(char::is_whitespace);
        let name = words.next().unwrap_or("");
        if !body.contains(char::is_whitespace) {
            return Completion::Command;
        }
        let previous = if ends_in_space {
            body.split_whitespace().last()
        } else {
            body.split_whitespace().rev().nth(1)
        };
        if PATH_COMMANDS.contains(&name) || previous == Some("-o") {
            return Completion::Path;
        }
        if name == "keys" {
            // The patch name after `:keys`.
            let start = before.trim_end_matches(|c: char| !c.is_whitespace()).len();
            return Completion::Word {
                start,
                in_string: true,
            };
        }
        return Completion::Word {
            start: before.len(),
            in_string: false,
        };
    }
    let start = before
        .char_indices()
        .rev()
        .take_while(|(_, c)| c.is_alphanumeric() || *c == '_')
        .last()
        .map_or(before.len(), |(i, _)| i);
    let quotes = before[..start].chars().filter(|&c| c == '"').count();
    Completion::Word {
        start,
        in_string: quotes % 2 == 1,
    }
}

/// The scene calls' option keys (`at`, `rotate` are functions too), new spellings only.
fn option_keys() -> impl Iterator<Item = &'static str> {
    let patch = lapclone::script::PATCH_OPTIONS.iter();
    patch.chain(&lapclone::script::OTHER_OPTION_KEYS).copied()
}

/// Candidates for a word completion: sorted, unique, starting with `prefix`.
pub fn word_candidates(prefix: &str, in_string: bool, words: &Words) -> Vec<String> {
    let mut out: Vec<String> = if in_string {
        words.patches.clone()
    } else {
        words
            .variables
            .iter()
            .chain(&words.functions)
            .cloned()
            .chain(KEYWORDS.iter().map(|k| k.to_string()))
            .chain(option_keys().map(String::from))
            .collect()
    };
    out.retain(|w| w.starts_with(prefix));
    out.sort();
    out.dedup();
    out
}

/// `:commands` starting with `prefix` (which includes the colon).
pub fn command_candidates(prefix: &str) -> Vec<String> {
    COMMANDS
        .iter()
        .map(|c| format!(":{}", c.name))
        .filter(|c| c.starts_with(prefix))
        .collect()
}

/// The rustyline completer over [`Words`].
pub struct ReplCompleter {
    words: SharedWords,
    files: FilenameCompleter,
}

impl ReplCompleter {
    pub fn new(words: SharedWords) -> Self {
        ReplCompleter {
            words,
            files: FilenameCompleter::new(),
        }
    }
}

fn pairs(words: Vec<String>) -> Vec<Pair> {
    words
        .into_iter()
        .map(|w| Pair {
            display: w.clone(),
            replacement: w,
        })
        .collect()
}

impl Completer for ReplCompleter {
    type Candidate = Pair;

    fn complete(
        &self,
        line: &str,
        pos: usize,
        ctx: &Context<'_>,
    ) -> rustyline::Result<(usize, Vec<Pair>)> {
        let before = &line[..pos];
        match classify(before) {
            Completion::Command => Ok((0, pairs(command_candidates(before)))),
            Completion::Path => self.files.complete(line, pos, ctx),
            Completion::Word { start, in_string } => {
                let words = crate::util::lock(&self.words);
                let found = word_candidates(&before[start..], in_string, &words);
                if found.is_empty() && in_string {
                    drop(words);
                    return self.files.complete(line, pos, ctx);
                }
                Ok((start, pairs(found)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words() -> Words {
        Words {
            patches: vec!["cat".into(), "coffee_cup".into(), "dog".into()],
            variables: vec!["cat".into(), "m".into()],
            functions: vec!["canvas".into(), "get_patch".into(), "key".into()],
        }
    }

    #[test]
    fn commands_complete_at_the_start() {
        assert_eq!(classify(":re"), Completion::Command);
        assert_eq!(command_candidates(":re"), [":reload", ":render"]);
        assert_eq!(command_candidates(":q"), [":quit"]);
        assert!(command_candidates(":zz").is_empty());
        assert_eq!(command_candidates(":").len(), COMMANDS.len());
    }

    #[test]
    fn paths_complete_after_file_commands_and_dash_o() {
        assert_eq!(classify(":load sce"), Completion::Path);
        assert_eq!(classify(":save "), Completion::Path);
        assert_eq!(classify(":gif out/a"), Completion::Path);
        assert_eq!(classify(":render 1..3 -o fr"), Completion::Path);
        assert_eq!(classify(":render 1..3 -o "), Completion::Path);
        assert!(matches!(classify(":render 1.."), Completion::Word { .. }));
    }

    #[test]
    fn words_complete_variables_functions_and_patch_names() {
        assert_eq!(
            classify("let x = ca"),
            Completion::Word {
                start: 8,
                in_string: false
            }
        );
        assert_eq!(word_candidates("ca", false, &words()), ["canvas", "cat"]);
        assert_eq!(
            classify("get_patch(\"co"),
            Completion::Word {
                start: 11,
                in_string: true
            }
        );
        assert_eq!(word_candidates("c", true, &words()), ["cat", "coffee_cup"]);
        assert_eq!(word_candidates("le", false, &words()), ["let"]);
        assert_eq!(word_candidates("mesh_", false, &words()), ["mesh_boundary"]);
        assert_eq!(
            word_candidates("boundary_", false, &words()),
            ["boundary_sampling"]
        );
        assert_eq!(
            word_candidates("source_", false, &words()),
            ["source_hold", "source_start_number"]
        );
        assert!(word_candidates("zz", false, &words()).is_empty());
    }

    #[test]
    fn editing_calls_and_keys_patch_names_complete() {
        let options =
            lapclone::script::ScriptOptions::for_scene_file(std::path::Path::new("a.rhai"));
        let engine = lapclone::script::SceneEngine::new(&options);
        let names = function_names(engine.engine());
        for call in [
            "remove_key",
            "move_key",
            "remove_patch",
            "remove_handle",
            "remove_pin",
            "rename",
            "to_front",
            "to_back",
            "opacity",
            "radius",
        ] {
            assert!(names.iter().any(|n| n == call), "{call}");
        }
        assert_eq!(
            classify(":keys ca"),
            Completion::Word {
                start: 6,
                in_string: true
            }
        );
    }

    #[test]
    fn function_names_include_the_scene_api() {
        let engine = Engine::new();
        let names = function_names(&engine);
        assert!(names.iter().any(|n| n == "len"));
        assert!(names.iter().all(|n| !n.contains(['+', '$', '('])));
    }
}
