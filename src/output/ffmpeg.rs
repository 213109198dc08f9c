//! Video files through an `ffmpeg` process: takes frames in order and gives an MP4, WebM or
//! MOV. Frames go down a pipe (written by a thread of their own, so encoding overlaps
//! rendering) into ffmpeg, which writes a temporary file; it is renamed onto the destination
//! only when ffmpeg exits 0. On failure the last lines ffmpeg printed are in the error; an
//! abandoned writer kills ffmpeg and leaves no file.
//!
//! ffmpeg is started by [`FfmpegWriter::start`] before the frames are known, so that its own
//! start-up (loading a few hundred shared libraries) overlaps the caller's loading of the
//! scene; [`PendingVideo::begin`] then takes the frames' size and rate.
//!
//! Codecs: MP4 is H.264 in yuv420p at constant quality (CRF 20 by default); WebM is VP9 in
//! yuv420p at constant quality (CRF 32); MOV is H.264 like MP4 for opaque frames and ProRes
//! 4444 with alpha when the canvas has transparency (CRF does not apply to it).
//!
//! For the 4:2:0 codecs lapclone converts each frame itself (the `yuv` module: BT.709,
//! limited range, integer maths, in row bands on the caller's threads) and feeds ffmpeg a
//! 4:2:0 Y4M stream, 1.5 bytes a pixel instead of RGBA's 4, sparing ffmpeg its serial
//! conversion; the stream's header carries size, rate, centred chroma and limited range, and
//! the encoded stream is tagged BT.709 / limited range so players decode the colours
//! lapclone meant. 4:2:0 needs even sides: an odd side is padded by one pixel (repeating the
//! last row or column), which [`FfmpegWriter::padded`] reports. ProRes 4444 is fed raw RGBA
//! and converted by ffmpeg (to 10-bit 4:4:4 with alpha), with the same BT.709 matrix,
//! limited range and tags.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{ChildStdin, Command, ExitStatus, Stdio};
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::Arc;
use std::thread::JoinHandle;

use crate::util::TempOutput;
use super::yuv::{frame_to_yuv420, yuv420_size};
use super::y4m::{check_stream, fps_fraction, stream_header};
use super::{FrameRef, OutputError};
use crate::process::Child;

/// How lapclone's videos are tagged, as ffmpeg options (before `-i` for the 4:2:0 input,
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

/// The frames a video receives, known once the scene is loaded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VideoFrames {
    pub width: u32,
    pub height: u32,
    pub fps: f64,
    /// Whether frames have transparency worth keeping (MOV only).
    pub alpha: bool,
}

/// Everything about a video: the container and quality (known before any frame) and the
/// frames.
#[derive(Clone, Copy, Debug, PartialEq)]
struct VideoOptions {
    kind: VideoKind,
    /// Constant-quality value; the codec's default when `None`.
    crf: Option<u32>,
    frames: VideoFrames,
}

impl VideoOptions {
    /// Whether this encodes ProRes 4444 with alpha rather than 4:2:0.
    fn keeps_alpha(&self) -> bool {
        self.frames.alpha && self.kind == VideoKind::Mov
    }

    /// The encoded size: sides padded to even for 4:2:0.
    fn encoded_size(&self) -> (u32, u32) {
        if self.keeps_alpha() {
            (self.frames.width, self.frames.height)
        } else {
            yuv420_size(self.frames.width, self.frames.height)
        }
    }

    /// The ffmpeg arguments for the input on standard input, `-i -` included: a 4:2:0 Y4M
    /// stream (its header carries size and rate), or raw RGBA of the frames' size for ProRes.
    fn input_args(&self) -> Vec<String> {
        if !self.keeps_alpha() {
            return y4m_input_args();
        }
        let (w, h) = self.encoded_size();
        let (num, den) = fps_fraction(self.frames.fps);
        let mut args: Vec<String> = ["-f", "rawvideo", "-pix_fmt", "rgba"]
            .map(String::from)
            .into();
        args.extend(["-s".into(), format!("{w}x{h}")]);
        args.extend(["-framerate".into(), format!("{num}/{den}")]);
        args.extend(["-i", "-"].map(String::from));
        args
    }

