//! The compositing canvas: takes a [`FloatImage`] (the target or background) and gives the
//! frame being drawn on, stored in the output bit depth — RGBA `u8` for 8-bit targets, RGBA
//! `u16` for 16-bit ones — with float reads, bilinear sampling, an allocation-free reset
//! ([`Canvas::copy_from`]) and PNG output in any [`PixelFormat`].

use std::ops::Range;
use std::path::Path;

use super::float_image::check_size;
use super::png_encode::{interleave, write_png_rgba};
use super::PixelRect;
use super::{sample_bilinear_rgba, Depth, FloatImage, PixelError, PixelFormat};

/// A channel type that stores a value in [0, 1].
pub trait Texel: Copy + Send + Sync + 'static {
    fn to_unit(self) -> f32;
    /// Rounds a value in [0, 1] (clamped) to the nearest representable one.
    fn from_unit(value: f32) -> Self;
    /// [`from_unit`](Self::from_unit) of four values (one pixel's channels), the same
    /// values; vector code where that is faster.
    #[inline]
    fn from_unit4(values: [f32; 4]) -> [Self; 4] {
        values.map(Self::from_unit)
    }
    /// The pixels as 8-bit levels, if they are (the shading's eight-lane path writes only
    /// those).
    #[doc(hidden)]
    #[inline(always)]
    fn as_levels_mut(_pixels: &mut [[Self; 4]]) -> Option<&mut [[u8; 4]]> {
        None
    }
}

impl Texel for f32 {
    #[inline]
    fn to_unit(self) -> f32 {
        self
    }
    #[inline]
    fn from_unit(value: f32) -> Self {
        value.clamp(0.0, 1.0)
    }
}

impl Texel for u8 {
    #[inline]
    fn to_unit(self) -> f32 {
        f32::from(self) * (1.0 / 255.0)
    }
    #[inline]
    fn from_unit(value: f32) -> Self {
        // `as` saturates and maps NaN to 0.
        (value * 255.0 + 0.5) as u8
    }
    #[inline(always)]
    fn from_unit4(values: [f32; 4]) -> [Self; 4] {
        crate::simd::unit_to_levels(values)
    }
    #[inline(always)]
    fn as_levels_mut(pixels: &mut [[Self; 4]]) -> Option<&mut [[u8; 4]]> {
        Some(pixels)
    }
}

impl Texel for u16 {
    #[inline]
    fn to_unit(self) -> f32 {
        f32::from(self) * (1.0 / 65535.0)
    }
    #[inline]
    fn from_unit(value: f32) -> Self {
        (value * 65535.0 + 0.5) as u16
    }
}

/// Canvas storage in the output bit depth (straight, non-premultiplied RGBA, row-major).
#[derive(Clone, Debug, PartialEq)]
pub enum CanvasPixels {
    /// 8 bits per channel (an 8-bit target or background).
    Eight(Vec<[u8; 4]>),
    /// 16 bits per channel.
    Sixteen(Vec<[u16; 4]>),
}

/// The frame being composited.
#[derive(Clone, Debug, PartialEq)]
pub struct Canvas {
    width: u32,
    height: u32,
    pixels: CanvasPixels,
}

impl Canvas {
    /// A transparent canvas; both sizes must be non-zero.
    pub fn new(width: u32, height: u32, depth: Depth) -> Result<Canvas, PixelError> {
        if width == 0 || height == 0 {
            return Err(PixelError::EmptyImage { width, height });
        }
        let count = width as usize * height as usize;
        let pixels = match depth {
            Depth::Eight => CanvasPixels::Eight(vec![[0; 4]; count]),
            Depth::Sixteen => CanvasPixels::Sixteen(vec![[0; 4]; count]),
        };
        Ok(Canvas {
            width,
            height,
            pixels,
        })
    }

    /// An 8-bit canvas holding `pixels` (straight RGBA, row-major).
    pub fn from_rgba8(width: u32, height: u32, pixels: Vec<[u8; 4]>) -> Result<Canvas, PixelError> {
        check_size(width, height, pixels.len())?;
        Ok(Canvas {
            width,
            height,
            pixels: CanvasPixels::Eight(pixels),
        })
    }

    /// A decoded 8-bit image (grey, grey+alpha, RGB, RGBA) as a canvas, straight from its
    /// bytes: the same canvas as [`from_image`](Self::from_image) of its [`FloatImage`],
    /// without the float copy. `None` for other formats.
    pub fn from_eight_bit(decoded: &image::DynamicImage) -> Option<Canvas> {
        let pixels = super::format::rgba8_levels(decoded)?;
        Canvas::from_rgba8(decoded.width(), decoded.height(), pixels).ok()
    }

