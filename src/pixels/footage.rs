//! Footage: takes a printf-style numbered image pattern (`plate_%04d.png`, `%d`, `%0Nd`,
//! `%%`) with a start number, or a video file decoded by an `ffmpeg` process, and gives one
//! frame at a time as a [`FloatImage`]. Only the frame asked for is held: sequences load one
//! file per frame, videos are streamed as raw RGBA frames at the scene's frame rate (frame i
//! is the picture shown at t = i / fps), never all at once.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};

use super::{FloatImage, PixelError, PixelFormat};

/// File extensions read as video (through ffmpeg) rather than as an image pattern.
pub const VIDEO_EXTENSIONS: [&str; 4] = ["mp4", "mov", "webm", "mkv"];

/// Whether `path` names a video file by its extension.
pub fn is_video_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| VIDEO_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// Why footage cannot be opened or read.
#[derive(Debug, thiserror::Error)]
pub enum FootageError {
    /// The pattern (the text as given) has no `%d` / `%0Nd`.
    #[error("pattern `{0}` has no frame number: use %d or %0Nd (e.g. frame_%04d.png)")]
    NoNumber(String),
    /// A `%` that starts neither `%d`, `%0Nd` nor `%%`, or a second number.
    #[error("pattern `{0}`: `%` must start %d, %0Nd or %% (one number per pattern)")]
    BadPattern(String),
    /// The number is in a folder name rather than the file name.
    #[error("pattern `{0}`: the number must be in the file name, not a folder")]
    NumberInFolder(String),
    /// No file in the folder matches the pattern (no start number can be found).
    #[error("pattern `{pattern}` matches no files in {}", folder.display())]
    NoFiles {
        /// The pattern as given.
        pattern: String,
        /// The folder searched.
        folder: PathBuf,
    },
    /// The path (or a frame's file) is a folder.
    #[error("{} is a folder, not an image or video", .0.display())]
    IsFolder(PathBuf),
    /// The video file does not exist.
    #[error("{} not found", .0.display())]
    NotFound(PathBuf),
    /// A frame's file is missing and the footage does not hold its last frame.
    #[error("frame {frame} needs {}, which does not exist{}", file.display(), hold_hint(hold_key, *held))]
    MissingFrame {
        /// The frame, counted from 1.
        frame: u64,
        /// The file it needs.
        file: PathBuf,
        /// The setting that would hold the last frame ([`Footage::hold_key`]).
        hold_key: String,
        /// Whether that setting is already on (then only an earlier file can help).
        held: bool,
    },
    /// A frame's size differs from the first frame's.
    #[error("{}: frame {frame} is {width}×{height}, but the footage is {expected_width}×{expected_height}", file.display())]
    SizeChanged {
        /// The frame's file.
        file: PathBuf,
        /// The frame, counted from 1.
        frame: u64,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The footage's width.
        expected_width: u32,
        /// The footage's height.
        expected_height: u32,
    },
    /// A video needs `ffmpeg` / `ffprobe`, and neither is on `PATH`.
    #[error("{}", crate::util::FFMPEG_MISSING_FOR_FOOTAGE)]
    NoFfmpeg,
    /// ffmpeg or ffprobe cannot read the video.
    #[error("cannot read video {}: {message}", path.display())]
    Video {
        /// The video file.
        path: PathBuf,
        /// What ffmpeg or ffprobe said (its last lines).
        message: String,
    },
    /// The video ends before the scene does and the footage does not hold its last frame.
    #[error("video {}: has {available} frames at the scene's fps, frame {frame} is needed (add `{hold_key}: true` to hold the last one)", path.display())]
    VideoTooShort {
        /// The video file.
        path: PathBuf,
        /// The first frame it lacks, counted from 1.
        frame: u64,
        /// Frames it has at the scene's frame rate.
        available: u64,
        /// The setting that would hold the last frame ([`Footage::hold_key`]).
        hold_key: String,
    },
    /// A frame's file cannot be read or decoded.
    #[error(transparent)]
    Image(#[from] Box<PixelError>),
}

/// The end of a missing-frame message: how holding would help, unless it is already on.
fn hold_hint(hold_key: &str, held: bool) -> String {
    if held {
        format!(" (`{hold_key}` holds the last file of the unbroken run from the first one; the first is missing)")
    } else {
        format!(" (add `{hold_key}: true` to hold the last one)")
    }
}

/// A printf-style file name: a prefix, one frame number (zero-padded to `digits`, 0 for
/// plain `%d`) and a suffix.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pattern {
    folder: PathBuf,
    prefix: String,
    digits: usize,
    suffix: String,
    text: String,
}

