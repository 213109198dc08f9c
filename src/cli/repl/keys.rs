//! `:keys NAME`: takes a patch and gives its keyframe tracks (and its handles' tracks) as a
//! small table: track, time, value, easing, one key per row.

use std::fmt::Write as _;

use glam::DVec2;
use lapclone::scene::{Interpolate, Patch, Track};

/// The table for `patch`.
pub fn key_table(patch: &Patch) -> String {
    let mut rows: Vec<[String; 4]> = Vec::new();
    let p = &patch.placement;
    track_rows(&mut rows, "at", &p.position, point);
    track_rows(&mut rows, "scale", &p.scale, |v| v.to_string());
    track_rows(&mut rows, "rotate", &p.rotation, |v| v.to_string());
    track_rows(&mut rows, "depth", &p.depth, |v| v.to_string());
    track_rows(&mut rows, "opacity", &p.opacity, |v| v.to_string());
    for (i, h) in patch.handles.iter().enumerate() {
        track_rows(&mut rows, &format!("handle {i} at"), &h.to, point);
        track_rows(&mut rows, &format!("handle {i} rotate"), &h.rotation, |v| {
            v.to_string()
        });
    }
    let mut out = format!("patch {:?}", patch.name);
    if rows.is_empty() {
        out.push_str(": no keys\n");
        return out;
    }
    out.push('\n');
    let header = ["track", "t", "value", "easing"].map(String::from);
    let mut widths = [0usize; 4];
    for row in std::iter::once(&header).chain(&rows) {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    for row in std::iter::once(&header).chain(&rows) {
        let _ = writeln!(
            out,
            "  {:<a$}  {:>b$}  {:<c$}  {}",
            row[0],
            row[1],
            row[2],
            row[3],
            a = widths[0],
            b = widths[1],
            c = widths[2]
        );
    }
    out
}

fn track_rows<T: Interpolate>(
    rows: &mut Vec<[String; 4]>,
    name: &str,
    track: &Track<T>,
    value: impl Fn(&T) -> String,
) {
    for key in track.keys() {
        rows.push([
            name.to_string(),
            key.time.to_string(),
            value(&key.value),
            key.easing.name().to_string(),
        ]);
    }
}

fn point(p: &DVec2) -> String {
    format!("[{}, {}]", p.x, p.y)
}
