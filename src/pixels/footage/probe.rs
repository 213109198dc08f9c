//! What ffprobe says of a video: takes its path and gives its frame size and stated
//! duration, or a [`FootageError::Video`] with ffprobe's last lines.

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};

use super::FootageError;
use crate::process::Child;

/// Starts the program `name` (ffmpeg or ffprobe) with `command`'s arguments applied.
pub(super) fn spawn(
    name: &str,
    path: &Path,
    command: impl FnOnce(&mut Command) -> &mut Command,
) -> Result<Child, FootageError> {
    let program = crate::util::find_program(name).ok_or(FootageError::NoFfmpeg)?;
    Child::spawn(command(&mut Command::new(program))).map_err(|e| video_error(path, e.to_string()))
}

/// The error for `path` with what the stopped `child` printed last, or `otherwise`.
pub(super) fn failure(path: &Path, child: &mut Child, otherwise: &str) -> FootageError {
    let last = child.last_lines(3).join("; ");
    let message = if last.is_empty() { otherwise.into() } else { last };
    video_error(path, message)
}

pub(super) fn video_error(path: &Path, message: String) -> FootageError {
    FootageError::Video {
        path: path.to_path_buf(),
        message,
    }
}

fn ffprobe_entry(path: &Path, entry: &str) -> Result<String, FootageError> {
    let mut child = spawn("ffprobe", path, |c| {
        c.args(["-v", "error", "-select_streams", "v:0", "-show_entries", entry])
            .args(["-of", "default=noprint_wrappers=1:nokey=1"])
            .arg(path)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
    })?;
    let mut text = String::new();
    // invariant: requested as a pipe just above.
    let read = child.take_stdout().expect("piped stdout").read_to_string(&mut text);
    let status = child.wait(None).map_err(|e| video_error(path, e.to_string()))?;
    read.map_err(|e| video_error(path, e.to_string()))?;
    let text = text.trim().to_string();
    if !status.is_some_and(|s| s.success()) || text.is_empty() {
        return Err(failure(path, &mut child, "no video stream"));
    }
    Ok(text)
}

/// The size of the video's first stream.
pub(super) fn probe_video(path: &Path) -> Result<(u32, u32), FootageError> {
    let text = ffprobe_entry(path, "stream=width,height")?;
    let mut numbers = text.lines().filter_map(|l| l.trim().parse::<u32>().ok());
    match (numbers.next(), numbers.next()) {
        (Some(w), Some(h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(video_error(path, format!("no frame size in `{text}`"))),
    }
}

/// The video's duration in seconds, if the container states one.
pub(super) fn probe_duration(path: &Path) -> Result<Option<f64>, FootageError> {
    let text = ffprobe_entry(path, "format=duration")?;
    Ok(text
        .lines()
        .find_map(|l| l.trim().parse::<f64>().ok())
        .filter(|d| d.is_finite() && *d > 0.0))
}