impl Pattern {
    /// Parses `path`; `Ok(None)` when it holds no `%` at all (a plain file name).
    pub fn parse(path: &Path) -> Result<Option<Pattern>, FootageError> {
        let text = path.to_string_lossy().into_owned();
        if !text.contains('%') {
            return Ok(None);
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
        if folder.to_string_lossy().contains('%') {
            return Err(FootageError::NumberInFolder(text));
        }
        let (prefix, digits, suffix) = split_name(&name).map_err(|bad| match bad {
            PatternProblem::NoNumber => FootageError::NoNumber(text.clone()),
            PatternProblem::Bad => FootageError::BadPattern(text.clone()),
        })?;
        Ok(Some(Pattern {
            folder,
            prefix,
            digits,
            suffix,
            text,
        }))
    }

    /// The file of frame number `n`.
    pub fn path(&self, n: u64) -> PathBuf {
        let digits = self.digits;
        let name = format!("{}{n:0digits$}{}", self.prefix, self.suffix);
        self.folder.join(name)
    }

    /// The pattern as given.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The number in `name` if it is one of this pattern's file names.
    fn number_of(&self, name: &str) -> Option<u64> {
        let middle = name
            .strip_prefix(&self.prefix)?
            .strip_suffix(&self.suffix)?;
        let all_digits = !middle.is_empty() && middle.bytes().all(|b| b.is_ascii_digit());
        let padded_ok = if self.digits == 0 {
            middle == "0" || !middle.starts_with('0')
        } else {
            middle.len() >= self.digits && (middle.len() == self.digits || !middle.starts_with('0'))
        };
        (all_digits && padded_ok).then(|| middle.parse().ok())?
    }

    /// The lowest frame number that has a file.
    pub fn lowest_number(&self) -> Result<u64, FootageError> {
        let folder = if self.folder.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &self.folder
        };
        let no_files = || FootageError::NoFiles {
            pattern: self.text.clone(),
            folder: folder.to_path_buf(),
        };
        let entries = std::fs::read_dir(folder).map_err(|_| no_files())?;
        entries
            .filter_map(|e| e.ok())
            .filter_map(|e| self.number_of(&e.file_name().to_string_lossy()))
            .min()
            .ok_or_else(no_files)
    }
}

enum PatternProblem {
    NoNumber,
    Bad,
}

/// Splits a file name around its one `%d` / `%0Nd`, unescaping `%%`.
fn split_name(name: &str) -> Result<(String, usize, String), PatternProblem> {
    let mut parts = (String::new(), String::new());
    let mut digits = None;
    let mut chars = name.chars().peekable();
    while let Some(c) = chars.next() {
        let part = if digits.is_some() {
            &mut parts.1
        } else {
            &mut parts.0
        };
        if c != '%' {
            part.push(c);
            continue;
        }
        if chars.peek() == Some(&'%') {
            chars.next();
            part.push('%');
            continue;
        }
        let mut width = String::new();
        while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
            width.push(*d);
            chars.next();
        }
        let zero_padded = width.is_empty() || (width.starts_with('0') && width.len() >= 2);
        if chars.next() != Some('d') || !zero_padded || digits.is_some() {
            return Err(PatternProblem::Bad);
        }
        let n: usize = if width.is_empty() {
            0
        } else {
            width.parse().map_err(|_| PatternProblem::Bad)?
        };
        if n > 18 {
            return Err(PatternProblem::Bad);
        }
        digits = Some(n);
    }
    let digits = digits.ok_or(PatternProblem::NoNumber)?;
    Ok((parts.0, digits, parts.1))
}

/// Where footage comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FootageSource {
    /// Numbered image files: scene frame i is file `start + i`.
    Sequence {
        /// The files' names.
        pattern: Pattern,
        /// The number of the file frame 0 shows.
        start: u64,
    },
    /// A video file, decoded by ffmpeg.
    Video(PathBuf),
}

/// Footage as a scene names it: where its frames come from, their size (all the same), and
/// whether the last frame holds once the footage runs out. [`Footage::open`] fills it in from
/// a pattern or a video path; a scene uses it as a background
/// ([`Background::Footage`](crate::animation::Background::Footage)) or as a patch's animated
/// source ([`Patch::footage`](crate::animation::Patch::footage)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Footage {
    /// The numbered files or the video.
    pub source: FootageSource,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Whether the last frame is shown once the footage runs out (else that is an error).
    pub hold: bool,
    /// The setting that sets `hold`, named in errors: `background_hold` or `source_hold` in a
    /// scene file; whatever name an embedding program shows its users.
    pub hold_key: String,
}

