//! Converting Rhai values into scene values: takes `Dynamic`s from scene calls and gives
//! finite numbers (integers and floats alike), points, easings, colours and option maps,
//! or a message saying what was wrong.

use rhai::{Array, Dynamic, Map};

use crate::scene::Easing;
use crate::util::number_text;
use glam::DVec2;

/// A finite number from an integer or a float.
pub fn number(value: &Dynamic, what: &str) -> Result<f64, String> {
    let v = if let Ok(i) = value.as_int() {
        i as f64
    } else if let Ok(f) = value.as_float() {
        f
    } else {
        return Err(format!("{what} must be a number, got {}", type_name(value)));
    };
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{what} must be a finite number, got {v}"))
    }
}

/// A number `ok` accepts; otherwise the error says it must be `rule`.
pub(super) fn number_where(
    value: &Dynamic,
    what: &str,
    ok: impl Fn(f64) -> bool,
    rule: &str,
) -> Result<f64, String> {
    let v = number(value, what)?;
    if ok(v) {
        Ok(v)
    } else {
        Err(format!("{what} must be {rule}, got {}", crate::util::number_text(v)))
    }
}

pub fn positive(value: &Dynamic, what: &str) -> Result<f64, String> {
    number_where(value, what, |v| v > 0.0, "> 0")
}

pub fn non_negative(value: &Dynamic, what: &str) -> Result<f64, String> {
    number_where(value, what, |v| v >= 0.0, "≥ 0")
}

/// A feather width: within [0, `limits::MAX_FEATHER`], checked at the call that gives it.
pub fn feather(value: &Dynamic) -> Result<f64, String> {
    let rule = format!("in [0, {}]", crate::limits::MAX_FEATHER);
    number_where(value, "feather", crate::limits::feather_in_range, &rule)
}

/// A number in [0, 1] (opacity).
pub fn unit(value: &Dynamic, what: &str) -> Result<f64, String> {
    number_where(value, what, |v| (0.0..=1.0).contains(&v), "in [0, 1]")
}

/// A key time: finite and ≥ 0.
pub fn time(value: &Dynamic) -> Result<f64, String> {
    number_where(value, "key time", |t| t >= 0.0, "≥ 0")
}

/// A canvas side: a whole number of pixels ≥ 1.
pub fn size(value: &Dynamic, what: &str) -> Result<u32, String> {
    let max = crate::scene::MAX_CANVAS_SIDE;
    let whole = |v: f64| v.fract() == 0.0 && (1.0..=max as f64).contains(&v);
    let rule = format!("a whole number of pixels in 1..={max}");
    Ok(number_where(value, what, whole, &rule)? as u32)
}

/// `[x, y]` with finite numbers.
pub fn point(value: &Dynamic, what: &str) -> Result<DVec2, String> {
    let array = value
        .read_lock::<Array>()
        .ok_or_else(|| format!("{what} must be a point [x, y], got {}", type_name(value)))?;
    if array.len() != 2 {
        return Err(format!(
            "{what} must be a point [x, y], got {} numbers",
            array.len()
        ));
    }
    Ok(DVec2::new(
        number(&array[0], what)?,
        number(&array[1], what)?,
    ))
}

/// A point a scene places something at: finite, within [`crate::limits::MAX_POSITION`].
pub fn position(value: &Dynamic, what: &str) -> Result<DVec2, String> {
    let p = point(value, what)?;
    match [p.x, p.y].into_iter().find_map(crate::limits::position_error) {
        Some(error) => Err(format!("{what}: {error}")),
        None => Ok(p),
    }
}

/// A patch's scale: > 0 and at most [`crate::limits::MAX_SCALE`].
pub fn scale(value: &Dynamic, what: &str) -> Result<f64, String> {
    let v = number(value, what)?;
    match crate::limits::scale_error(v) {
        Some(error) => Err(format!("{what}: {error}")),
        None => Ok(v),
    }
}

/// A rotation (degrees) or a depth: finite, within
/// [`crate::limits::MAX_ROTATION_OR_DEPTH`].
pub fn rotation_or_depth(value: &Dynamic, what: &str) -> Result<f64, String> {
    let v = number(value, what)?;
    match crate::limits::rotation_or_depth_error(v) {
        Some(error) => Err(format!("{what}: {error}")),
        None => Ok(v),
    }
}

pub fn string(value: &Dynamic, what: &str) -> Result<String, String> {
    value
        .read_lock::<rhai::ImmutableString>()
        .map(|s| s.to_string())
        .ok_or_else(|| format!("{what} must be a string, got {}", type_name(value)))
}

