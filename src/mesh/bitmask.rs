//! [`BitMask`]: a binary inside/outside pixel mask, read from any image the `image` crate
//! decodes (alpha ≥ threshold when the image has alpha, else luminance ≥ threshold) or built
//! in code. It is the input of `mesh_mask` and of the mask-aware coverage checks.

use std::path::Path;

use super::MeshError;

/// The one definition of "inside" every caller shares (`lapclone clone` and `mesh` by
/// default, a scene's check and its render): alpha, or luminance without alpha, at least
/// half scale.
pub const MASK_THRESHOLD: f32 = 0.5;

/// The first index from `from` on whose byte differs from `value` (`bytes.len()` if none),
/// eight bytes per test where it can.
pub fn run_end(bytes: &[u8], from: usize, value: u8) -> usize {
    let repeated = u64::from_ne_bytes([value; 8]);
    let mut at = from;
    while at + 8 <= bytes.len() && word(&bytes[at..at + 8]) == repeated {
        at += 8;
    }
    at + bytes[at..].iter().take_while(|&&b| b == value).count()
}

/// Where the trailing zero bytes of `bytes` start (0 when all are zero), eight bytes per
/// test where it can.
pub fn zero_suffix_start(bytes: &[u8]) -> usize {
    let mut end = bytes.len();
    while end >= 8 && word(&bytes[end - 8..end]) == 0 {
        end -= 8;
    }
    bytes[..end]
        .iter()
        .rposition(|&b| b != 0)
        .map_or(0, |last| last + 1)
}

/// Eight bytes as one word.
#[inline]
pub(crate) fn word(bytes: &[u8]) -> u64 {
    let mut eight = [0; 8];
    eight.copy_from_slice(bytes);
    u64::from_ne_bytes(eight)
}

/// Positions where two equally long 0/1 byte slices differ, eight per word.
pub(crate) fn differing_bytes(a: &[u8], b: &[u8]) -> usize {
    let (mut words_a, mut words_b) = (a.chunks_exact(8), b.chunks_exact(8));
    let whole: u32 = (&mut words_a)
        .zip(&mut words_b)
        .map(|(x, y)| (word(x) ^ word(y)).count_ones())
        .sum();
    let rest = words_a.remainder().iter().zip(words_b.remainder());
    whole as usize + rest.filter(|(x, y)| x != y).count()
}

/// Pixel edges between inside and outside (the image border counting as outside): for every
/// line between rows y − 1 and y, the vertical neighbours that differ, and along every row
/// the horizontal ones.
pub(crate) fn crack_edge_count(mask: &BitMask) -> usize {
    let (width, height) = (mask.width, mask.height);
    if width == 0 {
        return 0;
    }
    let outside_row = vec![0u8; width];
    let row = |y: usize| match y {
        0 => &outside_row[..],
        _ if y > height => &outside_row[..],
        _ => mask.row_bytes(y - 1),
    };
    (0..=height)
        .map(|y| {
            let mut edges = differing_bytes(row(y), row(y + 1));
            if y < height {
                let bytes = mask.row_bytes(y);
                edges += usize::from(bytes[0]) + usize::from(bytes[width - 1]);
                edges += differing_bytes(&bytes[..width - 1], &bytes[1..]);
            }
            edges
        })
        .sum()
}

/// The inside flags through the image's float conversion: the definition.
fn from_floats(image: &image::DynamicImage, threshold: f32) -> Vec<bool> {
    if image.color().has_alpha() {
        let rgba = image.to_rgba32f();
        rgba.pixels().map(|p| p.0[3] >= threshold).collect()
    } else {
        let luma = image.to_luma32f();
        luma.pixels().map(|p| p.0[0] >= threshold).collect()
    }
}

