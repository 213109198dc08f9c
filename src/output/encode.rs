//! One PNG image from one frame: takes a [`FrameRef`] and a writer, gives PNG bytes
//! (RGBA, 8 or 16 bits, deterministic for a given frame and compression).

use std::io::Write;

use super::{FrameRef, OutputError};

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
            PngCompression::Fast => png::Compression::Fast,
            PngCompression::Default => png::Compression::Default,
            PngCompression::Best => png::Compression::Best,
        }
    }
}

/// Encodes `frame` into `out`; `scratch` holds the byte form of the samples between calls.
pub fn encode_png(
    frame: &FrameRef<'_>,
    out: impl Write,
    compression: PngCompression,
    scratch: &mut Vec<u8>,
) -> Result<(), OutputError> {
    let mut encoder = png::Encoder::new(out, frame.width(), frame.height());
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(if frame.is_16_bit() {
        png::BitDepth::Sixteen
    } else {
        png::BitDepth::Eight
    });
    encoder.set_compression(compression.to_png());
    let mut writer = encoder.write_header()?;
    frame.write_png_bytes(scratch);
    writer.write_image_data(scratch)?;
    writer.finish()?;
    Ok(())
}