    /// The image quantised to its own bit depth.
    pub fn from_image(image: &FloatImage) -> Canvas {
        let pixels = match (image.format().depth, image.eight_bit_texels()) {
            // Quantising k / 255 gives k back (tested), so the levels are the canvas.
            (Depth::Eight, Some(levels)) => CanvasPixels::Eight(levels.to_vec()),
            (Depth::Eight, None) => CanvasPixels::Eight(quantise(image.pixels())),
            (Depth::Sixteen, _) => CanvasPixels::Sixteen(quantise(image.pixels())),
        };
        Canvas {
            width: image.width(),
            height: image.height(),
            pixels,
        }
    }

    /// Columns.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Bits per channel of the frame and its output.
    pub fn depth(&self) -> Depth {
        match self.pixels {
            CanvasPixels::Eight(_) => Depth::Eight,
            CanvasPixels::Sixteen(_) => Depth::Sixteen,
        }
    }

    /// The premultiplied pixels, row-major.
    pub fn pixels(&self) -> &CanvasPixels {
        &self.pixels
    }

    /// Whether every pixel's alpha is full.
    pub fn pixels_opaque(&self) -> bool {
        match &self.pixels {
            CanvasPixels::Eight(p) => p.iter().all(|px| px[3] == u8::MAX),
            CanvasPixels::Sixteen(p) => p.iter().all(|px| px[3] == u16::MAX),
        }
    }

    /// The premultiplied pixels, mutable.
    pub fn pixels_mut(&mut self) -> &mut CanvasPixels {
        &mut self.pixels
    }

    /// Makes this canvas equal to `other`: one memcpy when size and depth agree (the
    /// per-frame "reset to background"), a reallocation otherwise.
    pub fn copy_from(&mut self, other: &Canvas) {
        match (&mut self.pixels, &other.pixels) {
            (CanvasPixels::Eight(dst), CanvasPixels::Eight(src)) if dst.len() == src.len() => {
                dst.copy_from_slice(src)
            }
            (CanvasPixels::Sixteen(dst), CanvasPixels::Sixteen(src)) if dst.len() == src.len() => {
                dst.copy_from_slice(src)
            }
            _ => self.pixels = other.pixels.clone(),
        }
        self.width = other.width;
        self.height = other.height;
    }

    /// Copies the pixels of `rect` (clipped to the canvas) from `other`, which must have the
    /// same size and depth: the cheap per-frame reset that restores only the rectangles the
    /// previous frame drew into (e.g. a raster draw's work rectangle).
    pub fn copy_rect_from(&mut self, other: &Canvas, rect: PixelRect) -> Result<(), PixelError> {
        if (self.width, self.height, self.depth()) != (other.width, other.height, other.depth()) {
            return Err(PixelError::CanvasMismatch {
                width: self.width,
                height: self.height,
                depth: self.depth(),
                other_width: other.width,
                other_height: other.height,
                other_depth: other.depth(),
            });
        }
        let clipped = rect.intersect(&self.bounds());
        if clipped.is_empty() {
            return Ok(());
        }
        match (&mut self.pixels, &other.pixels) {
            (CanvasPixels::Eight(dst), CanvasPixels::Eight(src)) => {
                copy_rows(dst, src, self.width as usize, clipped)
            }
            (CanvasPixels::Sixteen(dst), CanvasPixels::Sixteen(src)) => {
                copy_rows(dst, src, self.width as usize, clipped)
            }
            // invariant: depths were compared above.
            _ => unreachable!("depths checked equal"),
        }
        Ok(())
    }

    /// The whole canvas as a pixel rectangle, for clipping.
    pub fn bounds(&self) -> PixelRect {
        let side = |n: u32| n.min(i32::MAX as u32) as i32;
        PixelRect {
            x0: 0,
            y0: 0,
            x1: side(self.width),
            y1: side(self.height),
        }
    }

    /// Pixel (i, j) as straight RGBA in [0, 1]; `None` outside the canvas.
    pub fn pixel_f32(&self, i: u32, j: u32) -> Option<[f32; 4]> {
        if i >= self.width || j >= self.height {
            return None;
        }
        let index = j as usize * self.width as usize + i as usize;
        Some(match &self.pixels {
            CanvasPixels::Eight(p) => p[index].map(Texel::to_unit),
            CanvasPixels::Sixteen(p) => p[index].map(Texel::to_unit),
        })
    }

