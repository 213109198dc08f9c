//! PNG encoding: takes straight RGBA pixels of any [`Texel`] type and a [`PixelFormat`] and
//! gives PNG bytes in exactly that format (grey / grey+alpha / RGB / RGBA, 8 or 16 bit),
//! written with the `png` crate because tiny-skia cannot hold 16-bit pixels.

use super::float_image::LUMA_709;
use super::{ColorKind, Depth, PixelError, PixelFormat, Texel};

pub(crate) fn encode_png_rgba<T: Texel>(
    pixels: &[[T; 4]],
    width: u32,
    height: u32,
    format: PixelFormat,
) -> Result<Vec<u8>, PixelError> {
    let samples = interleave(pixels, format);
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
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
        writer.write_image_data(&samples)?;
        writer.finish()?;
    }
    Ok(bytes)
}

/// Channel samples in PNG order and byte layout (16-bit big-endian).
fn interleave<T: Texel>(pixels: &[[T; 4]], format: PixelFormat) -> Vec<u8> {
    let bytes_per_sample = match format.depth {
        Depth::Eight => 1,
        Depth::Sixteen => 2,
    };
    let mut out = Vec::with_capacity(pixels.len() * format.channel_count() * bytes_per_sample);
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
    out
}
