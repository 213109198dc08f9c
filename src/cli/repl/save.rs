//! `:save`: takes the live scene, the loaded file's text and the session's successful
//! entries, and gives the text to write. Preferred form: the file's text followed by the
//! entries as Rhai lines (helper calls, imports and variable names kept), used when running
//! it from the saved file's folder rebuilds exactly the live scene; otherwise the scene's
//! own keys ([`Scene::to_rhai_in`]) with paths relative to that folder.

use std::path::{Path, PathBuf};

use lapclone::scene::{Background, Scene, Shape};
use lapclone::script::{parse_scene, ScriptOptions};

/// Which form a save took.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SaveForm {
    /// The loaded text and the session's entries.
    Script,
    /// Every key written out.
    Keys,
}

/// The text to write to `path` for `scene`.
pub fn saved_text(
    scene: &Scene,
    base: Option<&str>,
    edits: &[String],
    path: &Path,
) -> (String, SaveForm) {
    let script = script_text(base, edits);
    let options = ScriptOptions::for_scene_file(path);
    let rebuilt = parse_scene(&script, path, &options).ok();
    if rebuilt.is_some_and(|loaded| canonical(&loaded.scene) == canonical(scene)) {
        return (script, SaveForm::Script);
    }
    let folder = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    };
    (scene.to_rhai_in(&folder), SaveForm::Keys)
}

/// The loaded text, then each entry on its own lines, every statement ended.
fn script_text(base: Option<&str>, edits: &[String]) -> String {
    let mut out = base.unwrap_or("").to_string();
    if edits.is_empty() {
        return out;
    }
    if !out.is_empty() && !out.ends_with('\n') {
        out.push('\n');
    }
    if !out.is_empty() {
        out.push('\n');
    }
    out.push_str("// Edits made in the lapclone REPL.\n");
    for edit in edits {
        let edit = edit.trim_end();
        out.push_str(edit);
        if !(edit.ends_with(';') || edit.ends_with('}')) {
            out.push(';');
        }
        out.push('\n');
    }
    out
}

/// The scene with every path made canonical, so two spellings of one file compare equal.
fn canonical(scene: &Scene) -> Scene {
    let fix = |p: &mut PathBuf| {
        if let Ok(c) = p.canonicalize() {
            *p = c;
        }
    };
    let mut scene = scene.clone();
    if let Background::Image(p) = &mut scene.canvas.background {
        fix(p);
    }
    for patch in &mut scene.patches {
        fix(&mut patch.source);
        if let Shape::Mask(p) = &mut patch.shape {
            fix(p);
        }
    }
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_follow_the_text_with_statements_ended() {
        let text = script_text(
            Some("canvas(10, 10);"),
            &["let a = 1".into(), "fn f() { 2 }".into()],
        );
        assert_eq!(
            text,
            "canvas(10, 10);\n\n// Edits made in the lapclone REPL.\nlet a = 1;\nfn f() { 2 }\n"
        );
        assert_eq!(script_text(Some("x"), &[]), "x");
    }
}
