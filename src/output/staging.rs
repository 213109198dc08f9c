//! A PNG frame folder written whole: takes the destination folder, the renderer's frame
//! count and the range being written, and gives a [`PngSequenceWriter`] into a temporary
//! folder beside the destination plus the [`PngStaging`] that moves the frames into place
//! once every one is written. Frame files of another render in the destination are refused,
//! or removed at the end with `force`, so the folder never holds a mixed set.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use super::request::{check_output_folder, FrameRange, SinkSettings};
use super::{foreign_frames, frame_digits, frame_file_name, OutputError, PngSequenceWriter};
use crate::render::Renderer;

/// A PNG sequence's frames, written into a temporary folder beside the destination and
/// moved into place only once every frame is written: a failed or interrupted render
/// leaves no new folder, and an existing folder exactly as it was.
pub(crate) struct PngStaging {
    dest: PathBuf,
    temp: crate::util::TempFolder,
    /// Frame files of an earlier render to remove at the end (`force`).
    foreign: Vec<PathBuf>,
}

impl PngStaging {
    /// Moves the written frames into the destination (or the whole folder, if it is new).
    pub(crate) fn commit(self, written: &[PathBuf]) -> Result<PathBuf, OutputError> {
        let dest = self.dest;
        let moving = |source| OutputError::Moving {
            dest: dest.clone(),
            source,
        };
        if !dest.exists() {
            let temp = self.temp.keep();
            if let Err(e) = std::fs::rename(&temp, &dest) {
                let _ = std::fs::remove_dir_all(&temp);
                return Err(moving(e));
            }
            return Ok(dest);
        }
        for path in &self.foreign {
            std::fs::remove_file(path).map_err(|source| OutputError::Removing {
                path: path.clone(),
                source,
            })?;
        }
        for path in written {
            // invariant: the writer names every frame `temp/frame_N.png`.
            let name = path.file_name().expect("a frame file name");
            std::fs::rename(path, dest.join(name)).map_err(moving)?;
        }
        Ok(dest)
    }
}

/// The PNG frame folder (created at the end if missing, its parent never) and the writer
/// into its temporary twin.
pub(crate) fn open_png_folder(
    output: &Path,
    renderer: &Renderer,
    range: FrameRange,
    jobs: usize,
    cancel: Arc<AtomicBool>,
    settings: SinkSettings,
) -> Result<(PngSequenceWriter, PngStaging), OutputError> {
    let foreign = if output.is_dir() {
        existing_frames(output, renderer.frame_count(), range, settings)?
    } else if output.exists() || output.symlink_metadata().is_ok() {
        return Err(OutputError::NotAFrameFolder(output.to_path_buf()));
    } else {
        check_output_folder(output)?;
        Vec::new()
    };
    let temp = crate::util::TempFolder::beside(output).map_err(|source| {
        OutputError::CreatingFolder {
            beside: output.to_path_buf(),
            source,
        }
    })?;
    let writer = PngSequenceWriter::new(
        temp.path(),
        renderer.frame_count(),
        jobs,
        settings.png_compression,
        cancel,
    )?;
    let staging = PngStaging {
        dest: output.to_path_buf(),
        temp,
        foreign,
    };
    Ok((writer, staging))
}

/// The frame files of another render in the existing folder `output`: an error without
/// `force`, else the files to remove once the new frames are in.
fn existing_frames(
    output: &Path,
    frame_count: u64,
    range: FrameRange,
    settings: SinkSettings,
) -> Result<Vec<PathBuf>, OutputError> {
    let digits = frame_digits(frame_count);
    let ours: std::collections::BTreeSet<String> = (range.first..=range.last)
        .map(|n| frame_file_name(n, digits))
        .collect();
    let foreign =
        foreign_frames(output, |name| ours.contains(name)).map_err(|source| {
            OutputError::ReadingFolder {
                path: output.to_path_buf(),
                source,
            }
        })?;
    // A folder, FIFO or link with a frame's name would be replaced by a rename, or fail it
    // half-way through the moves: refused before anything is rendered.
    let named = ours.iter().map(|name| output.join(name));
    for path in named.chain(foreign.iter().cloned()) {
        if let Some(kind) = not_a_plain_file(&path) {
            return Err(OutputError::NotAFrameFile { path, kind });
        }
    }
    if let Some(first) = foreign.first() {
        if !settings.force {
            return Err(OutputError::ForeignFrames {
                folder: output.to_path_buf(),
                count: foreign.len(),
                example: first.file_name().unwrap_or_default().to_string_lossy().into_owned(),
            });
        }
    }
    Ok(foreign)
}

/// What `path` is when it exists and is no regular file (a link counts as a link, whatever
/// it points to); `None` for a regular file or nothing there.
fn not_a_plain_file(path: &Path) -> Option<&'static str> {
    let meta = path.symlink_metadata().ok()?;
    if meta.file_type().is_symlink() {
        return Some("is a symbolic link");
    }
    crate::util::not_a_file(path)
}
