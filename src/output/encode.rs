//! One PNG image from one frame: takes a [`FrameRef`] and a writer, gives PNG bytes
//! (8 or 16 bits; RGB when every pixel is opaque, as other tools write, else RGBA;
//! deterministic for a given frame and compression).

use std::io::Write;

use super::{FrameRef, OutputError, Pixels};

/// PNG compression effort; `Fast` is the default for frame sequences.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PngCompression {
    #[default]
    Fast,
    Default,
    Best,
}

impl PngCompression {
    fn to_png(self) -> png::Compression {
        match self {
            PngCompression::Fast => png::Compression::Fastest,
            PngCompression::Default => png::Compression::Balanced,
            PngCompression::Best => png::Compression::High,
        }
    }
}

/// Encodes `frame` into `out`; `scratch` holds the byte form of the samples between calls
/// (an opaque or 16-bit frame's; an 8-bit RGBA frame is encoded straight from its pixels).
pub fn encode_png(
    frame: &FrameRef<'_>,
    out: impl Write,
    compression: PngCompression,
    scratch: &mut Vec<u8>,
) -> Result<(), OutputError> {
    let opaque = frame.is_opaque();
    let mut encoder = png::Encoder::new(out, frame.width(), frame.height());
    encoder.set_color(if opaque {
        png::ColorType::Rgb
    } else {
        png::ColorType::Rgba
    });
    encoder.set_depth(if frame.is_16_bit() {
        png::BitDepth::Sixteen
    } else {
        png::BitDepth::Eight
    });
    encoder.set_compression(compression.to_png());
    let mut writer = encoder.write_header()?;
    let samples: &[u8] = match frame.pixels() {
        Pixels::Rgba8(pixels) if !opaque => pixels,
        _ => {
            frame.write_png_samples(scratch, opaque);
            scratch
        }
    };
    writer.write_image_data(samples)?;
    writer.finish()?;
    Ok(())
}
