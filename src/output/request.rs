//! What a render asks of its output before any frame exists: the settings beyond format and
//! path ([`SinkSettings`]), the frames wanted ([`FrameRange`]), and the check that the
//! output's folder exists. Takes plain values and paths; gives them checked, for the sink and
//! the PNG staging alike.

use std::path::Path;

use super::{OutputError, PngCompression};

/// Output settings beyond the format and path.
#[derive(Clone, Copy, Debug, Default)]
pub struct SinkSettings {
    /// Remove frame files of another render from a PNG folder instead of refusing.
    pub force: bool,
    /// PNG deflate effort for frame folders.
    pub png_compression: PngCompression,
    /// Constant quality for MP4/WebM/MOV (lower is better; ffmpeg's codec default if unset).
    pub crf: Option<u32>,
}

/// An inclusive frame range (frame numbers as in the file names, from 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// The first frame written.
    pub first: u64,
    /// The last frame written.
    pub last: u64,
}

impl FrameRange {
    /// Every frame of a scene of `total` frames.
    pub fn all(total: u64) -> Self {
        FrameRange {
            first: 1,
            last: total,
        }
    }

    /// How many frames it holds (0 when `last` is before `first`).
    pub fn len(&self) -> u64 {
        match self.last.checked_sub(self.first) {
            Some(span) => span.saturating_add(1),
            None => 0,
        }
    }

    /// Refuses a range that is empty, starts at 0 or ends past a scene's `total` frames.
    pub fn check(&self, total: u64) -> Result<(), OutputError> {
        if self.first == 0 || self.is_empty() || self.last > total {
            return Err(OutputError::FramesOutOfRange {
                range: *self,
                total,
            });
        }
        Ok(())
    }

    /// Whether it holds no frame (`last` before `first`).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Fails before any work when the output's folder does not exist or cannot be reached (a
/// path too long, a folder that may not be searched): the message says which.
pub fn check_output_folder(output: &Path) -> Result<(), OutputError> {
    let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) else {
        return Ok(());
    };
    match std::fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => Ok(()),
        Ok(_) => Err(missing(output, dir, true)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(missing(output, dir, false)),
        // Not a missing folder: a path too long, a folder that may not be searched.
        Err(e) => Err(OutputError::io(output, e)),
    }
}

fn missing(output: &Path, folder: &Path, exists: bool) -> OutputError {
    OutputError::MissingFolder {
        output: output.to_path_buf(),
        folder: folder.to_path_buf(),
        exists,
    }
}
