//! The live view's page messages: takes one text message from a page (JSON, bounded) and
//! gives a checked [`Request`]; a scene edit in it becomes the readable Rhai line the
//! session runs (`cat.at(1.25, [240, 180]);`), and the same edit can be applied to a
//! [`Scene`] directly for the drag preview, with exactly the values the line writes.

use glam::DVec2;
use lapclone::scene::{Easing, Handle, Patch, Scene};
use lapclone::util::number_text;
use serde::Deserialize;

/// Largest text message a page may send, bytes.
pub const MAX_MESSAGE_BYTES: usize = 16 * 1024;
/// Largest coordinate, radius or time a page may send (anything a user controls has a bound).
const MAX_MAGNITUDE: f64 = 1e6;
/// Longest patch name a page may send.
const MAX_NAME: usize = 256;

/// One message from a page.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Request {
    /// Move the playhead (no history).
    Seek { t: f64 },
    /// Where a canvas point falls: the patch on top there and its source coordinates.
    Locate { x: f64, y: f64 },
    /// A scene edit made against revision `rev`: previewed while a gesture runs
    /// (`commit: false`), run as one REPL line when it ends (`commit: true`). `t` is the
    /// playhead the page showed when the gesture began, where its keys go (the gesture's
    /// values were measured there, even if another page has moved the playhead since);
    /// without it, the session's playhead.
    Edit {
        rev: u64,
        commit: bool,
        edit: Edit,
        #[serde(default)]
        t: Option<f64>,
    },
    /// Escape: drop the gesture's preview. (Braces, so that serde refuses unknown fields
    /// here too: it does not for a unit variant of a tagged enum.)
    Cancel {},
    /// Ctrl+Z: `:undo`.
    Undo {},
    /// Ctrl+S (after the page's confirmation): `:save` to the loaded file.
    Save { rev: u64 },
    /// This page wants the placed meshes with every scene message (overlay on).
    Mesh { on: bool },
}

/// A keyframable track, as the scene functions name it: a patch has all five, a handle
/// `at` (its target) and `rotate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Track {
    At,
    Scale,
    Rotate,
    Depth,
    Opacity,
}

impl Track {
    /// Whether a handle has this track.
    fn on_handle(self) -> bool {
        matches!(self, Track::At | Track::Rotate)
    }

    /// Its scene-language name (the one the page sends).
    fn name(self) -> &'static str {
        ["at", "scale", "rotate", "depth", "opacity"][self as usize]
    }
}

/// A scene edit from a page: which patch, which handle, which value. Keys go at the
/// session's playhead, which the server supplies.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum Edit {
    At {
        patch: String,
        value: [f64; 2],
    },
    Rotate {
        patch: String,
        value: f64,
    },
    Scale {
        patch: String,
        value: f64,
    },
    HandleKey {
        patch: String,
        handle: usize,
        value: [f64; 2],
    },
    HandleRadius {
        patch: String,
        handle: usize,
        value: f64,
    },
    AddHandle {
        patch: String,
        from: [f64; 2],
        radius: f64,
    },
    AddPin {
        patch: String,
        at: [f64; 2],
    },
    RemoveHandle {
        patch: String,
        handle: usize,
    },
    RemovePin {
        patch: String,
        pin: usize,
    },
    /// A key of the patch's track, or of its handle's when `handle` is given.
    MoveKey {
        patch: String,
        #[serde(default)]
        handle: Option<usize>,
        track: Track,
        from: f64,
        to: f64,
    },
    RemoveKey {
        patch: String,
        #[serde(default)]
        handle: Option<usize>,
        track: Track,
        t: f64,
    },
}

/// Parses and bounds a page message; the error is shown in the page.
pub fn parse_request(text: &str) -> Result<Request, String> {
    if text.len() > MAX_MESSAGE_BYTES {
        return Err(format!("message over {MAX_MESSAGE_BYTES} bytes"));
    }
    let mut request: Request =
        serde_json::from_str(text).map_err(|e| format!("malformed message: {e}"))?;
    // A time of -0 is 0: the lines it reaches read `0`, not `-0`.
    match &mut request {
        Request::Seek { t } | Request::Edit { t: Some(t), .. } => *t += 0.0,
        _ => {}
    }
    match &request {
        Request::Seek { t } => time(*t)?,
        Request::Locate { x, y } => {
            bounded(*x)?;
            bounded(*y)?;
        }
        Request::Edit { edit, t, .. } => {
            t.map_or(Ok(()), time)?;
            check_edit(edit)?
        }
        _ => {}
    }
    Ok(request)
}

