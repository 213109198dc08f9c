//! Footage options of `canvas` and `patch`: takes a `background` or `source` string and the
//! call's option map (`KEY_start_number`, `KEY_hold`) and gives the [`Footage`] it names — a
//! printf-style numbered pattern (`plate_%04d.png`) or a video file — or `None` for a plain
//! image path.

use crate::util::ShowPath;
use std::path::Path;

use rhai::Map;

use super::values;
use crate::pixels::footage::is_video_path;
use crate::scene::Footage;

/// The option keys footage adds to a call whose path option is `key`.
pub fn footage_keys(key: &str) -> [String; 2] {
    [format!("{key}_start_number"), format!("{key}_hold")]
}

/// The footage `text` names (resolved against `base_dir`), or `None` when it is a plain
/// image path and no footage option is given.
pub fn footage_option(
    base_dir: &Path,
    text: &str,
    options: &Map,
    key: &str,
) -> Result<Option<Footage>, String> {
    let [start_key, hold_key] = footage_keys(key);
    let start = match options.get(start_key.as_str()) {
        Some(v) => Some(frame_number(v, &start_key)?),
        None => None,
    };
    let hold = match options.get(hold_key.as_str()) {
        Some(v) => Some(
            v.as_bool()
                .map_err(|_| format!("`{hold_key}` must be true or false"))?,
        ),
        None => None,
    };
    let path = base_dir.join(text);
    if !text.contains('%') && !is_video_path(&path) {
        if start.is_some() || hold.is_some() {
            return Err(format!(
                "{key} `{text}` has no frame number: `{start_key}` and `{hold_key}` need a \
                 numbered pattern (%d or %0Nd, e.g. frame_%04d.png) or a video file"
            ));
        }
        return Ok(None);
    }
    if is_video_path(&path) && start.is_some() {
        return Err(format!(
            "`{start_key}` applies to numbered image patterns, not to a video"
        ));
    }
    if is_video_path(&path) {
        if let Some(problem) = crate::util::not_a_file(&path).filter(|p| *p != "does not exist") {
            return Err(format!("{key} `{text}` {problem} ({})", path.shown()));
        }
    }
    Footage::open(&path, start, hold.unwrap_or(false), &hold_key)
        .map(Some)
        .map_err(|e| format!("{key} footage: {e}"))
}

fn frame_number(value: &rhai::Dynamic, what: &str) -> Result<u64, String> {
    let n = values::number(value, what)?;
    let max = crate::limits::MAX_START_NUMBER;
    if n.fract() != 0.0 || !(0.0..=max as f64).contains(&n) {
        let n = crate::util::number_text(n);
        return Err(format!("`{what}` must be a whole number in [0, {max}], not {n}"));
    }
    Ok(n as u64)
}
