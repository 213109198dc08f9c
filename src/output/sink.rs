//! Where a render's frames go: takes an output path, its [`OutputKind`] and
//! [`SinkSettings`], and gives a [`FrameSink`] that takes a renderer's canvases in order
//! and writes a PNG folder (through [`PngStaging`](super::staging)), a GIF, an APNG, a Y4M
//! stream or a video through ffmpeg. A [`SinkPlan`] is made before the scene loads, so a
//! video's ffmpeg starts up meanwhile.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use super::request::{check_output_folder, FrameRange, SinkSettings};
use super::staging::{open_png_folder, PngStaging};
use super::{
    ApngWriter, FfmpegWriter, Frame, FrameData, FrameRef, GifWriter, OutputError, OutputKind,
    PendingVideo, Pixels, PngSequenceWriter, VideoFrames, VideoKind, Y4mWriter,
};
use crate::pixels::{Canvas, CanvasPixels, Depth};
use crate::render::Renderer;

/// An output chosen before the scene is loaded; a video's ffmpeg is already starting.
pub struct SinkPlan {
    kind: OutputKind,
    output: PathBuf,
    settings: SinkSettings,
    video: Option<PendingVideo>,
}

impl SinkPlan {
    /// Checks the output path and, for a video, starts ffmpeg.
    pub fn new(kind: OutputKind, output: &Path, settings: SinkSettings) -> Result<Self, OutputError> {
        if kind != OutputKind::PngFolder && output.is_dir() {
            return Err(OutputError::IsAFolder {
                path: output.to_path_buf(),
                kind,
            });
        }
        let video_kind = match kind {
            OutputKind::Mp4 => Some(VideoKind::Mp4),
            OutputKind::Webm => Some(VideoKind::Webm),
            OutputKind::Mov => Some(VideoKind::Mov),
            _ => None,
        };
        let video = match video_kind {
            Some(video_kind) => {
                check_output_folder(output)?;
                Some(FfmpegWriter::start(output, video_kind, settings.crf)?)
            }
            None => None,
        };
        Ok(SinkPlan {
            kind,
            output: output.to_path_buf(),
            settings,
            video,
        })
    }

    /// Opens the sink for `renderer`'s frames in `range`, encoding on `jobs` threads.
    pub fn open(
        self,
        renderer: &Renderer,
        range: FrameRange,
        jobs: usize,
        cancel: Arc<AtomicBool>,
    ) -> Result<FrameSink, OutputError> {
        // A FIFO output waits for its reader until the render is cancelled.
        crate::util::interrupt_waits_with(&cancel);
        let canvas = &renderer.scene().canvas;
        let output = self.output.as_path();
        // A file's folder must exist (a PNG folder's is checked as it is staged, a video's
        // when its ffmpeg started; `-` is standard output).
        let file = matches!(self.kind, OutputKind::Gif | OutputKind::Apng | OutputKind::Y4m);
        if file && output.as_os_str() != "-" {
            check_output_folder(output)?;
        }
        let mut note = None;
        let sink = match self.kind {
            OutputKind::PngFolder => {
                let (writer, staging) =
                    open_png_folder(output, renderer, range, jobs, cancel, self.settings)?;
                Sink::Png(writer, Box::new(staging))
            }
            OutputKind::Gif => {
                note = super::gif::slow_in_players(canvas.fps);
                Sink::Gif(Box::new(GifWriter::create(output, canvas.fps)?))
            }
            OutputKind::Y4m => {
                let path = (output.as_os_str() != "-").then_some(output);
                let writer = Y4mWriter::create(path, canvas.width, canvas.height, canvas.fps)?;
                Sink::Y4m(Box::new(writer))
            }
            OutputKind::Mp4 | OutputKind::Webm | OutputKind::Mov => {
                // invariant: `new` starts a video for exactly these kinds.
                let pending = self.video.expect("a started video");
                let (writer, padded) = begin_video(pending, renderer, jobs, cancel)?;
                note = padded;
                Sink::Video(Box::new(writer))
            }
            OutputKind::Apng => Sink::Apng(Box::new(open_apng(output, renderer, range)?)),
        };
        Ok(FrameSink {
            sink,
            note,
            path: self.output,
        })
    }
}

fn begin_video(
    pending: PendingVideo,
    renderer: &Renderer,
    jobs: usize,
    cancel: Arc<AtomicBool>,
) -> Result<(FfmpegWriter, Option<String>), OutputError> {
    let canvas = &renderer.scene().canvas;
    let frames = VideoFrames {
        width: canvas.width,
        height: canvas.height,
        fps: canvas.fps,
        alpha: !renderer.frame().pixels_opaque(),
    };
    let writer = pending.begin(frames, jobs)?.with_cancel(cancel);
    let note = writer.padded().map(|(w, h)| {
        format!(
            "{}×{} has an odd side; the video is padded to {w}×{h} (4:2:0 needs even sides; the edge pixels repeat)",
            canvas.width, canvas.height
        )
    });
    Ok((writer, note))
}