fn bounded(v: f64) -> Result<(), String> {
    if v.is_finite() && v.abs() <= MAX_MAGNITUDE {
        Ok(())
    } else {
        Err(format!(
            "{} is not a finite number within ±{MAX_MAGNITUDE}",
            number_text(v)
        ))
    }
}

fn time(t: f64) -> Result<(), String> {
    bounded(t)?;
    if t < 0.0 {
        return Err(format!("time {} is negative", number_text(t)));
    }
    Ok(())
}

fn positive(v: f64) -> Result<(), String> {
    bounded(v)?;
    if v <= 0.0 {
        return Err(format!("{} must be greater than 0", number_text(v)));
    }
    Ok(())
}

/// A handle's or pin's index: no patch has anywhere near [`MAX_MAGNITUDE`] of them, and a
/// larger one would not be read back as an integer.
fn index(i: usize, what: &str) -> Result<(), String> {
    if i as f64 > MAX_MAGNITUDE {
        return Err(format!("{what} index {i} is past ±{MAX_MAGNITUDE}"));
    }
    Ok(())
}

fn check_edit(edit: &Edit) -> Result<(), String> {
    let patch = edit.patch();
    if patch.is_empty() || patch.len() > MAX_NAME {
        return Err(format!(
            "a patch name must have 1 to {MAX_NAME} bytes, not {}",
            patch.len()
        ));
    }
    edit.indices()
        .into_iter()
        .try_for_each(|(i, what)| index(i, what))?;
    match edit {
        Edit::At { value, .. } | Edit::HandleKey { value, .. } => {
            value.iter().try_for_each(|v| bounded(*v))
        }
        Edit::AddPin { at: value, .. } => value.iter().try_for_each(|v| bounded(*v)),
        Edit::Rotate { value, .. } => bounded(*value),
        Edit::Scale { value, .. } | Edit::HandleRadius { value, .. } => positive(*value),
        Edit::AddHandle { from, radius, .. } => {
            from.iter().try_for_each(|v| bounded(*v))?;
            positive(*radius)
        }
        Edit::RemoveHandle { .. } | Edit::RemovePin { .. } => Ok(()),
        Edit::MoveKey {
            from,
            to,
            handle,
            track,
            ..
        } => {
            handle_track(*handle, *track)?;
            time(*from).and(time(*to))
        }
        Edit::RemoveKey {
            t, handle, track, ..
        } => {
            handle_track(*handle, *track)?;
            time(*t)
        }
    }
}

/// A handle's key edit names one of the handle's tracks.
fn handle_track(handle: Option<usize>, track: Track) -> Result<(), String> {
    if handle.is_some() && !track.on_handle() {
        return Err(format!(
            "a handle has no {:?} track; tracks: at, rotate",
            track.name()
        ));
    }
    Ok(())
}

impl Edit {
    /// The patch this edit is about.
    pub fn patch(&self) -> &str {
        match self {
            Edit::At { patch, .. }
            | Edit::Rotate { patch, .. }
            | Edit::Scale { patch, .. }
            | Edit::HandleKey { patch, .. }
            | Edit::HandleRadius { patch, .. }
            | Edit::AddHandle { patch, .. }
            | Edit::AddPin { patch, .. }
            | Edit::RemoveHandle { patch, .. }
            | Edit::RemovePin { patch, .. }
            | Edit::MoveKey { patch, .. }
            | Edit::RemoveKey { patch, .. } => patch,
        }
    }

    /// The time this edit puts a key at besides the playhead: where `move_key` moves one.
    pub fn keys_elsewhere(&self) -> Option<f64> {
        match self {
            Edit::MoveKey { to, .. } => Some(*to),
            _ => None,
        }
    }