/// The inside flags of an 8-bit grey, grey + alpha or RGBA image straight from its bytes,
/// through a table of the 256 byte values (`None` for other layouts). The table is made by
/// running a 256 × 1 image of the same layout holding every byte value through the general
/// path's own float conversion, so the flags are the same; what is skipped is converting the
/// whole image to floats first.
fn from_bytes(image: &image::DynamicImage, threshold: f32) -> Option<Vec<bool>> {
    use image::DynamicImage::{ImageLuma8, ImageLumaA8, ImageRgba8};
    let channels = match image {
        ImageLuma8(_) => 1,
        ImageLumaA8(_) => 2,
        ImageRgba8(_) => 4,
        _ => return None,
    };
    let every_value: Vec<u8> = (0..=255u8)
        .flat_map(|v| std::iter::repeat_n(v, channels))
        .collect();
    let all = match channels {
        1 => ImageLuma8(image::GrayImage::from_raw(256, 1, every_value)?),
        2 => ImageLumaA8(image::GrayAlphaImage::from_raw(256, 1, every_value)?),
        _ => ImageRgba8(image::RgbaImage::from_raw(256, 1, every_value)?),
    };
    let table: [bool; 256] = from_floats(&all, threshold).try_into().ok()?;
    let pixels = image.width() as usize * image.height() as usize;
    let bytes = image.as_bytes();
    if channels == 1 {
        return Some(bytes.get(..pixels)?.iter().map(|&b| table[usize::from(b)]).collect());
    }
    // The byte read per pixel: the last channel (alpha).
    let alpha = bytes.get(channels - 1..)?.iter().step_by(channels);
    Some(alpha.take(pixels).map(|&b| table[usize::from(b)]).collect())
}