    /// Bilinear sample at `(x, y)` (pixel centres at i + 0.5, clamped to edge).
    pub fn sample_bilinear(&self, x: f64, y: f64) -> [f32; 4] {
        match &self.pixels {
            CanvasPixels::Eight(p) => sample_bilinear_rgba(p, self.width, self.height, x, y),
            CanvasPixels::Sixteen(p) => sample_bilinear_rgba(p, self.width, self.height, x, y),
        }
    }

    /// The canvas as a float image tagged with `format`.
    pub fn to_float_image(&self, format: PixelFormat) -> FloatImage {
        let pixels = match &self.pixels {
            CanvasPixels::Eight(p) => p.iter().map(|px| px.map(Texel::to_unit)).collect(),
            CanvasPixels::Sixteen(p) => p.iter().map(|px| px.map(Texel::to_unit)).collect(),
        };
        let image = FloatImage::new(self.width, self.height, pixels, format);
        image.expect("well-formed") // invariant: a canvas is non-empty with width·height pixels
    }

    /// PNG bytes in `format` (grey formats store Rec. 709 luma; without alpha the alpha
    /// channel is dropped, not composited).
    pub fn encode_png(&self, format: PixelFormat) -> Result<Vec<u8>, PixelError> {
        let mut bytes = Vec::new();
        self.write_png(format, 1, &mut bytes)?;
        Ok(bytes)
    }

    /// Writes PNG bytes in `format` to `out` (as [`encode_png`](Self::encode_png), streamed),
    /// compressing bands of rows on `threads` scoped threads; the bytes are the same for any
    /// count.
    pub fn write_png(
        &self,
        format: PixelFormat,
        threads: usize,
        out: impl std::io::Write,
    ) -> Result<(), PixelError> {
        let (w, h) = (self.width, self.height);
        match &self.pixels {
            CanvasPixels::Eight(p) => write_png_rgba(p, w, h, format, threads, out),
            CanvasPixels::Sixteen(p) => write_png_rgba(p, w, h, format, threads, out),
        }
    }

    /// The frame's channel samples as a PNG in `format` stores them, row-major and
    /// interleaved (grey formats hold Rec. 709 luma; without alpha the alpha channel is
    /// dropped, not composited; 16-bit samples big-endian): for callers that hand frames to
    /// other software as arrays rather than files, with the values a saved PNG decodes to.
    pub fn samples(&self, format: PixelFormat) -> Vec<u8> {
        self.samples_in(format, 0..self.width, 0..self.height)
    }

    /// [`samples`](Self::samples) of the columns `x` and rows `y` only (clipped to the
    /// canvas): the part of a frame a clone changed.
    pub fn samples_in(&self, format: PixelFormat, x: Range<u32>, y: Range<u32>) -> Vec<u8> {
        let sample_bytes = match format.depth {
            Depth::Eight => 1,
            Depth::Sixteen => 2,
        };
        let (x0, x1) = (x.start.min(self.width) as usize, x.end.min(self.width) as usize);
        let (y0, y1) = (y.start.min(self.height), y.end.min(self.height));
        let columns = x1.saturating_sub(x0);
        let row_bytes = columns * format.channel_count() * sample_bytes;
        let mut out = vec![0; row_bytes * y1.saturating_sub(y0) as usize];
        if row_bytes == 0 {
            return out;
        }
        let width = self.width as usize;
        for (row, y) in out.chunks_exact_mut(row_bytes).zip(y0..y1) {
            let start = y as usize * width + x0;
            match &self.pixels {
                CanvasPixels::Eight(p) => interleave(&p[start..start + columns], format, row),
                CanvasPixels::Sixteen(p) => interleave(&p[start..start + columns], format, row),
            }
        }
        out
    }

    /// A decoded image as a canvas in its own bit depth: 8-bit images straight from their
    /// bytes ([`from_eight_bit`](Self::from_eight_bit)), others through their
    /// [`FloatImage`] ([`from_image`](Self::from_image)).
    pub fn from_dynamic(decoded: &image::DynamicImage) -> Result<Canvas, PixelError> {
        match Canvas::from_eight_bit(decoded) {
            Some(canvas) => Ok(canvas),
            None => Ok(Canvas::from_image(&FloatImage::from_dynamic(decoded)?)),
        }
    }

