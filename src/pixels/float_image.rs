//! The source image: takes an image file or `image::DynamicImage` and gives a
//! [`FloatImage`] — straight (non-premultiplied) RGBA in [0, 1], row-major, with the
//! [`PixelFormat`] it was stored in. Grey images are expanded to R = G = B. An 8-bit image
//! keeps its 8-bit levels `k` (value `k / 255`) and is sampled from them; its `f32` pixels
//! are made only when a caller asks for the whole buffer. Other depths are held as `f32`.

use std::path::Path;
use std::sync::{Arc, OnceLock};

use glam::Vec4;

use super::bilinear::sample_bilinear_by;
use super::png_decode::decode_png_levels;
use super::{format::rgba8_levels, ColorKind, Depth, PixelError, PixelFormat};

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

/// The values `k / 255` of a pixel's 8-bit levels.
#[inline(always)]
fn level_values(levels: [u8; 4]) -> [f32; 4] {
    levels.map(|k| LEVEL_VALUES[usize::from(k)])
}

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

/// A straight-alpha RGBA image with `f32` values.
#[derive(Clone, Debug)]
pub struct FloatImage {
    width: u32,
    height: u32,
    format: PixelFormat,
    store: Store,
}

/// How the pixels are held.
#[derive(Clone, Debug)]
enum Store {
    /// `f32` pixels, and their 8-bit view when every value is some `k / 255` (see
    /// [`FloatImage::eight_bit_texels`]); the view is built with the image, dropped by
    /// [`FloatImage::pixels_mut`] and rebuilt on its next use.
    Float {
        pixels: Vec<[f32; 4]>,
        eight_bit: OnceLock<Option<EightBitView>>,
    },
    /// 8-bit levels as decoded, and the `f32` pixels once a caller has asked for them.
    Levels {
        view: EightBitView,
        floats: OnceLock<Vec<[f32; 4]>>,
    },
}

/// The 8-bit texels, and whether every alpha level is 255. The texels are never changed
/// once made, so copies of an image share them: patches cloned from one source file hold
/// its pixels once, not once each (200 patches of a 4096² source took 13 GB).
#[derive(Clone, Debug)]
struct EightBitView {
    texels: Arc<[[u8; 4]]>,
    opaque: bool,
}

impl EightBitView {
    fn new(texels: Arc<[[u8; 4]]>) -> EightBitView {
        let opaque = texels.iter().all(|t| t[3] == u8::MAX);
        EightBitView { texels, opaque }
    }
}

impl PartialEq for FloatImage {
    fn eq(&self, other: &Self) -> bool {
        // Values, not storage: an 8-bit image equals the f32 image of its values.
        (self.width, self.height, self.format) == (other.width, other.height, other.format)
            && match (&self.store, &other.store) {
                (Store::Levels { view: a, .. }, Store::Levels { view: b, .. }) => {
                    a.texels == b.texels
                }
                _ => (0..self.len()).all(|i| self.value_at(i) == other.value_at(i)),
            }
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
        check_size(width, height, pixels.len())?;
        Ok(FloatImage::with_eight_bit_view(
            width, height, pixels, format,
        ))
    }

