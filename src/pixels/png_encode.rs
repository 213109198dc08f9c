//! PNG encoding: takes straight RGBA pixels of any [`Texel`] type and a [`PixelFormat`] and
//! writes PNG bytes in exactly that format (grey / grey+alpha / RGB / RGBA, 8 or 16 bit) to
//! any writer (tiny-skia cannot hold 16-bit pixels). Every row is Up-filtered and the rows
//! are deflated by `fdeflate` (what the `png` crate's fastest setting does), in a pipeline:
//! a scoped helper thread lays out and filters bands of rows while the caller's thread
//! compresses them into IDAT chunks, so no whole-image sample buffer exists. The zlib stream
//! is the png crate's own for `Compression::Fastest` (tested), except that data deflate
//! would enlarge stays deflated instead of falling back to stored blocks. The bytes depend
//! only on the pixels and the format.

use std::io::Write;
use std::sync::mpsc;

use super::float_image::LUMA_709;
use super::{ColorKind, Depth, PixelError, PixelFormat, Texel};

/// Rows laid out, filtered and compressed per step: large enough that the per-step cost
/// vanishes, small enough to stay in cache.
const BAND_ROWS: usize = 16;

/// Compressed bytes per IDAT chunk.
const IDAT_BYTES: usize = 1 << 20;

/// PNG's Up filter: each byte minus the byte above it.
const FILTER_UP: u8 = 2;

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
    let mut writer = encoder.write_header()?;
    write_idat(pixels, width as usize, format, &mut writer)?;
    writer.finish()?;
    Ok(())
}

/// The image data: bands filtered on a helper thread, compressed here into IDAT chunks.
fn write_idat<T: PngSample, W: Write>(
    pixels: &[[T; 4]],
    width: usize,
    format: PixelFormat,
    writer: &mut png::Writer<W>,
) -> Result<(), png::EncodingError> {
    let mut idat = IdatChunks {
        writer,
        pending: Vec::with_capacity(IDAT_BYTES),
    };
    let mut compressor = fdeflate::Compressor::new(&mut idat)?;
    std::thread::scope(|scope| {
        let (bands, filtered) = mpsc::sync_channel(2);
        let (spares, spare) = mpsc::channel();
        scope.spawn(move || filter_bands(pixels, width, format, bands, spare));
        let row_bytes = 1 + width * format.channel_count() * depth_bytes(format.depth);
        for band in filtered {
            // Row by row, as the png crate feeds fdeflate: the same stream, byte for byte.
            for row in band.chunks(row_bytes) {
                compressor.write_data(row)?;
            }
            // The helper may have finished: a spare nobody takes is simply dropped.
            let _ = spares.send(band);
        }
        Ok::<_, std::io::Error>(())
    })?;
    compressor.finish()?;
    idat.write_pending()
}

/// Lays out `pixels` band by band (rows of `width`), Up-filters every row and sends the
/// bands in order; stops when the receiver is gone. Buffers come back through `spare`.
fn filter_bands<T: PngSample>(
    pixels: &[[T; 4]],
    width: usize,
    format: PixelFormat,
    bands: mpsc::SyncSender<Vec<u8>>,
    spare: mpsc::Receiver<Vec<u8>>,
) {
    let row_bytes = width * format.channel_count() * depth_bytes(format.depth);
    let mut samples = Vec::new();
    let mut above = vec![0u8; row_bytes];
    for rows in pixels.chunks(width * BAND_ROWS) {
        samples.clear();
        interleave(rows, format, &mut samples);
        let mut band = spare.try_recv().unwrap_or_default();
        band.clear();
        for row in samples.chunks_exact(row_bytes) {
            band.push(FILTER_UP);
            band.extend(row.iter().zip(&above).map(|(&x, &b)| x.wrapping_sub(b)));
            above.copy_from_slice(row);
        }
        if bands.send(band).is_err() {
            return;
        }
    }
}

/// Bytes per sample in `depth`.
fn depth_bytes(depth: Depth) -> usize {
    match depth {
        Depth::Eight => 1,
        Depth::Sixteen => 2,
    }
}

/// The zlib stream, cut into IDAT chunks of [`IDAT_BYTES`] as it comes.
struct IdatChunks<'a, W: Write> {
    writer: &'a mut png::Writer<W>,
    pending: Vec<u8>,
}

