//! What ffprobe says of a video: takes its path and gives its frame size and stated
//! duration, or a [`FootageError::Video`] with ffprobe's last lines.

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};

use super::FootageError;
use crate::pixels::PixelError;
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

/// ffprobe's `key=value` lines for `entry` of the first video stream.
fn ffprobe_entry(path: &Path, entry: &str) -> Result<String, FootageError> {
    let mut child = spawn("ffprobe", path, |c| {
        c.args(["-v", "error", "-select_streams", "v:0", "-show_entries", entry])
            .args(["-of", "default=noprint_wrappers=1"])
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

/// The value of `key` in ffprobe's `key=value` lines.
fn value<T: std::str::FromStr>(text: &str, key: &str) -> Option<T> {
    text.lines()
        .find_map(|l| l.trim().strip_prefix(key)?.strip_prefix('='))
        .and_then(|v| v.trim().parse().ok())
}

/// The size of the video's first stream as ffmpeg decodes it: a stream stored turned a
/// quarter (a phone's, with a rotation in its display matrix) comes out upright, its width
/// and height swapped.
pub(super) fn probe_video(path: &Path) -> Result<(u32, u32), FootageError> {
    let text = ffprobe_entry(path, "stream=width,height:stream_side_data=rotation")?;
    let size = (value::<u32>(&text, "width"), value::<u32>(&text, "height"));
    let (Some(w), Some(h)) = size else {
        return Err(video_error(path, format!("no frame size in `{text}`")));
    };
    if w == 0 || h == 0 {
        return Err(video_error(path, format!("no frame size in `{text}`")));
    }
    // The frames are decoded whole: their size takes the image limits, as a plate's does.
    if let Err(source) = crate::limits::check_image_size(u64::from(w), u64::from(h)) {
        let path = path.to_path_buf();
        return Err(Box::new(PixelError::TooLarge { path, source }).into());
    }
    let rotation = value::<f64>(&text, "rotation").unwrap_or(0.0);
    let quarter = (rotation / 90.0).round().rem_euclid(2.0) == 1.0;
    Ok(if quarter { (h, w) } else { (w, h) })
}

/// The video's duration in seconds, if the container states one.
pub(super) fn probe_duration(path: &Path) -> Result<Option<f64>, FootageError> {
    let text = ffprobe_entry(path, "format=duration")?;
    Ok(value::<f64>(&text, "duration").filter(|d| d.is_finite() && *d > 0.0))
}