impl Footage {
    /// Opens footage at `path`: a printf-style pattern of numbered images
    /// (`plates/frame_%04d.png`) or a video file (`.mp4`, `.mov`, `.webm`, `.mkv`, read
    /// through ffmpeg). Finds the start number if not given (the lowest number with a file)
    /// and reads the first frame's size (a video's through ffprobe). `hold` and `hold_key`
    /// become the fields of the same names.
    pub fn open(
        path: &Path,
        start: Option<u64>,
        hold: bool,
        hold_key: &str,
    ) -> Result<Footage, FootageError> {
        if path.is_dir() {
            return Err(FootageError::IsFolder(path.to_path_buf()));
        }
        let (source, (width, height)) = if is_video_path(path) {
            if !path.is_file() {
                return Err(FootageError::NotFound(path.to_path_buf()));
            }
            (FootageSource::Video(path.to_path_buf()), probe_video(path)?)
        } else {
            let pattern =
                Pattern::parse(path)?.ok_or_else(|| FootageError::NoNumber(path_text(path)))?;
            let start = match start {
                Some(s) => s,
                None => pattern.lowest_number()?,
            };
            let first = pattern.path(start);
            if !first.is_file() {
                return Err(FootageError::MissingFrame {
                    frame: 1,
                    file: first,
                    hold_key: hold_key.into(),
                    held: hold,
                });
            }
            let size = image_size(&first)?;
            (FootageSource::Sequence { pattern, start }, size)
        };
        Ok(Footage {
            source,
            width,
            height,
            hold,
            hold_key: hold_key.into(),
        })
    }

    /// The file (or video) shown first, for messages and validation.
    pub fn first_path(&self) -> PathBuf {
        match &self.source {
            FootageSource::Sequence { pattern, start } => pattern.path(*start),
            FootageSource::Video(path) => path.clone(),
        }
    }

    /// The pattern or video path as the scene wrote it.
    pub fn describe(&self) -> String {
        match &self.source {
            FootageSource::Sequence { pattern, .. } => pattern.text().to_string(),
            FootageSource::Video(path) => path_text(path),
        }
    }

    /// Checks, before anything is rendered, that frames `0..frames` exist (or hold) and have
    /// the footage's size: every file of a sequence (its header), a video's duration from
    /// ffprobe.
    pub fn check_covers(&self, frames: u64, fps: f64) -> Result<(), FootageError> {
        match &self.source {
            FootageSource::Sequence { pattern, start } => {
                for i in 0..frames {
                    let file = pattern.path(start + i);
                    if !file.is_file() {
                        if self.hold && i > 0 {
                            return Ok(());
                        }
                        return Err(FootageError::MissingFrame {
                            frame: i + 1,
                            file,
                            hold_key: self.hold_key.clone(),
                            held: self.hold,
                        });
                    }
                    let (width, height) = image_size(&file)?;
                    if (width, height) != (self.width, self.height) {
                        return Err(FootageError::SizeChanged {
                            file,
                            frame: i + 1,
                            width,
                            height,
                            expected_width: self.width,
                            expected_height: self.height,
                        });
                    }
                }
                Ok(())
            }
            FootageSource::Video(path) => {
                let Some(seconds) = probe_duration(path)? else {
                    return Ok(());
                };
                // Frames whose time i / fps is before the end; half a frame of slack for
                // containers that round their duration.
                let available = (seconds * fps + 0.5).floor() as u64;
                if !self.hold && available < frames {
                    return Err(FootageError::VideoTooShort {
                        path: path.clone(),
                        frame: available + 1,
                        available,
                        hold_key: self.hold_key.clone(),
                    });
                }
                Ok(())
            }
        }
    }
}

fn path_text(path: &Path) -> String {
    path.to_string_lossy().into_owned()
}

fn image_size(path: &Path) -> Result<(u32, u32), FootageError> {
    image::image_dimensions(path).map_err(|source| {
        FootageError::Image(Box::new(PixelError::Decode {
            path: path.to_path_buf(),
            source,
        }))
    })
}

fn ffprobe() -> Result<PathBuf, FootageError> {
    crate::util::find_program("ffprobe").ok_or(FootageError::NoFfmpeg)
}

