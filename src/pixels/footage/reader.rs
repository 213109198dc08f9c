//! Reading footage: takes a [`Footage`] and the scene's frame rate and gives scene frame i
//! as a [`FloatImage`], from the numbered file or the video stream, holding only the frame
//! asked for last.

use std::path::Path;

use super::video::VideoStream;
use super::{Footage, FootageError, FootageSource, Pattern};
use crate::pixels::{FloatImage, PixelFormat};

/// Reads footage frame by frame, keeping only the last frame read.
pub struct FootageReader {
    footage: Footage,
    fps: f64,
    current: Option<(u64, FloatImage)>,
    video: Option<VideoStream>,
}

impl FootageReader {
    pub fn new(footage: Footage, fps: f64) -> Self {
        FootageReader {
            footage,
            fps,
            current: None,
            video: None,
        }
    }

    pub fn footage(&self) -> &Footage {
        &self.footage
    }

    /// Scene frame `index` (from 0).
    pub fn frame(&mut self, index: u64) -> Result<&FloatImage, FootageError> {
        let fresh = !matches!(&self.current, Some((i, _)) if *i == index);
        if fresh {
            let image = match self.footage.source.clone() {
                FootageSource::Sequence { pattern, start } => {
                    self.sequence_frame(&pattern, start, index)?
                }
                FootageSource::Video(path) => self.video_frame(&path, index)?,
            };
            self.current = Some((index, image));
        }
        // invariant: `current` was set above when it did not hold `index`.
        Ok(&self.current.as_ref().expect("frame just read").1)
    }

    /// Scene frame `index` (from 0), handed over rather than kept: for a reader whose
    /// frames go elsewhere, which would otherwise copy each one.
    pub fn take_frame(&mut self, index: u64) -> Result<FloatImage, FootageError> {
        self.frame(index)?;
        // invariant: `frame` just stored frame `index`.
        Ok(self.current.take().expect("frame just read").1)
    }

    fn sequence_frame(
        &self,
        pattern: &Pattern,
        start: u64,
        index: u64,
    ) -> Result<FloatImage, FootageError> {
        // Saturating: a time far beyond any footage names a far frame, never frame 0.
        let mut file = pattern.path(start.saturating_add(index));
        if self.footage.hold && !super::plate_present(&file)? {
            // The last file of the unbroken run from the start holds.
            let mut last = 0;
            while last < index && super::plate_present(&pattern.path(start + last + 1))? {
                last += 1;
            }
            file = pattern.path(start + last);
        }
        if file.is_dir() {
            return Err(FootageError::IsFolder(file));
        }
        if !file.is_file() {
            let missing = || self.footage.missing(index, file.clone());
            return Err(super::not_a_file_error(&file).unwrap_or_else(missing));
        }
        let image = FloatImage::load(&file).map_err(|e| FootageError::Image(Box::new(e)))?;
        let size = (image.width(), image.height());
        self.footage.check_size(&file, index, size)?;
        Ok(image)
    }

    fn video_frame(&mut self, path: &Path, index: u64) -> Result<FloatImage, FootageError> {
        let (w, h) = (self.footage.width, self.footage.height);
        if self.video.as_ref().is_none_or(|v| v.next > index) {
            self.video = None;
            self.video = Some(VideoStream::start(path, w, h, self.fps)?);
        }
        // invariant: set just above when absent.
        let stream = self.video.as_mut().expect("stream started");
        while stream.next <= index {
            if !stream.read_next()? {
                break;
            }
        }
        match (&stream.last, stream.next > index || self.footage.hold) {
            (Some(bytes), true) => rgba8_image(w, h, bytes),
            _ => Err(FootageError::VideoTooShort {
                path: path.to_path_buf(),
                frame: index.saturating_add(1),
                available: stream.next,
                hold_key: self.footage.hold_key.clone(),
            }),
        }
    }
}

const OPAQUE_RGB8: PixelFormat = PixelFormat {
    alpha: false,
    ..PixelFormat::RGBA8
};

/// An 8-bit RGBA buffer as an opaque-format image of its levels.
fn rgba8_image(width: u32, height: u32, bytes: &[u8]) -> Result<FloatImage, FootageError> {
    let levels = bytemuck::cast_slice(bytes).to_vec();
    FloatImage::from_levels(width, height, levels, OPAQUE_RGB8)
        .map_err(|e| FootageError::Image(Box::new(e)))
}
