//! An animated PNG from frames: takes the frame count, fps and frames in order, gives one
//! file (looping forever), written through a temporary file and renamed on
//! [`ApngWriter::finish`], so a failed or cancelled write leaves nothing behind.
//!
//! Lossless frame differencing: each frame after the first stores only the bounding
//! rectangle of samples that differ from the previous frame (a 1×1 rectangle when nothing
//! changed), with `BlendOp::Source` and `DisposeOp::None`, so compositing the records gives
//! back every frame exactly, transparency included.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::util::TempOutput;
use super::{FrameRef, OutputError};

pub struct ApngWriter {
    path: PathBuf,
    temp: TempOutput,
    writer: png::Writer<BufWriter<File>>,
    delays: Vec<(u16, u16)>,
    written: usize,
    width: u32,
    height: u32,
    sixteen_bit: bool,
    scratch: Vec<u8>,
    previous: Vec<u8>,
    rect: Vec<u8>,
}

impl ApngWriter {
    /// An animation of `frame_count` frames of `width`×`height` (16-bit if `sixteen_bit`)
    /// shown at `fps`.
    pub fn create(
        path: &Path,
        width: u32,
        height: u32,
        sixteen_bit: bool,
        frame_count: u32,
        fps: f64,
    ) -> Result<Self, OutputError> {
        if frame_count == 0 || width == 0 || height == 0 {
            return Err(OutputError::BadFrame(
                "an animation needs at least one frame of at least 1×1".into(),
            ));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(OutputError::BadFrame(format!("fps {fps} must be > 0")));
        }
        let io = |e| OutputError::io(path, e);
        let temp = TempOutput::new(path).map_err(io)?;
        let file = temp.open().map_err(io)?;
        let mut encoder = png::Encoder::new(BufWriter::with_capacity(1 << 16, file), width, height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(if sixteen_bit {
            png::BitDepth::Sixteen
        } else {
            png::BitDepth::Eight
        });
        encoder.set_compression(png::Compression::Fast);
        encoder.set_animated(frame_count, 0)?;
        encoder.set_blend_op(png::BlendOp::Source)?;
        encoder.set_dispose_op(png::DisposeOp::None)?;
        let writer = encoder.write_header()?;
        Ok(ApngWriter {
            path: path.to_path_buf(),
            temp,
            writer,
            delays: apng_delays(frame_count as usize, fps),
            written: 0,
            width,
            height,
            sixteen_bit,
            scratch: Vec::new(),
            previous: Vec::new(),
            rect: Vec::new(),
        })
    }

    /// Appends the next frame; it must have the animation's size and bit depth.
    pub fn add(&mut self, frame: &FrameRef<'_>) -> Result<(), OutputError> {
        if (frame.width(), frame.height(), frame.is_16_bit())
            != (self.width, self.height, self.sixteen_bit)
        {
            return Err(OutputError::BadFrame(format!(
                "frame is {}×{} ({}-bit), the animation is {}×{} ({}-bit)",
                frame.width(),
                frame.height(),
                if frame.is_16_bit() { 16 } else { 8 },
                self.width,
                self.height,
                if self.sixteen_bit { 16 } else { 8 }
            )));
        }
        let Some(&(numerator, denominator)) = self.delays.get(self.written) else {
            return Err(OutputError::BadFrame(format!(
                "more frames than the {} announced",
                self.delays.len()
            )));
        };
        self.writer.set_frame_delay(numerator, denominator)?;
        frame.write_png_bytes(&mut self.scratch);
        if self.written == 0 {
            self.writer.write_image_data(&self.scratch)?;
        } else {
            self.write_changes()?;
        }
        std::mem::swap(&mut self.scratch, &mut self.previous);
        self.written += 1;
        Ok(())
    }

    /// Writes the rectangle of `scratch` that differs from `previous`.
    fn write_changes(&mut self) -> Result<(), OutputError> {
        let pixel = if self.sixteen_bit { 8 } else { 4 };
        let row = self.width as usize * pixel;
        let (x, y, w, h) =
            changed_rect(&self.scratch, &self.previous, row, pixel).unwrap_or((0, 0, 1, 1));
        self.rect.clear();
        for r in y..y + h {
            let start = r * row + x * pixel;
            self.rect
                .extend_from_slice(&self.scratch[start..start + w * pixel]);
        }
        // Shrinking first keeps every intermediate position in bounds.
        self.writer.set_frame_position(0, 0)?;
        self.writer.set_frame_dimension(w as u32, h as u32)?;
        self.writer.set_frame_position(x as u32, y as u32)?;
        self.writer.write_image_data(&self.rect)?;
        Ok(())
    }

    /// Completes the file and moves it into place; every announced frame must have been added.
    pub fn finish(self) -> Result<PathBuf, OutputError> {
        if self.written != self.delays.len() {
            return Err(OutputError::BadFrame(format!(
                "{} of {} frames written",
                self.written,
                self.delays.len()
            )));
        }
        self.writer.finish()?;
        self.temp
            .commit()
            .map_err(|e| OutputError::io(&self.path, e))?;
        Ok(self.path)
    }
}

/// (x, y, width, height) in pixels of the samples that differ, `None` if none do.
fn changed_rect(
    current: &[u8],
    previous: &[u8],
    row: usize,
    pixel: usize,
) -> Option<(usize, usize, usize, usize)> {
    let rows = || current.chunks_exact(row).zip(previous.chunks_exact(row));
    let top = rows().position(|(c, p)| c != p)?;
    let bottom = rows().rposition(|(c, p)| c != p)? + 1;
    let (mut left, mut right) = (usize::MAX, 0);
    for (c, p) in rows().take(bottom).skip(top) {
        if let Some(first) = c.iter().zip(p).position(|(a, b)| a != b) {
            // invariant: the row differs somewhere, so a last difference exists too.
            let last = c
                .iter()
                .zip(p)
                .rposition(|(a, b)| a != b)
                .expect("row differs"); // invariant: only rows that differ are searched
            left = left.min(first / pixel);
            right = right.max(last / pixel + 1);
        }
    }
    Some((left, top, right - left, bottom - top))
}

/// Per-frame delays as fractions of a second: `1/fps` exactly when the rate's fraction
/// ([`fps_fraction`](super::fps_fraction)) fits the 16-bit fields, otherwise the finest
/// unit (a millisecond, or coarser for slow rates) whose steps fit, rounded from the exact
/// frame times so the error never accumulates.
pub fn apng_delays(frames: usize, fps: f64) -> Vec<(u16, u16)> {
    let (num, den) = super::fps_fraction(fps);
    if let (Ok(num), Ok(den)) = (u16::try_from(num), u16::try_from(den)) {
        return vec![(den, num); frames];
    }
    let fits = |steps: &Vec<u64>| steps.iter().all(|&s| s <= u64::from(u16::MAX));
    for unit in [1000u16, 100, 10, 1] {
        let steps = super::rounded_steps(frames, fps, f64::from(unit));
        if fits(&steps) {
            return steps.into_iter().map(|s| (s as u16, unit)).collect();
        }
    }
    // Only past a frame every 65,535 s, far beyond the scene's slowest rate.
    vec![(u16::MAX, 1); frames]
}
