//! One PNG image from one frame: takes a [`Frame`] and a writer, gives PNG bytes (8 or 16
//! bits; RGB when every pixel is opaque, as other tools write, else RGBA). The fast setting
//! uses the band encoder of [`crate::png_bands`] and, across a sequence, reuses the bands
//! whose rows did not change since the frame before; the others use the png crate's
//! adaptive filters and zlib levels. Deterministic for a given frame and compression.

use std::io::Write;

use crate::png_bands::{BandEncoder, EncodedBand, PngColor, PngHeader};

use super::{Frame, FrameRef, OutputError, Pixels};

/// PNG compression effort; `Fast` is the default for frame sequences (also the values of
/// `lapclone render --png-compression`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum PngCompression {
    /// Fast deflate; a sequence's unchanged rows reuse the frame before's bands.
    #[default]
    Fast,
    /// The encoder's default effort.
    Default,
    /// The smallest files.
    Best,
}

/// Encodes the frames of a sequence, one after another.
pub struct FrameEncoder {
    compression: PngCompression,
    bands: BandEncoder,
    previous: Option<Encoded>,
    scratch: Vec<u8>,
}

/// A frame encoded with the band encoder, kept to compare the next frame with.
struct Encoded {
    frame: Frame,
    header: PngHeader,
    bands: Vec<EncodedBand>,
}

impl FrameEncoder {
    pub fn new(compression: PngCompression) -> Self {
        FrameEncoder {
            compression,
            bands: BandEncoder::new(),
            previous: None,
            scratch: Vec::new(),
        }
    }

    /// Encodes `frame` into `out`; gives back the frame it no longer needs, for reuse.
    pub fn encode(&mut self, frame: Frame, out: impl Write) -> Result<Option<Frame>, OutputError> {
        let frame_ref = frame.as_ref()?;
        if self.compression != PngCompression::Fast {
            encode_with_png_crate(&frame_ref, out, self.compression, &mut self.scratch)?;
            return Ok(Some(frame));
        }
        let header = png_header(&frame_ref);
        let (old_frame, mut old_bands) = match self.previous.take() {
            Some(p) if p.header == header => (Some(p.frame), p.bands),
            _ => (None, Vec::new()),
        };
        let before = old_frame.as_ref().map(Frame::as_ref).transpose()?;
        let (before, now) = (before.map(|f| f.pixels()), frame_ref.pixels());
        let mut bands = Vec::with_capacity(header.band_count());
        for index in 0..header.band_count() {
            let mut band = old_bands.get_mut(index).map(std::mem::take).unwrap_or_default();
            let unchanged = before.is_some_and(|before| same_rows(before, now, &header, index));
            if !unchanged {
                let fill = |y, row: &mut [u8]| fill_row(&frame_ref, header.color, y, row);
                self.bands.encode_band(&header, index, fill, &mut band);
            }
            bands.push(band);
        }
        crate::png_bands::write_png(&header, &bands, out).map_err(png_io)?;
        self.previous = Some(Encoded {
            frame,
            header,
            bands,
        });
        Ok(old_frame)
    }
}

fn png_io(e: std::io::Error) -> OutputError {
    OutputError::Png(png::EncodingError::IoError(e))
}

fn png_header(frame: &FrameRef<'_>) -> PngHeader {
    PngHeader {
        width: frame.width(),
        height: frame.height(),
        color: if frame.is_opaque() {
            PngColor::Rgb
        } else {
            PngColor::Rgba
        },
        sixteen_bit: frame.is_16_bit(),
    }
}

/// Whether the rows band `index` is made from (its own and the one above) are equal in the
/// pixels of two frames with the same header.
fn same_rows(a: Pixels<'_>, b: Pixels<'_>, header: &PngHeader, index: usize) -> bool {
    let rows = header.band_rows(index);
    let per_row = header.width as usize * 4;
    let samples = rows.start.saturating_sub(1) as usize * per_row..rows.end as usize * per_row;
    match (a, b) {
        (Pixels::Rgba8(a), Pixels::Rgba8(b)) => a[samples.clone()] == b[samples],
        (Pixels::Rgba16(a), Pixels::Rgba16(b)) => a[samples.clone()] == b[samples],
        _ => false,
    }
}