    /// Writes a PNG in `format` atomically (temporary file, then rename), streamed into the
    /// file, on this thread.
    pub fn save_png(&self, path: &Path, format: PixelFormat) -> Result<(), PixelError> {
        self.save_png_threaded(path, format, 1)
    }

    /// [`save_png`](Self::save_png), compressing on `threads` scoped threads (the same bytes).
    pub fn save_png_threaded(
        &self,
        path: &Path,
        format: PixelFormat,
        threads: usize,
    ) -> Result<(), PixelError> {
        let write_error = |source| PixelError::Write {
            path: path.to_path_buf(),
            source,
        };
        let mut failure = None;
        crate::util::write_atomic_with(path, |file| {
            let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
            match self.write_png(format, threads, &mut out) {
                Ok(()) => std::io::Write::flush(&mut out),
                Err(PixelError::Encode(png::EncodingError::IoError(error))) => Err(error),
                // Kept whole; the atomic write only needs to know that it failed.
                Err(error) => {
                    failure = Some(error);
                    Err(std::io::Error::other("encoding failed"))
                }
            }
        })
        .map_err(|error| failure.take().unwrap_or_else(|| write_error(error)))
    }

    /// A straight-alpha 8-bit RGBA copy (16-bit values are rounded), e.g. for overlays.
    pub fn to_rgba8_image(&self) -> image::RgbaImage {
        let bytes: Vec<u8> = match &self.pixels {
            CanvasPixels::Eight(p) => p.iter().flatten().copied().collect(),
            CanvasPixels::Sixteen(p) => p
                .iter()
                .flatten()
                .map(|&v| u8::from_unit(v.to_unit()))
                .collect(),
        };
        let image = image::RgbaImage::from_raw(self.width, self.height, bytes);
        image.expect("buffer size") // invariant: the buffer holds width × height RGBA pixels
    }
}

/// Copies `rect` (non-empty, inside both buffers) row by row.
fn copy_rows<T: Copy>(dst: &mut [T], src: &[T], width: usize, rect: PixelRect) {
    let (x0, x1) = (rect.x0 as usize, rect.x1 as usize);
    for y in rect.y0 as usize..rect.y1 as usize {
        let row = y * width;
        dst[row + x0..row + x1].copy_from_slice(&src[row + x0..row + x1]);
    }
}

fn quantise<T: Texel>(pixels: &[[f32; 4]]) -> Vec<[T; 4]> {
    pixels.iter().map(|px| px.map(T::from_unit)).collect()
}

