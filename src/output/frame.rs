//! Frames handed to the writers: RGBA pixels, 8 or 16 bits per channel, row-major, straight
//! alpha. [`FrameRef`] borrows them (what the renderer hands over), [`Frame`] owns them (what
//! a parallel writer queues and recycles).

use super::OutputError;

/// Borrowed RGBA samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pixels<'a> {
    Rgba8(&'a [u8]),
    Rgba16(&'a [u16]),
}

/// A borrowed frame whose sample count matches its size (checked by [`FrameRef::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRef<'a> {
    width: u32,
    height: u32,
    pixels: Pixels<'a>,
}

impl<'a> FrameRef<'a> {
    pub fn new(width: u32, height: u32, pixels: Pixels<'a>) -> Result<Self, OutputError> {
        let expected = width as usize * height as usize * 4;
        let actual = match pixels {
            Pixels::Rgba8(p) => p.len(),
            Pixels::Rgba16(p) => p.len(),
        };
        if width == 0 || height == 0 || actual != expected {
            return Err(OutputError::BadFrame(format!(
                "{width}×{height} RGBA needs {expected} samples, got {actual}"
            )));
        }
        Ok(FrameRef {
            width,
            height,
            pixels,
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn pixels(&self) -> Pixels<'a> {
        self.pixels
    }

    pub fn is_16_bit(&self) -> bool {
        matches!(self.pixels, Pixels::Rgba16(_))
    }

    /// Writes the 8-bit RGBA form into `out` (16-bit samples rounded to the nearest 8-bit).
    pub fn write_rgba8(&self, out: &mut Vec<u8>) {
        out.clear();
        match self.pixels {
            Pixels::Rgba8(p) => out.extend_from_slice(p),
            Pixels::Rgba16(p) => {
                out.extend(p.iter().map(|&v| ((v as u32 * 255 + 32767) / 65535) as u8))
            }
        }
    }

    /// Whether every pixel's alpha is full.
    pub fn is_opaque(&self) -> bool {
        match self.pixels {
            // Folded without an early exit, so it vectorises.
            Pixels::Rgba8(p) => p.chunks_exact(4).fold(u8::MAX, |a, px| a & px[3]) == u8::MAX,
            Pixels::Rgba16(p) => p.chunks_exact(4).all(|px| px[3] == u16::MAX),
        }
    }

    /// Writes the samples as PNG wants them: bytes, 16-bit ones big-endian.
    pub fn write_png_bytes(&self, out: &mut Vec<u8>) {
        self.write_png_samples(out, false);
    }

    /// [`write_png_bytes`](Self::write_png_bytes), RGB without the alpha samples if
    /// `drop_alpha`.
    pub fn write_png_samples(&self, out: &mut Vec<u8>, drop_alpha: bool) {
        out.clear();
        let channels = if drop_alpha { 3 } else { 4 };
        match self.pixels {
            Pixels::Rgba8(p) if !drop_alpha => out.extend_from_slice(p),
            Pixels::Rgba8(p) => {
                out.resize(p.len() / 4 * 3, 0);
                for (rgb, px) in out.chunks_exact_mut(3).zip(p.chunks_exact(4)) {
                    rgb.copy_from_slice(&px[..3]);
                }
            }
            Pixels::Rgba16(p) => {
                for px in p.chunks_exact(4) {
                    out.extend(px[..channels].iter().flat_map(|v| v.to_be_bytes()));
                }
            }
        }
    }
}

/// Owned samples.
#[derive(Clone, Debug, PartialEq)]
pub enum FrameData {
    Rgba8(Vec<u8>),
    Rgba16(Vec<u16>),
}

/// An owned frame; its buffer can be reused for the next frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub data: FrameData,
}

impl Frame {
    pub fn as_ref(&self) -> Result<FrameRef<'_>, OutputError> {
        let pixels = match &self.data {
            FrameData::Rgba8(p) => Pixels::Rgba8(p),
            FrameData::Rgba16(p) => Pixels::Rgba16(p),
        };
        FrameRef::new(self.width, self.height, pixels)
    }
}
