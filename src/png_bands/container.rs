//! The PNG file around encoded bands: takes a header and the bands in row order, gives the
//! signature, IHDR, the zlib stream (header, the bands' blocks, an empty final block, the
//! Adler-32 combined from the bands') with one IDAT chunk per band, and IEND. Bands can be
//! written as they come, so a file streams out while later bands are still being encoded.

use std::io::Write;

use super::deflate_block::FINAL_BLOCK;
use super::{EncodedBand, PngHeader};

const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
/// Deflate with a 32 KiB window, "fastest" flag, check bits making it a multiple of 31.
const ZLIB_HEADER: [u8; 2] = [0x78, 0x01];
const ADLER_MODULUS: u32 = 65_521;

/// A PNG being written band by band: the signature and IHDR first, then one IDAT chunk per
/// band as it comes (in row order), then the end of the zlib stream and IEND.
pub struct PngStream<W: Write> {
    out: W,
    adler: u32,
    started: bool,
}

impl<W: Write> PngStream<W> {
    /// Writes the signature and IHDR of `header`.
    pub fn start(header: &PngHeader, mut out: W) -> std::io::Result<Self> {
        out.write_all(&SIGNATURE)?;
        let mut ihdr = Vec::with_capacity(13);
        ihdr.extend_from_slice(&header.width.to_be_bytes());
        ihdr.extend_from_slice(&header.height.to_be_bytes());
        ihdr.extend_from_slice(&[
            if header.sixteen_bit { 16 } else { 8 },
            header.color.code(),
            0, // deflate
            0, // adaptive filtering (each row says its filter)
            0, // not interlaced
        ]);
        write_chunk(&mut out, b"IHDR", &[&ihdr])?;
        Ok(PngStream {
            out,
            adler: 1,
            started: false,
        })
    }

    /// Writes the next band (bands are small, so each chunk is far under PNG's limit).
    pub fn band(&mut self, band: &EncodedBand) -> std::io::Result<()> {
        let header: &[u8] = if self.started { &[] } else { &ZLIB_HEADER };
        self.started = true;
        self.adler = adler32_combine(self.adler, band.adler, band.filtered_len);
        write_chunk(&mut self.out, b"IDAT", &[header, &band.bytes])
    }

    /// Closes the zlib stream and the file; gives the writer back, flushed.
    pub fn finish(mut self) -> std::io::Result<W> {
        let header: &[u8] = if self.started { &[] } else { &ZLIB_HEADER };
        let adler = self.adler.to_be_bytes();
        write_chunk(&mut self.out, b"IDAT", &[header, &FINAL_BLOCK, &adler])?;
        write_chunk(&mut self.out, b"IEND", &[])?;
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Writes the PNG of `bands` (all of `header`'s bands, in order) to `out`.
pub fn write_png(header: &PngHeader, bands: &[EncodedBand], out: impl Write) -> std::io::Result<()> {
    debug_assert_eq!(bands.len(), header.band_count());
    let mut stream = PngStream::start(header, out)?;
    for band in bands {
        stream.band(band)?;
    }
    stream.finish().map(drop)
}

fn write_chunk(out: &mut impl Write, kind: &[u8; 4], pieces: &[&[u8]]) -> std::io::Result<()> {
    let len: usize = pieces.iter().map(|p| p.len()).sum();
    // invariant: a band is at most a few rows (`BAND_BYTES` of samples unless one row is
    // longer, and `limits` bounds a row far below 2^31 bytes); IHDR and IEND are tiny.
    let len = u32::try_from(len).expect("chunk under 2^31 bytes");
    out.write_all(&len.to_be_bytes())?;
    out.write_all(kind)?;
    let mut crc = crc32fast::Hasher::new();
    crc.update(kind);
    for piece in pieces {
        crc.update(piece);
        out.write_all(piece)?;
    }
    out.write_all(&crc.finalize().to_be_bytes())
}

/// The Adler-32 of `a`'s data followed by `len_b` bytes whose Adler-32 is `b` (zlib's
/// `adler32_combine`).
fn adler32_combine(a: u32, b: u32, len_b: usize) -> u32 {
    let m = u64::from(ADLER_MODULUS);
    let rem = len_b as u64 % m;
    let (a1, a2) = (u64::from(a & 0xffff), u64::from(a >> 16));
    let (b1, b2) = (u64::from(b & 0xffff), u64::from(b >> 16));
    let sum1 = (a1 + b1 + m - 1) % m;
    let sum2 = (rem * a1 % m + a2 + b2 + m - rem) % m;
    ((sum2 << 16) | sum1) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, rng_seed: proptest::test_runner::RngSeed::Fixed(3), ..ProptestConfig::default() })]

        #[test]
        fn adler_combine_matches_a_whole_checksum(
            first in proptest::collection::vec(any::<u8>(), 0..70_000),
            second in proptest::collection::vec(any::<u8>(), 0..70_000),
        ) {
            let whole = simd_adler32::adler32(&[first.clone(), second.clone()].concat().as_slice());
            let combined = adler32_combine(
                simd_adler32::adler32(&first.as_slice()),
                simd_adler32::adler32(&second.as_slice()),
                second.len(),
            );
            prop_assert_eq!(combined, whole);
        }
    }
}
