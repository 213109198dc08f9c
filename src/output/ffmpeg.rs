//! Video files through an `ffmpeg` process: takes frames in order and gives an MP4, WebM or
//! MOV. Raw frames go down a pipe (written by a thread of their own, so encoding overlaps
//! rendering) into `ffmpeg -f rawvideo`, which writes a temporary file; it is renamed onto
//! the destination only when ffmpeg exits 0. On failure the last lines ffmpeg printed are in
//! the error; an abandoned writer kills ffmpeg and leaves no file.
//!
//! Codecs: MP4 is H.264 in yuv420p at constant quality (CRF 20 by default); WebM is VP9 in
//! yuv420p at constant quality (CRF 32); MOV is H.264 like MP4 for opaque frames and ProRes
//! 4444 with alpha when the canvas has transparency (CRF does not apply to it).
//!
//! For the 4:2:0 codecs lapclone converts each frame itself (the `yuv` module: BT.709,
//! limited range, integer maths, in row bands on the caller's threads) and feeds ffmpeg
//! `yuv420p`, 1.5 bytes a pixel instead of RGBA's 4, sparing ffmpeg its serial conversion;
//! input and output are tagged BT.709 / limited range so players decode the colours lapclone
//! meant. 4:2:0 needs even sides: an odd side is padded by one pixel (repeating the last row
//! or column), which [`FfmpegWriter::padded`] reports. ProRes 4444 is fed RGBA and converted
//! by ffmpeg, which keeps the alpha.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::Arc;
use std::time::Duration;
use std::thread::JoinHandle;

use super::atomic::TempOutput;
use super::yuv::{frame_to_yuv420, yuv420_size};
use super::{fps_fraction, FrameRef, OutputError};

/// How lapclone's 4:2:0 frames are tagged, as ffmpeg options (before `-i` for the raw input,
/// after it for the encoded stream): BT.709 matrix, primaries and transfer, limited range.
const BT709_TAGS: [&str; 8] = [
    "-color_range",
    "tv",
    "-colorspace",
    "bt709",
    "-color_primaries",
    "bt709",
    "-color_trc",
    "bt709",
];

/// The containers written through ffmpeg.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VideoKind {
    Mp4,
    Webm,
    Mov,
}

impl VideoKind {
    fn muxer(self) -> &'static str {
        match self {
            VideoKind::Mp4 => "mp4",
            VideoKind::Webm => "webm",
            VideoKind::Mov => "mov",
        }
    }

    /// The default constant-quality value (lower is better) of its codec.
    pub fn default_crf(self) -> u32 {
        match self {
            VideoKind::Mp4 | VideoKind::Mov => 20,
            VideoKind::Webm => 32,
        }
    }
}

/// How a video is encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VideoOptions {
    pub kind: VideoKind,
    pub width: u32,
    pub height: u32,
    pub fps: f64,
    /// Constant-quality value; the codec's default when `None`.
    pub crf: Option<u32>,
    /// Whether frames have transparency worth keeping (MOV only).
    pub alpha: bool,
}

impl VideoOptions {
    /// Whether this encodes ProRes 4444 with alpha rather than 4:2:0.
    fn keeps_alpha(&self) -> bool {
        self.alpha && self.kind == VideoKind::Mov
    }

    /// The encoded size: sides padded to even for 4:2:0.
    pub fn encoded_size(&self) -> (u32, u32) {
        if self.keeps_alpha() {
            (self.width, self.height)
        } else {
            yuv420_size(self.width, self.height)
        }
    }

    /// The ffmpeg arguments describing the raw frames on standard input, `-i -` included.
    pub fn input_args(&self) -> Vec<String> {
        let (w, h) = self.encoded_size();
        let (num, den) = fps_fraction(self.fps);
        let mut args: Vec<String> = ["-f", "rawvideo", "-pix_fmt"].map(String::from).into();
        if self.keeps_alpha() {
            args.push("rgba".into());
        } else {
            args.push("yuv420p".into());
            args.extend(BT709_TAGS.map(String::from));
        }
        args.extend(["-s".into(), format!("{w}x{h}")]);
        args.extend(["-framerate".into(), format!("{num}/{den}")]);
        args.extend(["-i", "-"].map(String::from));
        args
    }