/// Source-over in straight alpha: `source_premultiplied` is the source colour times
/// `source_alpha`. When the destination is opaque this is `src·α + (1 − α)·dst`.
#[inline(always)]
pub(crate) fn composite_over_straight(
    source_premultiplied: [f32; 3],
    source_alpha: f32,
    destination: [f32; 4],
) -> [f32; 4] {
    let keep = 1.0 - source_alpha;
    let dst_alpha = destination[3];
    if dst_alpha >= 1.0 {
        // Opaque destination (the common case): no division.
        return [
            (source_premultiplied[0] + keep * destination[0]).clamp(0.0, 1.0),
            (source_premultiplied[1] + keep * destination[1]).clamp(0.0, 1.0),
            (source_premultiplied[2] + keep * destination[2]).clamp(0.0, 1.0),
            1.0,
        ];
    }
    let out_alpha = source_alpha + keep * dst_alpha;
    if out_alpha <= 0.0 {
        return [0.0; 4];
    }
    let weight = keep * dst_alpha;
    let mut out = [0.0, 0.0, 0.0, out_alpha];
    for c in 0..3 {
        out[c] = ((source_premultiplied[c] + weight * destination[c]) / out_alpha).clamp(0.0, 1.0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `samples` are the samples its PNG decodes to (png crate), in every format and
    /// depth; `samples_in` is their rectangle, clipped to the canvas.
    #[test]
    fn samples_are_what_the_png_decodes_to() {
        let (w, h) = (23u32, 17u32);
        let levels: Vec<[u8; 4]> = (0..w * h)
            .map(|i| [(i * 7) as u8, (i * 13 + 5) as u8, (i * 3 + 1) as u8, (100 + i % 150) as u8])
            .collect();
        let eight = Canvas::from_rgba8(w, h, levels).unwrap();
        let sixteen = Canvas::from_image(&eight.to_float_image(PixelFormat::RGBA16));
        for canvas in [&eight, &sixteen] {
            for color in [super::super::ColorKind::Grey, super::super::ColorKind::Rgb] {
                for alpha in [false, true] {
                    for depth in [Depth::Eight, Depth::Sixteen] {
                        let format = PixelFormat { color, alpha, depth };
                        let png = canvas.encode_png(format).unwrap();
                        let mut reader = png::Decoder::new(std::io::Cursor::new(&png))
                            .read_info()
                            .unwrap();
                        let mut decoded = vec![0; reader.output_buffer_size().unwrap()];
                        reader.next_frame(&mut decoded).unwrap();
                        let samples = canvas.samples(format);
                        assert_eq!(samples, decoded, "{format:?}");
                        let pixel = samples.len() / (w * h) as usize;
                        let rect = canvas.samples_in(format, 5..40, 3..9);
                        let expected: Vec<u8> = (3..9)
                            .flat_map(|y| {
                                let start = (y * w as usize + 5) * pixel;
                                samples[start..start + (w as usize - 5) * pixel].to_vec()
                            })
                            .collect();
                        assert_eq!(rect, expected, "{format:?}");
                        assert!(canvas.samples_in(format, 30..40, 0..5).is_empty());
                    }
                }
            }
        }
    }

    #[test]
    fn texel_round_trips_are_exact() {
        for v in 0..=255u8 {
            assert_eq!(u8::from_unit(v.to_unit()), v);
        }
        for v in 0..=65535u16 {
            assert_eq!(u16::from_unit(v.to_unit()), v);
        }
        assert_eq!(u8::from_unit(f32::NAN), 0);
        assert_eq!(u8::from_unit(7.0), 255);
    }

    #[test]
    fn over_opaque_is_the_linear_mix() {
        let out = composite_over_straight([0.25, 0.0, 0.5], 0.5, [0.2, 0.4, 0.6, 1.0]);
        let expected = [0.25 + 0.5 * 0.2, 0.5 * 0.4, 0.5 + 0.5 * 0.6, 1.0];
        for c in 0..4 {
            assert!((out[c] - expected[c]).abs() < 1e-6, "{out:?}");
        }
    }

    #[test]
    fn copy_rect_from_restores_only_the_clipped_rectangle() {
        let image = FloatImage::from_fn(9, 7, PixelFormat::RGBA16, |i, j| {
            [i as f32 / 9.0, j as f32 / 7.0, 0.25, 1.0]
        })
        .unwrap();
        let background = Canvas::from_image(&image);
        let blank = Canvas::new(9, 7, Depth::Sixteen).unwrap();
        let mut frame = blank.clone();
        let rect = PixelRect {
            x0: 6,
            y0: -2,
            x1: 20,
            y1: 3,
        };
        frame.copy_rect_from(&background, rect).unwrap();
        for j in 0..7 {
            for i in 0..9 {
                let inside = (6..9).contains(&i) && (0..3).contains(&j);
                let expected = if inside { &background } else { &blank };
                assert_eq!(
                    frame.pixel_f32(i, j),
                    expected.pixel_f32(i, j),
                    "({i}, {j})"
                );
            }
        }
        let everything = PixelRect {
            x0: i32::MIN,
            y0: i32::MIN,
            x1: i32::MAX,
            y1: i32::MAX,
        };
        frame.copy_rect_from(&background, everything).unwrap();
        assert_eq!(frame, background);
        let eight = Canvas::new(9, 7, Depth::Eight).unwrap();
        assert!(frame.copy_rect_from(&eight, rect).is_err());
        let smaller = Canvas::new(9, 6, Depth::Sixteen).unwrap();
        assert!(frame.copy_rect_from(&smaller, rect).is_err());
    }

    #[test]
    fn copy_from_resets_without_reallocating() {
        let image = FloatImage::from_fn(3, 2, PixelFormat::RGBA8, |i, j| {
            [i as f32 / 3.0, j as f32 / 2.0, 0.5, 1.0]
        })
        .unwrap();
        let background = Canvas::from_image(&image);
        let mut frame = Canvas::new(3, 2, Depth::Eight).unwrap();
        let before = match frame.pixels() {
            CanvasPixels::Eight(p) => p.as_ptr(),
            CanvasPixels::Sixteen(_) => unreachable!(),
        };
        frame.copy_from(&background);
        assert_eq!(frame, background);
        match frame.pixels() {
            CanvasPixels::Eight(p) => assert_eq!(p.as_ptr(), before),
            CanvasPixels::Sixteen(_) => unreachable!(),
        }
    }
}
