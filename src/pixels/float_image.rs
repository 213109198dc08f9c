//! The float source image: takes an image file or `image::DynamicImage` and gives a
//! [`FloatImage`] — straight (non-premultiplied) RGBA `f32` in [0, 1], row-major, with the
//! [`PixelFormat`] it was stored in. Grey images are expanded to R = G = B.

use std::path::Path;
use std::sync::OnceLock;

use super::{sample_bilinear_rgba, ColorKind, Depth, PixelError, PixelFormat};

/// Rec. 709 luma weights (sum exactly 1 in real numbers).
pub(crate) const LUMA_709: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// `k / 255` for every 8-bit level `k`: the values the 8-bit loader gives (const evaluation
/// rounds like the run-time division).
const LEVEL_VALUES: [f32; 256] = {
    let mut values = [0.0; 256];
    let mut k = 0;
    while k < 256 {
        values[k] = k as f32 / 255.0;
        k += 1;
    }
    values
};

/// The 8-bit levels `k` of a pixel whose channels are exactly `k / 255` (bit for bit: −0,
/// NaN and values off the levels or out of [0, 1] give `None`). Called once per pixel when
/// an image is made, so it rounds by truncating `v·255 + ½` instead of calling libm's
/// `round`; a wrong level only fails the comparison.
#[inline]
fn level_of(pixel: &[f32; 4]) -> Option<[u8; 4]> {
    let levels = pixel.map(|v| (v * 255.0 + 0.5) as u8);
    let values = levels.map(|k| LEVEL_VALUES[usize::from(k)].to_bits());
    (values == pixel.map(f32::to_bits)).then_some(levels)
}

/// A straight-alpha RGBA float image.
#[derive(Clone, Debug)]
pub struct FloatImage {
    width: u32,
    height: u32,
    pixels: Vec<[f32; 4]>,
    format: PixelFormat,
    /// The pixels as 8-bit texels, when they are exactly that (see
    /// [`eight_bit_texels`](Self::eight_bit_texels)); built with the image, dropped by
    /// [`pixels_mut`](Self::pixels_mut) and rebuilt on the next use.
    eight_bit: OnceLock<Option<EightBitView>>,
}

/// The 8-bit texels, and whether every alpha level is 255.
#[derive(Clone, Debug)]
struct EightBitView {
    texels: Box<[[u8; 4]]>,
    opaque: bool,
}

impl PartialEq for FloatImage {
    fn eq(&self, other: &Self) -> bool {
        // The 8-bit view is a function of the rest.
        (self.width, self.height, self.format) == (other.width, other.height, other.format)
            && self.pixels == other.pixels
    }
}

impl FloatImage {
    /// Wraps a pixel buffer; `pixels.len()` must be `width * height`, both non-zero.
    pub fn new(
        width: u32,
        height: u32,
        pixels: Vec<[f32; 4]>,
        format: PixelFormat,
    ) -> Result<FloatImage, PixelError> {
        if width == 0 || height == 0 {
            return Err(PixelError::EmptyImage { width, height });
        }
        if pixels.len() != width as usize * height as usize {
            return Err(PixelError::BufferSize {
                width,
                height,
                actual: pixels.len(),
            });
        }
        Ok(FloatImage::with_eight_bit_view(
            width, height, pixels, format,
        ))
    }

    /// The image with its 8-bit view built now, while it is being made (loading), rather
    /// than in the first draw that samples it.
    fn with_eight_bit_view(
        width: u32,
        height: u32,
        pixels: Vec<[f32; 4]>,
        format: PixelFormat,
    ) -> FloatImage {
        let image = FloatImage {
            width,
            height,
            pixels,
            format,
            eight_bit: OnceLock::new(),
        };
        image.eight_bit_texels();
        image
    }

    /// An image whose pixel (i, j) is `colour(i, j)`.
    pub fn from_fn(
        width: u32,
        height: u32,
        format: PixelFormat,
        mut colour: impl FnMut(u32, u32) -> [f32; 4],
    ) -> Result<FloatImage, PixelError> {
        let mut pixels = Vec::with_capacity(width as usize * height as usize);
        for j in 0..height {
            for i in 0..width {
                pixels.push(colour(i, j));
            }
        }
        FloatImage::new(width, height, pixels, format)
    }

    /// Reads and decodes an image file (format guessed from its content); images over the
    /// size limits of `limits` are refused from their header, before decoding.
    pub fn load(path: &Path) -> Result<FloatImage, PixelError> {
        let decoded = Self::decode(path)?;
        FloatImage::from_dynamic(&decoded).map_err(|err| match err {
            PixelError::EmptyImage { width, height } => PixelError::Empty {
                path: path.to_path_buf(),
                width,
                height,
            },
            other => other,
        })
    }