/// A width × height grid of inside/outside pixels. Pixel (x, y) covers [x, x+1] × [y, y+1].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitMask {
    /// Columns.
    pub width: usize,
    /// Rows.
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
        let inside = from_bytes(image, threshold).unwrap_or_else(|| from_floats(image, threshold));
        Self {
            width,
            height,
            inside,
        }
    }

    /// Reads a mask image; the error names the path. Masks over the size limits of
    /// `limits` are refused from their header, before decoding.
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

    /// How many pixels are inside.
    pub fn count_inside(&self) -> usize {
        let bytes = self.as_bytes();
        let mut words = bytes.chunks_exact(8);
        // Each byte is 0 or 1, so a word's byte sum is its popcount.
        let whole: u32 = (&mut words).map(|w| word(w).count_ones()).sum();
        whole as usize + words.remainder().iter().filter(|&&b| b != 0).count()
    }

    /// Row-major inside flags.
    pub fn as_slice(&self) -> &[bool] {
        &self.inside
    }

    /// Row-major inside flags as bytes (1 inside, 0 outside), for word-at-a-time scans.
    pub fn as_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.inside)
    }

    /// Row `y`'s flags as bytes.
    pub fn row_bytes(&self, y: usize) -> &[u8] {
        &self.as_bytes()[y * self.width..(y + 1) * self.width]
    }

    /// Corners of the bounding box of the inside pixels (pixel (x, y) spans [x, x+1] ×
    /// [y, y+1]); `None` for an empty mask. Reads each row only until the box so far
    /// decides it.
    pub fn inside_bounds(&self) -> Option<((usize, usize), (usize, usize))> {
        let has_inside = |y: usize| run_end(self.row_bytes(y), 0, 0) < self.width;
        let y0 = (0..self.height).find(|&y| has_inside(y))?;
        // invariant: row y0 has an inside pixel, so a last such row exists.
        let y1 = (y0..self.height)
            .rev()
            .find(|&y| has_inside(y))
            .expect("row y0");
        let (mut x0, mut x1) = (self.width, 0);
        for y in y0..=y1 {
            let row = self.row_bytes(y);
            x0 = run_end(&row[..x0], 0, 0).min(x0);
            x1 += zero_suffix_start(&row[x1..]);
        }
        Some(((x0, y0), (x1, y1 + 1)))
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
    fn the_byte_table_gives_the_float_conversion_s_flags() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut byte = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 24) as u8
        };
        let mut images = Vec::new();
        // Every byte value, then random ones, in each 8-bit layout the table serves.
        let grey: Vec<u8> = (0..=255u8).chain((0..700).map(|_| byte())).collect();
        let n = grey.len() as u32;
        images.push(image::DynamicImage::ImageLuma8(
            image::GrayImage::from_raw(n, 1, grey.clone()).unwrap(),
        ));
        let pairs = grey.iter().flat_map(|&a| [byte(), a]).collect();
        images.push(image::DynamicImage::ImageLumaA8(
            image::GrayAlphaImage::from_raw(n, 1, pairs).unwrap(),
        ));
        let quads = grey.iter().flat_map(|&a| [byte(), byte(), byte(), a]).collect();
        images.push(image::DynamicImage::ImageRgba8(
            image::RgbaImage::from_raw(n, 1, quads).unwrap(),
        ));
        for image in &images {
            for threshold in [0.0, 0.25, 0.5, 127.5 / 255.0, 128.0 / 255.0, 1.0, 1.5] {
                let table = from_bytes(image, threshold).expect("an 8-bit layout");
                assert_eq!(table, from_floats(image, threshold), "{:?} at {threshold}", image.color());
                assert_eq!(BitMask::from_image(image, threshold).inside, table);
            }
        }
        let rgb = image::DynamicImage::ImageRgb8(image::RgbImage::new(2, 2));
        assert!(from_bytes(&rgb, 0.5).is_none());
    }

    #[test]
    fn out_of_range_is_outside() {
        let mask = BitMask::from_fn(2, 2, |_, _| true);
        assert!(mask.get(1, 1));
        assert!(!mask.get(-1, 0) && !mask.get(2, 0) && !mask.get(0, 2));
    }

    /// Random masks with long inside and outside runs (so the word paths run) and isolated
    /// pixels (so the byte tails do).
    fn random_mask(width: usize, height: usize, seed: u64) -> BitMask {
        let mut state = seed | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut inside = false;
        BitMask::from_fn(width, height, |_, _| {
            if next() % 13 == 0 {
                inside = !inside;
            }
            inside && next() % 29 != 0
        })
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 200,
            rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0xb175),
            ..Default::default()
        })]

        /// The word-at-a-time scans agree with pixel-by-pixel definitions.
        #[test]
        fn word_scans_match_pixel_scans(width in 0usize..40, height in 0usize..12, seed: u64) {
            let mask = random_mask(width, height, seed);
            let flags = mask.as_slice();
            proptest::prop_assert_eq!(mask.count_inside(), flags.iter().filter(|&&b| b).count());
            let mut naive: Option<((usize, usize), (usize, usize))> = None;
            for (i, _) in flags.iter().enumerate().filter(|(_, &b)| b) {
                let (x, y) = (i % width, i / width);
                let ((x0, y0), (x1, y1)) = naive.unwrap_or(((x, y), (x + 1, y + 1)));
                naive = Some(((x0.min(x), y0.min(y)), (x1.max(x + 1), y1.max(y + 1))));
            }
            proptest::prop_assert_eq!(mask.inside_bounds(), naive);
            for y in 0..height {
                let row = mask.row_bytes(y);
                for from in 0..=width {
                    for value in [0, 1] {
                        let end = (from..width).find(|&x| row[x] != value).unwrap_or(width);
                        proptest::prop_assert_eq!(run_end(row, from, value), end);
                    }
                    let suffix = row[..from].iter().rposition(|&b| b != 0).map_or(0, |l| l + 1);
                    proptest::prop_assert_eq!(zero_suffix_start(&row[..from]), suffix);
                }
            }
        }
    }

    #[test]
    fn missing_file_error_names_path() {
        let err = BitMask::load(Path::new("/nonexistent/mask.png"), 0.5).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/mask.png"), "{err}");
    }
}