/// A patch's name: a string, not empty, and without control or bidirectional formatting
/// characters, which messages quote as they are (`patch \`cat\`: …`): a newline would split
/// a message and a right-to-left override would show its text reversed.
pub fn patch_name(value: &Dynamic) -> Result<String, String> {
    let name = string(value, "patch name")?;
    if name.is_empty() {
        return Err("patch name must not be empty".into());
    }
    let hidden = |c: char| {
        c.is_control()
            || matches!(c, '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
    };
    if let Some(c) = name.chars().find(|&c| hidden(c)) {
        return Err(format!(
            "patch name {name:?} holds {}, a control or bidirectional formatting character",
            c.escape_unicode()
        ));
    }
    Ok(name)
}

pub fn array(value: &Dynamic, what: &str) -> Result<Array, String> {
    value
        .read_lock::<Array>()
        .map(|a| a.clone())
        .ok_or_else(|| format!("{what} must be an array, got {}", type_name(value)))
}

pub fn map(value: &Dynamic, what: &str) -> Result<Map, String> {
    value
        .read_lock::<Map>()
        .map(|m| m.clone())
        .ok_or_else(|| format!("{what} must be a map #{{ ... }}, got {}", type_name(value)))
}

pub fn easing(name: &str) -> Result<Easing, String> {
    Easing::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Easing::ALL.iter().map(|e| e.name()).collect();
        format!(
            "unknown easing `{name}` (expected one of: {})",
            names.join(", ")
        )
    })
}

/// Refuses keys of `options` not in `allowed`, naming the allowed ones.
pub fn check_keys(options: &Map, allowed: &[&str], what: &str) -> Result<(), String> {
    for key in options.keys() {
        if !allowed.contains(&key.as_str()) {
            return Err(format!(
                "unknown option `{key}` for {what} (expected: {})",
                allowed.join(", ")
            ));
        }
    }
    Ok(())
}

/// Option keys the scene language renamed, old spelling first; the old one still works,
/// with a warning.
pub const RENAMED_KEYS: [(&str, &str); 4] = [
    ("boundary", "mesh_boundary"),
    ("boundary_data", "boundary_sampling"),
    ("background_start", "background_start_number"),
    ("source_start", "source_start_number"),
];

/// Moves every old spelling in `options` to its new name; gives the old names it found.
pub fn rename_keys(options: &mut Map) -> Result<Vec<&'static str>, String> {
    let mut found = Vec::new();
    for (old, new) in RENAMED_KEYS {
        let Some(value) = options.remove(old) else {
            continue;
        };
        if options.insert(new.into(), value).is_some() {
            return Err(format!("give `{new}` only (`{old}` is its old name)"));
        }
        found.push(old);
    }
    Ok(found)
}

/// A colour: `"#rrggbb"`, `"#rrggbbaa"`, `[r, g, b]` or `[r, g, b, a]` with channels in [0, 1].
pub fn colour(value: &Dynamic) -> Result<[f32; 4], String> {
    if let Some(text) = value.read_lock::<rhai::ImmutableString>() {
        return hex_colour(&text);
    }
    let channels = array(value, "colour")?;
    if !(3..=4).contains(&channels.len()) {
        return Err(format!(
            "colour must have 3 or 4 channels, got {}",
            channels.len()
        ));
    }
    let mut rgba = [1.0f32; 4];
    for (slot, c) in rgba.iter_mut().zip(&channels) {
        let v = number(c, "colour channel")?;
        if !(0.0..=1.0).contains(&v) {
            return Err(format!("colour channels must be in [0, 1], got {}", number_text(v)));
        }
        *slot = v as f32;
    }
    Ok(rgba)
}

fn hex_colour(text: &str) -> Result<[f32; 4], String> {
    let digits = text.strip_prefix('#').unwrap_or(text);
    let bad = || format!("colour `{text}` must be #rrggbb or #rrggbbaa");
    if !(digits.len() == 6 || digits.len() == 8) || !digits.is_ascii() {
        return Err(bad());
    }
    let mut rgba = [1.0f32; 4];
    for (i, slot) in rgba.iter_mut().enumerate().take(digits.len() / 2) {
        let byte = u8::from_str_radix(&digits[2 * i..2 * i + 2], 16).map_err(|_| bad())?;
        *slot = byte as f32 / 255.0;
    }
    Ok(rgba)
}

fn type_name(value: &Dynamic) -> &'static str {
    match value.type_name() {
        "i64" | "i32" => "an integer",
        "f64" | "f32" => "a float",
        "string" | "ImmutableString" => "a string",
        "array" => "an array",
        "map" => "a map",
        "bool" => "a boolean",
        "()" => "nothing (unit)",
        _ => "another type",
    }
}
