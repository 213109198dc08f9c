//! The comparison itself: takes an expected and an actual [`GoldenFrame`] and [`Thresholds`]
//! and gives the figures and the verdict, or the [`Mismatch`] (size, bit depth) that fails a
//! frame before any pixel is compared.

use std::fmt;

use super::{GoldenFrame, Thresholds};

/// A channel of an RGBA pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    R,
    G,
    B,
    A,
}

impl Channel {
    const ALL: [Channel; 4] = [Channel::R, Channel::G, Channel::B, Channel::A];

    pub fn letter(self) -> &'static str {
        match self {
            Channel::R => "R",
            Channel::G => "G",
            Channel::B => "B",
            Channel::A => "A",
        }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.letter())
    }
}

/// The outcome of a frame, worst last.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    Pass,
    Warn,
    Fail,
}

impl Verdict {
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Pass => "PASS",
            Verdict::Warn => "WARN",
            Verdict::Fail => "FAIL",
        }
    }
}

/// The largest channel difference and where it is (the first such pixel in row order, the
/// first such channel in RGBA order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaxError {
    /// In 8-bit units.
    pub value: f64,
    pub x: u32,
    pub y: u32,
    pub channel: Channel,
}

/// What a comparison measured. Errors are in 8-bit units, averaged over every pixel and
/// compared channel (RGB, and alpha when either frame has it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Figures {
    pub mean_error: f64,
    pub rms_error: f64,
    /// Peak signal-to-noise ratio in dB; `None` when the frames are identical (infinite).
    pub psnr: Option<f64>,
    /// Structural similarity (mean SSIM over 8×8 windows, the smallest of R, G, B); 1 for
    /// identical frames.
    pub ssim: f64,
    pub failing_pixels: u64,
    pub failing_percent: f64,
    pub warning_pixels: u64,
    pub warning_percent: f64,
    pub max: MaxError,
}

/// Figures and the verdict they give under the thresholds used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    pub verdict: Verdict,
    pub figures: Figures,
}

/// Frames that cannot be compared pixel by pixel; always a failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Mismatch {
    #[error("size mismatch: golden is {expected_width}×{expected_height}, frame is {actual_width}×{actual_height}")]
    Size {
        expected_width: u32,
        expected_height: u32,
        actual_width: u32,
        actual_height: u32,
    },
    #[error("bit depth mismatch: golden is {expected}-bit, frame is {actual}-bit")]
    Depth { expected: u32, actual: u32 },
}

/// Compares `actual` with `expected` under `thresholds`.
pub fn compare(
    expected: &GoldenFrame,
    actual: &GoldenFrame,
    thresholds: &Thresholds,
) -> Result<Comparison, Mismatch> {
    check_shapes(expected, actual)?;
    let mut figures = measure(expected, actual, thresholds);
    if figures.max.value > 0.0 {
        figures.ssim = ssim(expected, actual);
    }
    Ok(Comparison {
        verdict: verdict(&figures, thresholds),
        figures,
    })
}

fn check_shapes(expected: &GoldenFrame, actual: &GoldenFrame) -> Result<(), Mismatch> {
    if (expected.width, expected.height) != (actual.width, actual.height) {
        return Err(Mismatch::Size {
            expected_width: expected.width,
            expected_height: expected.height,
            actual_width: actual.width,
            actual_height: actual.height,
        });
    }
    if expected.depth != actual.depth {
        return Err(Mismatch::Depth {
            expected: expected.bits(),
            actual: actual.bits(),
        });
    }
    Ok(())
}

/// Sums and counts in one pass over the pixels (SSIM is left at 1).
fn measure(expected: &GoldenFrame, actual: &GoldenFrame, thresholds: &Thresholds) -> Figures {
    let channels = if expected.alpha || actual.alpha { 4 } else { 3 };
    let unit = 255.0 / f64::from(expected.max_value());
    let (mut sum, mut sum_sq) = (0u64, 0u128);
    let (mut failing, mut warning) = (0u64, 0u64);
    let (mut worst, mut worst_at) = (0u16, (0usize, 0usize));
    for (index, (e, a)) in expected.pixels.iter().zip(&actual.pixels).enumerate() {
        let mut pixel_worst = (0u16, 0usize);
        for c in 0..channels {
            let d = e[c].abs_diff(a[c]);
            sum += u64::from(d);
            sum_sq += u128::from(u32::from(d) * u32::from(d));
            if d > pixel_worst.0 {
                pixel_worst = (d, c);
            }
        }
        if pixel_worst.0 > worst {
            (worst, worst_at) = (pixel_worst.0, (index, pixel_worst.1));
        }
        let pixel_error = f64::from(pixel_worst.0) * unit;
        failing += u64::from(pixel_error > thresholds.fail);
        warning += u64::from(pixel_error > thresholds.warn);
    }
    let pixels = expected.pixels.len() as f64;
    let samples = pixels * channels as f64;
    let mean_error = sum as f64 / samples * unit;
    let rms_error = (sum_sq as f64 / samples).sqrt() * unit;
    let width = expected.width as usize;
    Figures {
        mean_error,
        rms_error,
        psnr: (rms_error > 0.0).then(|| 20.0 * (255.0 / rms_error).log10()),
        ssim: 1.0,
        failing_pixels: failing,
        failing_percent: failing as f64 * 100.0 / pixels,
        warning_pixels: warning,
        warning_percent: warning as f64 * 100.0 / pixels,
        max: MaxError {
            value: f64::from(worst) * unit,
            x: (worst_at.0 % width) as u32,
            y: (worst_at.0 / width) as u32,
            channel: Channel::ALL[worst_at.1],
        },
    }
}

/// idiff's rule: too many pixels over the threshold, or one beyond the hard limit.
fn verdict(figures: &Figures, thresholds: &Thresholds) -> Verdict {
    let below_ssim = thresholds.min_ssim.is_some_and(|min| figures.ssim < min);
    if figures.failing_percent > thresholds.fail_percent
        || figures.max.value > thresholds.hard_fail
        || below_ssim
    {
        Verdict::Fail
    } else if figures.warning_percent > thresholds.warn_percent {
        Verdict::Warn
    } else {
        Verdict::Pass
    }
}

/// SSIM from `image-compare` on the 8-bit RGB samples.
fn ssim(expected: &GoldenFrame, actual: &GoldenFrame) -> f64 {
    let algorithm = image_compare::Algorithm::MSSIMSimple;
    match image_compare::rgb_similarity_structure(&algorithm, &expected.rgb8(), &actual.rgb8()) {
        Ok(similarity) => similarity.score,
        // Sizes were checked above; a frame too small for one window has no structure to
        // compare, so it counts as dissimilar rather than passing silently.
        Err(_) => 0.0,
    }
}
