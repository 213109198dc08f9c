//! Frame writers: take rendered frames ([`FrameRef`], RGBA 8 or 16 bits) and give a PNG
//! sequence (`DIR/frame_0001.png …`, encoded in parallel), an animated GIF, an animated
//! PNG, a YUV4MPEG2 stream, or an MP4/WebM/MOV through an ffmpeg process; plus the format an
//! output path names ([`OutputKind::from_path`]). Every file appears whole or not at all
//! (temporary file + rename).

mod apng;
mod encode;
mod ffmpeg;
mod format;
mod frame;
mod gif;
mod gif_frame;
mod gif_palette;
mod png_sequence;
mod pool;
mod y4m;
mod yuv;

pub use apng::{apng_delays, ApngWriter};
pub use crate::util::TempOutput;
pub use encode::{FrameEncoder, PngCompression};
pub use ffmpeg::{FfmpegWriter, PendingVideo, VideoFrames, VideoKind};
pub use format::OutputKind;
pub use frame::{Frame, FrameData, FrameRef, Pixels};
pub use gif::{gif_delays_cs, GifOptions, GifWriter, PALETTE_FRAMES};
pub use gif_palette::{Palette, PaletteMap};
pub use png_sequence::{
    foreign_frames, frame_digits, frame_file_name, write_png_file, PngSequenceWriter,
};
pub use y4m::{fps_fraction, Y4mWriter};
pub use yuv::{frame_to_yuv420, rgb_to_ycbcr, yuv420_len, yuv420_size};

use std::path::{Path, PathBuf};

impl OutputError {
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),
    #[error("GIF encoding failed: {0}")]
    Gif(#[from] ::gif::EncodingError),
    #[error("bad frame: {0}")]
    BadFrame(String),
    #[error("output folder {} does not exist", .0.display())]
    NotAFolder(PathBuf),
    #[error("{0}")]
    Worker(String),
    #[error("{}", crate::util::FFMPEG_MISSING)]
    NoFfmpeg,
    #[error("ffmpeg failed writing {}; it said:\n  {stderr}", path.display())]
    Ffmpeg { path: PathBuf, stderr: String },
    #[error("cancelled")]
    Cancelled,
}

/// Whole `unit`s per frame (e.g. 100 for centiseconds), rounded from the exact frame times
/// i·unit/fps so rounding never accumulates over the animation.
fn rounded_steps(frames: usize, fps: f64, unit: f64) -> Vec<u64> {
    let at = |i: usize| (i as f64 * unit / fps).round() as u64;
    (0..frames).map(|i| at(i + 1) - at(i)).collect()
}
