//! Tracking: takes footage frames (as the footage reader gives them) and points to follow,
//! and gives per frame each point's sub-pixel position and confidence ([`PointTracker`]),
//! written as CSV ([`write_csv`]); and takes track files — that CSV, a plain CSV whose header
//! names its columns, or After Effects' "Keyframe Data" text — and gives the keys a scene
//! follows ([`TrackFile::load`], [`TrackFile::follow_keys`]). Malformed files are
//! [`TrackError::Malformed`] at their line. This stage knows no scene: the script stage
//! turns the keys into a patch's or a handle's tracks.

mod after_effects;
mod csv;
mod error;
mod lucas_kanade;
mod pyramid;
mod read_ahead;
mod tracker;

use crate::util::ShowPath;
use std::path::{Path, PathBuf};

use glam::DVec2;

pub use csv::{write_csv, TrackedFrame};
pub use error::TrackError;
pub use read_ahead::read_ahead;
pub use tracker::{pair_motion, Estimate, LostReason, PointTracker, TrackOptions, LOST_BELOW};

/// Largest track file read, in bytes.
pub const MAX_FILE_BYTES: u64 = 64 * 1024 * 1024;
/// Most rows (or keys) a track file may hold.
pub const MAX_ROWS: usize = 1_000_000;
/// Most points a track file may hold.
pub const MAX_POINTS: usize = 64;

/// When a row of a track happens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrackTime {
    /// A frame number as `render` numbers frames (the first is 1).
    Frame(u64),
    /// Seconds from the start.
    Seconds(f64),
}

impl TrackTime {
    /// Seconds from the start at `fps` frames per second.
    pub fn seconds(self, fps: f64) -> f64 {
        match self {
            TrackTime::Frame(n) => (n - 1) as f64 / fps,
            TrackTime::Seconds(s) => s,
        }
    }

    /// The frame number (from 1) shown at this time at `fps`.
    pub fn frame(self, fps: f64) -> u64 {
        match self {
            TrackTime::Frame(n) => n,
            TrackTime::Seconds(s) => (s * fps).round() as u64 + 1,
        }
    }
}

/// One row of a track: a point's position at a time, with what else the file gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackRow {
    /// When.
    pub time: TrackTime,
    /// Where, in pixels.
    pub at: DVec2,
    /// The tracker's confidence (0–1), when the file has it.
    pub confidence: Option<f64>,
    /// Rotation in degrees, when the file has it.
    pub rotate: Option<f64>,
    /// Uniform scale (1 = as at the start), when the file has it.
    pub scale: Option<f64>,
}

/// A loaded track: each point's rows in time order.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackFile {
    /// The file it came from.
    pub path: PathBuf,
    /// `points[i]` holds point i + 1's rows.
    pub points: Vec<Vec<TrackRow>>,
}

/// How a scene follows a track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FollowSettings {
    /// Which point drives the position (from 1).
    pub point: usize,
    /// Added to the point, turned and scaled with the track when those follow.
    pub offset: DVec2,
    /// Follow the track's rotation (`None`: when it has one).
    pub rotate: Option<bool>,
    /// Follow the track's scale (`None`: when it has one).
    pub scale: Option<bool>,
    /// Leave out rows before this frame (from 1).
    pub from_frame: Option<u64>,
}

impl Default for FollowSettings {
    fn default() -> Self {
        FollowSettings {
            point: 1,
            offset: DVec2::ZERO,
            rotate: None,
            scale: None,
            from_frame: None,
        }
    }
}

/// One key of a followed track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FollowKey {
    /// Seconds.
    pub t: f64,
    /// The point plus the offset.
    pub at: DVec2,
    /// Rotation in degrees, when followed.
    pub rotate: Option<f64>,
    /// Scale, when followed.
    pub scale: Option<f64>,
}