/// Row `y`'s PNG samples: RGB or RGBA, 16-bit ones big-endian.
fn fill_row(frame: &FrameRef<'_>, color: PngColor, y: u32, row: &mut [u8]) {
    let per_row = frame.width() as usize * 4;
    let start = y as usize * per_row;
    let keep_alpha = color == PngColor::Rgba;
    match frame.pixels() {
        Pixels::Rgba8(p) if keep_alpha => row.copy_from_slice(&p[start..start + per_row]),
        Pixels::Rgba8(p) => {
            let pixels = &p[start..start + per_row];
            // Four bytes per pixel written three apart: each write's alpha byte is
            // overwritten by the next pixel's red, and the last pixel is copied exactly.
            let (body, last) = pixels.split_at(per_row - 4);
            for (i, px) in body.chunks_exact(4).enumerate() {
                row[3 * i..3 * i + 4].copy_from_slice(px);
            }
            let end = row.len();
            row[end - 3..].copy_from_slice(&last[..3]);
        }
        Pixels::Rgba16(p) => {
            let channels = if keep_alpha { 4 } else { 3 };
            let pixels = p[start..start + per_row].chunks_exact(4);
            for (out, px) in row.chunks_exact_mut(2 * channels).zip(pixels) {
                for (pair, v) in out.chunks_exact_mut(2).zip(px) {
                    pair.copy_from_slice(&v.to_be_bytes());
                }
            }
        }
    }
}

fn encode_with_png_crate(
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
    encoder.set_compression(match compression {
        PngCompression::Best => png::Compression::High,
        _ => png::Compression::Balanced,
    });
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::FrameData;

    /// A frame whose rows `changed` differ from the base picture by `shift`.
    fn frame(width: u32, height: u32, sixteen: bool, alpha: u8, changed: std::ops::Range<u32>, shift: u8) -> Frame {
        let mut samples: Vec<u8> = (0..width * height * 4)
            .map(|i| if i % 4 == 3 { alpha } else { (i * 7 / 5 % 251) as u8 })
            .collect();
        for y in changed {
            let row = (y * width * 4) as usize..((y + 1) * width * 4) as usize;
            for (i, s) in samples[row].iter_mut().enumerate() {
                if i % 4 != 3 {
                    *s = s.wrapping_add(shift);
                }
            }
        }
        let data = if sixteen {
            FrameData::Rgba16(
                samples
                    .iter()
                    .enumerate()
                    .map(|(i, &s)| (u16::from(s) * 257).wrapping_add(if i % 4 == 3 { 0 } else { u16::from(shift) }))
                    .collect(),
            )
        } else {
            FrameData::Rgba8(samples)
        };
        Frame { width, height, data }
    }

    fn alone(frame: &Frame) -> Vec<u8> {
        let mut bytes = Vec::new();
        FrameEncoder::new(PngCompression::Fast)
            .encode(frame.clone(), &mut bytes)
            .expect("in memory");
        bytes
    }

    /// Reusing the bands of unchanged rows gives exactly the bytes of encoding each frame
    /// alone, whichever rows changed (band edges, the row above a band, everything).
    #[test]
    fn reused_bands_give_the_bytes_of_a_fresh_encode() {
        for (sixteen, alpha) in [(false, 255), (false, 100), (true, 255), (true, 7)] {
            let (width, height) = (97, 301);
            let rows_per_band = png_header(&frame(width, height, sixteen, alpha, 0..0, 0).as_ref().unwrap()).rows_per_band();
            let edge = rows_per_band;
            let sequence = [
                (0..0, 0),
                (40..60, 3),
                (40..60, 3),
                (edge - 1..edge, 9),
                (edge..edge + 1, 9),
                (0..height, 1),
                (height - 1..height, 2),
            ];
            let mut encoder = FrameEncoder::new(PngCompression::Fast);
            for (changed, shift) in sequence {
                let f = frame(width, height, sixteen, alpha, changed.clone(), shift);
                let expected = alone(&f);
                let mut bytes = Vec::new();
                encoder.encode(f, &mut bytes).expect("in memory");
                assert_eq!(bytes, expected, "rows {changed:?} changed (16-bit {sixteen}, alpha {alpha})");
            }
        }
    }

    /// The png crate reads back the frame's samples: RGB for opaque frames, RGBA otherwise.
    #[test]
    fn decodes_to_the_frame() {
        for (sixteen, alpha) in [(false, 255), (false, 100), (true, 255), (true, 7)] {
            let f = frame(33, 20, sixteen, alpha, 3..5, 4);
            let bytes = alone(&f);
            let mut reader = png::Decoder::new(std::io::Cursor::new(&bytes)).read_info().unwrap();
            let mut decoded = vec![0; reader.output_buffer_size().unwrap()];
            let info = reader.next_frame(&mut decoded).unwrap();
            let opaque = alpha == 255;
            assert_eq!(info.color_type, if opaque { png::ColorType::Rgb } else { png::ColorType::Rgba });
            let mut expected = Vec::new();
            f.as_ref().unwrap().write_png_samples(&mut expected, opaque);
            assert_eq!(decoded, expected);
        }
    }
}
