//! Why tracking or reading a track failed: options out of range, a point outside the first
//! frame, a frame of another size, and malformed track files (`file:line: what is wrong`).

use crate::util::ShowPath;
use std::path::PathBuf;

/// Why a track cannot be made or read.
#[derive(Debug, thiserror::Error)]
pub enum TrackError {
    /// A tracking option is out of range.
    #[error("{0}")]
    Options(String),
    /// A point to track lies outside the first frame.
    #[error("point {point} ({x}, {y}) is outside the first frame ({width}×{height})")]
    PointOutside {
        /// The point, counted from 1.
        point: usize,
        /// Its x.
        x: f64,
        /// Its y.
        y: f64,
        /// The frame's width.
        width: u32,
        /// The frame's height.
        height: u32,
    },
    /// A frame's size differs from the first frame's.
    #[error("a frame is {width}×{height}, but the first was {expected_width}×{expected_height}")]
    FrameSize {
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The first frame's width.
        expected_width: u32,
        /// The first frame's height.
        expected_height: u32,
    },
    /// A track file cannot be read.
    #[error("cannot read track {}: {source}", path.shown())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A track file is malformed at a line.
    #[error("{}:{line}: {message}", path.shown())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// The line, counted from 1.
        line: usize,
        /// What is wrong.
        message: String,
    },
}
