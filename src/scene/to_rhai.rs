//! Writing a [`Scene`] back as a Rhai scene file (the REPL's `:save` when the session's own
//! text cannot be kept): takes a scene (and the folder the file will live in) and gives
//! source text that the scene language parses back into an equal scene. Numbers are written
//! in Rust's shortest round-trip form, so no value changes on the way; paths are written
//! relative to the file's folder where they can be; each patch's variable is named after it.

use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};

use glam::DVec2;

use super::types::{Follow, FollowTarget};
use super::track::{Interpolate, Track};
use super::types::{
    Background, Canvas, Footage, FootageSource, Handle, Patch, Pin, Polygon, Scene, Shape,
};

impl Scene {
    /// Rhai source that re-creates this scene (paths written as stored, i.e. resolved).
    pub fn to_rhai(&self) -> String {
        self.write_rhai(None)
    }

    /// Rhai source for a file in `folder`: paths relative to it (when both it and the file
    /// exist), otherwise as [`Scene::to_rhai`].
    pub fn to_rhai_in(&self, folder: &Path) -> String {
        self.write_rhai(Some(folder))
    }

    fn write_rhai(&self, folder: Option<&Path>) -> String {
        let mut out = String::from("// Scene written by lapclone.\n");
        let paths = Paths(folder.and_then(|f| f.canonicalize().ok()));
        write_canvas(&mut out, &self.canvas, &paths);
        let mut taken = Vec::new();
        for patch in &self.patches {
            out.push('\n');
            let var = variable_name(&patch.name, &taken);
            write_patch(&mut out, patch, &var, &paths);
            taken.push(var);
        }
        if let Some(golden) = &self.golden {
            out.push('\n');
            out.push_str(&golden.to_rhai());
        }
        out
    }
}

/// How paths are written: relative to this (canonical) folder, or as stored.
struct Paths(Option<PathBuf>);

impl Paths {
    fn literal(&self, path: &Path) -> String {
        let relative = self
            .0
            .as_ref()
            .and_then(|folder| relative_path(folder, path));
        path_literal(relative.as_deref().unwrap_or(path))
    }
}

/// `path` relative to `folder` (both made canonical), with `..` where needed; `None` when
/// they share no more than the file-system root (the absolute path reads better then).
fn relative_path(folder: &Path, path: &Path) -> Option<PathBuf> {
    let path = path.canonicalize().ok()?;
    let common = folder
        .components()
        .zip(path.components())
        .take_while(|(a, b)| a == b)
        .count();
    let roots = folder
        .components()
        .take_while(|c| matches!(c, Component::Prefix(_) | Component::RootDir))
        .count();
    if common <= roots {
        return None;
    }
    let mut out = PathBuf::new();
    for _ in folder.components().skip(common) {
        out.push("..");
    }
    for part in path.components().skip(common) {
        out.push(part);
    }
    Some(out)
}

/// Whether Rhai refuses `name` as a variable: its keywords and the words it reserves, as the
/// parser itself says (a copied list drifts from the Rhai in use).
fn is_reserved(name: &str) -> bool {
    rhai::Engine::new_raw()
        .compile(format!("let {name} = 0;"))
        .is_err()
}

/// A Rhai variable named after the patch (`cat`, `big_dog`), unique among `taken`.
fn variable_name(patch: &str, taken: &[String]) -> String {
    let mut base: String = patch
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    base = base.trim_matches('_').to_string();
    if base.is_empty() || base.starts_with(|c: char| c.is_ascii_digit()) {
        base = format!("patch_{base}");
    }
    if is_reserved(&base) {
        base.push_str("_patch");
    }
    let mut name = base.clone();
    let mut n = 2;
    // Handles are written as `{patch variable}_h1`, `_h2`, …: no patch variable may look like one.
    let clashes = |name: &str| {
        taken
            .iter()
            .any(|t| t == name || is_handle_of(name, t) || is_handle_of(t, name))
    };
    while clashes(&name) {
        name = format!("{base}_{n}");
        n += 1;
    }
    name
}

