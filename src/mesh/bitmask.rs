//! [`BitMask`]: a binary inside/outside pixel mask, read from any image the `image` crate
//! decodes (alpha ≥ threshold when the image has alpha, else luminance ≥ threshold) or built
//! in code. It is the input of `mesh_mask` and of the mask-aware coverage checks.

use std::path::Path;

use super::MeshError;

/// A width × height grid of inside/outside pixels. Pixel (x, y) covers [x, x+1] × [y, y+1].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitMask {
    pub width: usize,
    pub height: usize,
    inside: Vec<bool>,
}

impl BitMask {
    /// An all-outside mask.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            inside: vec![false; width * height],
        }
    }

    /// Builds a mask from a predicate on pixel coordinates.
    pub fn from_fn(
        width: usize,
        height: usize,
        mut inside: impl FnMut(usize, usize) -> bool,
    ) -> Self {
        let mut mask = Self::new(width, height);
        for y in 0..height {
            for x in 0..width {
                mask.inside[y * width + x] = inside(x, y);
            }
        }
        mask
    }

    /// Inside = alpha ≥ `threshold` if the image has an alpha channel, else luminance ≥
    /// `threshold` (both in [0, 1]).
    pub fn from_image(image: &image::DynamicImage, threshold: f32) -> Self {
        let (width, height) = (image.width() as usize, image.height() as usize);
        let inside = if image.color().has_alpha() {
            let rgba = image.to_rgba32f();
            rgba.pixels().map(|p| p.0[3] >= threshold).collect()
        } else {
            let luma = image.to_luma32f();
            luma.pixels().map(|p| p.0[0] >= threshold).collect()
        };
        Self {
            width,
            height,
            inside,
        }
    }

    /// Reads a mask image; the error names the path. Masks over the size limits of
    /// [`crate::limits`] are refused from their header, before decoding.
    pub fn load(path: &Path, threshold: f32) -> Result<Self, MeshError> {
        use crate::limits::{open_image, ImageOpenError};
        let image = open_image(path).map_err(|error| {
            let source = match error {
                ImageOpenError::Read(io) => image::ImageError::IoError(io),
                ImageOpenError::Decode(decode) => decode,
                ImageOpenError::TooLarge(source) => {
                    return MeshError::MaskTooLarge {
                        path: path.to_path_buf(),
                        source,
                    }
                }
            };
            MeshError::MaskRead {
                path: path.to_path_buf(),
                source,
            }
        })?;
        Ok(Self::from_image(&image, threshold))
    }

    /// Whether pixel (x, y) is inside; coordinates outside the image are outside.
    #[inline]
    pub fn get(&self, x: i64, y: i64) -> bool {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return false;
        }
        self.inside[y as usize * self.width + x as usize]
    }

    /// Sets pixel (x, y); coordinates outside the image are ignored.
    pub fn set(&mut self, x: i64, y: i64, inside: bool) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            self.inside[y as usize * self.width + x as usize] = inside;
        }
    }

    pub fn count_inside(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }

    /// Row-major inside flags.
    pub fn as_slice(&self) -> &[bool] {
        &self.inside
    }

    /// White inside, black outside.
    pub fn to_image(&self) -> image::GrayImage {
        let data = self
            .inside
            .iter()
            .map(|&b| if b { 255 } else { 0 })
            .collect();
        // invariant: data has exactly width * height bytes.
        image::GrayImage::from_raw(self.width as u32, self.height as u32, data)
            .expect("size matches") // invariant: the buffer has width × height bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luminance_threshold_without_alpha() {
        let img =
            image::GrayImage::from_fn(3, 1, |x, _| image::Luma([[0u8, 127, 128][x as usize]]));
        let mask = BitMask::from_image(&image::DynamicImage::ImageLuma8(img), 0.5);
        assert_eq!(
            (mask.get(0, 0), mask.get(1, 0), mask.get(2, 0)),
            (false, false, true)
        );
        assert_eq!(mask.count_inside(), 1);
    }

    #[test]
    fn alpha_decides_when_present() {
        // Bright but transparent pixel is outside; dark but opaque pixel is inside.
        let img = image::RgbaImage::from_fn(2, 1, |x, _| {
            if x == 0 {
                image::Rgba([255, 255, 255, 0])
            } else {
                image::Rgba([0, 0, 0, 255])
            }
        });
        let mask = BitMask::from_image(&image::DynamicImage::ImageRgba8(img), 0.5);
        assert!(!mask.get(0, 0));
        assert!(mask.get(1, 0));
    }

    #[test]
    fn out_of_range_is_outside() {
        let mask = BitMask::from_fn(2, 2, |_, _| true);
        assert!(mask.get(1, 1));
        assert!(!mask.get(-1, 0) && !mask.get(2, 0) && !mask.get(0, 2));
    }

    #[test]
    fn missing_file_error_names_path() {
        let err = BitMask::load(Path::new("/nonexistent/mask.png"), 0.5).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/mask.png"), "{err}");
    }
}
