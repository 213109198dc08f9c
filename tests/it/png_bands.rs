//! The band PNG encoder: its streams decode (png crate) to the rows given, one band or
//! many, on any thread count.

use lapclone::png_bands::{encode_image_parallel, BandEncoder, PngColor, PngHeader};
use proptest::prelude::*;

fn decode(bytes: &[u8]) -> (png::OutputInfo, Vec<u8>) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .expect("a PNG header");
    let mut pixels = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut pixels).expect("a valid PNG");
    pixels.truncate(info.buffer_size());
    (info, pixels)
}

fn image(header: &PngHeader, seed: u64) -> Vec<u8> {
    // Smooth areas, flat runs and noise, as photos and graphics have.
    let len = header.row_bytes() * header.height as usize;
    let mut state = seed | 1;
    (0..len)
        .map(|i| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            match (i / 997) % 3 {
                0 => (i / 3 % 256) as u8,
                1 => 40,
                _ => state as u8,
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, rng_seed: proptest::test_runner::RngSeed::Fixed(5), ..ProptestConfig::default() })]

    /// The png crate decodes exactly the samples given, for every colour type and depth,
    /// and the bytes do not depend on the thread count.
    #[test]
    fn decodes_to_the_samples(
        width in 1u32..300,
        height in 1u32..200,
        color in prop_oneof![Just(PngColor::Grey), Just(PngColor::GreyAlpha), Just(PngColor::Rgb), Just(PngColor::Rgba)],
        sixteen_bit in any::<bool>(),
        seed in any::<u64>(),
    ) {
        let header = PngHeader { width, height, color, sixteen_bit };
        let samples = image(&header, seed);
        let row_bytes = header.row_bytes();
        let fill = |y: u32, buf: &mut [u8]| {
            let start = y as usize * row_bytes;
            buf.copy_from_slice(&samples[start..start + row_bytes]);
        };
        let mut serial = Vec::new();
        BandEncoder::new().encode_image(&header, fill, &mut serial).expect("in memory");
        let (info, decoded) = decode(&serial);
        prop_assert_eq!((info.width, info.height), (width, height));
        prop_assert_eq!(info.bit_depth == png::BitDepth::Sixteen, sixteen_bit);
        prop_assert_eq!(&decoded, &samples);
        for threads in [1, 2, 3, 7] {
            let mut parallel = Vec::new();
            encode_image_parallel(&header, fill, threads, &mut parallel).expect("in memory");
            prop_assert_eq!(&parallel, &serial);
        }
    }
}

#[test]
fn bands_cover_every_row_once() {
    for (width, height) in [(1, 1), (1920, 1080), (70_000, 3), (5, 100_000)] {
        let header = PngHeader {
            width,
            height,
            color: PngColor::Rgb,
            sixteen_bit: false,
        };
        let mut next = 0;
        for band in 0..header.band_count() {
            let rows = header.band_rows(band);
            assert_eq!(rows.start, next);
            assert!(rows.end > rows.start);
            next = rows.end;
        }
        assert_eq!(next, height);
    }
}