    /// The ffmpeg arguments after the raw input, up to (not including) the output path.
    pub fn codec_args(&self) -> Vec<String> {
        let crf = self.crf.unwrap_or(self.kind.default_crf()).to_string();
        let mut args: Vec<String> = Vec::new();
        let codec: &[&str] = if self.keeps_alpha() {
            &[
                "-c:v",
                "prores_ks",
                "-profile:v",
                "4444",
                "-pix_fmt",
                "yuva444p10le",
            ]
        } else {
            match self.kind {
                VideoKind::Mp4 | VideoKind::Mov => &[
                    "-c:v", "libx264", "-preset", "veryfast", "-pix_fmt", "yuv420p", "-crf",
                ],
                VideoKind::Webm => &[
                    "-c:v",
                    "libvpx-vp9",
                    "-pix_fmt",
                    "yuv420p",
                    "-b:v",
                    "0",
                    "-row-mt",
                    "1",
                    "-deadline",
                    "good",
                    "-cpu-used",
                    "4",
                    "-crf",
                ],
            }
        };
        args.extend(codec.iter().map(|s| s.to_string()));
        if !self.keeps_alpha() {
            args.push(crf);
            args.extend(BT709_TAGS.map(String::from));
            // Each chroma sample is its 2×2 block's mean.
            args.extend(["-chroma_sample_location", "center"].map(String::from));
        }
        if self.kind != VideoKind::Webm {
            args.extend(["-movflags".into(), "+faststart".into()]);
        }
        args.extend(["-f".into(), self.kind.muxer().into()]);
        args
    }
}

/// An ffmpeg process encoding frames into a temporary file next to the destination.
pub struct FfmpegWriter {
    path: PathBuf,
    /// Taken when committed.
    temp: Option<TempOutput>,
    child: Child,
    sender: Option<SyncSender<Vec<u8>>>,
    spare: Receiver<Vec<u8>>,
    feeder: Option<JoinHandle<std::io::Result<()>>>,
    stderr: Option<JoinHandle<String>>,
    options: VideoOptions,
    /// Threads converting a frame to 4:2:0.
    threads: usize,
    /// Set by Ctrl-C: [`finish`](Self::finish) stops waiting for ffmpeg and fails.
    cancel: Option<Arc<AtomicBool>>,
}

impl FfmpegWriter {
    /// Starts ffmpeg for a video at `path`, converting frames on up to `threads` threads;
    /// fails with the install hint when ffmpeg is not on `PATH`.
    pub fn create(path: &Path, options: VideoOptions, threads: usize) -> Result<Self, OutputError> {
        let ffmpeg = crate::util::find_program("ffmpeg").ok_or(OutputError::NoFfmpeg)?;
        let temp = TempOutput::new(path);
        let mut command = Command::new(ffmpeg);
        command
            .args(["-v", "error", "-nostdin", "-y"])
            .args(options.input_args())
            .args(options.codec_args())
            .arg(temp.temp_path())
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        #[cfg(unix)]
        {
            // Its own process group: Ctrl-C reaches lapclone, which then stops ffmpeg and
            // removes the file, instead of ffmpeg finishing a partial video by itself.
            use std::os::unix::process::CommandExt;
            command.process_group(0);
        }
        let mut child = command.spawn().map_err(|e| OutputError::io(path, e))?;
        // invariant: both were requested as pipes just above.
        let mut stdin = child.stdin.take().expect("piped stdin");
        let mut stderr_pipe = child.stderr.take().expect("piped stderr");
        let stderr = std::thread::spawn(move || {
            let mut text = String::new();
            let _ = stderr_pipe.read_to_string(&mut text);
            text
        });
        let (sender, frames) = sync_channel::<Vec<u8>>(2);
        let (spare_sender, spare) = sync_channel::<Vec<u8>>(4);
        let feeder = std::thread::spawn(move || {
            for frame in frames {
                stdin.write_all(&frame)?;
                let _ = spare_sender.try_send(frame);
            }
            stdin.flush()
        });
        Ok(FfmpegWriter {
            path: path.to_path_buf(),
            temp: Some(temp),
            child,
            sender: Some(sender),
            spare,
            feeder: Some(feeder),
            stderr: Some(stderr),
            options,
            threads: threads.max(1),
            cancel: None,
        })
    }