fn ffprobe_entry(path: &Path, entry: &str) -> Result<String, FootageError> {
    let output = Command::new(ffprobe()?)
        .args([
            "-v",
            "error",
            "-select_streams",
            "v:0",
            "-show_entries",
            entry,
        ])
        .args(["-of", "default=noprint_wrappers=1:nokey=1"])
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| video_error(path, e.to_string()))?;
    let text = String::from_utf8_lossy(&output.stdout).trim().to_string();
    if !output.status.success() || text.is_empty() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let last = last_lines(&stderr, 3);
        let message = if last.is_empty() {
            "no video stream".to_string()
        } else {
            last
        };
        return Err(video_error(path, message));
    }
    Ok(text)
}

fn probe_video(path: &Path) -> Result<(u32, u32), FootageError> {
    let text = ffprobe_entry(path, "stream=width,height")?;
    let mut numbers = text.lines().filter_map(|l| l.trim().parse::<u32>().ok());
    match (numbers.next(), numbers.next()) {
        (Some(w), Some(h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(video_error(path, format!("no frame size in `{text}`"))),
    }
}

/// The video's duration in seconds, if the container states one.
fn probe_duration(path: &Path) -> Result<Option<f64>, FootageError> {
    let text = ffprobe_entry(path, "format=duration")?;
    Ok(text
        .lines()
        .find_map(|l| l.trim().parse::<f64>().ok())
        .filter(|d| d.is_finite() && *d > 0.0))
}

fn video_error(path: &Path, message: String) -> FootageError {
    FootageError::Video {
        path: path.to_path_buf(),
        message,
    }
}

/// The last `n` non-empty lines of `text`, joined by "; ".
pub fn last_lines(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    lines[lines.len().saturating_sub(n)..].join("; ")
}

/// Reads footage frame by frame, keeping only the last frame read.
pub struct FootageReader {
    footage: Footage,
    fps: f64,
    current: Option<(u64, FloatImage)>,
    video: Option<VideoStream>,
}

impl FootageReader {
    pub fn new(footage: Footage, fps: f64) -> Self {
        FootageReader {
            footage,
            fps,
            current: None,
            video: None,
        }
    }

    pub fn footage(&self) -> &Footage {
        &self.footage
    }

    /// Scene frame `index` (from 0).
    pub fn frame(&mut self, index: u64) -> Result<&FloatImage, FootageError> {
        let fresh = !matches!(&self.current, Some((i, _)) if *i == index);
        if fresh {
            let image = match self.footage.source.clone() {
                FootageSource::Sequence { pattern, start } => {
                    self.sequence_frame(&pattern, start, index)?
                }
                FootageSource::Video(path) => self.video_frame(&path, index)?,
            };
            self.current = Some((index, image));
        }
        // invariant: `current` was set above when it did not hold `index`.
        Ok(&self.current.as_ref().expect("frame just read").1)
    }

    fn sequence_frame(
        &self,
        pattern: &Pattern,
        start: u64,
        index: u64,
    ) -> Result<FloatImage, FootageError> {
        // Saturating: a time far beyond any footage names a far frame, never frame 0.
        let mut file = pattern.path(start.saturating_add(index));
        if !file.is_file() && self.footage.hold {
            // The last file of the unbroken run from the start holds.
            let mut last = 0;
            while last < index && pattern.path(start + last + 1).is_file() {
                last += 1;
            }
            file = pattern.path(start + last);
        }
        if file.is_dir() {
            return Err(FootageError::IsFolder(file));
        }
        if !file.is_file() {
            return Err(FootageError::MissingFrame {
                frame: index.saturating_add(1),
                file,
                hold_key: self.footage.hold_key.clone(),
                held: self.footage.hold,
            });
        }
        let image = FloatImage::load(&file).map_err(|e| FootageError::Image(Box::new(e)))?;
        self.check_size(&file, index, image.width(), image.height())?;
        Ok(image)
    }

    fn check_size(&self, file: &Path, index: u64, w: u32, h: u32) -> Result<(), FootageError> {
        if (w, h) != (self.footage.width, self.footage.height) {
            return Err(FootageError::SizeChanged {
                file: file.to_path_buf(),
                frame: index.saturating_add(1),
                width: w,
                height: h,
                expected_width: self.footage.width,
                expected_height: self.footage.height,
            });
        }
        Ok(())
    }

    fn video_frame(&mut self, path: &Path, index: u64) -> Result<FloatImage, FootageError> {
        let (w, h) = (self.footage.width, self.footage.height);
        if self.video.as_ref().is_none_or(|v| v.next > index) {
            self.video = None;
            self.video = Some(VideoStream::start(path, w, h, self.fps)?);
        }
        // invariant: set just above when absent.
        let stream = self.video.as_mut().expect("stream started");
        while stream.next <= index {
            if !stream.read_next()? {
                break;
            }
        }
        match (&stream.last, stream.next > index || self.footage.hold) {
            (Some(bytes), true) => rgba8_image(w, h, bytes),
            _ => Err(FootageError::VideoTooShort {
                path: path.to_path_buf(),
                frame: index.saturating_add(1),
                available: stream.next,
                hold_key: self.footage.hold_key.clone(),
            }),
        }
    }
}

const OPAQUE_RGB8: PixelFormat = PixelFormat {
    alpha: false,
    ..PixelFormat::RGBA8
};

/// An 8-bit RGBA buffer as an opaque-format image of its levels.
fn rgba8_image(width: u32, height: u32, bytes: &[u8]) -> Result<FloatImage, FootageError> {
    let levels = bytes
        .chunks_exact(4)
        .map(|p| [p[0], p[1], p[2], p[3]])
        .collect();
    FloatImage::from_levels(width, height, levels, OPAQUE_RGB8)
        .map_err(|e| FootageError::Image(Box::new(e)))
}

/// An ffmpeg process decoding one video to raw RGBA frames at a fixed rate.
struct VideoStream {
    path: PathBuf,
    child: Child,
    stdout: ChildStdout,
    stderr: Option<std::thread::JoinHandle<String>>,
    frame_bytes: usize,
    /// Index of the next frame to read.
    next: u64,
    last: Option<Vec<u8>>,
    spare: Vec<u8>,
}

impl VideoStream {
    fn start(path: &Path, width: u32, height: u32, fps: f64) -> Result<Self, FootageError> {
        let ffmpeg = crate::util::find_program("ffmpeg").ok_or(FootageError::NoFfmpeg)?;
        let mut child = Command::new(ffmpeg)
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(path)
            .args(["-map", "0:v:0", "-vf", &format!("fps={fps}")])
            .args(["-f", "rawvideo", "-pix_fmt", "rgba", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| video_error(path, e.to_string()))?;
        // invariant: both were requested as pipes just above.
        let stdout = child.stdout.take().expect("piped stdout");
        let mut stderr = child.stderr.take().expect("piped stderr");
        let stderr = std::thread::spawn(move || {
            let mut text = String::new();
            let _ = stderr.read_to_string(&mut text);
            text
        });
        Ok(VideoStream {
            path: path.to_path_buf(),
            child,
            stdout,
            stderr: Some(stderr),
            frame_bytes: width as usize * height as usize * 4,
            next: 0,
            last: None,
            spare: Vec::new(),
        })
    }

    /// Reads the next frame into `last`; false at the end of the video (`last` keeps the
    /// final whole frame, for a hold).
    fn read_next(&mut self) -> Result<bool, FootageError> {
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
            .wait()
            .map_err(|e| video_error(&self.path, e.to_string()))?;
        let stderr = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        if !status.success() || self.next == 0 {
            let message = last_lines(&stderr, 3);
            let message = if message.is_empty() {
                "ffmpeg decoded no frames".to_string()
            } else {
                message
            };
            return Err(video_error(&self.path, message));
        }
        Ok(false)
    }
}

impl Drop for VideoStream {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_parse_and_format() {
        let p = Pattern::parse(Path::new("dir/plate_%04d.png"))
            .unwrap()
            .unwrap();
        assert_eq!(p.path(7), Path::new("dir/plate_0007.png"));
        assert_eq!(p.path(12345), Path::new("dir/plate_12345.png"));
        assert_eq!(p.number_of("plate_0042.png"), Some(42));
        assert_eq!(p.number_of("plate_042.png"), None);
        let q = Pattern::parse(Path::new("f%d_100%%.png")).unwrap().unwrap();
        assert_eq!(q.path(3), Path::new("f3_100%.png"));
        assert_eq!(q.number_of("f03_100%.png"), None);
        assert_eq!(q.number_of("f30_100%.png"), Some(30));
        assert!(Pattern::parse(Path::new("plain.png")).unwrap().is_none());
    }

    #[test]
    fn bad_patterns_are_refused() {
        for bad in ["a_%s.png", "a_%4d.png", "a_%d_%d.png", "a%"] {
            assert!(
                matches!(
                    Pattern::parse(Path::new(bad)),
                    Err(FootageError::BadPattern(_))
                ),
                "{bad}"
            );
        }
        assert!(matches!(
            Pattern::parse(Path::new("100%%.png")),
            Err(FootageError::NoNumber(_))
        ));
        assert!(matches!(
            Pattern::parse(Path::new("d%04d/a.png")),
            Err(FootageError::NumberInFolder(_))
        ));
    }
}