impl<W: Write> IdatChunks<'_, W> {
    fn write_pending(&mut self) -> Result<(), png::EncodingError> {
        if !self.pending.is_empty() {
            self.writer.write_chunk(png::chunk::IDAT, &self.pending)?;
            self.pending.clear();
        }
        Ok(())
    }
}

impl<W: Write> Write for IdatChunks<'_, W> {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.pending.extend_from_slice(bytes);
        if self.pending.len() >= IDAT_BYTES {
            self.write_pending()?;
        }
        Ok(bytes.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Appends the channel samples of `pixels` in PNG order and byte layout (16-bit big-endian).
/// RGB samples in the texels' own depth are copied as they are (quantising a texel's value
/// gives the texel back); grey and other depths go through [0, 1].
fn interleave<T: PngSample>(pixels: &[[T; 4]], format: PixelFormat, out: &mut Vec<u8>) {
    let channels = if format.alpha { 4 } else { 3 };
    if format.color == ColorKind::Rgb && format.depth == T::DEPTH {
        let start = out.len();
        out.resize(start + pixels.len() * channels * T::BYTES, 0);
        let bytes = out[start..].chunks_exact_mut(channels * T::BYTES);
        for (px, bytes) in pixels.iter().zip(bytes) {
            for (&c, sample) in px.iter().zip(bytes.chunks_exact_mut(T::BYTES)) {
                c.put_raw(sample);
            }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The concatenated IDAT payloads of a PNG file.
    fn idat_stream(png: &[u8]) -> Vec<u8> {
        let mut stream = Vec::new();
        let mut at = 8;
        while at + 8 <= png.len() {
            let len = u32::from_be_bytes(png[at..at + 4].try_into().unwrap()) as usize;
            if &png[at + 4..at + 8] == b"IDAT" {
                stream.extend_from_slice(&png[at + 8..at + 8 + len]);
            }
            at += len + 12;
        }
        stream
    }

    /// The zlib stream is the `png` crate's own for its fastest setting (Up filter, fdeflate)
    /// on the same samples, across several bands and both depths.
    #[test]
    fn the_stream_is_the_png_crates_fastest() {
        let (width, height) = (37u32, 3 * BAND_ROWS as u32 + 5);
        // Smooth ramps with a little noise: compressible, so the png crate keeps the deflated
        // stream rather than falling back to stored blocks.
        let noise = |i: u32| ((i.wrapping_mul(2_654_435_761) >> 13) % 3) as u8;
        let eight: Vec<[u8; 4]> = (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as u8, (i / width) as u8);
                [x * 3 + noise(i), y * 2, 40 + noise(i + 1), 255]
            })
            .collect();
        let sixteen: Vec<[u16; 4]> = eight
            .iter()
            .map(|p| p.map(|v| u16::from(v) * 251))
            .collect();
        for (alpha, depth) in [(false, Depth::Eight), (true, Depth::Sixteen)] {
            let format = PixelFormat {
                color: ColorKind::Rgb,
                alpha,
                depth,
            };
            let mut ours = Vec::new();
            let mut samples = Vec::new();
            match depth {
                Depth::Eight => {
                    write_png_rgba(&eight, width, height, format, &mut ours).unwrap();
                    interleave(&eight, format, &mut samples);
                }
                Depth::Sixteen => {
                    write_png_rgba(&sixteen, width, height, format, &mut ours).unwrap();
                    interleave(&sixteen, format, &mut samples);
                }
            }
            let mut reference = Vec::new();
            let mut encoder = png::Encoder::new(&mut reference, width, height);
            encoder.set_color(if alpha {
                png::ColorType::Rgba
            } else {
                png::ColorType::Rgb
            });
            encoder.set_depth(match depth {
                Depth::Eight => png::BitDepth::Eight,
                Depth::Sixteen => png::BitDepth::Sixteen,
            });
            encoder.set_compression(png::Compression::Fastest);
            let mut writer = encoder.write_header().unwrap();
            writer.write_image_data(&samples).unwrap();
            writer.finish().unwrap();
            let (ours_stream, reference_stream) = (idat_stream(&ours), idat_stream(&reference));
            let stored = fdeflate::StoredOnlyCompressor::<()>::compressed_size(
                samples.len() + height as usize,
            );
            assert!(reference_stream.len() < stored, "the reference is deflated");
            assert!(ours_stream == reference_stream, "{format:?}");
            assert_eq!(ours[..33], reference[..33], "signature and IHDR");
        }
    }
}
