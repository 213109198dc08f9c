//! The `golden(#{ … })` scene call: takes a map of frames and thresholds and gives the
//! scene's [`GoldenSettings`], validated at the call (a refusal is a runtime error at its
//! position). Only `lapclone test` reads the settings; rendering ignores them.

use rhai::{Dynamic, Engine, Map, NativeCallContext};

use super::draft::SharedDraft;
use crate::util::number_text;
use super::refs::{fail, Fallible};
use super::values;
use crate::golden::GoldenSettings;

pub fn register(engine: &mut Engine, draft: &SharedDraft) {
    let d = draft.clone();
    engine.register_fn(
        "golden",
        move |ctx: NativeCallContext, options: Dynamic| -> Fallible<()> {
            let mut draft = d.lock();
            let frame_count = draft.canvas.as_ref().map(|c| c.frame_count());
            let settings = parse(&options, frame_count).map_err(|m| fail(&ctx, m))?;
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
            Some(p) if p > 100.0 => Err(format!("{key} must be a percentage in 0..=100, got {}", number_text(p))),
            _ => Ok(value),
        }
    };
    let min_ssim = options
        .get("min_ssim")
        .map(|v| values::number_where(v, "min_ssim", |s| (0.0..=1.0).contains(&s), "in 0..=1"))
        .transpose()?;
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
        let shown = crate::util::number_text(n);
        if n.fract() != 0.0 || n < 1.0 {
            return Err(format!(
                "frame numbers count from 1 (as in `lapclone render`), got {shown}"
            ));
        }
        let most = crate::limits::MAX_FRAMES;
        if n > most as f64 {
            return Err(format!("frame {shown} is past the most frames a scene has ({most})"));
        }
        let n = n as u64;
        if let Some(count) = frame_count.filter(|&c| n > c) {
            return Err(format!(
                "frame {n} is past the end: the scene has {count} frames"
            ));
        }
        numbers.push(n);
    }
    numbers.sort_unstable();
    numbers.dedup();
    Ok(Some(numbers))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::script::{parse_scene, ScriptOptions};

    fn run(text: &str) -> Result<Option<GoldenSettings>, String> {
        let options = ScriptOptions::for_scene_file(Path::new("scene.rhai"));
        parse_scene(text, Path::new("scene.rhai"), &options)
            .map(|loaded| loaded.scene.golden)
            .map_err(|e| e.to_string())
    }

    use super::GoldenSettings;

    fn run_scene(text: &str) -> crate::scene::Scene {
        let options = ScriptOptions::for_scene_file(Path::new("scene.rhai"));
        parse_scene(text, Path::new("scene.rhai"), &options)
            .unwrap()
            .scene
    }

    #[test]
    fn golden_stores_frames_and_thresholds() {
        let settings = run("canvas(8, 8, #{ fps: 4, duration: 12 });\n\
             golden(#{ frames: [47, 0 + 1, 12], fail: 2, fail_percent: 0.1, min_ssim: 0.98 });")
        .unwrap()
        .unwrap();
        assert_eq!(settings.frames, Some(vec![1, 12, 47]));
        assert_eq!(settings.fail, Some(2.0));
        assert_eq!(settings.fail_percent, Some(0.1));
        assert_eq!(settings.min_ssim, Some(0.98));
        assert_eq!(settings.hard_fail, None);
        assert_eq!(run("canvas(8, 8);").unwrap(), None);
        // Written back by `Scene::to_rhai` (the REPL's :save), it reads back equal.
        let scene = run_scene(
            "canvas(8, 8, #{ fps: 4, duration: 12 });\n\
             golden(#{ frames: [3, 40], warn: 0.5, hard_fail: 9, min_ssim: 0.875 });",
        );
        assert_eq!(run_scene(&scene.to_rhai()), scene);
    }

    #[test]
    fn bad_golden_calls_are_positioned_errors() {
        let head = "canvas(8, 8, #{ fps: 4, duration: 1 });\n";
        for (call, message) in [
            ("golden(#{ frames: [0] });", "count from 1"),
            ("golden(#{ frames: [1e300] });", "frame 1e300 is past the most frames"),
            ("golden(#{ frames: [-1e300] });", "got -1e300"),
            (
                "golden(#{ frames: [5] });",
                "frame 5 is past the end: the scene has 4 frames",
            ),
            ("golden(#{ frames: [] });", "at least one frame"),
            ("golden(#{ fail: -1 });", "fail must be ≥ 0"),
            ("golden(#{ fail_percent: 101 });", "percentage"),
            ("golden(#{ min_ssim: 2 });", "min_ssim must be in 0..=1"),
            ("golden(#{ tolerance: 1 });", "tolerance"),
        ] {
            let error = run(&format!("{head}{call}")).unwrap_err();
            assert!(error.contains(message), "{call}: {error}");
            assert!(error.contains("scene.rhai:2:1"), "{call}: {error}");
        }
    }
}
