//! Errors of the pixel layer: takes failures of decoding, encoding and file output and gives
//! one typed error that names the file involved.

use std::path::PathBuf;

/// Why an image cannot be read, decoded, checked, encoded or written.
#[derive(Debug, thiserror::Error)]
pub enum PixelError {
    /// The file cannot be read.
    #[error("cannot read image {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not an image in a supported format.
    #[error("cannot decode image {path}: {source}")]
    Decode {
        /// The file.
        path: PathBuf,
        /// The decoder's error.
        #[source]
        source: image::ImageError,
    },
    /// The image exceeds a resource limit (checked from its header).
    #[error("image {path}: {source}")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Which limit.
        #[source]
        source: crate::limits::LimitError,
    },
    /// The image has no pixels.
    #[error("image {path} is empty ({width}×{height})")]
    Empty {
        /// The file.
        path: PathBuf,
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
    },
    /// An in-memory image has no pixels.
    #[error("image is empty ({width}×{height})")]
    EmptyImage {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
    },
    /// PNG encoding failed.
    #[error("cannot encode PNG: {0}")]
    Encode(#[from] png::EncodingError),
    /// The output cannot be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Two canvases that must match differ in size or depth.
    #[error("canvases differ: {width}×{height} {depth:?} vs {other_width}×{other_height} {other_depth:?}")]
    CanvasMismatch {
        /// Columns of the first.
        width: u32,
        /// Rows of the first.
        height: u32,
        /// Depth of the first.
        depth: super::Depth,
        /// Columns of the second.
        other_width: u32,
        /// Rows of the second.
        other_height: u32,
        /// Depth of the second.
        other_depth: super::Depth,
    },
    /// Reading footage (an image sequence or a video) failed.
    #[error(transparent)]
    Footage(#[from] Box<super::FootageError>),
    /// A pixel buffer's length does not match the size given.
    #[error("pixel buffer of {actual} pixels does not match {width}×{height}")]
    BufferSize {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
        /// Pixels in the buffer.
        actual: usize,
    },
}
