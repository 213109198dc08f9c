//! Numbered PNG frames in a folder: takes frames (with their frame numbers) and gives
//! `DIR/frame_0001.png …`, zero-padded to the width of the last frame number (at least 4
//! digits). Encoding runs on `jobs` worker threads while the caller renders the next frames;
//! each file is independent, so the bytes are identical for any number of jobs. Each frame
//! is written to a temporary file and renamed, so no half-written frame ever exists (files
//! are not fsynced: the guarantee is against failure and cancellation, not power loss).

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::Arc;

use crate::util::TempOutput;
use super::encode::{FrameEncoder, PngCompression};
use super::pool::WorkerPool;
use super::{Frame, OutputError};

/// `frame_` + the number zero-padded to `digits`.
pub fn frame_file_name(number: u64, digits: usize) -> String {
    format!("frame_{number:0digits$}.png")
}

/// Digits for numbers up to `last` (at least 4).
pub fn frame_digits(last: u64) -> usize {
    last.to_string().len().max(4)
}

/// Files in `dir` named like frames (`frame_` + digits + `.png`) for which `ours` is false:
/// the frames of another render, which a new render would leave beside its own.
pub fn foreign_frames(dir: &Path, ours: impl Fn(&str) -> bool) -> std::io::Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_frame = name
            .strip_prefix("frame_")
            .and_then(|rest| rest.strip_suffix(".png"))
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
        if is_frame && !ours(&name) {
            found.push(entry.path());
        }
    }
    found.sort();
    Ok(found)
}

/// Writes one frame file atomically (also usable without the worker pool); gives back the
/// frame `encoder` no longer needs.
pub fn write_png_file(
    path: &Path,
    frame: Frame,
    encoder: &mut FrameEncoder,
) -> Result<Option<Frame>, OutputError> {
    let io = |e: std::io::Error| OutputError::io(path, e);
    let temp = TempOutput::new(path).map_err(io)?;
    let file = temp.open().map_err(io)?;
    let mut out = BufWriter::with_capacity(1 << 16, file);
    let spare = encoder.encode(frame, &mut out)?;
    out.flush().map_err(io)?;
    drop(out);
    temp.commit().map_err(io)?;
    Ok(spare)
}

struct Job {
    path: PathBuf,
    frame: Frame,
}

/// A pool of PNG encoders writing numbered frames into a folder.
pub struct PngSequenceWriter {
    dir: PathBuf,
    digits: usize,
    pool: WorkerPool<Job, OutputError>,
    spare: Receiver<Frame>,
    cancel: Arc<AtomicBool>,
    written: Vec<PathBuf>,
}

impl PngSequenceWriter {
    /// Frames numbered up to `last_number` go into `dir` (which must exist), encoded by
    /// `jobs` threads (at least 1). Raising `cancel` stops after the frames in flight.
    pub fn new(
        dir: &Path,
        last_number: u64,
        jobs: usize,
        compression: PngCompression,
        cancel: Arc<AtomicBool>,
    ) -> Result<Self, OutputError> {
        if !dir.is_dir() {
            return Err(OutputError::NotAFolder(dir.to_path_buf()));
        }
        let jobs = jobs.max(1);
        let (spare_sender, spare) = sync_channel::<Frame>(2 * jobs + 2);
        let stop = cancel.clone();
        let pool = WorkerPool::new(jobs, move || {
            // Each worker compares a frame with the one it encoded before (a few frames
            // earlier), reusing the bands of unchanged rows.
            let mut encoder = FrameEncoder::new(compression);
            let (stop, spare_sender) = (stop.clone(), spare_sender.clone());
            move |job: Job| {
                if stop.load(Ordering::Relaxed) {
                    return Ok(()); // drain the queue without writing
                }
                if let Some(frame) = write_png_file(&job.path, job.frame, &mut encoder)? {
                    let _ = spare_sender.try_send(frame);
                }
                Ok(())
            }
        });
        Ok(PngSequenceWriter {
            dir: dir.to_path_buf(),
            digits: frame_digits(last_number),
            pool,
            spare,
            cancel,
            written: Vec::new(),
        })
    }

    pub fn path_for(&self, number: u64) -> PathBuf {
        self.dir.join(frame_file_name(number, self.digits))
    }

    /// A buffer of an already-written frame, to render the next frame into (no allocation).
    pub fn spare_frame(&self) -> Option<Frame> {
        self.spare.try_recv().ok()
    }

    /// Queues frame `number`; blocks while all workers are busy. Fails once a worker failed
    /// or the cancel flag is raised.
    pub fn submit(&mut self, number: u64, frame: Frame) -> Result<(), OutputError> {
        frame.as_ref()?;
        if self.cancel.load(Ordering::Relaxed) {
            return Err(OutputError::Cancelled);
        }
        if self.pool.failed() {
            return Err(self.take_error());
        }
        let path = self.path_for(number);
        self.written.push(path.clone());
        self.pool
            .send(Job { path, frame })
            .map_err(|_| OutputError::Cancelled)
    }

    /// Waits for every queued frame; gives the paths written, in submission order.
    pub fn finish(mut self) -> Result<Vec<PathBuf>, OutputError> {
        self.pool
            .stop(|| OutputError::Worker("a PNG encoder thread panicked".into()));
        if self.pool.failed() {
            return Err(self.take_error());
        }
        if self.cancel.load(Ordering::Relaxed) {
            return Err(OutputError::Cancelled);
        }
        Ok(std::mem::take(&mut self.written))
    }

    fn take_error(&self) -> OutputError {
        self.pool
            .take_error()
            .unwrap_or_else(|| OutputError::Worker("an earlier frame failed".into()))
    }
}
