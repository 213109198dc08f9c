//! Why footage cannot be opened or read: [`FootageError`], naming the pattern, file, frame
//! or video and the setting that would help.

use crate::util::ShowPath;
use std::path::PathBuf;

use crate::pixels::PixelError;

/// Why footage cannot be opened or read.
#[derive(Debug, thiserror::Error)]
pub enum FootageError {
    /// The pattern (the text as given) has no `%d` / `%0Nd`.
    #[error("pattern `{0}` has no frame number: use %d or %0Nd (e.g. frame_%04d.png)")]
    NoNumber(String),
    /// A `%` that starts neither `%d`, `%0Nd` nor `%%`, or a second number.
    #[error("pattern `{0}`: `%` must start %d, %0Nd or %% (one number per pattern)")]
    BadPattern(String),
    /// The number is in a folder name rather than the file name.
    #[error("pattern `{0}`: the number must be in the file name, not a folder")]
    NumberInFolder(String),
    /// No file in the folder matches the pattern (no start number can be found).
    #[error("pattern `{pattern}` matches no files in {}", folder.shown())]
    NoFiles {
        /// The pattern as given.
        pattern: String,
        /// The folder searched.
        folder: PathBuf,
    },
    /// The path (or a frame's file) is a folder.
    #[error("{} is a folder, not an image or video", .0.shown())]
    IsFolder(PathBuf),
    /// A plate or video path holds something other than a regular file (a FIFO, a device,
    /// a dangling link; a plate that is a folder).
    #[error("{} {kind}", file.shown())]
    NotAFile {
        /// The path.
        file: PathBuf,
        /// What it is instead, as a phrase ("is not a regular file (a FIFO)").
        kind: &'static str,
    },
    /// The video file does not exist.
    #[error("{} not found", .0.shown())]
    NotFound(PathBuf),
    /// A frame's file is missing and the footage does not hold its last frame.
    #[error("frame {frame} needs {}, which does not exist{}", file.shown(), hold_hint(hold_key, *held))]
    MissingFrame {
        /// The frame, counted from 1.
        frame: u64,
        /// The file it needs.
        file: PathBuf,
        /// The setting that would hold the last frame ([`Footage::hold_key`](super::Footage::hold_key)).
        hold_key: String,
        /// Whether that setting is already on (then only an earlier file can help).
        held: bool,
    },
    /// A frame's size differs from the first frame's.
    #[error("{}: frame {frame} is {width}×{height}, but the footage is {expected_width}×{expected_height}", file.shown())]
    SizeChanged {
        /// The frame's file.
        file: PathBuf,
        /// The frame, counted from 1.
        frame: u64,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The footage's width.
        expected_width: u32,
        /// The footage's height.
        expected_height: u32,
    },
    /// A video needs `ffmpeg` / `ffprobe`, and neither is on `PATH`.
    #[error("{}", crate::util::FFMPEG_MISSING_FOR_FOOTAGE)]
    NoFfmpeg,
    /// ffmpeg or ffprobe cannot read the video.
    #[error("cannot read video {}: {message}", path.shown())]
    Video {
        /// The video file.
        path: PathBuf,
        /// What ffmpeg or ffprobe said (its last lines).
        message: String,
    },
    /// The video ends before the scene does and the footage does not hold its last frame.
    #[error("video {}: has {available} frames at the scene's fps, frame {frame} is needed{}", path.shown(), hold_hint(hold_key, false))]
    VideoTooShort {
        /// The video file.
        path: PathBuf,
        /// The first frame it lacks, counted from 1.
        frame: u64,
        /// Frames it has at the scene's frame rate.
        available: u64,
        /// The setting that would hold the last frame ([`Footage::hold_key`](super::Footage::hold_key)).
        hold_key: String,
    },
    /// A frame's file cannot be read or decoded.
    #[error(transparent)]
    Image(#[from] Box<PixelError>),
}

/// The end of a missing-frame message: how holding would help, unless it is already on
/// (nothing where there is no such setting: an empty `hold_key`).
fn hold_hint(hold_key: &str, held: bool) -> String {
    if hold_key.is_empty() {
        String::new()
    } else if held {
        format!(" (`{hold_key}` holds the last file of the unbroken run from the first one; the first is missing)")
    } else {
        format!(" (add `{hold_key}: true` to hold the last one)")
    }
}