    /// The handle and pin indices this edit names, with what each indexes.
    fn indices(&self) -> Vec<(usize, &'static str)> {
        match self {
            Edit::HandleKey { handle, .. }
            | Edit::HandleRadius { handle, .. }
            | Edit::RemoveHandle { handle, .. }
            | Edit::MoveKey {
                handle: Some(handle),
                ..
            }
            | Edit::RemoveKey {
                handle: Some(handle),
                ..
            } => vec![(*handle, "handle")],
            Edit::RemovePin { pin, .. } => vec![(*pin, "pin")],
            _ => Vec::new(),
        }
    }

    /// The same edit with its values rounded as the line writes them (hundredths of a pixel
    /// or degree, ten-thousandths of a scale), so a preview and its committed line agree.
    pub fn rounded(&self) -> Edit {
        let mut edit = self.clone();
        let p2 = |v: &mut [f64; 2]| v.iter_mut().for_each(|x| *x = round(*x, 100.0));
        match &mut edit {
            Edit::At { value, .. } | Edit::HandleKey { value, .. } => p2(value),
            Edit::AddPin { at, .. } => p2(at),
            Edit::AddHandle { from, radius, .. } => {
                p2(from);
                *radius = round(*radius, 100.0).max(0.01);
            }
            Edit::Rotate { value, .. } => *value = round(*value, 100.0),
            Edit::HandleRadius { value, .. } => *value = round(*value, 100.0).max(0.01),
            Edit::Scale { value, .. } => *value = round(*value, 10_000.0).max(0.0001),
            _ => {}
        }
        edit
    }

    /// The Rhai line for this edit at playhead `t`; `patch` is how the session names the
    /// patch (a variable holding it, else `get_patch("name")`); `handle_name` names a new
    /// handle's variable.
    pub fn line(&self, t: f64, patch: &str, handle_name: &str) -> String {
        let t = num(t);
        match self.rounded() {
            Edit::At { value, .. } => format!("{patch}.at({t}, {});", point(value)),
            Edit::Rotate { value, .. } => format!("{patch}.rotate({t}, {});", num(value)),
            Edit::Scale { value, .. } => format!("{patch}.scale({t}, {});", num(value)),
            Edit::HandleKey { handle, value, .. } => {
                format!("{patch}.handle({handle}).key({t}, {});", point(value))
            }
            Edit::HandleRadius { handle, value, .. } => {
                format!("{patch}.handle({handle}).radius({});", num(value))
            }
            Edit::AddHandle { from, radius, .. } => format!(
                "let {handle_name} = {patch}.drag({}, {});",
                point(from),
                num(radius)
            ),
            Edit::AddPin { at, .. } => format!("{patch}.pin({});", point(at)),
            Edit::RemoveHandle { handle, .. } => format!("{patch}.remove_handle({handle});"),
            Edit::RemovePin { pin, .. } => format!("{patch}.remove_pin({pin});"),
            Edit::MoveKey {
                handle,
                track,
                from,
                to,
                ..
            } => format!(
                "{}.move_key({}, {}, \"{}\");",
                owner(patch, handle),
                num(from),
                num(to),
                track.name()
            ),
            Edit::RemoveKey {
                handle, track, t, ..
            } => format!(
                "{}.remove_key({}, \"{}\");",
                owner(patch, handle),
                num(t),
                track.name()
            ),
        }
    }

    /// Applies a gesture's edit (at, rotate, scale, a handle's target or radius) to `scene`
    /// as its line would, for the preview of a gesture in progress. Other edits are not
    /// previewed.
    pub fn apply_key(&self, scene: &mut Scene, t: f64) -> Result<(), String> {
        let edit = self.rounded();
        let patch = scene
            .patches
            .iter_mut()
            .find(|p| p.name == edit.patch())
            .ok_or_else(|| format!("no patch {:?}", edit.patch()))?;
        let p = &mut patch.placement;
        let linear = Easing::default();
        let result = match edit {
            Edit::At { value, .. } => p.position.push(t, DVec2::from(value), linear),
            Edit::Rotate { value, .. } => p.rotation.push(t, value, linear),
            Edit::Scale { value, .. } => p.scale.push(t, value, linear),
            Edit::HandleKey { handle, value, .. } => {
                handle_of(patch, handle)?
                    .to
                    .push(t, DVec2::from(value), linear)
            }
            Edit::HandleRadius { handle, value, .. } => {
                handle_of(patch, handle)?.radius = value;
                Ok(())
            }
            _ => return Err("this edit has no preview".into()),
        };
        result.map_err(|e| e.to_string())
    }

