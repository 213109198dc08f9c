//! Footage: takes a printf-style numbered image pattern (`plate_%04d.png`, `%d`, `%0Nd`,
//! `%%`) with a start number, or a video file decoded by an `ffmpeg` process, and gives one
//! frame at a time as a [`FloatImage`](super::FloatImage). Only the frame asked for is held: sequences load one
//! file per frame, videos are streamed as raw RGBA frames at the scene's frame rate (frame i
//! is the picture shown at t = i / fps), never all at once. This file says what footage is
//! and checks it covers a scene; the pattern, ffprobe, the reader and the decoding ffmpeg
//! process have a file each.

use std::path::{Path, PathBuf};

use super::PixelError;

mod error;
mod pattern;
mod probe;
mod reader;
mod video;

pub use error::FootageError;
pub use pattern::Pattern;
pub use reader::FootageReader;

/// File extensions read as video (through ffmpeg) rather than as an image pattern.
pub const VIDEO_EXTENSIONS: [&str; 4] = ["mp4", "mov", "webm", "mkv"];

/// Whether `path` names a video file by its extension.
pub fn is_video_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| VIDEO_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// Where footage comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FootageSource {
    /// Numbered image files: scene frame i is file `start + i`.
    Sequence {
        /// The files' names.
        pattern: Pattern,
        /// The number of the file frame 0 shows.
        start: u64,
    },
    /// A video file, decoded by ffmpeg.
    Video(PathBuf),
}

/// Footage as a scene names it: where its frames come from, their size (all the same), and
/// whether the last frame holds once the footage runs out. [`Footage::open`] fills it in from
/// a pattern or a video path; a scene uses it as a background
/// ([`Background::Footage`](crate::animation::Background::Footage)) or as a patch's animated
/// source ([`Patch::footage`](crate::animation::Patch::footage)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Footage {
    /// The numbered files or the video.
    pub source: FootageSource,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Whether the last frame is shown once the footage runs out (else that is an error).
    pub hold: bool,
    /// The setting that sets `hold`, named in errors: `background_hold` or `source_hold` in a
    /// scene file; whatever name an embedding program shows its users.
    pub hold_key: String,
}

/// Why `file` (a plate or a video) cannot be read, when it is there but is no regular file
/// (a FIFO, a device, a dangling link, a folder); `None` when it is a file or is missing.
pub(super) fn not_a_file_error(file: &Path) -> Option<FootageError> {
    match crate::util::not_a_file(file) {
        None | Some("does not exist") => None,
        Some(kind) => Some(FootageError::NotAFile {
            file: file.to_path_buf(),
            kind,
        }),
    }
}

/// Whether plate `file` is there: `Ok(true)` for a file, `Ok(false)` when nothing is
/// there (which ends the run a hold keeps), an error when something other than a file is
/// (a FIFO or a folder mid-sequence is no end of the footage).
pub(super) fn plate_present(file: &Path) -> Result<bool, FootageError> {
    if file.is_file() {
        return Ok(true);
    }
    not_a_file_error(file).map_or(Ok(false), Err)
}

