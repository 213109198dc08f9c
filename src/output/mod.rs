//! Frame writers: take rendered frames ([`FrameRef`], RGBA 8 or 16 bits) and give a PNG
//! sequence (`DIR/frame_0001.png …`, encoded in parallel), an animated GIF, an animated
//! PNG, a YUV4MPEG2 stream, or an MP4/WebM/MOV through an ffmpeg process; plus the format an
//! output path names ([`OutputKind::from_path`]). Every file appears whole or not at all
//! (temporary file + rename). On top of the writers, a [`SinkPlan`] / [`FrameSink`] picks
//! the writer for a path and a renderer, and [`render_scene`] renders a loaded scene to a
//! path (refusing an output that is one of the scene's inputs).

mod apng;
mod encode;
mod ffmpeg;
mod format;
mod frame;
mod gif;
mod gif_frame;
mod gif_palette;
mod inputs;
mod png_sequence;
mod pool;
mod request;
mod scene_render;
mod sink;
mod staging;
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
pub use inputs::{
    refuse_footage_input, refuse_input, refuse_render_input, refuse_scene_input, refuse_scene_reads,
};
pub use scene_render::{
    render_error_at_call, render_frames, render_scene, RenderOptions, RenderProgress, Rendered,
};
pub use request::{check_output_folder, FrameRange, SinkSettings};
pub use sink::{FrameSink, SinkPlan};
pub use y4m::{fps_fraction, Y4mWriter};
pub use yuv::{frame_to_yuv420, rgb_to_ycbcr, yuv420_len, yuv420_size};

use crate::util::ShowPath;
use std::path::{Path, PathBuf};

impl OutputError {
    /// An I/O failure on `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// This error met writing `path`: an encoder's I/O failure (a full disk) names the file
    /// it could not write; other errors stay as they are.
    pub(crate) fn writing(self, path: &Path) -> Self {
        match self {
            OutputError::Png(png::EncodingError::IoError(source))
            | OutputError::Gif(::gif::EncodingError::Io(source)) => OutputError::io(path, source),
            other => other,
        }
    }
}