    /// Makes [`finish`](Self::finish) give up (stopping ffmpeg, leaving no file) once
    /// `cancel` is set, instead of waiting for ffmpeg to complete the video.
    pub fn with_cancel(mut self, cancel: Arc<AtomicBool>) -> Self {
        self.cancel = Some(cancel);
        self
    }

    /// The size the video was padded to, when a side was odd.
    pub fn padded(&self) -> Option<(u32, u32)> {
        let size = self.options.encoded_size();
        (size != (self.options.width, self.options.height)).then_some(size)
    }

    /// Queues the next frame (of the video's size; 16-bit frames are rounded to 8 bits):
    /// converted to 4:2:0 here, or copied as RGBA for ProRes 4444.
    pub fn add(&mut self, frame: &FrameRef<'_>) -> Result<(), OutputError> {
        if (frame.width(), frame.height()) != (self.options.width, self.options.height) {
            return Err(OutputError::BadFrame(
                "frame size differs from the video's".into(),
            ));
        }
        let mut buffer = self.spare.try_recv().unwrap_or_default();
        if self.options.keeps_alpha() {
            frame.write_rgba8(&mut buffer);
        } else {
            frame_to_yuv420(frame, &mut buffer, self.threads);
        }
        let sent = self.sender.as_ref().is_some_and(|s| s.send(buffer).is_ok());
        if !sent {
            // The feeder stopped: ffmpeg exited early. Its message says why.
            return Err(self.failure());
        }
        Ok(())
    }

    /// Closes the pipe, waits for ffmpeg and renames the video into place.
    pub fn finish(mut self) -> Result<PathBuf, OutputError> {
        self.sender = None;
        let fed = self.feeder.take().map(|f| f.join());
        let status = self.wait_unless_cancelled()?;
        let fed_ok = matches!(fed, Some(Ok(Ok(()))));
        if !status.success() || !fed_ok {
            return Err(self.failure());
        }
        if let Some(temp) = self.temp.take() {
            temp.commit().map_err(|e| OutputError::io(&self.path, e))?;
        }
        Ok(self.path.clone())
    }

    /// ffmpeg's exit status; `Cancelled` as soon as the cancel flag is set (dropping the
    /// writer then stops ffmpeg and removes the temporary file).
    fn wait_unless_cancelled(&mut self) -> Result<ExitStatus, OutputError> {
        let io = |e| OutputError::io(&self.path, e);
        let Some(cancel) = self.cancel.clone() else {
            return self.child.wait().map_err(io);
        };
        loop {
            if let Some(status) = self.child.try_wait().map_err(io)? {
                return Ok(status);
            }
            if cancel.load(Ordering::Relaxed) {
                return Err(OutputError::Cancelled);
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    fn failure(&mut self) -> OutputError {
        self.sender = None;
        let _ = self.child.kill();
        let _ = self.child.wait();
        let stderr = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        let last = lines[lines.len().saturating_sub(5)..].join("\n  ");
        OutputError::Ffmpeg {
            path: self.path.clone(),
            stderr: if last.is_empty() {
                "(ffmpeg printed nothing)".into()
            } else {
                last
            },
        }
    }
}

impl Drop for FfmpegWriter {
    fn drop(&mut self) {
        // Unless finished: stop ffmpeg before the temporary file is removed.
        self.sender = None;
        let _ = self.child.kill();
        let _ = self.child.wait();
        if let Some(feeder) = self.feeder.take() {
            let _ = feeder.join();
        }
    }
}