    /// Reads and decodes an image file as [`load`](Self::load) does, without converting it.
    pub fn decode(path: &Path) -> Result<image::DynamicImage, PixelError> {
        use crate::limits::{open_image, ImageOpenError};
        let path_buf = || path.to_path_buf();
        open_image(path).map_err(|error| match error {
            ImageOpenError::Read(source) => PixelError::Read {
                path: path_buf(),
                source,
            },
            ImageOpenError::Decode(source) => PixelError::Decode {
                path: path_buf(),
                source,
            },
            ImageOpenError::TooLarge(source) => PixelError::TooLarge {
                path: path_buf(),
                source,
            },
        })
    }

    /// Converts a decoded image, keeping its format for output.
    pub fn from_dynamic(image: &image::DynamicImage) -> Result<FloatImage, PixelError> {
        let format = PixelFormat::of(image);
        let (width, height) = (image.width(), image.height());
        let pixels: Vec<[f32; 4]> = match image {
            image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_) => image
                .to_rgba32f()
                .pixels()
                .map(|p| {
                    p.0.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) })
                })
                .collect(),
            _ if format.depth == Depth::Eight => image
                .to_rgba8()
                .pixels()
                .map(|p| p.0.map(|v| LEVEL_VALUES[usize::from(v)]))
                .collect(),
            _ => image
                .to_rgba16()
                .pixels()
                .map(|p| p.0.map(|v| f32::from(v) / 65535.0))
                .collect(),
        };
        FloatImage::new(width, height, pixels, format)
    }

    /// Columns.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The format the image was stored in.
    pub fn format(&self) -> PixelFormat {
        self.format
    }

    /// Row-major straight RGBA pixels.
    pub fn pixels(&self) -> &[[f32; 4]] {
        &self.pixels
    }

    /// The pixels, for writing (the 8-bit view is rebuilt on its next use).
    pub fn pixels_mut(&mut self) -> &mut [[f32; 4]] {
        self.eight_bit = OnceLock::new();
        &mut self.pixels
    }

    /// The pixels as 8-bit texels `k` (channel value = k / 255), when the image is 8-bit and
    /// every channel value is exactly some `k as f32 / 255.0` — as loaded from an 8-bit file.
    /// The raster samples these (a quarter of the memory traffic of `f32` texels). Built when
    /// the image is made, and again on the first call after [`pixels_mut`](Self::pixels_mut)
    /// (O(pixels) each time).
    pub fn eight_bit_texels(&self) -> Option<&[[u8; 4]]> {
        self.eight_bit_view().map(|(texels, _)| texels)
    }

    /// [`eight_bit_texels`](Self::eight_bit_texels), and whether every texel's alpha level
    /// is 255 (then every bilinear sample's alpha is exactly 1, which the raster's kernel
    /// need not test pixel by pixel).
    pub(crate) fn eight_bit_view(&self) -> Option<(&[[u8; 4]], bool)> {
        self.eight_bit
            .get_or_init(|| self.quantised_exactly())
            .as_ref()
            .map(|view| (&view.texels[..], view.opaque))
    }

    fn quantised_exactly(&self) -> Option<EightBitView> {
        if self.format.depth != Depth::Eight {
            return None;
        }
        let mut view = vec![[0u8; 4]; self.pixels.len()];
        let mut opaque = true;
        for (levels, pixel) in view.iter_mut().zip(&self.pixels) {
            *levels = level_of(pixel)?;
            opaque &= levels[3] == u8::MAX;
        }
        Some(EightBitView {
            texels: view.into_boxed_slice(),
            opaque,
        })
    }

    /// Pixel (i, j); `None` outside the image.
    pub fn pixel(&self, i: u32, j: u32) -> Option<[f32; 4]> {
        (i < self.width && j < self.height)
            .then(|| self.pixels[j as usize * self.width as usize + i as usize])
    }

    /// Bilinear sample at `(x, y)` in pixel coordinates (centres at i + 0.5), clamped to edge.
    #[inline(always)]
    pub fn sample_bilinear(&self, x: f64, y: f64) -> [f32; 4] {
        sample_bilinear_rgba(&self.pixels, self.width, self.height, x, y)
    }

    /// Rec. 709 luma into R = G = B, alpha kept (the `monochrome` cloning mode). The format
    /// becomes grey.
    pub fn to_grey(&self) -> FloatImage {
        let pixels = self
            .pixels
            .iter()
            .map(|&[r, g, b, a]| {
                let luma = (LUMA_709[0] * r + LUMA_709[1] * g + LUMA_709[2] * b).clamp(0.0, 1.0);
                [luma, luma, luma, a]
            })
            .collect();
        let format = PixelFormat {
            color: ColorKind::Grey,
            ..self.format
        };
        FloatImage::with_eight_bit_view(self.width, self.height, pixels, format)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_of_grey_is_identity_and_of_colour_is_luma() {
        let image = FloatImage::from_fn(2, 1, PixelFormat::RGBA8, |i, _| {
            if i == 0 {
                [0.4, 0.4, 0.4, 0.5]
            } else {
                [1.0, 0.0, 0.0, 1.0]
            }
        })
        .unwrap();
        let grey = image.to_grey();
        assert!((grey.pixels()[0][0] - 0.4).abs() < 1e-6);
        assert_eq!(grey.pixels()[0][3], 0.5);
        assert!((grey.pixels()[1][1] - 0.2126).abs() < 1e-6);
        assert_eq!(grey.format().color, ColorKind::Grey);
    }

    #[test]
    fn eight_bit_texels_exist_exactly_when_every_value_is_k_over_255() {
        let image = |format, value: f32| {
            FloatImage::from_fn(3, 2, format, |i, j| {
                let k = (i * 97 + j * 51) as f32;
                [
                    k / 255.0,
                    1.0,
                    0.0,
                    if (i, j) == (2, 1) { value } else { 1.0 },
                ]
            })
            .unwrap()
        };
        let exact = image(PixelFormat::RGBA8, 77.0 / 255.0);
        let texels = exact.eight_bit_texels().expect("8-bit values");
        assert_eq!(texels[4], [(97 + 51) as u8, 255, 0, 255]);
        assert_eq!(texels[5][3], 77);
        for value in [0.3, 77.5 / 255.0, -0.0 + 1e-9, 1.5, f32::NAN] {
            assert!(
                image(PixelFormat::RGBA8, value)
                    .eight_bit_texels()
                    .is_none(),
                "{value}"
            );
        }
        let sixteen = PixelFormat {
            depth: Depth::Sixteen,
            ..PixelFormat::RGBA8
        };
        assert!(image(sixteen, 77.0 / 255.0).eight_bit_texels().is_none());
        // Writing drops the view; the next call sees the new values.
        let mut written = exact.clone();
        assert!(written.eight_bit_texels().is_some());
        written.pixels_mut()[0][0] = 0.5;
        assert!(written.eight_bit_texels().is_none());
        written.pixels_mut()[0][0] = 128.0 / 255.0;
        assert_eq!(written.eight_bit_texels().unwrap()[0][0], 128);
    }

    #[test]
    fn the_eight_bit_view_is_opaque_exactly_when_every_alpha_level_is_255() {
        let image = |alpha: f32| {
            FloatImage::from_fn(3, 2, PixelFormat::RGBA8, |i, j| {
                [0.0, 1.0, 0.0, if (i, j) == (1, 1) { alpha } else { 1.0 }]
            })
            .unwrap()
        };
        assert_eq!(
            image(1.0).eight_bit_view().map(|(_, opaque)| opaque),
            Some(true)
        );
        assert_eq!(
            image(254.0 / 255.0).eight_bit_view().map(|(_, o)| o),
            Some(false)
        );
        let mut written = image(1.0);
        written.pixels_mut()[0][3] = 0.0;
        assert_eq!(written.eight_bit_view().map(|(_, o)| o), Some(false));
    }

    #[test]
    fn level_values_are_the_divisions() {
        for k in 0..=255u8 {
            assert_eq!(
                LEVEL_VALUES[usize::from(k)].to_bits(),
                (f32::from(k) / 255.0).to_bits()
            );
        }
    }

    #[test]
    fn levels_are_found_exactly_and_nothing_else_is() {
        for k in 0..=255u8 {
            let v = LEVEL_VALUES[usize::from(k)];
            assert_eq!(level_of(&[v, 1.0, 0.0, v]), Some([k, 255, 0, k]));
            for off in [f32::from_bits(v.to_bits() + 1), v + 0.4 / 255.0, -v - 1e-3] {
                assert_eq!(level_of(&[1.0, off, 0.0, 1.0]), None, "{k}: {off}");
            }
        }
        for odd in [
            -0.0,
            f32::NAN,
            1.0 + f32::EPSILON,
            2.0,
            -1.0,
            f32::INFINITY,
            1e12,
        ] {
            assert_eq!(level_of(&[odd, 0.0, 0.0, 1.0]), None, "{odd}");
        }
    }

    #[test]
    fn empty_and_mismatched_buffers_are_errors() {
        assert!(FloatImage::new(0, 3, vec![], PixelFormat::RGBA8).is_err());
        assert!(FloatImage::new(2, 2, vec![[0.0; 4]; 3], PixelFormat::RGBA8).is_err());
    }
}
