//! The PNG file around encoded bands: takes a header and the bands in row order, gives the
//! signature, IHDR, the zlib stream (header, the bands' blocks, an empty final block, the
//! Adler-32 combined from the bands') in IDAT chunks, and IEND.

use std::io::Write;

use super::deflate_block::FINAL_BLOCK;
use super::{EncodedBand, PngHeader};

const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
/// Deflate with a 32 KiB window, "fastest" flag, check bits making it a multiple of 31.
const ZLIB_HEADER: [u8; 2] = [0x78, 0x01];
/// IDAT chunks stay well under PNG's 2³¹ − 1 byte limit.
const MAX_IDAT: usize = 1 << 30;
const ADLER_MODULUS: u32 = 65_521;

/// Writes the PNG of `bands` (all of `header`'s bands, in order) to `out`.
pub fn write_png(
    header: &PngHeader,
    bands: &[EncodedBand],
    mut out: impl Write,
) -> std::io::Result<()> {
    debug_assert_eq!(bands.len(), header.band_count());
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
    let adler = bands.iter().fold(1u32, |sum, band| {
        adler32_combine(sum, band.adler, band.filtered_len)
    });
    let adler = adler.to_be_bytes();
    let mut pieces: Vec<&[u8]> = vec![&ZLIB_HEADER];
    pieces.extend(bands.iter().map(|band| band.bytes.as_slice()));
    pieces.push(&FINAL_BLOCK);
    pieces.push(&adler);
    for chunk in idat_chunks(&pieces, MAX_IDAT) {
        write_chunk(&mut out, b"IDAT", &chunk)?;
    }
    write_chunk(&mut out, b"IEND", &[])?;
    out.flush()
}

/// Groups consecutive pieces into chunks of at most `max` bytes, splitting a piece only if
/// it alone is larger.
fn idat_chunks<'a>(pieces: &[&'a [u8]], max: usize) -> Vec<Vec<&'a [u8]>> {
    let mut chunks = vec![Vec::new()];
    let mut size = 0;
    for &piece in pieces {
        for part in piece.chunks(max) {
            if size + part.len() > max {
                chunks.push(Vec::new());
                size = 0;
            }
            size += part.len();
            // invariant: `chunks` starts non-empty and only grows.
            chunks.last_mut().expect("a chunk").push(part);
        }
    }
    chunks
}

fn write_chunk(out: &mut impl Write, kind: &[u8; 4], pieces: &[&[u8]]) -> std::io::Result<()> {
    let len: usize = pieces.iter().map(|p| p.len()).sum();
    // invariant: idat_chunks keeps every chunk under 2^30 bytes; IHDR and IEND are tiny.
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

    #[test]
    fn idat_chunks_keep_order_and_size() {
        let max = 16;
        let big = vec![1u8; max + 10];
        let small = [2u8; 5];
        let chunks = idat_chunks(&[&small, &big, &small], max);
        let sizes: Vec<usize> = chunks.iter().map(|c| c.iter().map(|p| p.len()).sum()).collect();
        assert!(sizes.iter().all(|&s| s <= max));
        assert_eq!(sizes.iter().sum::<usize>(), max + 20);
        let flat: Vec<u8> = chunks.iter().flatten().flat_map(|p| p.iter().copied()).collect();
        assert_eq!(flat[..5], small);
        assert_eq!(flat[flat.len() - 5..], small);
    }
}
