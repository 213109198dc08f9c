//! Writing a [`Scene`] back as a Rhai scene file (the REPL's `:save`): takes a scene and gives
//! source text that the scene language parses back into an equal scene. Numbers are written
//! in Rust's shortest round-trip form, so no value changes on the way.

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec2;

use super::track::{Interpolate, Track};
use super::types::{
    Background, Canvas, Footage, FootageSource, Handle, Patch, Pin, Polygon, Scene, Shape,
};

impl Scene {
    /// Rhai source that re-creates this scene (paths written as stored, i.e. resolved).
    pub fn to_rhai(&self) -> String {
        let mut out = String::from("// Scene written by lapclone.\n");
        write_canvas(&mut out, &self.canvas);
        for (i, patch) in self.patches.iter().enumerate() {
            out.push('\n');
            write_patch(&mut out, patch, &format!("p{}", i + 1));
        }
        out
    }
}

fn write_canvas(out: &mut String, canvas: &Canvas) {
    let background = match &canvas.background {
        Background::Image(path) => path_literal(path),
        Background::Colour(c) => format!(
            "[{}, {}, {}, {}]",
            num_f32(c[0]),
            num_f32(c[1]),
            num_f32(c[2]),
            num_f32(c[3])
        ),
        Background::Footage(footage) => footage_options(footage, "background"),
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

/// `KEY: "pattern or video", KEY_start: N, KEY_hold: b`, with `background: ` left out of the
/// background's own text (the caller writes the key).
fn footage_options(footage: &Footage, key: &str) -> String {
    let mut text = match &footage.source {
        FootageSource::Sequence { pattern, start } => format!(
            "{}, {key}_start: {start}",
            rhai_string_literal(pattern.text())
        ),
        FootageSource::Video(path) => path_literal(path),
    };
    if footage.hold {
        text.push_str(&format!(", {key}_hold: true"));
    }
    if key == "source" {
        text.insert_str(0, "source: ");
    }
    text
}

fn write_patch(out: &mut String, patch: &Patch, var: &str) {
    let mut options = vec![match &patch.footage {
        Some(footage) => footage_options(footage, "source"),
        None => format!("source: {}", path_literal(&patch.source)),
    }];
    match &patch.shape {
        Shape::Mask(path) => options.push(format!("mask: {}", path_literal(path))),
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
    options.push(format!("boundary_data: \"{}\"", patch.boundary_data.name()));
    options.push(format!("boundary: \"{}\"", patch.boundary.name()));
    let _ = writeln!(
        out,
        "let {var} = patch({}, #{{ {} }});",
        rhai_string_literal(&patch.name),
        options.join(", ")
    );
    let p = &patch.placement;
    write_track(out, var, "at", &p.position, point);
    write_track(out, var, "scale", &p.scale, |v| num(*v));
    write_track(out, var, "rotate", &p.rotation, |v| num(*v));
    write_track(out, var, "depth", &p.depth, |v| num(*v));
    for (i, handle) in patch.handles.iter().enumerate() {
        write_handle(out, handle, &format!("{var}_h{}", i + 1), var);
    }
    for pin in &patch.pins {
        write_pin(out, pin, var);
    }
}

fn write_handle(out: &mut String, handle: &Handle, var: &str, patch_var: &str) {
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
    write_track(out, var, "key", &handle.to, point);
    write_track(out, var, "rotate", &handle.rotation, |v| num(*v));
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
