//! The band encoder's Huffman code lengths (length-limited, Kraft-complete) and canonical
//! codes.

use lapclone::png_bands::{canonical_codes, code_lengths};
use proptest::prelude::*;

fn kraft(lengths: &[u8]) -> f64 {
    lengths
        .iter()
        .filter(|&&l| l > 0)
        .map(|&l| 0.5f64.powi(l as i32))
        .sum()
}

#[test]
fn known_code() {
    // RFC 1951's example: lengths (3, 3, 3, 3, 3, 2, 4, 4) give these codes.
    let lengths = [3, 3, 3, 3, 3, 2, 4, 4];
    let mut codes = [0u16; 8];
    canonical_codes(&lengths, &mut codes);
    let expected = [0b010, 0b011, 0b100, 0b101, 0b110, 0b00, 0b1110, 0b1111];
    for ((&c, &e), &l) in codes.iter().zip(&expected).zip(&lengths) {
        assert_eq!(c, (e as u16).reverse_bits() >> (16 - l));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]

    /// Complete (Kraft sum 1), within the limit, no worse than a fixed-length code, and
    /// never giving a rarer symbol a shorter code.
    #[test]
    fn lengths_are_a_complete_limited_code(
        freqs in proptest::collection::vec(prop_oneof![Just(0u32), 1u32..4, 1u32..1_000_000], 2..300),
        limit in 7u8..=15,
    ) {
        prop_assume!(freqs.iter().filter(|&&f| f > 0).count() >= 2);
        prop_assume!(freqs.len() <= 1 << limit);
        let mut lengths = vec![0u8; freqs.len()];
        code_lengths(&freqs, limit, &mut lengths);
        prop_assert!((kraft(&lengths) - 1.0).abs() < 1e-12);
        for (&f, &l) in freqs.iter().zip(&lengths) {
            prop_assert_eq!(f > 0, l > 0);
            prop_assert!(l <= limit);
        }
        for (i, (&fi, &li)) in freqs.iter().zip(&lengths).enumerate() {
            for (&fj, &lj) in freqs[i + 1..].iter().zip(&lengths[i + 1..]) {
                if fi > 0 && fj > 0 && fi < fj {
                    prop_assert!(li >= lj, "a rarer symbol got a shorter code");
                }
            }
        }
    }
}

#[test]
fn skewed_frequencies_respect_the_limit() {
    // Fibonacci frequencies make the optimal code as deep as the alphabet.
    let mut freqs = vec![1u32, 1];
    while freqs.len() < 30 {
        let n = freqs.len();
        freqs.push(freqs[n - 1] + freqs[n - 2]);
    }
    let mut lengths = vec![0u8; 30];
    code_lengths(&freqs, 15, &mut lengths);
    assert_eq!(*lengths.iter().max().unwrap(), 15);
    assert!((kraft(&lengths) - 1.0).abs() < 1e-12);
}