/// Why an output was refused or failed. Messages name the path; the causes (I/O errors)
/// are their `source`s.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Reading or writing `path` failed.
    #[error("{}: {source}", path.shown())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The PNG encoder failed.
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),
    /// The GIF encoder failed.
    #[error("GIF encoding failed: {0}")]
    Gif(#[from] ::gif::EncodingError),
    /// A frame whose size or samples do not fit the output.
    #[error("bad frame: {0}")]
    BadFrame(String),
    /// A frame folder that does not exist.
    #[error("output folder {} does not exist", .0.shown())]
    NotAFolder(PathBuf),
    /// An encoder thread failed.
    #[error("{0}")]
    Worker(String),
    /// A video format without an `ffmpeg` on `PATH`.
    #[error("{}", crate::util::FFMPEG_MISSING)]
    NoFfmpeg,
    /// ffmpeg failed; the last lines it wrote.
    #[error("ffmpeg failed writing {}; it said:\n  {stderr}", path.shown())]
    Ffmpeg {
        /// The video.
        path: PathBuf,
        /// ffmpeg's last lines on stderr.
        stderr: String,
    },
    /// A writer stopped because the cancel flag was raised.
    #[error("cancelled")]
    Cancelled,
    /// The output's parent folder is missing (`exists` false) or not a folder.
    #[error("{}: the output folder {} {}", output.shown(), folder.shown(), if *exists { "is not a folder" } else { "does not exist" })]
    MissingFolder {
        /// The output path.
        output: PathBuf,
        /// Its parent folder.
        folder: PathBuf,
        /// Whether something that is not a folder is there.
        exists: bool,
    },
    /// A file output names an existing folder.
    #[error("{} is a folder; name a file for {kind:?} output", path.shown())]
    IsAFolder {
        /// The output path.
        path: PathBuf,
        /// The format asked for.
        kind: OutputKind,
    },
    /// A PNG frame folder's path is a file.
    #[error("{} exists and is not a folder; name a folder for PNG frames", .0.shown())]
    NotAFrameFolder(PathBuf),
    /// A PNG frame folder holds frame files of another render (and `force` is off).
    #[error("{} holds {count} frame files of another render (e.g. {example}); use --force to remove them, or another folder", folder.shown())]
    ForeignFrames {
        /// The folder.
        folder: PathBuf,
        /// How many such files.
        count: usize,
        /// One of their names.
        example: String,
    },
    /// The output would replace one of the inputs.
    #[error("{}: the output would replace an input of this command ({input}); write it elsewhere", output.shown())]
    ReplacesInput {
        /// The output path (or the frame file in a PNG folder).
        output: PathBuf,
        /// The input: its path or footage pattern.
        input: String,
    },
    /// The output path's extension names no format.
    #[error("{}: unknown output extension `.{extension}` (use .gif, .apng, .mp4, .webm, .mov, .y4m, a folder name without an extension, or a format)", path.shown())]
    UnknownExtension {
        /// The output path.
        path: PathBuf,
        /// Its extension.
        extension: String,
    },
    /// A format name that is none of png, gif, apng, mp4, webm, mov, y4m.
    #[error("unknown output format `{0}` (use png, gif, apng, mp4, webm, mov or y4m)")]
    UnknownFormat(String),
    /// `-` (standard output) for a format other than Y4M.
    #[error("- (standard output) needs the y4m format")]
    StdoutNeedsY4m,
    /// Frames asked for beyond the scene's end.
    #[error("frames {}..{}: the scene has {total} frames", range.first, range.last)]
    FramesOutOfRange {
        /// The range asked for.
        range: FrameRange,
        /// The scene's frame count.
        total: u64,
    },
    /// More frames than an APNG holds.
    #[error("too many frames for an APNG")]
    TooManyFrames(#[source] std::num::TryFromIntError),
    /// Listing a frame folder failed.
    #[error("reading {}", path.shown())]
    ReadingFolder {
        /// The folder.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The temporary folder beside the output could not be made.
    #[error("creating a folder beside {}", beside.shown())]
    CreatingFolder {
        /// The output.
        beside: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// An entry of a PNG frame folder, named as a frame this render writes or one it would
    /// remove, is no regular file: it is never written over or removed.
    #[error("{} {kind}: only a regular frame file is written over or removed; move it away", path.shown())]
    NotAFrameFile {
        /// The entry.
        path: PathBuf,
        /// What it is ("is a folder, not a file", "is a symbolic link", …).
        kind: &'static str,
    },
    /// Moving the finished frames into the destination failed.
    #[error("moving the frames to {}", dest.shown())]
    Moving {
        /// The destination folder.
        dest: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Removing another render's frame file (with `force`) failed.
    #[error("removing {}", path.shown())]
    Removing {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The renderer failed on a frame (not positioned; [`render_scene`] gives
    /// [`OutputError::Scene`] instead).
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// An error about the scene, positioned at the call it is about.
    #[error(transparent)]
    Scene(#[from] crate::script::SceneError),
    /// The render was cancelled after `after` frames of the range were written.
    #[error("interrupted: stopped after frame {after}")]
    Interrupted {
        /// The last frame number pushed (one before the range's first when none was).
        after: u64,
    },
    /// The render was cancelled while the writers finished the last frames.
    #[error("interrupted: stopped while writing the last frames")]
    InterruptedFinishing,
}

/// Whole `unit`s per frame (e.g. 100 for centiseconds), rounded from the exact frame times
/// i·unit/fps so rounding never accumulates over the animation.
fn rounded_steps(frames: usize, fps: f64, unit: f64) -> Vec<u64> {
    let at = |i: usize| (i as f64 * unit / fps).round() as u64;
    (0..frames).map(|i| at(i + 1) - at(i)).collect()
}
