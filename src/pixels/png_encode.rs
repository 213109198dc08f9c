//! PNG encoding: takes straight RGBA pixels of any [`Texel`] type and a [`PixelFormat`] and
//! writes PNG bytes in exactly that format (grey / grey+alpha / RGB / RGBA, 8 or 16 bit) to
//! any writer, with the `png` crate (tiny-skia cannot hold 16-bit pixels). Rows are laid out
//! a band at a time and streamed into the encoder, so no whole-image sample buffer exists.

use std::io::Write;

use super::float_image::LUMA_709;
use super::{ColorKind, Depth, PixelError, PixelFormat, Texel};

/// Rows laid out per write into the encoder: large enough that the per-write cost vanishes,
/// small enough to stay in cache.
const BAND_ROWS: usize = 16;

/// Compressed bytes per IDAT chunk.
const IDAT_BYTES: usize = 1 << 20;

/// A texel type PNG stores directly, in its own depth.
pub(crate) trait PngSample: Texel {
    /// The depth the texel type stores.
    const DEPTH: Depth;
    /// Appends the sample's big-endian bytes.
    fn push_raw(self, out: &mut Vec<u8>);
}

impl PngSample for u8 {
    const DEPTH: Depth = Depth::Eight;
    #[inline(always)]
    fn push_raw(self, out: &mut Vec<u8>) {
        out.push(self);
    }
}

impl PngSample for u16 {
    const DEPTH: Depth = Depth::Sixteen;
    #[inline(always)]
    fn push_raw(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_be_bytes());
    }
}

/// Encodes `pixels` (`width` × `height`, row-major) as a PNG in `format` into `out`.
pub(crate) fn write_png_rgba<T: PngSample>(
    pixels: &[[T; 4]],
    width: u32,
    height: u32,
    format: PixelFormat,
    out: impl Write,
) -> Result<(), PixelError> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(match (format.color, format.alpha) {
        (ColorKind::Grey, false) => png::ColorType::Grayscale,
        (ColorKind::Grey, true) => png::ColorType::GrayscaleAlpha,
        (ColorKind::Rgb, false) => png::ColorType::Rgb,
        (ColorKind::Rgb, true) => png::ColorType::Rgba,
    });
    encoder.set_depth(match format.depth {
        Depth::Eight => png::BitDepth::Eight,
        Depth::Sixteen => png::BitDepth::Sixteen,
    });
    // The png crate's fast (fdeflate) setting: its default deflate is several times slower.
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header()?;
    let mut stream = writer.stream_writer_with_size(IDAT_BYTES)?;
    let mut band = Vec::new();
    for rows in pixels.chunks(width as usize * BAND_ROWS) {
        band.clear();
        interleave(rows, format, &mut band);
        stream.write_all(&band).map_err(png::EncodingError::from)?;
    }
    stream.finish()?;
    writer.finish()?;
    Ok(())
}

/// Appends the channel samples of `pixels` in PNG order and byte layout (16-bit big-endian).
/// RGB samples in the texels' own depth are copied as they are (quantising a texel's value
/// gives the texel back); grey and other depths go through [0, 1].
fn interleave<T: PngSample>(pixels: &[[T; 4]], format: PixelFormat, out: &mut Vec<u8>) {
    let channels = if format.alpha { 4 } else { 3 };
    if format.color == ColorKind::Rgb && format.depth == T::DEPTH {
        for px in pixels {
            px[..channels].iter().for_each(|&c| c.push_raw(out));
        }
        return;
    }
    let mut push = |value: f32| match format.depth {
        Depth::Eight => out.push(u8::from_unit(value)),
        Depth::Sixteen => out.extend_from_slice(&u16::from_unit(value).to_be_bytes()),
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
