//! The `golden(#{ … })` scene call: takes a map of frames and thresholds and gives the
//! scene's [`GoldenSettings`], validated at the call (a refusal is a runtime error at its
//! position). Only `lapclone test` reads the settings; rendering ignores them.

use rhai::{Dynamic, Engine, EvalAltResult, Map, NativeCallContext};

use super::draft::SharedDraft;
use super::values;
use crate::golden::GoldenSettings;

pub fn register(engine: &mut Engine, draft: &SharedDraft) {
    let d = draft.clone();
    engine.register_fn(
        "golden",
        move |ctx: NativeCallContext, options: Dynamic| -> Result<(), Box<EvalAltResult>> {
            let fail = |m: String| -> Box<EvalAltResult> {
                EvalAltResult::ErrorRuntime(m.into(), ctx.call_position()).into()
            };
            let mut draft = d.lock();
            let frame_count = draft.canvas.as_ref().map(|c| c.frame_count());
            let settings = parse(&options, frame_count).map_err(fail)?;
            draft.golden = Some(settings);
            Ok(())
        },
    );
}

fn parse(options: &Dynamic, frame_count: Option<u64>) -> Result<GoldenSettings, String> {
    let options = values::map(options, "golden options")?;
    values::check_keys(&options, &GoldenSettings::KEYS, "golden")?;
    let level = |key: &str| -> Result<Option<f64>, String> {
        options
            .get(key)
            .map(|v| values::non_negative(v, key))
            .transpose()
    };
    let percent = |key: &str| -> Result<Option<f64>, String> {
        let value = level(key)?;
        match value {
            Some(p) if p > 100.0 => Err(format!("{key} must be a percentage in 0..=100, got {p}")),
            _ => Ok(value),
        }
    };
    let min_ssim = match options.get("min_ssim") {
        None => None,
        Some(v) => {
            let s = values::number(v, "min_ssim")?;
            if !(0.0..=1.0).contains(&s) {
                return Err(format!("min_ssim must be in 0..=1, got {s}"));
            }
            Some(s)
        }
    };
    Ok(GoldenSettings {
        frames: frames(&options, frame_count)?,
        fail: level("fail")?,
        fail_percent: percent("fail_percent")?,
        hard_fail: level("hard_fail")?,
        warn: level("warn")?,
        warn_percent: percent("warn_percent")?,
        min_ssim,
    })
}

/// Frame numbers from 1, as `lapclone render` numbers them; past the end is refused when
/// the canvas is already known (otherwise `lapclone test` refuses it).
fn frames(options: &Map, frame_count: Option<u64>) -> Result<Option<Vec<u64>>, String> {
    let Some(value) = options.get("frames") else {
        return Ok(None);
    };
    let list = values::array(value, "frames")?;
    if list.is_empty() {
        return Err("frames must name at least one frame".into());
    }
    let mut numbers = Vec::with_capacity(list.len());
    for item in &list {
        let n = values::number(item, "frame number")?;
        if n.fract() != 0.0 || n < 1.0 {
            return Err(format!(
                "frame numbers count from 1 (as in `lapclone render`), got {n}"
            ));
        }
        let n = n as u64;
        if let Some(count) = frame_count.filter(|&c| n > c) {
            return Err(format!("frame {n} is past the end: the scene has {count} frames"));
        }
        numbers.push(n);
    }
    numbers.sort_unstable();
    numbers.dedup();
    Ok(Some(numbers))
}