fn open_apng(
    output: &Path,
    renderer: &Renderer,
    range: FrameRange,
) -> Result<ApngWriter, OutputError> {
    let canvas = &renderer.scene().canvas;
    let frames = u32::try_from(range.len()).map_err(OutputError::TooManyFrames)?;
    let sixteen = renderer.output_format().depth == Depth::Sixteen;
    ApngWriter::create(
        output,
        canvas.width,
        canvas.height,
        sixteen,
        frames,
        canvas.fps,
    )
}

/// Where rendered frames go, opened by [`SinkPlan::open`]: frames are pushed in order,
/// then the sink is finished (the output appears whole) or abandoned (nothing appears).
pub struct FrameSink {
    sink: Sink,
    note: Option<String>,
    /// The output, named in an encoder's I/O failure.
    path: PathBuf,
}

enum Sink {
    Png(PngSequenceWriter, Box<PngStaging>),
    Gif(Box<GifWriter>),
    Apng(Box<ApngWriter>),
    Y4m(Box<Y4mWriter>),
    Video(Box<FfmpegWriter>),
}

impl FrameSink {
    /// A note for the user about the output (a video padded to even sides), if any.
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// Writes frame `number` (from 1).
    pub fn push(&mut self, number: u64, canvas: &Canvas) -> Result<(), OutputError> {
        self.push_frame(number, canvas)
            .map_err(|e| e.writing(&self.path))
    }

    fn push_frame(&mut self, number: u64, canvas: &Canvas) -> Result<(), OutputError> {
        match &mut self.sink {
            Sink::Png(writer, _) => {
                let mut frame = writer.spare_frame().unwrap_or_else(|| empty_frame(canvas));
                fill_frame(&mut frame, canvas);
                writer.submit(number, frame)?;
            }
            Sink::Gif(writer) => writer.add(&frame_ref(canvas)?)?,
            Sink::Apng(writer) => writer.add(&frame_ref(canvas)?)?,
            Sink::Y4m(writer) => writer.add(&frame_ref(canvas)?)?,
            Sink::Video(writer) => writer.add(&frame_ref(canvas)?)?,
        }
        Ok(())
    }

    /// Finishes the output and gives its path.
    pub fn finish(self) -> Result<PathBuf, OutputError> {
        let finished = match self.sink {
            Sink::Png(writer, staging) => writer
                .finish()
                .and_then(|written| staging.commit(&written)),
            Sink::Gif(writer) => writer.finish(),
            Sink::Apng(writer) => writer.finish(),
            Sink::Y4m(writer) => writer.finish(),
            Sink::Video(writer) => writer.finish(),
        };
        finished.map_err(|e| e.writing(&self.path))
    }

    /// Drops the sink after a failure or an interruption: writers remove their temporary
    /// files (a PNG sequence its temporary folder).
    pub fn abandon(self) {
        if let Sink::Png(writer, _) = self.sink {
            let _ = writer.finish();
        }
    }
}

fn frame_ref(canvas: &Canvas) -> Result<FrameRef<'_>, OutputError> {
    let pixels = match canvas.pixels() {
        CanvasPixels::Eight(p) => Pixels::Rgba8(p.as_flattened()),
        CanvasPixels::Sixteen(p) => Pixels::Rgba16(p.as_flattened()),
    };
    FrameRef::new(canvas.width(), canvas.height(), pixels)
}

fn empty_frame(canvas: &Canvas) -> Frame {
    Frame {
        width: canvas.width(),
        height: canvas.height(),
        data: FrameData::Rgba8(Vec::new()),
    }
}

/// Copies the canvas into a (recycled) frame buffer without reallocating when sizes match.
fn fill_frame(frame: &mut Frame, canvas: &Canvas) {
    frame.width = canvas.width();
    frame.height = canvas.height();
    match (canvas.pixels(), &mut frame.data) {
        (CanvasPixels::Eight(p), FrameData::Rgba8(out)) => {
            out.clear();
            out.extend_from_slice(p.as_flattened());
        }
        (CanvasPixels::Sixteen(p), FrameData::Rgba16(out)) => {
            out.clear();
            out.extend_from_slice(p.as_flattened());
        }
        (CanvasPixels::Eight(p), data) => *data = FrameData::Rgba8(p.as_flattened().to_vec()),
        (CanvasPixels::Sixteen(p), data) => *data = FrameData::Rgba16(p.as_flattened().to_vec()),
    }
}
