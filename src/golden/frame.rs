//! Frames as the comparator sees them: takes a rendered [`Canvas`] (with the format its PNG is
//! written in), a [`FloatImage`] or PNG bytes / files, and gives straight RGBA samples at the
//! file's bit depth (0–255 or 0–65535), so a frame compares exactly as it would after being
//! written and read back.

use std::path::{Path, PathBuf};

use crate::pixels::{Canvas, CanvasPixels, ColorKind, Depth, FloatImage, PixelError, PixelFormat};

/// Why a frame could not be read.
#[derive(Debug, thiserror::Error)]
pub enum GoldenError {
    #[error("cannot read {path}: {message}")]
    Read { path: PathBuf, message: String },
    #[error("{path} is not a readable PNG: {message}")]
    Decode { path: PathBuf, message: String },
    #[error("encoding a frame: {0}")]
    Encode(#[from] PixelError),
}

/// An RGBA frame at 8 or 16 bits per channel; samples are stored in `u16` either way.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GoldenFrame {
    pub width: u32,
    pub height: u32,
    pub depth: Depth,
    /// Whether the file has an alpha channel (without one, alpha is opaque and not compared).
    pub alpha: bool,
    /// Row-major, straight (not premultiplied) RGBA; a file without alpha reads as opaque.
    pub pixels: Vec<[u16; 4]>,
}

impl GoldenFrame {
    /// The largest sample value: 255 or 65535.
    pub fn max_value(&self) -> u16 {
        match self.depth {
            Depth::Eight => 255,
            Depth::Sixteen => 65535,
        }
    }

    pub fn bits(&self) -> u32 {
        match self.depth {
            Depth::Eight => 8,
            Depth::Sixteen => 16,
        }
    }

    /// The frame as its PNG in `format` would read back. RGB formats are copied (alpha set
    /// opaque when the format has none); grey formats go through the encoder, which owns
    /// the luma weights.
    pub fn from_canvas(canvas: &Canvas, format: PixelFormat) -> Result<GoldenFrame, GoldenError> {
        if format.color == ColorKind::Grey || format.depth != canvas.depth() {
            let bytes = canvas.encode_png(format)?;
            return GoldenFrame::decode(&bytes, Path::new("<rendered frame>"));
        }
        let mut pixels: Vec<[u16; 4]> = match canvas.pixels() {
            CanvasPixels::Eight(p) => p.iter().map(|px| px.map(u16::from)).collect(),
            CanvasPixels::Sixteen(p) => p.clone(),
        };
        let frame_max = match format.depth {
            Depth::Eight => 255,
            Depth::Sixteen => 65535,
        };
        if !format.alpha {
            pixels.iter_mut().for_each(|px| px[3] = frame_max);
        }
        Ok(GoldenFrame {
            width: canvas.width(),
            height: canvas.height(),
            depth: format.depth,
            alpha: format.alpha,
            pixels,
        })
    }

    /// A float image rounded to 16 bits (8-bit levels k/255 land exactly on k·257), for
    /// comparisons with a tolerance finer than one 8-bit level.
    pub fn from_float_image(image: &FloatImage) -> GoldenFrame {
        let quantise = |v: f32| (v.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16;
        GoldenFrame {
            width: image.width(),
            height: image.height(),
            depth: Depth::Sixteen,
            alpha: image.format().alpha,
            pixels: image.pixels().iter().map(|px| px.map(quantise)).collect(),
        }
    }

    /// The same frame at 16 bits (8-bit samples times 257).
    pub fn to_sixteen(&self) -> GoldenFrame {
        match self.depth {
            Depth::Sixteen => self.clone(),
            Depth::Eight => GoldenFrame {
                depth: Depth::Sixteen,
                pixels: self.pixels.iter().map(|px| px.map(|v| v * 257)).collect(),
                ..*self
            },
        }
    }

    /// Decodes PNG (or any image) bytes; `path` names them in errors.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<GoldenFrame, GoldenError> {
        let decoded = image::load_from_memory(bytes).map_err(|e| GoldenError::Decode {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Ok(GoldenFrame::from_dynamic(&decoded))
    }

    /// Reads an image file, refusing images over the size limits from their header.
    pub fn load(path: &Path) -> Result<GoldenFrame, GoldenError> {
        use crate::limits::{open_image, ImageOpenError};
        let decoded = open_image(path).map_err(|error| match error {
            ImageOpenError::Read(e) => GoldenError::Read {
                path: path.to_path_buf(),
                message: e.to_string(),
            },
            other => GoldenError::Decode {
                path: path.to_path_buf(),
                message: other.to_string(),
            },
        })?;
        Ok(GoldenFrame::from_dynamic(&decoded))
    }

    fn from_dynamic(image: &image::DynamicImage) -> GoldenFrame {
        let format = PixelFormat::of(image);
        let depth = format.depth;
        let pixels = match depth {
            Depth::Eight => image
                .to_rgba8()
                .pixels()
                .map(|p| p.0.map(u16::from))
                .collect(),
            Depth::Sixteen => image.to_rgba16().pixels().map(|p| p.0).collect(),
        };
        GoldenFrame {
            width: image.width(),
            height: image.height(),
            depth,
            alpha: format.alpha,
            pixels,
        }
    }

    /// 8-bit RGB samples (16-bit ones rounded), for SSIM and pictures.
    pub(crate) fn rgb8(&self) -> image::RgbImage {
        let eight = |v: u16| match self.depth {
            Depth::Eight => v as u8,
            Depth::Sixteen => ((u32::from(v) * 255 + 32767) / 65535) as u8,
        };
        let bytes = self
            .pixels
            .iter()
            .flat_map(|px| [eight(px[0]), eight(px[1]), eight(px[2])])
            .collect();
        let image = image::RgbImage::from_raw(self.width, self.height, bytes);
        image.expect("buffer size") // invariant: pixels holds width × height entries
    }

    /// Pixel (x, y) as 8-bit RGBA, if inside.
    pub(crate) fn rgba8_at(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let px = self.pixels[(y as usize) * (self.width as usize) + x as usize];
        Some(px.map(|v| match self.depth {
            Depth::Eight => v as u8,
            Depth::Sixteen => ((u32::from(v) * 255 + 32767) / 65535) as u8,
        }))
    }
}