    /// An image of 8-bit levels (channel value `k / 255`), row-major; `levels.len()` must be
    /// `width * height`, both non-zero. Held as the levels: no `f32` copy is made.
    pub fn from_levels(
        width: u32,
        height: u32,
        levels: Vec<[u8; 4]>,
        format: PixelFormat,
    ) -> Result<FloatImage, PixelError> {
        check_size(width, height, levels.len())?;
        Ok(FloatImage {
            width,
            height,
            format,
            store: Store::Levels {
                view: EightBitView::new(levels.into()),
                floats: OnceLock::new(),
            },
        })
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
            format,
            store: Store::Float {
                pixels,
                eight_bit: OnceLock::new(),
            },
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
    /// size limits of `limits` are refused from their header, before decoding. An 8-bit PNG
    /// is decoded row by row straight into its levels.
    pub fn load(path: &Path) -> Result<FloatImage, PixelError> {
        let empty = |err| match err {
            PixelError::EmptyImage { width, height } => PixelError::Empty {
                path: path.to_path_buf(),
                width,
                height,
            },
            other => other,
        };
        match decode_png_levels(path).map_err(|error| open_error(path, error))? {
            Some(png) => FloatImage::from_levels(png.width, png.height, png.levels, png.format)
                .map_err(empty),
            None => FloatImage::from_dynamic(&Self::decode(path)?).map_err(empty),
        }
    }

    /// Reads and decodes an image file as [`load`](Self::load) does, without converting it.
    pub fn decode(path: &Path) -> Result<image::DynamicImage, PixelError> {
        crate::limits::open_image(path).map_err(|error| open_error(path, error))
    }

    /// Converts a decoded image, keeping its format for output (8-bit images keep their
    /// levels).
    pub fn from_dynamic(image: &image::DynamicImage) -> Result<FloatImage, PixelError> {
        let format = PixelFormat::of(image);
        let (width, height) = (image.width(), image.height());
        if let Some(levels) = rgba8_levels(image) {
            return FloatImage::from_levels(width, height, levels, format);
        }
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
                .map(|p| level_values(p.0))
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

    /// Pixels in the image.
    fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Pixel `index` (row-major) without making the `f32` buffer.
    #[inline(always)]
    fn value_at(&self, index: usize) -> [f32; 4] {
        match &self.store {
            Store::Float { pixels, .. } => pixels[index],
            Store::Levels { view, .. } => level_values(view.texels[index]),
        }
    }

    /// Row-major straight RGBA pixels. An 8-bit image makes them on the first call
    /// (O(pixels), 16 bytes each) and keeps them; samplers never need them.
    pub fn pixels(&self) -> &[[f32; 4]] {
        match &self.store {
            Store::Float { pixels, .. } => pixels,
            Store::Levels { view, floats } => {
                floats.get_or_init(|| view.texels.iter().map(|&t| level_values(t)).collect())
            }
        }
    }

    /// The pixels, for writing (the 8-bit view is rebuilt on its next use).
    pub fn pixels_mut(&mut self) -> &mut [[f32; 4]] {
        if let Store::Levels { view, floats } = &mut self.store {
            let pixels = floats
                .take()
                .unwrap_or_else(|| view.texels.iter().map(|&t| level_values(t)).collect());
            self.store = Store::Float {
                pixels,
                eight_bit: OnceLock::new(),
            };
        }
        match &mut self.store {
            Store::Float { pixels, eight_bit } => {
                *eight_bit = OnceLock::new();
                pixels
            }
            // invariant: an 8-bit store was replaced by an f32 one just above.
            Store::Levels { .. } => unreachable!("converted to f32 above"),
        }
    }

    /// The pixels as 8-bit texels `k` (channel value = k / 255), when the image is 8-bit and
    /// every channel value is exactly some `k as f32 / 255.0` — as loaded from an 8-bit file.
    /// The raster samples these (a quarter of the memory traffic of `f32` texels). An image
    /// made from `f32` pixels builds them when it is made, and again on the first call after
    /// [`pixels_mut`](Self::pixels_mut) (O(pixels) each time).
    pub fn eight_bit_texels(&self) -> Option<&[[u8; 4]]> {
        self.eight_bit_view().map(|(texels, _)| texels)
    }

    /// [`eight_bit_texels`](Self::eight_bit_texels), and whether every texel's alpha level
    /// is 255 (then every bilinear sample's alpha is exactly 1, which the raster's kernel
    /// need not test pixel by pixel).
    pub(crate) fn eight_bit_view(&self) -> Option<(&[[u8; 4]], bool)> {
        let view = match &self.store {
            Store::Float { pixels, eight_bit } => eight_bit
                .get_or_init(|| quantised_exactly(self.format, pixels))
                .as_ref(),
            Store::Levels { view, .. } => Some(view),
        };
        view.map(|view| (&view.texels[..], view.opaque))
    }

    /// The 8-bit texels when the image is stored as them (as decoded from an 8-bit file),
    /// without building anything: for readers of a few pixels of many frames, where
    /// [`eight_bit_texels`](Self::eight_bit_texels)' scan of an `f32` image would cost more
    /// than the reading.
    pub(crate) fn stored_texels(&self) -> Option<&[[u8; 4]]> {
        match &self.store {
            Store::Levels { view, .. } => Some(&view.texels[..]),
            Store::Float { .. } => None,
        }
    }

    /// Pixel (i, j); `None` outside the image.
    pub fn pixel(&self, i: u32, j: u32) -> Option<[f32; 4]> {
        (i < self.width && j < self.height)
            .then(|| self.value_at(j as usize * self.width as usize + i as usize))
    }

    /// Bilinear sample at `(x, y)` in pixel coordinates (centres at i + 0.5), clamped to edge.
    /// An 8-bit image gives the same bits as the `f32` image of its values.
    #[inline(always)]
    pub fn sample_bilinear(&self, x: f64, y: f64) -> [f32; 4] {
        let (w, h) = (self.width, self.height);
        match &self.store {
            Store::Float { pixels, .. } => {
                sample_bilinear_by(pixels, w, h, x, y, |&p| Vec4::from_array(p))
            }
            Store::Levels { view, .. } => sample_bilinear_by(&view.texels, w, h, x, y, |&t| {
                Vec4::from_array(level_values(t))
            }),
        }
    }

    /// Rec. 709 luma into R = G = B, alpha kept (the `monochrome` cloning mode). The format
    /// becomes grey.
    pub fn to_grey(&self) -> FloatImage {
        let pixels = (0..self.len())
            .map(|index| {
                let [r, g, b, a] = self.value_at(index);
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

/// The pixel error of a failed [`open_image`](crate::limits::open_image) of `path`.
pub(crate) fn open_error(path: &Path, error: crate::limits::ImageOpenError) -> PixelError {
    use crate::limits::ImageOpenError;
    let path = path.to_path_buf();
    match error {
        ImageOpenError::Read(source) => PixelError::Read { path, source },
        ImageOpenError::Decode(source) => PixelError::Decode { path, source },
        ImageOpenError::TooLarge(source) => PixelError::TooLarge { path, source },
    }
}

/// Both sizes non-zero and `len` pixels for them.
pub(super) fn check_size(width: u32, height: u32, len: usize) -> Result<(), PixelError> {
    if width == 0 || height == 0 {
        return Err(PixelError::EmptyImage { width, height });
    }
    if len != width as usize * height as usize {
        return Err(PixelError::BufferSize {
            width,
            height,
            actual: len,
        });
    }
    Ok(())
}

/// The 8-bit view of `f32` pixels, when the format is 8-bit and every value is a level.
fn quantised_exactly(format: PixelFormat, pixels: &[[f32; 4]]) -> Option<EightBitView> {
    if format.depth != Depth::Eight {
        return None;
    }
    let texels = pixels.iter().map(level_of).collect::<Option<Arc<[_]>>>()?;
    Some(EightBitView::new(texels))
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

    /// A `width`×`height` image of 8-bit levels from `seed`, and the `f32` image of the same
    /// values.
    fn level_and_float_images(width: u32, height: u32, seed: u32) -> (FloatImage, FloatImage) {
        let levels: Vec<[u8; 4]> = (0..width * height)
            .map(|i| {
                let h = (i ^ seed).wrapping_mul(0x9e37_79b9);
                [h >> 24, h >> 16, h >> 8, h | 0xf0].map(|v| v as u8)
            })
            .collect();
        let floats = levels.iter().map(|&t| t.map(|k| f32::from(k) / 255.0)).collect();
        (
            FloatImage::from_levels(width, height, levels, PixelFormat::RGBA8).unwrap(),
            FloatImage::new(width, height, floats, PixelFormat::RGBA8).unwrap(),
        )
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 64,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x1e7e_1500),
            ..proptest::prelude::ProptestConfig::default()
        })]

        /// An image held as levels reads and samples bit for bit like the f32 image of its
        /// values, everywhere (outside the image too).
        #[test]
        fn levels_sample_like_their_f32_values(
            width in 1u32..9, height in 1u32..9, seed in 0u32..1000,
            points in proptest::collection::vec((-3.0f64..12.0, -3.0f64..12.0), 1..40),
        ) {
            let (levels, floats) = level_and_float_images(width, height, seed);
            for (x, y) in points {
                let (a, b) = (levels.sample_bilinear(x, y), floats.sample_bilinear(x, y));
                proptest::prop_assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "({}, {})", x, y);
            }
            for (i, j) in [(0, 0), (width - 1, height - 1), (width / 2, height / 2), (width, 0)] {
                proptest::prop_assert_eq!(levels.pixel(i, j), floats.pixel(i, j));
            }
            proptest::prop_assert_eq!(levels.eight_bit_view(), floats.eight_bit_view());
            proptest::prop_assert_eq!(levels.pixels(), floats.pixels());
            proptest::prop_assert!(levels == floats);
            proptest::prop_assert!(floats == levels);
            proptest::prop_assert!(levels.to_grey() == floats.to_grey());
        }
    }

    #[test]
    fn writing_a_level_image_keeps_its_values_and_drops_the_view_when_off_the_levels() {
        let (mut levels, floats) = level_and_float_images(4, 3, 7);
        assert!(levels.eight_bit_texels().is_some());
        levels.pixels_mut()[5][1] = 0.5;
        assert!(levels.eight_bit_texels().is_none());
        assert_eq!(levels.pixel(1, 1).unwrap()[1], 0.5);
        assert_eq!(levels.pixel(2, 2), floats.pixel(2, 2));
        assert!(levels != floats);
        let (mut written, _) = level_and_float_images(4, 3, 7);
        written.pixels_mut()[0][0] = 1.0;
        assert_eq!(written.eight_bit_texels().unwrap()[0][0], 255);
    }

    #[test]
    fn from_dynamic_keeps_the_levels_of_every_eight_bit_type() {
        let rgba = image::RgbaImage::from_fn(5, 3, |i, j| image::Rgba([i as u8 * 50, j as u8 * 80, 7, 200]));
        let decoded = [
            image::DynamicImage::ImageRgba8(rgba.clone()),
            image::DynamicImage::ImageRgb8(image::DynamicImage::ImageRgba8(rgba.clone()).to_rgb8()),
            image::DynamicImage::ImageLumaA8(image::DynamicImage::ImageRgba8(rgba.clone()).to_luma_alpha8()),
            image::DynamicImage::ImageLuma8(image::DynamicImage::ImageRgba8(rgba).to_luma8()),
        ];
        for image in decoded {
            let loaded = FloatImage::from_dynamic(&image).unwrap();
            let expected: Vec<[u8; 4]> = image.to_rgba8().pixels().map(|p| p.0).collect();
            assert_eq!(loaded.eight_bit_texels(), Some(&expected[..]), "{:?}", image.color());
            assert_eq!(loaded.format(), PixelFormat::of(&image));
        }
    }

    #[test]
    fn empty_and_mismatched_buffers_are_errors() {
        assert!(FloatImage::new(0, 3, vec![], PixelFormat::RGBA8).is_err());
        assert!(FloatImage::new(2, 2, vec![[0.0; 4]; 3], PixelFormat::RGBA8).is_err());
    }
}
