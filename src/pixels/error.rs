//! Errors of the pixel layer: takes failures of decoding, encoding and file output and gives
//! one typed error that names the file involved.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum PixelError {
    #[error("cannot read image {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot decode image {path}: {source}")]
    Decode {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("image {path}: {source}")]
    TooLarge {
        path: PathBuf,
        #[source]
        source: crate::limits::LimitError,
    },
    #[error("image {path} is empty ({width}×{height})")]
    Empty {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    #[error("image is empty ({width}×{height})")]
    EmptyImage { width: u32, height: u32 },
    #[error("cannot encode PNG: {0}")]
    Encode(#[from] png::EncodingError),
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("canvases differ: {width}×{height} {depth:?} vs {other_width}×{other_height} {other_depth:?}")]
    CanvasMismatch {
        width: u32,
        height: u32,
        depth: super::Depth,
        other_width: u32,
        other_height: u32,
        other_depth: super::Depth,
    },
    #[error(transparent)]
    Footage(#[from] Box<super::FootageError>),
    #[error("pixel buffer of {actual} pixels does not match {width}×{height}")]
    BufferSize {
        width: u32,
        height: u32,
        actual: usize,
    },
}
