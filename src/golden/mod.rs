//! Golden-frame comparison: takes a rendered frame and its reference (golden) frame and gives
//! idiff-style figures (mean and RMS error, PSNR, SSIM, pixels over the fail and warn
//! thresholds, the largest error with its pixel and channel), a verdict under
//! [`Thresholds`] (pass, warn, fail), a difference image and an `expected | difference |
//! actual` triptych. It knows nothing of files, scenes or the command line: `lapclone test`
//! and the project's own golden tests both call it, so there is one implementation of the
//! thresholds and the pictures.
//!
//! Errors are stated in 8-bit units (one level of an 8-bit channel is 1; a 16-bit frame's
//! difference is divided by 257), so the same thresholds apply to 8- and 16-bit frames.

mod compare;
mod frame;
mod picture;
mod settings;

pub use compare::{compare, Channel, Comparison, Figures, MaxError, Mismatch, Verdict};
pub use frame::{GoldenError, GoldenFrame};
pub use picture::{difference_image, encode_rgba_png, triptych};
pub use settings::{GoldenSettings, Thresholds};