impl Footage {
    /// Opens footage at `path`: a printf-style pattern of numbered images
    /// (`plates/frame_%04d.png`) or a video file (`.mp4`, `.mov`, `.webm`, `.mkv`, read
    /// through ffmpeg). Finds the start number if not given (the lowest number with a file)
    /// and reads the first frame's size (a video's through ffprobe). `hold` and `hold_key`
    /// become the fields of the same names.
    pub fn open(
        path: &Path,
        start: Option<u64>,
        hold: bool,
        hold_key: &str,
    ) -> Result<Footage, FootageError> {
        if path.is_dir() {
            return Err(FootageError::IsFolder(path.to_path_buf()));
        }
        let (source, (width, height)) = if is_video_path(path) {
            if !path.is_file() {
                let missing = || FootageError::NotFound(path.to_path_buf());
                return Err(not_a_file_error(path).unwrap_or_else(missing));
            }
            (FootageSource::Video(path.to_path_buf()), probe::probe_video(path)?)
        } else {
            let pattern =
                Pattern::parse(path)?.ok_or_else(|| FootageError::NoNumber(path_text(path)))?;
            let start = match start {
                Some(s) => s,
                None => pattern.lowest_number()?,
            };
            let first = pattern.path(start);
            if let Some(error) = not_a_file_error(&first) {
                return Err(error);
            }
            if !first.is_file() {
                return Err(FootageError::MissingFrame {
                    frame: 1,
                    file: first,
                    hold_key: hold_key.into(),
                    held: hold,
                });
            }
            let size = image_size(&first)?;
            (FootageSource::Sequence { pattern, start }, size)
        };
        Ok(Footage {
            source,
            width,
            height,
            hold,
            hold_key: hold_key.into(),
        })
    }

    /// The file (or video) shown first, for messages and validation.
    pub fn first_path(&self) -> PathBuf {
        match &self.source {
            FootageSource::Sequence { pattern, start } => pattern.path(*start),
            FootageSource::Video(path) => path.clone(),
        }
    }

    /// The pattern or video path as the scene wrote it.
    pub fn describe(&self) -> String {
        match &self.source {
            FootageSource::Sequence { pattern, .. } => pattern.text().to_string(),
            FootageSource::Video(path) => path_text(path),
        }
    }

    /// Checks, before anything is rendered, that frames `0..frames` exist (or hold) and have
    /// the footage's size: every file of a sequence (its header), a video's duration from
    /// ffprobe.
    pub fn check_covers(&self, frames: u64, fps: f64) -> Result<(), FootageError> {
        match &self.source {
            FootageSource::Sequence { pattern, start } => {
                for i in 0..frames {
                    let file = pattern.path(start + i);
                    if !plate_present(&file)? {
                        if self.hold && i > 0 {
                            return Ok(());
                        }
                        return Err(self.missing(i, file));
                    }
                    self.check_size(&file, i, image_size(&file)?)?;
                }
                Ok(())
            }
            FootageSource::Video(path) => {
                let Some(seconds) = probe::probe_duration(path)? else {
                    return Ok(());
                };
                // Frames whose time i / fps is before the end; half a frame of slack for
                // containers that round their duration. Frame 1 (t = 0) is in any video
                // with a duration, however short against the frame rate.
                let available = ((seconds * fps + 0.5).floor() as u64).max(u64::from(seconds > 0.0));
                if !self.hold && available < frames {
                    return Err(FootageError::VideoTooShort {
                        path: path.clone(),
                        frame: available + 1,
                        available,
                        hold_key: self.hold_key.clone(),
                    });
                }
                Ok(())
            }
        }
    }

    /// Scene frame `index`'s `file` is missing.
    fn missing(&self, index: u64, file: PathBuf) -> FootageError {
        FootageError::MissingFrame {
            frame: index.saturating_add(1),
            file,
            hold_key: self.hold_key.clone(),
            held: self.hold,
        }
    }

    /// Refuses scene frame `index`'s `file` unless it has the footage's size.
    fn check_size(&self, file: &Path, index: u64, size: (u32, u32)) -> Result<(), FootageError> {
        if size == (self.width, self.height) {
            return Ok(());
        }
        Err(FootageError::SizeChanged {
            file: file.to_path_buf(),
            frame: index.saturating_add(1),
            width: size.0,
            height: size.1,
            expected_width: self.width,
            expected_height: self.height,
        })
    }
}

fn path_text(path: &Path) -> String {
    path.to_string_lossy().into_owned()
}

fn image_size(path: &Path) -> Result<(u32, u32), FootageError> {
    image::image_dimensions(path).map_err(|source| {
        FootageError::Image(Box::new(PixelError::Decode {
            path: path.to_path_buf(),
            source,
        }))
    })
}

