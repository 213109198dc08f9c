//! `:keys NAME`: takes a patch and gives its keyframe tracks (and its handles' tracks) as a
//! small table: track, time, value, easing, one key per row.

use std::fmt::Write as _;

use glam::DVec2;
use lapclone::scene::{Follow, FollowTarget, Interpolate, Patch, Track};

/// The table for `patch`.
pub fn key_table(patch: &Patch) -> String {
    let mut rows: Vec<[String; 4]> = Vec::new();
    let mut followed: Vec<String> = Vec::new();
    let p = &patch.placement;
    let follow = patch.intact_follows(FollowTarget::Patch).last();
    if let Some(f) = follow {
        followed.push(follow_line("at", f));
    } else {
        track_rows(&mut rows, "at", &p.position, point);
    }
    if follow.is_none_or(|f| f.scale_keys.is_none()) {
        track_rows(&mut rows, "scale", &p.scale, |v| v.to_string());
    }
    if follow.is_none_or(|f| f.rotation.is_none()) {
        track_rows(&mut rows, "rotate", &p.rotation, |v| v.to_string());
    }
    track_rows(&mut rows, "depth", &p.depth, |v| v.to_string());
    track_rows(&mut rows, "opacity", &p.opacity, |v| v.to_string());
    for (i, h) in patch.handles.iter().enumerate() {
        let follow = patch.intact_follows(FollowTarget::Handle(i)).last();
        match follow {
            Some(f) => followed.push(follow_line(&format!("handle {i} at"), f)),
            None => track_rows(&mut rows, &format!("handle {i} at"), &h.to, point),
        }
        if follow.is_none_or(|f| f.rotation.is_none()) {
            track_rows(&mut rows, &format!("handle {i} rotate"), &h.rotation, |v| {
                v.to_string()
            });
        }
    }
    let mut out = format!("patch {:?}", patch.name);
    if rows.is_empty() && followed.is_empty() {
        out.push_str(": no keys\n");
        return out;
    }
    out.push('\n');
    for line in &followed {
        let _ = writeln!(out, "  {line}");
    }
    if rows.is_empty() {
        return out;
    }
    write_table(&mut out, &rows);
    out
}

/// `rows` under a header, each column as wide as its widest cell.
fn write_table(out: &mut String, rows: &[[String; 4]]) {
    let header = ["track", "t", "value", "easing"].map(String::from);
    let mut widths = [0usize; 4];
    for row in std::iter::once(&header).chain(rows) {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    for row in std::iter::once(&header).chain(rows) {
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

/// `at: follows track.csv (96 keys)`, plus `rotate` and `scale` when the track drives them,
/// then the path the track gives: where it starts and ends, and when.
fn follow_line(name: &str, f: &Follow) -> String {
    let mut also = String::new();
    if f.rotation.is_some() {
        also.push_str(", rotate");
    }
    if f.scale_keys.is_some() {
        also.push_str(", scale");
    }
    let mut line = format!(
        "{name}{also}: follows {} ({} keys)",
        f.file_name(),
        f.key_count()
    );
    if let (Some(first), Some(last)) = (f.at.keys().first(), f.at.keys().last()) {
        line.push_str(&format!(
            ", path {} at {} s to {} at {} s",
            point(&first.value),
            first.time,
            point(&last.value),
            last.time
        ));
    }
    line
}

fn point(p: &DVec2) -> String {
    format!("[{}, {}]", p.x, p.y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lapclone::scene::{Easing, Shape};

    #[test]
    fn a_followed_track_is_one_entry_until_its_keys_change() {
        let mut patch = Patch::new("p", "a.png".into(), Shape::Mask("m.png".into()));
        for (t, x) in [(0.0, 1.0), (0.5, 2.0), (1.0, 3.5)] {
            let at = DVec2::new(x, 4.0);
            patch
                .placement
                .position
                .push(t, at, Easing::Linear)
                .unwrap();
        }
        patch.follows.push(Follow {
            file: "shots/track.csv".into(),
            target: FollowTarget::Patch,
            point: 1,
            offset: DVec2::ZERO,
            rotate: None,
            scale: None,
            from_frame: None,
            at: patch.placement.position.clone(),
            rotation: None,
            scale_keys: None,
        });
        let table = key_table(&patch);
        assert!(
            table.contains(
                "  at: follows track.csv (3 keys), path [1, 4] at 0 s to [3.5, 4] at 1 s\n"
            ),
            "{table}"
        );
        assert_eq!(table.lines().count(), 2, "{table}");
        // An edited key makes the keys the user's own again: listed one by one.
        patch
            .placement
            .position
            .push(2.0, DVec2::ONE, Easing::Linear)
            .unwrap();
        let table = key_table(&patch);
        assert!(!table.contains("follows"), "{table}");
        assert!(table.contains("[3.5, 4]"), "{table}");
    }
}