    /// Whether a gesture of this kind previews (the others only commit).
    pub fn previews(&self) -> bool {
        matches!(
            self,
            Edit::At { .. }
                | Edit::Rotate { .. }
                | Edit::Scale { .. }
                | Edit::HandleKey { .. }
                | Edit::HandleRadius { .. }
        )
    }
}

fn handle_of(patch: &mut Patch, handle: usize) -> Result<&mut Handle, String> {
    let count = patch.handles.len();
    patch
        .handles
        .get_mut(handle)
        .ok_or_else(|| format!("no handle {handle}: the patch has {count}"))
}

/// How a key edit's line names the owner of the track: the patch or one of its handles.
fn owner(patch: &str, handle: Option<usize>) -> String {
    match handle {
        Some(h) => format!("{patch}.handle({h})"),
        None => patch.to_string(),
    }
}

fn round(v: f64, per: f64) -> f64 {
    let r = (v * per).round() / per;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// A number as Rhai reads it back exactly: whole ones without a fraction (`240`), others in
/// their shortest form, with an exponent when tiny or huge (`5e-324`, not 324 digits).
fn num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v}")
    } else {
        format!("{v:?}")
    }
}

fn point(v: [f64; 2]) -> String {
    format!("[{}, {}]", num(v[0]), num(v[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edit(json: &str) -> Edit {
        match parse_request(&format!(
            r#"{{"type":"edit","rev":1,"commit":true,"edit":{json}}}"#
        )) {
            Ok(Request::Edit { edit, .. }) => edit,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_patch_name_past_the_limit_says_the_limit() {
        let name = "p".repeat(300);
        let text = format!(
            r#"{{"type":"edit","rev":1,"commit":true,"edit":{{"op":"at","patch":"{name}","value":[1,2]}}}}"#
        );
        let error = parse_request(&text).unwrap_err();
        assert!(
            error.contains("a patch name must have 1 to 256 bytes, not 300"),
            "{error}"
        );
    }

    #[test]
    fn each_edit_kind_gives_its_line() {
        let cases = [
            (
                r#"{"op":"at","patch":"cat","value":[240.004,180]}"#,
                "cat.at(1.25, [240, 180]);",
            ),
            (
                r#"{"op":"rotate","patch":"cat","value":-12.345}"#,
                "cat.rotate(1.25, -12.35);",
            ),
            (
                r#"{"op":"scale","patch":"cat","value":0.41234}"#,
                "cat.scale(1.25, 0.4123);",
            ),
            (
                r#"{"op":"handle_key","patch":"cat","handle":1,"value":[10.5,20]}"#,
                "cat.handle(1).key(1.25, [10.5, 20]);",
            ),
            (
                r#"{"op":"add_handle","patch":"cat","from":[118,298],"radius":70}"#,
                "let h2 = cat.drag([118, 298], 70);",
            ),
            (
                r#"{"op":"add_pin","patch":"cat","at":[5,6]}"#,
                "cat.pin([5, 6]);",
            ),
            (
                r#"{"op":"remove_handle","patch":"cat","handle":0}"#,
                "cat.remove_handle(0);",
            ),
            (
                r#"{"op":"remove_pin","patch":"cat","pin":2}"#,
                "cat.remove_pin(2);",
            ),
            (
                r#"{"op":"move_key","patch":"cat","track":"at","from":1,"to":1.5}"#,
                "cat.move_key(1, 1.5, \"at\");",
            ),
            (
                r#"{"op":"remove_key","patch":"cat","track":"scale","t":3}"#,
                "cat.remove_key(3, \"scale\");",
            ),
            (
                r#"{"op":"handle_radius","patch":"cat","handle":1,"value":55.555}"#,
                "cat.handle(1).radius(55.56);",
            ),
            (
                r#"{"op":"move_key","patch":"cat","handle":0,"track":"at","from":1,"to":1.5}"#,
                "cat.handle(0).move_key(1, 1.5, \"at\");",
            ),
            (
                r#"{"op":"remove_key","patch":"cat","handle":2,"track":"rotate","t":0.5}"#,
                "cat.handle(2).remove_key(0.5, \"rotate\");",
            ),
        ];
        for (json, line) in cases {
            assert_eq!(edit(json).line(1.25, "cat", "h2"), line, "{json}");
        }
    }

    /// A time of -0 is taken as 0, so no line or scene message reads `-0`.
    #[test]
    fn a_time_of_minus_zero_is_zero() {
        let seek = parse_request(r#"{"type":"seek","t":-0.0}"#).unwrap();
        assert!(
            matches!(seek, Request::Seek { t } if t.to_bits() == 0),
            "{seek:?}"
        );
        let edit = r#"{"type":"edit","rev":1,"commit":true,"t":-0.0,"edit":{"op":"scale","patch":"cat","value":2}}"#;
        let edit = parse_request(edit).unwrap();
        assert!(
            matches!(edit, Request::Edit { t: Some(t), .. } if t.to_bits() == 0),
            "{edit:?}"
        );
    }

    #[test]
    fn refuses_bad_values_and_unknown_fields() {
        for text in [
            r#"{"type":"seek","t":-1}"#,
            r#"{"type":"seek","t":1e300}"#,
            r#"{"type":"seek"}"#,
            r#"{"type":"locate","x":1,"y":2,"z":3}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"scale","patch":"cat","value":0}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"eval","patch":"cat"}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"at","patch":"","value":[1,2]}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"move_key","patch":"c","track":"x","from":1,"to":2}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"remove_key","patch":"c","handle":0,"track":"scale","t":1}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"handle_radius","patch":"c","handle":0,"value":0}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"handle_radius","patch":"c","handle":-1,"value":3}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"t":-0.5,"edit":{"op":"at","patch":"c","value":[1,2]}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"t":1e7,"edit":{"op":"at","patch":"c","value":[1,2]}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"t":"1","edit":{"op":"at","patch":"c","value":[1,2]}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"remove_handle","patch":"c","handle":18446744073709551615}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"remove_pin","patch":"c","pin":1000001}}"#,
            r#"{"type":"edit","rev":1,"commit":true,"edit":{"op":"move_key","patch":"c","handle":1000001,"track":"at","from":1,"to":2}}"#,
            r#"{"type":"undo","rev":12345}"#,
            r#"{"type":"cancel","code":"anything"}"#,
            "not json",
        ] {
            assert!(parse_request(text).is_err(), "{text}");
        }
        assert!(parse_request(&" ".repeat(MAX_MESSAGE_BYTES + 1)).is_err());
        for text in [r#"{"type":"undo"}"#, r#"{"type":"cancel"}"#] {
            assert!(parse_request(text).is_ok(), "{text}");
        }
        // Extreme numbers are named short in the refusal.
        let message = parse_request(r#"{"type":"seek","t":1e308}"#).unwrap_err();
        assert!(message.starts_with("1e308 is not"), "{message}");
    }

    /// Times are written exactly, and readably when tiny: Rhai reads the line back to the
    /// same key time.
    #[test]
    fn key_times_are_written_exactly_and_short() {
        let at = edit(r#"{"op":"at","patch":"cat","value":[1,2]}"#);
        for (t, shown) in [
            (5e-324, "5e-324"),
            (0.1 + 0.2, "0.30000000000000004"),
            (2.0, "2"),
        ] {
            let line = at.line(t, "cat", "h");
            assert_eq!(line, format!("cat.at({shown}, [1, 2]);"));
            assert_eq!(shown.parse::<f64>().unwrap(), t);
        }
    }

    #[test]
    fn an_edit_carries_the_playhead_its_gesture_began_at_or_none() {
        let with = r#"{"type":"edit","rev":1,"commit":false,"t":0.75,"edit":{"op":"at","patch":"c","value":[1,2]}}"#;
        let without = r#"{"type":"edit","rev":1,"commit":false,"edit":{"op":"at","patch":"c","value":[1,2]}}"#;
        let t = |text| match parse_request(text) {
            Ok(Request::Edit { t, .. }) => t,
            other => panic!("{other:?}"),
        };
        assert_eq!(t(with), Some(0.75));
        assert_eq!(t(without), None);
    }
}