    /// The Y4M stream header of the 4:2:0 input: centred chroma (`C420jpeg`, each chroma
    /// sample its 2×2 block's mean) and limited range.
    fn y4m_header(&self) -> Vec<u8> {
        let (w, h) = self.encoded_size();
        stream_header(w, h, self.frames.fps, "C420jpeg").into_bytes()
    }
}

/// The ffmpeg input arguments of a 4:2:0 Y4M stream on standard input: the same whatever the
/// frames, so ffmpeg can start before they are known.
fn y4m_input_args() -> Vec<String> {
    let mut args: Vec<String> = vec!["-f".into(), "yuv4mpegpipe".into()];
    args.extend(BT709_TAGS.map(String::from));
    args.extend(["-i", "-"].map(String::from));
    args
}

/// The ffmpeg arguments after the input, up to (not including) the output path.
fn codec_args(kind: VideoKind, crf: Option<u32>, keeps_alpha: bool) -> Vec<String> {
    let crf = crf.unwrap_or(kind.default_crf()).to_string();
    let mut args: Vec<String> = Vec::new();
    let codec: &[&str] = if keeps_alpha {
        &[
            // ffmpeg's own RGB→YUV defaults to the BT.601 matrix, while players take HD
            // video as BT.709: convert with BT.709 and say so in the stream.
            "-vf",
            "scale=out_color_matrix=bt709:out_range=tv",
            "-c:v",
            "prores_ks",
            "-profile:v",
            "4444",
            "-pix_fmt",
            "yuva444p10le",
            // The ProRes encoder leaves the colour fields of its frame headers unset; this
            // filter writes them (and ffprobe and players read them from there).
            "-bsf:v",
            "prores_metadata=color_primaries=bt709:color_trc=bt709:colorspace=bt709",
        ]
    } else {
        match kind {
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
    if !keeps_alpha {
        args.push(crf);
        args.extend(["-chroma_sample_location", "center"].map(String::from));
    }
    args.extend(BT709_TAGS.map(String::from));
    if kind != VideoKind::Webm {
        args.extend(["-movflags".into(), "+faststart".into()]);
    } else {
        // The Matroska muxer writes a random segment UID otherwise: the same scene would
        // give other bytes on every run.
        args.extend(["-fflags".into(), "+bitexact".into()]);
    }
    args.extend(["-f".into(), kind.muxer().into()]);
    args
}

/// The ffmpeg process and the temporary file it writes. Dropped unfinished, it stops
/// ffmpeg (the child field drops first), then the temporary file is removed.
struct Encoder {
    child: Child,
    temp: Option<TempOutput>,
}

/// A started ffmpeg with its input pipe still in hand.
struct Spawned {
    encoder: Encoder,
    stdin: ChildStdin,
}

/// Starts ffmpeg writing `path`'s temporary file with `args` (input and codec).
fn spawn_ffmpeg(path: &Path, args: Vec<String>) -> Result<Spawned, OutputError> {
    let ffmpeg = crate::util::find_program("ffmpeg").ok_or(OutputError::NoFfmpeg)?;
    let temp = TempOutput::new(path).map_err(|e| OutputError::io(path, e))?;
    let mut command = Command::new(ffmpeg);
    command
        .args(["-v", "error", "-nostdin", "-y"])
        .args(args)
        .arg(temp.temp_path())
        .stdin(Stdio::piped())
        .stdout(Stdio::null());
    #[cfg(unix)]
    {
        // Its own process group: Ctrl-C reaches lapclone, which then stops ffmpeg and
        // removes the file, instead of ffmpeg finishing a partial video by itself.
        use std::os::unix::process::CommandExt;
        command.process_group(0);
    }
    let mut child = Child::spawn(&mut command).map_err(|e| OutputError::io(path, e))?;
    // invariant: requested as a pipe just above.
    let stdin = child.take_stdin().expect("piped stdin");
    widen_pipe(&stdin);
    Ok(Spawned {
        encoder: Encoder {
            child,
            temp: Some(temp),
        },
        stdin,
    })
}

/// Asks for a 1 MiB pipe (Linux), so a frame crosses in a few writes instead of dozens. A
/// refusal (a lower system limit) keeps the default size, which is only slower.
#[cfg(target_os = "linux")]
fn widen_pipe(stdin: &ChildStdin) {
    let _ = rustix::pipe::fcntl_setpipe_size(stdin, 1 << 20);
}

#[cfg(not(target_os = "linux"))]
fn widen_pipe(_: &ChildStdin) {}

/// A video whose ffmpeg is started before its frames are known, so that ffmpeg's own
/// start-up (loading its libraries) overlaps the caller's loading of the scene. MP4 and
/// WebM start at once; MOV starts in [`begin`](Self::begin), since its codec depends on
/// whether the frames have alpha. Dropped before `begin`, it stops ffmpeg and leaves no
/// file.
pub struct PendingVideo {
    path: PathBuf,
    kind: VideoKind,
    crf: Option<u32>,
    spawned: Option<Spawned>,
}

impl PendingVideo {
    /// Takes the frames: writes the stream header (4:2:0) or starts ffmpeg (MOV), and gives
    /// the writer that converts frames on up to `threads` threads.
    pub fn begin(self, frames: VideoFrames, threads: usize) -> Result<FfmpegWriter, OutputError> {
        let options = VideoOptions {
            kind: self.kind,
            crf: self.crf,
            frames,
        };
        check_stream("a video", frames.width, frames.height, frames.fps)?;
        let spawned = match self.spawned {
            Some(spawned) => spawned,
            None => {
                let args = [
                    options.input_args(),
                    codec_args(options.kind, options.crf, options.keeps_alpha()),
                ]
                .concat();
                spawn_ffmpeg(&self.path, args)?
            }
        };
        Ok(FfmpegWriter::feed(self.path, spawned, options, threads))
    }
}

/// An ffmpeg process encoding frames into a temporary file next to the destination.
pub struct FfmpegWriter {
    path: PathBuf,
    encoder: Encoder,
    sender: Option<SyncSender<Vec<u8>>>,
    spare: Receiver<Vec<u8>>,
    feeder: Option<JoinHandle<std::io::Result<()>>>,
    options: VideoOptions,
    /// Threads converting a frame to 4:2:0.
    threads: usize,
    /// Set by Ctrl-C: [`finish`](Self::finish) stops waiting for ffmpeg and fails.
    cancel: Option<Arc<AtomicBool>>,
}

impl FfmpegWriter {
    /// Starts ffmpeg for a `kind` video at `path` at quality `crf` (the codec's default when
    /// `None`), before its frames are known; fails with the install hint when ffmpeg is not
    /// on `PATH`.
    pub fn start(path: &Path, kind: VideoKind, crf: Option<u32>) -> Result<PendingVideo, OutputError> {
        let spawned = match kind {
            VideoKind::Mov => {
                crate::util::find_program("ffmpeg").ok_or(OutputError::NoFfmpeg)?;
                None
            }
            VideoKind::Mp4 | VideoKind::Webm => {
                let args = [y4m_input_args(), codec_args(kind, crf, false)].concat();
                Some(spawn_ffmpeg(path, args)?)
            }
        };
        Ok(PendingVideo {
            path: path.to_path_buf(),
            kind,
            crf,
            spawned,
        })
    }

    /// Hands the pipe to a feeding thread, after the stream header for a 4:2:0 input.
    fn feed(path: PathBuf, spawned: Spawned, options: VideoOptions, threads: usize) -> Self {
        let Spawned {
            encoder,
            mut stdin,
        } = spawned;
        let y4m = !options.keeps_alpha();
        let header = if y4m { options.y4m_header() } else { Vec::new() };
        let (sender, frames) = sync_channel::<Vec<u8>>(8);
        let (spare_sender, spare) = sync_channel::<Vec<u8>>(10);
        let feeder = std::thread::spawn(move || {
            stdin.write_all(&header)?;
            for frame in frames {
                if y4m {
                    stdin.write_all(b"FRAME\n")?;
                }
                stdin.write_all(&frame)?;
                let _ = spare_sender.try_send(frame);
            }
            stdin.flush()
        });
        FfmpegWriter {
            path,
            encoder,
            sender: Some(sender),
            spare,
            feeder: Some(feeder),
            options,
            threads: threads.max(1),
            cancel: None,
        }
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
        let frames = self.options.frames;
        (size != (frames.width, frames.height)).then_some(size)
    }

    /// Queues the next frame (of the video's size; 16-bit frames are rounded to 8 bits):
    /// converted to 4:2:0 here, or copied as RGBA for ProRes 4444.
    pub fn add(&mut self, frame: &FrameRef<'_>) -> Result<(), OutputError> {
        let frames = self.options.frames;
        if (frame.width(), frame.height()) != (frames.width, frames.height) {
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
        // ffmpeg exits 0 when finishing the file fails (a full disk): the file is then cut
        // short, and must not replace a good one.
        let last = self.encoder.child.last_lines(5);
        let finishing = ["Error writing trailer", "Error closing file"];
        if last.iter().any(|l| finishing.iter().any(|f| l.contains(f))) {
            let (path, stderr) = (self.path.clone(), last.join("\n  "));
            return Err(OutputError::Ffmpeg { path, stderr });
        }
        if let Some(temp) = self.encoder.temp.take() {
            temp.commit().map_err(|e| OutputError::io(&self.path, e))?;
        }
        Ok(self.path.clone())
    }

    /// ffmpeg's exit status; `Cancelled` as soon as the cancel flag is set (dropping the
    /// writer then stops ffmpeg and removes the temporary file).
    fn wait_unless_cancelled(&mut self) -> Result<ExitStatus, OutputError> {
        let waited = self.encoder.child.wait(self.cancel.as_deref());
        waited
            .map_err(|e| OutputError::io(&self.path, e))?
            .ok_or(OutputError::Cancelled)
    }

    fn failure(&mut self) -> OutputError {
        self.sender = None;
        self.encoder.child.stop();
        let last = self.encoder.child.last_lines(5).join("\n  ");
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
        // Unless finished: stop ffmpeg (so the feeder's write fails) before the temporary
        // file is removed.
        self.sender = None;
        self.encoder.child.stop();
        if let Some(feeder) = self.feeder.take() {
            let _ = feeder.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(kind: VideoKind, width: u32, height: u32, alpha: bool) -> VideoOptions {
        VideoOptions {
            kind,
            crf: None,
            frames: VideoFrames {
                width,
                height,
                fps: 30000.0 / 1001.0,
                alpha,
            },
        }
    }

    #[test]
    fn a_4_2_0_stream_says_its_padded_size_rate_siting_and_range_in_band() {
        let mp4 = options(VideoKind::Mp4, 95, 63, true);
        assert_eq!(
            String::from_utf8(mp4.y4m_header()).unwrap(),
            "YUV4MPEG2 W96 H64 F30000:1001 Ip A1:1 C420jpeg XCOLORRANGE=LIMITED\n"
        );
        // The command line names no size: ffmpeg can start before the frames are known.
        assert_eq!(mp4.input_args(), y4m_input_args());
        assert!(!mp4.input_args().iter().any(|a| a == "-s"));
    }

    #[test]
    fn prores_takes_raw_rgba_of_the_frames_size_on_the_command_line() {
        let mov = options(VideoKind::Mov, 95, 63, true);
        let args = mov.input_args().join(" ");
        assert!(args.contains("-pix_fmt rgba -s 95x63 -framerate 30000/1001"), "{args}");
        let codec = codec_args(VideoKind::Mov, None, mov.keeps_alpha()).join(" ");
        assert!(codec.contains("prores_ks"), "{codec}");
        // ffmpeg converts it with the matrix and range the stream is tagged with.
        assert!(codec.contains("out_color_matrix=bt709:out_range=tv"), "{codec}");
        assert!(codec.contains("prores_metadata=color_primaries=bt709"), "{codec}");
        assert!(codec.contains(&BT709_TAGS.join(" ")), "{codec}");
        // Opaque MOV frames are H.264 over the same Y4M input as MP4.
        let opaque = options(VideoKind::Mov, 95, 63, false);
        assert_eq!(opaque.input_args(), y4m_input_args());
        let codec = codec_args(VideoKind::Mov, Some(18), false).join(" ");
        assert!(codec.contains("libx264") && codec.contains("-crf 18"), "{codec}");
    }
}
