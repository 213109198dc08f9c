//! Reference-image (golden) tests, resvg style: takes a case name and an actual image
//! (a `FloatImage` or PNG bytes) and compares it with `tests/golden/<case>/expected.png`
//! within a per-channel tolerance. On a mismatch it writes `expected | diff | actual` side by
//! side into `target/golden-diffs/<case>.png` and panics; with `LAPCLONE_REGEN=1` it (re)writes
//! `expected.png` from the actual image instead. See tests/README.md.
#![allow(dead_code)]

use std::path::PathBuf;

use lapclone::pixels::{Canvas, FloatImage, PixelFormat};

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
/// within `tolerance_per_channel` (in [0, 1] units: 1/255 is one 8-bit level).
pub fn assert_golden(case: &str, actual: &FloatImage, tolerance_per_channel: f32) {
    let expected_path = case_dir(case).join("expected.png");
    if std::env::var(REGEN_VAR).is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(case_dir(case)).expect("create golden case folder");
        Canvas::from_image(actual)
            .save_png(&expected_path, actual.format())
            .expect("write expected.png");
        return;
    }
    let expected = match FloatImage::load(&expected_path) {
        Ok(image) => image,
        Err(err) => {
            write_diff(case, None, actual, tolerance_per_channel);
            panic!("golden {case}: {err}; run with {REGEN_VAR}=1 to create it");
        }
    };
    let size_matches = expected.width() == actual.width() && expected.height() == actual.height();
    let (bad_pixels, worst) = if size_matches {
        mismatches(&expected, actual, tolerance_per_channel)
    } else {
        (usize::MAX, f32::INFINITY)
    };
    if bad_pixels > 0 {
        let path = write_diff(case, Some(&expected), actual, tolerance_per_channel);
        panic!(
            "golden {case}: {} (worst channel difference {worst:.4}, tolerance {tolerance_per_channel}); \
             expected | diff | actual written to {}",
            if size_matches { format!("{bad_pixels} pixels differ") } else { format!(
                "size {}×{} expected, got {}×{}", expected.width(), expected.height(), actual.width(), actual.height()) },
            path.display()
        );
    }
}

fn mismatches(expected: &FloatImage, actual: &FloatImage, tolerance: f32) -> (usize, f32) {
    let mut bad = 0;
    let mut worst = 0.0f32;
    for (e, a) in expected.pixels().iter().zip(actual.pixels()) {
        let difference = (0..4).map(|c| (e[c] - a[c]).abs()).fold(0.0, f32::max);
        worst = worst.max(difference);
        bad += usize::from(difference > tolerance);
    }
    (bad, worst)
}

/// Writes expected | diff | actual (8-bit RGBA) and returns the path. The diff panel shows
/// pixels over tolerance in red, others as a faint grey of the actual image.
fn write_diff(
    case: &str,
    expected: Option<&FloatImage>,
    actual: &FloatImage,
    tolerance: f32,
) -> PathBuf {
    let (w, h) = (actual.width(), actual.height());
    let ew = expected.map_or(0, FloatImage::width);
    let eh = expected.map_or(0, FloatImage::height);
    let panel = w.max(ew);
    let height = h.max(eh);
    let pixel = |image: Option<&FloatImage>, i: u32, j: u32| image.and_then(|im| im.pixel(i, j));
    let sheet = FloatImage::from_fn(panel * 3 + 2, height, PixelFormat::RGBA8, |x, y| {
        let (column, i) = (x / (panel + 1), x % (panel + 1));
        if i == panel {
            return [1.0, 0.0, 1.0, 1.0];
        }
        let e = pixel(expected, i, y);
        let a = pixel(Some(actual), i, y);
        match column {
            0 => e.unwrap_or([0.0; 4]),
            2 => a.unwrap_or([0.0; 4]),
            _ => match (e, a) {
                (Some(e), Some(a)) if (0..4).all(|c| (e[c] - a[c]).abs() <= tolerance) => {
                    let g = 0.8 + 0.2 * (a[0] + a[1] + a[2]) / 3.0;
                    [g, g, g, 1.0]
                }
                _ => [1.0, 0.0, 0.0, 1.0],
            },
        }
    })
    .expect("non-empty diff sheet");
    let path = diff_path(case);
    if let Some(parent) = path.parent() {
        let _ = std::fs::create_dir_all(parent);
    }
    let _ = Canvas::from_image(&sheet).save_png(&path, PixelFormat::RGBA8);
    path
}
