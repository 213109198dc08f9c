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
        ["R", "G", "B", "A"][self as usize]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixels::Depth;

    fn frame(width: u32, height: u32, depth: Depth, pixels: Vec<[u16; 4]>) -> GoldenFrame {
        GoldenFrame {
            width,
            height,
            depth,
            alpha: false,
            pixels,
        }
    }

    fn flat(value: u16, n: usize, depth: Depth) -> GoldenFrame {
        let max = if depth == Depth::Eight { 255 } else { 65535 };
        frame(
            3,
            (n / 3) as u32,
            depth,
            vec![[value, value, value, max]; n],
        )
    }

    #[test]
    fn figures_match_a_hand_computed_difference() {
        let expected = flat(100, 6, Depth::Eight);
        let mut actual = expected.clone();
        actual.pixels[0][0] = 101; // (0, 0) R: one level
        actual.pixels[5][1] = 63; // (2, 1) G: 37 levels
        let c = compare(&expected, &actual, &Thresholds::default()).unwrap();
        let f = c.figures;
        assert_eq!(
            f.max,
            MaxError {
                value: 37.0,
                x: 2,
                y: 1,
                channel: Channel::G
            }
        );
        // Three channels (no alpha) × 6 pixels.
        assert!((f.mean_error - 38.0 / 18.0).abs() < 1e-12);
        let rms = (1370.0f64 / 18.0).sqrt();
        assert!((f.rms_error - rms).abs() < 1e-12);
        let psnr = f.psnr.unwrap();
        assert!((psnr - 20.0 * (255.0 / rms).log10()).abs() < 1e-9);
        assert_eq!((f.failing_pixels, f.warning_pixels), (1, 2));
        assert!((f.failing_percent - 100.0 / 6.0).abs() < 1e-12);
        assert_eq!(c.verdict, Verdict::Fail);
        let lenient = Thresholds {
            fail_percent: 20.0,
            ..Thresholds::default()
        };
        assert_eq!(
            compare(&expected, &actual, &lenient).unwrap().verdict,
            Verdict::Warn
        );
        let hard = Thresholds {
            hard_fail: 30.0,
            ..lenient
        };
        assert_eq!(
            compare(&expected, &actual, &hard).unwrap().verdict,
            Verdict::Fail
        );
        let silent = Thresholds {
            warn: 40.0,
            ..lenient
        };
        assert_eq!(
            compare(&expected, &actual, &silent).unwrap().verdict,
            Verdict::Pass
        );
    }

    #[test]
    fn identical_frames_pass_with_infinite_psnr_and_unit_ssim() {
        let a = flat(7, 6, Depth::Sixteen);
        let c = compare(&a, &a, &Thresholds::default()).unwrap();
        assert_eq!(c.verdict, Verdict::Pass);
        assert_eq!(c.figures.psnr, None);
        assert_eq!(c.figures.ssim, 1.0);
        assert_eq!(c.figures.max.value, 0.0);
    }

    #[test]
    fn sixteen_bit_differences_are_in_eight_bit_units() {
        let a = flat(1000, 6, Depth::Sixteen);
        let mut b = a.clone();
        b.pixels[1][2] += 257; // exactly one 8-bit level: not over fail = 1
        let c = compare(&a, &b, &Thresholds::default()).unwrap();
        assert_eq!(c.figures.max.value, 1.0);
        assert_eq!(c.verdict, Verdict::Warn);
        b.pixels[1][2] += 1;
        let c = compare(&a, &b, &Thresholds::default()).unwrap();
        assert_eq!(c.verdict, Verdict::Fail);
    }

    #[test]
    fn the_first_largest_error_in_row_order_is_reported() {
        let a = flat(50, 6, Depth::Eight);
        let mut b = a.clone();
        b.pixels[4][2] = 60;
        b.pixels[2][0] = 40;
        let max = compare(&a, &b, &Thresholds::default()).unwrap().figures.max;
        assert_eq!((max.x, max.y, max.channel), (2, 0, Channel::R));
    }

    #[test]
    fn size_and_depth_mismatches_are_refused() {
        let a = flat(0, 6, Depth::Eight);
        let b = flat(0, 9, Depth::Eight);
        assert_eq!(
            compare(&a, &b, &Thresholds::default())
                .unwrap_err()
                .to_string(),
            "size mismatch: golden is 3×2, frame is 3×3"
        );
        let c = flat(0, 6, Depth::Sixteen);
        assert!(matches!(
            compare(&a, &c, &Thresholds::default()),
            Err(Mismatch::Depth {
                expected: 8,
                actual: 16
            })
        ));
    }

    #[test]
    fn a_visible_seam_lowers_ssim_below_noise() {
        // 32×32 texture; noise of one level everywhere versus a bright seam along a line.
        let texture: Vec<[u16; 4]> = (0..32 * 32)
            .map(|i| {
                let v = ((i * 37) % 200) as u16;
                [v, v / 2, 255 - v, 255]
            })
            .collect();
        let base = frame(32, 32, Depth::Eight, texture);
        let mut noise = base.clone();
        for (i, px) in noise.pixels.iter_mut().enumerate() {
            px[0] = if i % 2 == 0 { px[0] + 1 } else { px[0] };
        }
        let mut seam = base.clone();
        for y in 0..32 {
            seam.pixels[y * 32 + 16][1] = 255;
        }
        let t = Thresholds::default();
        let noise_ssim = compare(&base, &noise, &t).unwrap().figures.ssim;
        let seam_ssim = compare(&base, &seam, &t).unwrap().figures.ssim;
        assert!(noise_ssim > 0.99, "{noise_ssim}");
        assert!(seam_ssim < noise_ssim - 0.05, "{seam_ssim} vs {noise_ssim}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config {
            cases: 64,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x0901_de17),
            ..Default::default()
        })]
        #[test]
        fn figures_are_symmetric_and_the_max_bounds_the_mean(
            a in proptest::collection::vec(0u16..256, 36),
            b in proptest::collection::vec(0u16..256, 36),
        ) {
            let to_frame = |v: &[u16]| frame(3, 3, Depth::Eight,
                v.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect());
            let (x, y) = (to_frame(&a), to_frame(&b));
            let t = Thresholds::default();
            let (p, q) = (compare(&x, &y, &t).unwrap(), compare(&y, &x, &t).unwrap());
            proptest::prop_assert_eq!(p.figures.max, q.figures.max);
            proptest::prop_assert_eq!(p.figures.failing_pixels, q.figures.failing_pixels);
            proptest::prop_assert!((p.figures.mean_error - q.figures.mean_error).abs() < 1e-9);
            proptest::prop_assert!(p.figures.mean_error <= p.figures.rms_error + 1e-9);
            proptest::prop_assert!(p.figures.rms_error <= p.figures.max.value + 1e-9);
        }
    }
}