impl TrackFile {
    /// Reads `path`: After Effects keyframe text when it starts so, otherwise CSV.
    pub fn load(path: &Path) -> Result<TrackFile, TrackError> {
        let read = |source| TrackError::Read {
            path: path.to_path_buf(),
            source,
        };
        let Some(bytes) = crate::util::read_input_file(path, MAX_FILE_BYTES).map_err(read)? else {
            return Err(read(std::io::Error::other(format!(
                "it holds more than the {MAX_FILE_BYTES} bytes a track may have"
            ))));
        };
        let malformed = |line, message: &str| TrackError::Malformed {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        };
        if bytes.is_empty() {
            return Err(malformed(1, "the file is empty (0 bytes): expected a header line"));
        }
        let text = std::str::from_utf8(&bytes).map_err(|e| {
            let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
            malformed(line, "not UTF-8 text")
        })?;
        let points = if after_effects::is_keyframe_data(text) {
            after_effects::parse(text)
        } else {
            csv::parse(text)
        }
        .map_err(|(line, message)| malformed(line, &message))?;
        Ok(TrackFile {
            path: path.to_path_buf(),
            points,
        })
    }

    /// The keys that follow point `settings.point` at `fps`; rows the tracker marked lost
    /// (confidence below [`LOST_BELOW`]) are left out, so a patch glides over the gap.
    pub fn follow_keys(&self, settings: &FollowSettings, fps: f64) -> Result<Vec<FollowKey>, String> {
        let count = self.points.len();
        let rows = settings
            .point
            .checked_sub(1)
            .and_then(|i| self.points.get(i))
            .ok_or_else(|| {
                format!(
                    "point {} is not in {} (it has {count} point{})",
                    settings.point,
                    self.path.shown(),
                    if count == 1 { "" } else { "s" }
                )
            })?;
        let has = |f: fn(&TrackRow) -> Option<f64>| rows.iter().any(|r| f(r).is_some());
        let rotate = wanted(settings.rotate, has(|r| r.rotate), "rotate", &self.path)?;
        let scale = wanted(settings.scale, has(|r| r.scale), "scale", &self.path)?;
        let keys: Vec<FollowKey> = rows
            .iter()
            .filter(|r| r.confidence.is_none_or(|c| c >= LOST_BELOW))
            .filter(|r| settings.from_frame.is_none_or(|f| r.time.frame(fps) >= f))
            .map(|r| {
                let turn = if rotate { r.rotate.unwrap_or(0.0) } else { 0.0 };
                let size = if scale { r.scale.unwrap_or(1.0) } else { 1.0 };
                let offset = DVec2::from_angle(turn.to_radians()).rotate(settings.offset) * size;
                FollowKey {
                    t: r.time.seconds(fps),
                    at: r.at + offset,
                    rotate: rotate.then_some(turn),
                    scale: scale.then_some(size),
                }
            })
            .collect();
        if keys.is_empty() {
            return Err(format!(
                "{} has no sure rows to follow for point {}{}",
                self.path.shown(),
                settings.point,
                settings
                    .from_frame
                    .map(|f| format!(" from frame {f}"))
                    .unwrap_or_default()
            ));
        }
        Ok(keys)
    }
}

/// Whether to follow a channel: as asked, or when the track has it; asking for one it lacks
/// is an error.
fn wanted(asked: Option<bool>, present: bool, name: &str, path: &Path) -> Result<bool, String> {
    match asked {
        Some(true) if !present => Err(format!(
            "`{name}: true`, but {} has no {name} column (a two-point track or an imported one has)",
            path.shown()
        )),
        Some(value) => Ok(value),
        None => Ok(present),
    }
}

/// Most characters of a file's text an error quotes.
const SHOWN: usize = 60;

/// `text` as an error quotes it: at most [`SHOWN`] characters, control characters escaped.
pub(super) fn shown(text: &str) -> String {
    let mut out: String = text.chars().take(SHOWN).flat_map(char::escape_debug).collect();
    let length = text.chars().count();
    if length > SHOWN {
        out.push_str(&format!("… ({length} characters)"));
    }
    out
}

/// A track file's lines, numbered from 1, as every reader takes them: a byte-order mark (as
/// spreadsheets and editors write "UTF-8 with BOM") is skipped, and a line may end in `\n`,
/// `\r\n` or a lone `\r` (old Mac text), even mixed in one file.
fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    text.split('\n')
        .flat_map(|line| line.strip_suffix('\r').unwrap_or(line).split('\r'))
        .enumerate()
        .map(|(i, line)| (i + 1, line))
}