/// Whether `var` has the form of a handle variable of `patch_var` (`{patch_var}_h12`).
fn is_handle_of(var: &str, patch_var: &str) -> bool {
    var.strip_prefix(patch_var)
        .and_then(|rest| rest.strip_prefix("_h"))
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

fn write_canvas(out: &mut String, canvas: &Canvas, paths: &Paths) {
    let background = match &canvas.background {
        Background::Image(path) => paths.literal(path),
        Background::Colour(c) => format!(
            "[{}, {}, {}, {}]",
            num_f32(c[0]),
            num_f32(c[1]),
            num_f32(c[2]),
            num_f32(c[3])
        ),
        Background::Footage(footage) => footage_options(footage, "background", paths),
    };
    // invariant: writing to a String cannot fail.
    writeln!(
        out,
        "canvas({}, {}, #{{ fps: {}, duration: {}, background: {} }});",
        canvas.width,
        canvas.height,
        num(canvas.fps),
        num(canvas.duration),
        background
    )
    .expect("write to String"); // invariant: writing to a String cannot fail
}

/// `KEY: "pattern or video", KEY_start_number: N, KEY_hold: b`, with `background: ` left out of the
/// background's own text (the caller writes the key).
fn footage_options(footage: &Footage, key: &str, paths: &Paths) -> String {
    let mut text = match &footage.source {
        FootageSource::Sequence { pattern, start } => format!(
            "{}, {key}_start_number: {start}",
            rhai_string_literal(pattern.text())
        ),
        FootageSource::Video(path) => paths.literal(path),
    };
    if footage.hold {
        text.push_str(&format!(", {key}_hold: true"));
    }
    if key == "source" {
        text.insert_str(0, "source: ");
    }
    text
}

fn write_patch(out: &mut String, patch: &Patch, var: &str, paths: &Paths) {
    let mut options = vec![match &patch.footage {
        Some(footage) => footage_options(footage, "source", paths),
        None => format!("source: {}", paths.literal(&patch.source)),
    }];
    match &patch.shape {
        Shape::Mask(path) => options.push(format!("mask: {}", paths.literal(path))),
        Shape::Polygons(polygons) => {
            options.push(format!("polygons: {}", polygons_literal(polygons)))
        }
    }
    if let Some(d) = patch.density {
        options.push(format!("density: {}", num(d)));
    }
    options.push(format!("laplacian: \"{}\"", patch.laplacian.name()));
    options.push(format!("mode: \"{}\"", patch.mode.name()));
    options.push(format!("feather: {}", num(patch.feather)));
    options.push(format!("boundary_sampling: \"{}\"", patch.boundary_data.name()));
    options.push(format!("mesh_boundary: \"{}\"", patch.boundary.name()));
    let _ = writeln!(
        out,
        "let {var} = patch({}, #{{ {} }});",
        rhai_string_literal(&patch.name),
        options.join(", ")
    );
    let p = &patch.placement;
    let follow = patch.intact_follows(FollowTarget::Patch).last();
    match follow {
        Some(f) => write_follow(out, var, f, paths),
        None => write_track(out, var, "at", &p.position, point),
    }
    if follow.is_none_or(|f| f.scale_keys.is_none()) {
        write_track(out, var, "scale", &p.scale, |v| num(*v));
    }
    if follow.is_none_or(|f| f.rotation.is_none()) {
        write_track(out, var, "rotate", &p.rotation, |v| num(*v));
    }
    write_track(out, var, "depth", &p.depth, |v| num(*v));
    write_track(out, var, "opacity", &p.opacity, |v| num(*v));
    for (i, handle) in patch.handles.iter().enumerate() {
        let follow = patch.intact_follows(FollowTarget::Handle(i)).last();
        write_handle(out, handle, &format!("{var}_h{}", i + 1), var, follow, paths);
    }
    for pin in &patch.pins {
        write_pin(out, pin, var);
    }
}

/// `var.follow("file", #{ … });` with the settings as the scene wrote them.
fn write_follow(out: &mut String, var: &str, follow: &Follow, paths: &Paths) {
    let mut options = vec![format!("point: {}", follow.point)];
    if follow.offset != DVec2::ZERO {
        options.push(format!("offset: {}", point(&follow.offset)));
    }
    if let Some(r) = follow.rotate {
        options.push(format!("rotate: {r}"));
    }
    if let Some(s) = follow.scale {
        options.push(format!("scale: {s}"));
    }
    if let Some(f) = follow.from_frame {
        options.push(format!("from_frame: {f}"));
    }
    let _ = writeln!(
        out,
        "{var}.follow({}, #{{ {} }});",
        paths.literal(&follow.file),
        options.join(", ")
    );
}

fn write_handle(
    out: &mut String,
    handle: &Handle,
    var: &str,
    patch_var: &str,
    follow: Option<&Follow>,
    paths: &Paths,
) {
    let mut options = Vec::new();
    if let Some(d) = handle.depth {
        options.push(format!("depth: {}", num(d)));
    }
    if let Some(p) = handle.pivot {
        options.push(format!("pivot: {}", point(&p)));
    }
    let _ = writeln!(
        out,
        "let {var} = {patch_var}.drag({}, {}, #{{ {} }});",
        point(&handle.from),
        num(handle.radius),
        options.join(", ")
    );
    match follow {
        Some(f) => write_follow(out, var, f, paths),
        None => write_track(out, var, "key", &handle.to, point),
    }
    if follow.is_none_or(|f| f.rotation.is_none()) {
        write_track(out, var, "rotate", &handle.rotation, |v| num(*v));
    }
}

fn write_pin(out: &mut String, pin: &Pin, var: &str) {
    let mut window = vec![format!("start: {}", num(pin.start))];
    if let Some(end) = pin.end {
        window.push(format!("end: {}", num(end)));
    }
    let _ = writeln!(
        out,
        "{var}.pin({}, #{{ {} }});",
        point(&pin.at),
        window.join(", ")
    );
}

fn write_track<T: Interpolate>(
    out: &mut String,
    var: &str,
    method: &str,
    track: &Track<T>,
    value: impl Fn(&T) -> String,
) {
    for key in track.keys() {
        let _ = writeln!(
            out,
            "{var}.{method}({}, {}, \"{}\");",
            num(key.time),
            value(&key.value),
            key.easing.name()
        );
    }
}

fn polygons_literal(polygons: &[Polygon]) -> String {
    let ring = |r: &[DVec2]| format!("[{}]", r.iter().map(point).collect::<Vec<_>>().join(", "));
    let items: Vec<String> = polygons
        .iter()
        .map(|p| {
            let holes: Vec<String> = p.holes.iter().map(|h| ring(h)).collect();
            format!(
                "#{{ outer: {}, holes: [{}] }}",
                ring(&p.outer),
                holes.join(", ")
            )
        })
        .collect();
    format!("[{}]", items.join(", "))
}

fn point(p: &DVec2) -> String {
    format!("[{}, {}]", num(p.x), num(p.y))
}

/// Shortest round-trip decimal form, always with a decimal point so Rhai reads a float.
fn num(v: f64) -> String {
    let text = format!("{v:?}");
    with_decimal_point(text)
}

fn num_f32(v: f32) -> String {
    with_decimal_point(format!("{v:?}"))
}

fn with_decimal_point(text: String) -> String {
    if text.contains('.') || !text.chars().any(|c| c.is_ascii_digit()) {
        return text;
    }
    match text.find('e') {
        Some(e) => format!("{}.0{}", &text[..e], &text[e..]),
        None => format!("{text}.0"),
    }
}

fn path_literal(path: &Path) -> String {
    rhai_string_literal(&path.to_string_lossy())
}

/// The Rhai expression that gives back the scene's patch `name`: `get_patch("cat")`. The
/// REPL shows a patch as it, and a line written for the live view names a patch by it when
/// no variable holds the patch.
pub(crate) fn get_patch_call(name: &str) -> String {
    format!("get_patch({})", rhai_string_literal(name))
}

/// A Rhai string literal that evaluates to exactly `text`.
pub fn rhai_string_literal(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
