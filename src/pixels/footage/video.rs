//! A video decoded by an `ffmpeg` process: takes its path, frame size and the scene's frame
//! rate and gives raw RGBA frames one at a time, holding only the last one read.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{ChildStdout, Stdio};

use super::probe::{failure, spawn, video_error};
use super::FootageError;
use crate::process::Child;

/// An ffmpeg process decoding one video to raw RGBA frames at a fixed rate.
pub(super) struct VideoStream {
    path: PathBuf,
    size: (u32, u32),
    fps: f64,
    /// Decoding only the video's first frame, without the rate filter: for a video shorter
    /// than one frame at the scene's rate, of which the filter gives none.
    first_only: bool,
    child: Child,
    stdout: ChildStdout,
    frame_bytes: usize,
    /// Index of the next frame to read.
    pub(super) next: u64,
    /// The last whole frame read.
    pub(super) last: Option<Vec<u8>>,
    spare: Vec<u8>,
}

impl VideoStream {
    pub(super) fn start(path: &Path, width: u32, height: u32, fps: f64) -> Result<Self, FootageError> {
        Self::start_with(path, (width, height), fps, false)
    }

    fn start_with(
        path: &Path,
        (width, height): (u32, u32),
        fps: f64,
        first_only: bool,
    ) -> Result<Self, FootageError> {
        let rate = format!("fps={fps}");
        let frames: [&str; 2] = match first_only {
            true => ["-frames:v", "1"],
            false => ["-vf", &rate],
        };
        let mut child = spawn("ffmpeg", path, |c| {
            c.args(["-v", "error", "-nostdin", "-i"])
                .arg(path)
                .args(["-map", "0:v:0"])
                .args(frames)
                .args(["-f", "rawvideo", "-pix_fmt", "rgba", "-"])
                .stdin(Stdio::null())
                .stdout(Stdio::piped())
        })?;
        // invariant: requested as a pipe just above.
        let stdout = child.take_stdout().expect("piped stdout");
        Ok(VideoStream {
            path: path.to_path_buf(),
            size: (width, height),
            fps,
            first_only,
            child,
            stdout,
            frame_bytes: width as usize * height as usize * 4,
            next: 0,
            last: None,
            spare: Vec::new(),
        })
    }

    /// Reads the next frame into `last`; false at the end of the video (`last` keeps the
    /// final whole frame, for a hold).
    pub(super) fn read_next(&mut self) -> Result<bool, FootageError> {
        self.spare.resize(self.frame_bytes, 0);
        let mut filled = 0;
        while filled < self.spare.len() {
            match self.stdout.read(&mut self.spare[filled..]) {
                Ok(0) => break,
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(video_error(&self.path, e.to_string())),
            }
        }
        if filled == self.spare.len() {
            let previous = self.last.replace(std::mem::take(&mut self.spare));
            self.spare = previous.unwrap_or_default();
            self.next += 1;
            return Ok(true);
        }
        let status = self
            .child
            .wait(None)
            .map_err(|e| video_error(&self.path, e.to_string()))?;
        let succeeded = status.is_some_and(|s| s.success());
        if succeeded && self.next == 0 && !self.first_only {
            // A video shorter than one frame at the scene's rate (1 s at 0.4 fps): the rate
            // filter gives no frame, though frame 1, the picture at t = 0, is in the video.
            // Only then is its first frame decoded on its own; every other video keeps the
            // frames the filter gives.
            *self = Self::start_with(&self.path, self.size, self.fps, true)?;
            return self.read_next();
        }
        if !succeeded || self.next == 0 {
            return Err(failure(&self.path, &mut self.child, "ffmpeg decoded no frames"));
        }
        Ok(false)
    }
}
