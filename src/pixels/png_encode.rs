//! PNG encoding: takes straight RGBA pixels of any [`Texel`] type and a [`PixelFormat`] and
//! writes PNG bytes in exactly that format (grey / grey+alpha / RGB / RGBA, 8 or 16 bit) to
//! any writer (tiny-skia cannot hold 16-bit pixels). The rows go to [`crate::png_bands`],
//! which compresses independent bands of them on as many threads as the caller asks for; no
//! whole-image sample buffer exists, and the bytes depend only on the pixels and the format.

use std::io::Write;

use crate::png_bands::{encode_image_parallel, PngColor, PngHeader};

use super::float_image::LUMA_709;
use super::{ColorKind, Depth, PixelError, PixelFormat, Texel};

/// A texel type PNG stores directly, in its own depth.
pub(crate) trait PngSample: Texel {
    /// The depth the texel type stores.
    const DEPTH: Depth;
    /// Bytes per sample.
    const BYTES: usize;
    /// Writes the sample's big-endian bytes into `out` (`BYTES` long).
    fn put_raw(self, out: &mut [u8]);
}

impl PngSample for u8 {
    const DEPTH: Depth = Depth::Eight;
    const BYTES: usize = 1;
    #[inline(always)]
    fn put_raw(self, out: &mut [u8]) {
        out[0] = self;
    }
}

impl PngSample for u16 {
    const DEPTH: Depth = Depth::Sixteen;
    const BYTES: usize = 2;
    #[inline(always)]
    fn put_raw(self, out: &mut [u8]) {
        out.copy_from_slice(&self.to_be_bytes());
    }
}

/// Encodes `pixels` (`width` × `height`, row-major) as a PNG in `format` into `out`, its
/// bands compressed on `threads` scoped threads (the bytes are the same for any count).
pub(crate) fn write_png_rgba<T: PngSample>(
    pixels: &[[T; 4]],
    width: u32,
    height: u32,
    format: PixelFormat,
    threads: usize,
    out: impl Write,
) -> Result<(), PixelError> {
    let header = PngHeader {
        width,
        height,
        color: match (format.color, format.alpha) {
            (ColorKind::Grey, false) => PngColor::Grey,
            (ColorKind::Grey, true) => PngColor::GreyAlpha,
            (ColorKind::Rgb, false) => PngColor::Rgb,
            (ColorKind::Rgb, true) => PngColor::Rgba,
        },
        sixteen_bit: format.depth == Depth::Sixteen,
    };
    let width = width as usize;
    let fill = |y: u32, row: &mut [u8]| {
        let start = y as usize * width;
        interleave(&pixels[start..start + width], format, row);
    };
    encode_image_parallel(&header, fill, threads, out)
        .map_err(|e| PixelError::Encode(png::EncodingError::IoError(e)))
}

/// Writes the channel samples of `pixels` into `out` in PNG order and byte layout (16-bit
/// big-endian). RGB samples in the texels' own depth are copied as they are (quantising a
/// texel's value gives the texel back); grey and other depths go through [0, 1].
pub(crate) fn interleave<T: PngSample>(pixels: &[[T; 4]], format: PixelFormat, out: &mut [u8]) {
    let channels = if format.color == ColorKind::Grey { 1 } else { 3 } + usize::from(format.alpha);
    if format.color == ColorKind::Rgb && format.depth == T::DEPTH {
        for (px, bytes) in pixels.iter().zip(out.chunks_exact_mut(channels * T::BYTES)) {
            for (&c, sample) in px.iter().zip(bytes.chunks_exact_mut(T::BYTES)) {
                c.put_raw(sample);
            }
        }
        return;
    }
    let sample_bytes = match format.depth {
        Depth::Eight => 1,
        Depth::Sixteen => 2,
    };
    let mut samples = out.chunks_exact_mut(sample_bytes);
    let mut push = |value: f32| {
        // invariant: `out` holds `channels` samples per pixel, and each pixel pushes that many.
        let sample = samples.next().expect("a sample per channel");
        match format.depth {
            Depth::Eight => sample[0] = u8::from_unit(value),
            Depth::Sixteen => sample.copy_from_slice(&u16::from_unit(value).to_be_bytes()),
        }
    };
    for px in pixels {
        let [r, g, b, a] = px.map(Texel::to_unit);
        match format.color {
            ColorKind::Grey => push(LUMA_709[0] * r + LUMA_709[1] * g + LUMA_709[2] * b),
            ColorKind::Rgb => {
                push(r);
                push(g);
                push(b);
            }
        }
        if format.alpha {
            push(a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every format decodes (png crate) to the samples the pixels give: RGB ones exactly,
    /// grey ones as Rec. 709 luma, 16-bit ones big-endian; the thread count changes nothing.
    #[test]
    fn every_format_decodes_to_its_samples() {
        let (width, height) = (37u32, 45u32);
        let noise = |i: u32| ((i.wrapping_mul(2_654_435_761) >> 13) % 3) as u8;
        let eight: Vec<[u8; 4]> = (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as u8, (i / width) as u8);
                [x * 3 + noise(i), y * 2, 40 + noise(i + 1), 200 + noise(i)]
            })
            .collect();
        for color in [ColorKind::Grey, ColorKind::Rgb] {
            for alpha in [false, true] {
                for depth in [Depth::Eight, Depth::Sixteen] {
                    let format = PixelFormat { color, alpha, depth };
                    let mut bytes = Vec::new();
                    write_png_rgba(&eight, width, height, format, 1, &mut bytes).unwrap();
                    let mut reader = png::Decoder::new(std::io::Cursor::new(&bytes))
                        .read_info()
                        .unwrap();
                    let mut decoded = vec![0; reader.output_buffer_size().unwrap()];
                    reader.next_frame(&mut decoded).unwrap();
                    let channels = format.channel_count();
                    let row = width as usize * channels * if depth == Depth::Sixteen { 2 } else { 1 };
                    let mut expected = vec![0u8; row * height as usize];
                    for (pixels, out) in eight.chunks(width as usize).zip(expected.chunks_mut(row)) {
                        interleave(pixels, format, out);
                    }
                    assert_eq!(decoded, expected, "{format:?}");
                    if color == ColorKind::Rgb && depth == Depth::Eight {
                        let first: Vec<u8> = eight[0][..channels].to_vec();
                        assert_eq!(decoded[..channels], first[..], "RGB samples are the texels");
                    }
                    let mut parallel = Vec::new();
                    write_png_rgba(&eight, width, height, format, 3, &mut parallel).unwrap();
                    assert_eq!(parallel, bytes, "{format:?} on 3 threads");
                }
            }
        }
    }
}
