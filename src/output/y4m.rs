//! YUV4MPEG2 (`.y4m`) from frames, written by lapclone itself (no ffmpeg): takes frames in
//! order and gives one uncompressed stream any encoder reads (`ffmpeg -i x.y4m`, `x264`,
//! `aomenc`…), to a file (temporary file, renamed on [`Y4mWriter::finish`]) or to standard
//! output.
//!
//! The stream is 8-bit 4:4:4 (`C444`, no chroma subsampling, so odd sizes need nothing
//! special), progressive, square pixels, at the scene's fps as a fraction. Colours are
//! converted with [`rgb_to_ycbcr`] (the `yuv` module, shared with the ffmpeg pipe): BT.709
//! coefficients, limited ("TV") range — what encoders assume for HD when a stream says
//! nothing else. Y4M has no alpha: a transparent pixel is shown composited over black.
//! 16-bit frames are rounded to 8 bits first.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::util::TempOutput;
use super::yuv::rgb_to_ycbcr;
use super::{FrameRef, OutputError};

/// `fps` as the fraction Y4M (and ffmpeg) wants: whole rates exactly, NTSC-style rates
/// over 1001, others as the nearest fraction with a denominator up to 1000 (`1/3` exactly,
/// `12.5` as `25/2`, a rate typed to the thousandth as typed).
pub fn fps_fraction(fps: f64) -> (u64, u64) {
    if (fps - fps.round()).abs() < 1e-9 {
        return (fps.round() as u64, 1);
    }
    let ntsc = fps * 1001.0;
    if (ntsc - ntsc.round()).abs() < 1e-6 {
        return (ntsc.round() as u64, 1001);
    }
    nearest_fraction(fps, 1000)
}

/// The fraction nearest `x` (positive) whose denominator is at most `max_den`: the last
/// continued-fraction convergent within the bound, or the semiconvergent past it when that
/// is nearer.
fn nearest_fraction(x: f64, max_den: u64) -> (u64, u64) {
    // Convergents h/k, the one before in (h0, k0).
    let (mut h0, mut k0, mut h1, mut k1) = (0u64, 1u64, 1u64, 0u64);
    let mut rest = x;
    loop {
        let whole = rest.floor();
        let a = whole as u64;
        let (h2, k2) = (a.saturating_mul(h1).saturating_add(h0), a.saturating_mul(k1).saturating_add(k0));
        if k2 > max_den {
            let t = (max_den - k0) / k1;
            let (hs, ks) = (t * h1 + h0, t * k1 + k0);
            let error = |h: u64, k: u64| (h as f64 / k as f64 - x).abs();
            return if ks > 0 && error(hs, ks) < error(h1, k1) { (hs, ks) } else { (h1, k1) };
        }
        (h0, k0, h1, k1) = (h1, k1, h2, k2);
        let fraction = rest - whole;
        if fraction < 1e-9 {
            return (h1, k1);
        }
        rest = 1.0 / fraction;
    }
}

/// Refuses a stream (`what`) without a positive finite rate or with an empty side.
pub(super) fn check_stream(what: &str, width: u32, height: u32, fps: f64) -> Result<(), OutputError> {
    if !(fps.is_finite() && fps > 0.0) || width == 0 || height == 0 {
        return Err(OutputError::BadFrame(format!(
            "{what} needs fps > 0 and a size of at least 1×1, got {fps} and {width}×{height}"
        )));
    }
    Ok(())
}

/// A Y4M stream header: `width`×`height` progressive square pixels at `fps`, sampled as
/// `colour` (`C444`, `C420jpeg`…) in limited range.
pub fn stream_header(width: u32, height: u32, fps: f64, colour: &str) -> String {
    let (num, den) = fps_fraction(fps);
    format!("YUV4MPEG2 W{width} H{height} F{num}:{den} Ip A1:1 {colour} XCOLORRANGE=LIMITED\n")
}

/// Where a Y4M stream goes.
enum Sink {
    File {
        temp: TempOutput,
        path: PathBuf,
        out: BufWriter<std::fs::File>,
    },
    Stdout(BufWriter<std::io::Stdout>),
}

pub struct Y4mWriter {
    sink: Sink,
    width: u32,
    height: u32,
    rgba: Vec<u8>,
    planes: Vec<u8>,
}

impl Y4mWriter {
    /// A stream of `width`×`height` frames at `fps` into `path`, or standard output if
    /// `path` is `None`.
    pub fn create(
        path: Option<&Path>,
        width: u32,
        height: u32,
        fps: f64,
    ) -> Result<Self, OutputError> {
        check_stream("a Y4M stream", width, height, fps)?;
        let mut sink = match path {
            Some(path) => {
                let io = |e| OutputError::io(path, e);
                let temp = TempOutput::new(path).map_err(io)?;
                let file = temp.open().map_err(io)?;
                Sink::File {
                    temp,
                    path: path.to_path_buf(),
                    out: BufWriter::with_capacity(1 << 20, file),
                }
            }
            None => Sink::Stdout(BufWriter::with_capacity(1 << 20, std::io::stdout())),
        };
        let header = stream_header(width, height, fps, "C444");
        write_all(&mut sink, header.as_bytes())?;
        Ok(Y4mWriter {
            sink,
            width,
            height,
            rgba: Vec::new(),
            planes: Vec::new(),
        })
    }

    /// Appends the next frame (of the stream's size).
    pub fn add(&mut self, frame: &FrameRef<'_>) -> Result<(), OutputError> {
        if (frame.width(), frame.height()) != (self.width, self.height) {
            return Err(OutputError::BadFrame(format!(
                "frame is {}×{}, the stream {}×{}",
                frame.width(),
                frame.height(),
                self.width,
                self.height
            )));
        }
        frame.write_rgba8(&mut self.rgba);
        let n = self.width as usize * self.height as usize;
        self.planes.resize(3 * n, 0);
        let (y, chroma) = self.planes.split_at_mut(n);
        let (cb, cr) = chroma.split_at_mut(n);
        for (i, px) in self.rgba.chunks_exact(4).enumerate() {
            let [yy, u, v] = rgb_to_ycbcr([px[0], px[1], px[2], px[3]]);
            y[i] = yy;
            cb[i] = u;
            cr[i] = v;
        }
        write_all(&mut self.sink, b"FRAME\n")?;
        let planes = std::mem::take(&mut self.planes);
        let result = write_all(&mut self.sink, &planes);
        self.planes = planes;
        result
    }

    /// Flushes and, for a file, renames it into place; gives its path (`-` for stdout).
    pub fn finish(self) -> Result<PathBuf, OutputError> {
        match self.sink {
            Sink::File {
                temp,
                path,
                mut out,
            } => {
                out.flush().map_err(|e| OutputError::io(&path, e))?;
                drop(out);
                temp.commit().map_err(|e| OutputError::io(&path, e))?;
                Ok(path)
            }
            Sink::Stdout(mut out) => {
                out.flush()
                    .map_err(|e| OutputError::io(Path::new("standard output"), e))?;
                Ok(PathBuf::from("-"))
            }
        }
    }
}

fn write_all(sink: &mut Sink, bytes: &[u8]) -> Result<(), OutputError> {
    match sink {
        Sink::File { out, path, .. } => out.write_all(bytes).map_err(|e| OutputError::io(path, e)),
        Sink::Stdout(out) => out
            .write_all(bytes)
            .map_err(|e| OutputError::io(Path::new("standard output"), e)),
    }
}
