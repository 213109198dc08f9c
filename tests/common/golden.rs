//! Reference-image (golden) tests, resvg style: takes a case name and an actual image
//! (a `FloatImage` or PNG bytes) and compares it with `tests/golden/<case>/expected.png`
//! within a per-channel tolerance, with the library's comparator (`lapclone::golden`, shared
//! with `lapclone test`). On a mismatch it writes the comparator's `expected | difference |
//! actual` triptych into `target/golden-diffs/<case>.png` and panics; with `LAPCLONE_REGEN=1` it (re)writes
//! `expected.png` from the actual image instead. See tests/README.md.
#![allow(dead_code)]

use std::path::PathBuf;

use lapclone::golden::{compare, encode_rgba_png, triptych, GoldenFrame, Thresholds, Verdict};
use lapclone::pixels::{Canvas, FloatImage};

/// Environment variable that regenerates references instead of comparing.
pub const REGEN_VAR: &str = "LAPCLONE_REGEN";

pub fn case_dir(case: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("golden")
        .join(case)
}

pub fn diff_path(case: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("golden-diffs")
        .join(format!("{case}.png"))
}

/// Compares PNG bytes (decoded in their own format) with the case's reference.
pub fn assert_golden_png(case: &str, png_bytes: &[u8], tolerance_per_channel: f32) {
    let decoded = image::load_from_memory(png_bytes).expect("actual PNG decodes");
    let actual = FloatImage::from_dynamic(&decoded).expect("actual PNG is non-empty");
    assert_golden(case, &actual, tolerance_per_channel);
}

/// Compares `actual` with `tests/golden/<case>/expected.png`: every channel of every pixel
/// within `tolerance_per_channel` (in [0, 1] units: 1/255 is one 8-bit level), through the
/// library's comparator (`lapclone::golden`, the one `lapclone test` uses) at 16 bits.
pub fn assert_golden(case: &str, actual: &FloatImage, tolerance_per_channel: f32) {
    let expected_path = case_dir(case).join("expected.png");
    if std::env::var(REGEN_VAR).is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(case_dir(case)).expect("create golden case folder");
        Canvas::from_image(actual)
            .save_png(&expected_path, actual.format())
            .expect("write expected.png");
        return;
    }
    let actual = GoldenFrame::from_float_image(actual);
    let thresholds = Thresholds {
        fail: f64::from(tolerance_per_channel) * 255.0,
        warn: f64::INFINITY,
        ..Thresholds::default()
    };
    let expected = match GoldenFrame::load(&expected_path) {
        Ok(image) => image.to_sixteen(),
        Err(err) => {
            write_diff(case, None, &actual, &thresholds);
            panic!("golden {case}: {err}; run with {REGEN_VAR}=1 to create it");
        }
    };
    let problem = match compare(&expected, &actual, &thresholds) {
        Err(mismatch) => mismatch.to_string(),
        Ok(c) if c.verdict == Verdict::Fail => format!(
            "{} pixels differ (worst channel difference {:.4} at ({}, {}, {}), tolerance {tolerance_per_channel})",
            c.figures.failing_pixels,
            c.figures.max.value / 255.0,
            c.figures.max.x,
            c.figures.max.y,
            c.figures.max.channel
        ),
        Ok(_) => return,
    };
    let path = write_diff(case, Some(&expected), &actual, &thresholds);
    panic!(
        "golden {case}: {problem}; expected | diff | actual written to {}",
        path.display()
    );
}

/// Writes the library's `expected | difference | actual` triptych and returns its path.
fn write_diff(
    case: &str,
    expected: Option<&GoldenFrame>,
    actual: &GoldenFrame,
    thresholds: &Thresholds,
) -> PathBuf {
    let path = diff_path(case);
    if let Some(parent) = path.parent() {
        let _ = std::fs::create_dir_all(parent);
    }
    let sheet = triptych(expected, actual, thresholds);
    let _ = std::fs::write(&path, encode_rgba_png(&sheet));
    path
}
