//! One self-contained deflate block for a band of PNG-filtered rows: takes bytes, gives a
//! non-final dynamic-Huffman block (literals, and runs of zeros as distance-1 matches) whose
//! code is built from the band's own histogram, followed by an empty stored block so the
//! output ends on a byte boundary. The bytes depend only on the input, never on what comes
//! before or after, so blocks encoded separately (on other threads, or for an earlier frame)
//! can be concatenated into one zlib stream.

use super::huffman::{canonical_codes, code_lengths};

/// Literal/length symbols: 256 literals, end of block, 29 lengths.
const LITLEN_SYMBOLS: usize = 286;
const END_OF_BLOCK: usize = 256;
/// The order code-length code lengths are written in (RFC 1951 §3.2.7).
const CODE_LENGTH_ORDER: [usize; 19] = [
    16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15,
];
/// Longest literal/length code: four fit in one 64-bit write with the 7 bits left over.
const MAX_CODE_LENGTH: u8 = 12;
/// Shortest and longest match deflate codes.
const MIN_MATCH: u32 = 3;
const MAX_MATCH: u32 = 258;
/// A zero run this long or longer is a literal zero and a match; shorter runs stay literals.
const MIN_RUN: u32 = MIN_MATCH + 1;

/// The empty final block (fixed Huffman, end of block only) that closes a stream of bands.
pub const FINAL_BLOCK: [u8; 2] = [0x03, 0x00];

/// Encodes bands; holds the per-block tables between calls.
pub struct BlockEncoder {
    freqs: [u32; LITLEN_SYMBOLS],
    lengths: [u8; LITLEN_SYMBOLS],
    codes: [u16; LITLEN_SYMBOLS],
    /// Each literal's code (low 16 bits) and length (high bits), looked up once per byte.
    literal: [u32; 256],
    /// Where a block is written before it is copied out at its exact length.
    scratch: Vec<u8>,
    /// Length symbol (257..=285) and extra-bit count for each match length.
    length_symbol: [(u16, u8); MAX_MATCH as usize + 1],
}

impl Default for BlockEncoder {
    fn default() -> Self {
        Self::new()
    }
}

impl BlockEncoder {
    pub fn new() -> Self {
        let mut length_symbol = [(0u16, 0u8); MAX_MATCH as usize + 1];
        // RFC 1951 §3.2.5: symbols 257..284 cover 3..257 in groups of growing size; 285 is 258.
        let mut base = MIN_MATCH;
        for symbol in 257u16..285 {
            let extra = if symbol < 265 {
                0
            } else {
                ((symbol - 261) / 4) as u8
            };
            for length in base..base + (1 << extra) {
                length_symbol[length as usize] = (symbol, extra);
            }
            base += 1 << extra;
        }
        length_symbol[MAX_MATCH as usize] = (285, 0);
        BlockEncoder {
            freqs: [0; LITLEN_SYMBOLS],
            lengths: [0; LITLEN_SYMBOLS],
            codes: [0; LITLEN_SYMBOLS],
            literal: [0; 256],
            scratch: Vec::new(),
            length_symbol,
        }
    }

    /// Appends `data` as one non-final block plus the byte-aligning empty stored block.
    pub fn encode(&mut self, data: &[u8], out: &mut Vec<u8>) {
        self.count_symbols(data);
        code_lengths(&self.freqs, MAX_CODE_LENGTH, &mut self.lengths);
        canonical_codes(&self.lengths, &mut self.codes);
        for (packed, (&code, &len)) in self.literal.iter_mut().zip(self.codes.iter().zip(&self.lengths)) {
            *packed = u32::from(code) | u32::from(len) << 16;
        }
        // Written into a scratch buffer kept at its largest size (no zeroing per block), then
        // copied out at its exact length.
        let mut scratch = std::mem::take(&mut self.scratch);
        let bound = data.len() * usize::from(MAX_CODE_LENGTH) / 8 + 512;
        if scratch.len() < bound {
            scratch.resize(bound, 0);
        }
        let mut bits = BitWriter::new(&mut scratch);
        self.write_header(&mut bits);
        // The writer moves into the emitter and back, so its state can stay in registers.
        let mut emitter = Emitter {
            encoder: self,
            bits,
        };
        tokenize(data, &mut emitter);
        let mut bits = emitter.bits;
        bits.put(
            u64::from(self.codes[END_OF_BLOCK]),
            self.lengths[END_OF_BLOCK],
        );
        // An empty stored block: BFINAL 0, BTYPE 00, pad to the byte, LEN 0, NLEN !0.
        bits.put(0, 3);
        let len = bits.finish();
        out.extend_from_slice(&scratch[..len]);
        out.extend_from_slice(&[0x00, 0x00, 0xff, 0xff]);
        self.scratch = scratch;
    }

    /// Symbol frequencies for the code: the bytes outside all-zero 8-byte words as literals,
    /// the longest match once per 32 zero words (the runs they make), and every other
    /// length symbol and the end of block once. Any frequencies give a valid code as long as
    /// every symbol used has one; these are cheap to count and close enough to the token
    /// counts that the code is as short.
    fn count_symbols(&mut self, data: &[u8]) {
        let mut counts = [[0u32; 256]; 4];
        let mut zero_words = 0;
        let mut words = data.chunks_exact(8);
        for word in &mut words {
            if word.iter().all(|&b| b == 0) {
                zero_words += 1;
                continue;
            }
            for (i, &b) in word.iter().enumerate() {
                counts[i % 4][b as usize] += 1;
            }
        }
        for &b in words.remainder() {
            counts[0][b as usize] += 1;
        }
        for (symbol, freq) in self.freqs[..256].iter_mut().enumerate() {
            *freq = counts.iter().map(|lane| lane[symbol]).sum();
        }
        self.freqs[END_OF_BLOCK..].fill(1);
        self.freqs[0] += zero_words / 32;
        self.freqs[LITLEN_SYMBOLS - 1] += zero_words / 32;
    }

    fn write_header(&self, bits: &mut BitWriter<'_>) {
        let used = LITLEN_SYMBOLS - self.lengths.iter().rev().take_while(|&&l| l == 0).count();
        // Two distance codes of one bit (only distance 1 is used): a complete code.
        let distance_lengths = [1u8, 1];
        let mut all_lengths = self.lengths[..used].to_vec();
        all_lengths.extend_from_slice(&distance_lengths);
        let runs = code_length_runs(&all_lengths);
        let mut clen_freqs = [0u32; 19];
        for &(symbol, _) in &runs {
            clen_freqs[symbol as usize] += 1;
        }
        if clen_freqs.iter().filter(|&&f| f > 0).count() < 2 {
            // A one-symbol code-length code would be incomplete, which inflaters refuse.
            let spare = if clen_freqs[0] == 0 { 0 } else { 1 };
            clen_freqs[spare] = 1;
        }
        let mut clen_lengths = [0u8; 19];
        let mut clen_codes = [0u16; 19];
        code_lengths(&clen_freqs, 7, &mut clen_lengths);
        canonical_codes(&clen_lengths, &mut clen_codes);
        let written = 19
            - CODE_LENGTH_ORDER
                .iter()
                .rev()
                .take_while(|&&s| clen_lengths[s] == 0)
                .count();
        let written = written.max(4);
        // BFINAL 0, BTYPE 10 (dynamic), then HLIT, HDIST, HCLEN.
        bits.put(0b100, 3);
        bits.put((used - 257) as u64, 5);
        bits.put((distance_lengths.len() - 1) as u64, 5);
        bits.put((written - 4) as u64, 4);
        for &symbol in &CODE_LENGTH_ORDER[..written] {
            bits.put(u64::from(clen_lengths[symbol]), 3);
        }
        for (symbol, extra) in runs {
            let s = symbol as usize;
            bits.put(u64::from(clen_codes[s]), clen_lengths[s]);
            match symbol {
                16 => bits.put(u64::from(extra), 2),
                17 => bits.put(u64::from(extra), 3),
                18 => bits.put(u64::from(extra), 7),
                _ => {}
            }
        }
    }
}

/// Code lengths as code-length symbols (0–15 literal, 16 repeat, 17/18 zero runs) with their
/// extra-bit values.
fn code_length_runs(lengths: &[u8]) -> Vec<(u8, u8)> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < lengths.len() {
        let value = lengths[i];
        let mut count = lengths[i..].iter().take_while(|&&l| l == value).count();
        i += count;
        if value == 0 {
            while count >= 11 {
                let k = count.min(138);
                runs.push((18, (k - 11) as u8));
                count -= k;
            }
            if count >= 3 {
                runs.push((17, (count - 3) as u8));
                count = 0;
            }
        } else {
            runs.push((value, 0));
            count -= 1;
            while count >= 3 {
                let k = count.min(6);
                runs.push((16, (k - 3) as u8));
                count -= k;
            }
        }
        runs.extend(std::iter::repeat_n((value, 0), count));
    }
    runs
}

/// What [`tokenize`] hands its tokens to.
trait TokenSink {
    /// Eight literals, the bytes of `word` in little-endian order.
    fn word(&mut self, word: u64);
    fn literals(&mut self, bytes: &[u8]);
    /// `length` (`MIN_MATCH..=MAX_MATCH`) copies of the byte before.
    fn repeat(&mut self, length: u32);
}

/// Splits `data` into literals and zero runs. Zeros inside an 8-byte word that also holds
/// other bytes stay literals, which keeps the scan branch-light; runs start and end at word
/// edges or at the data's ends.
#[inline(always)]
fn tokenize(data: &[u8], sink: &mut impl TokenSink) {
    let mut zeros = 0u32;
    let mut words = data.chunks_exact(8);
    for word in &mut words {
        // invariant: chunks_exact(8) yields 8-byte slices.
        let value = u64::from_le_bytes(word.try_into().expect("8 bytes"));
        if value == 0 {
            zeros += 8;
            continue;
        }
        let leading = value.trailing_zeros() / 8;
        let trailing = value.leading_zeros() / 8;
        if zeros + leading + trailing == 0 {
            sink.word(value);
            continue;
        }
        flush_zeros(zeros + leading, sink);
        sink.literals(&word[leading as usize..8 - trailing as usize]);
        zeros = trailing;
    }
    let tail = words.remainder();
    let tail_zeros = tail.iter().take_while(|&&b| b == 0).count();
    flush_zeros(zeros + tail_zeros as u32, sink);
    if tail_zeros < tail.len() {
        sink.literals(&tail[tail_zeros..]);
    }
}

#[inline(always)]
fn flush_zeros(mut zeros: u32, sink: &mut impl TokenSink) {
    const ZEROS: [u8; MIN_RUN as usize] = [0; MIN_RUN as usize];
    if zeros < MIN_RUN {
        sink.literals(&ZEROS[..zeros as usize]);
        return;
    }
    sink.literals(&ZEROS[..1]);
    zeros -= 1;
    while zeros >= MIN_MATCH {
        // Never leave a remainder too short to be a match of its own.
        let take = if zeros > MAX_MATCH && zeros - MAX_MATCH < MIN_MATCH {
            zeros - MIN_MATCH
        } else {
            zeros.min(MAX_MATCH)
        };
        sink.repeat(take);
        zeros -= take;
    }
    sink.literals(&ZEROS[..zeros as usize]);
}

struct Emitter<'a> {
    encoder: &'a BlockEncoder,
    bits: BitWriter<'a>,
}

impl Emitter<'_> {
    /// Four packed literal codes (code in the low 16 bits, length above) in one write.
    #[inline(always)]
    fn put_four(&mut self, [a, b, c, d]: [u32; 4]) {
        let (la, lb, lc) = (a >> 16, b >> 16, c >> 16);
        let word = u64::from(a & 0xffff)
            | u64::from(b & 0xffff) << la
            | u64::from(c & 0xffff) << (la + lb)
            | u64::from(d & 0xffff) << (la + lb + lc);
        self.bits.put(word, (la + lb + lc + (d >> 16)) as u8);
    }
}

impl TokenSink for Emitter<'_> {
    #[inline(always)]
    fn word(&mut self, word: u64) {
        let literal = &self.encoder.literal;
        for half in [word as u32, (word >> 32) as u32] {
            let [a, b, c, d] = half.to_le_bytes().map(|byte| literal[byte as usize]);
            self.put_four([a, b, c, d]);
        }
    }

    #[inline(always)]
    fn literals(&mut self, bytes: &[u8]) {
        let literal = &self.encoder.literal;
        // Four codes of at most 12 bits go out in one write.
        let mut quads = bytes.chunks_exact(4);
        for quad in &mut quads {
            let [a, b, c, d] = [0, 1, 2, 3].map(|i| literal[quad[i] as usize]);
            self.put_four([a, b, c, d]);
        }
        for &byte in quads.remainder() {
            let code = literal[byte as usize];
            self.bits.put(u64::from(code & 0xffff), (code >> 16) as u8);
        }
    }

    #[inline(always)]
    fn repeat(&mut self, length: u32) {
        let (symbol, extra) = self.encoder.length_symbol[length as usize];
        let (symbol, base) = (symbol as usize, first_length(symbol));
        let code = u64::from(self.encoder.codes[symbol]);
        let len = self.encoder.lengths[symbol];
        // The length's extra bits, then distance code 0 (distance 1) in one bit.
        let word = code | (u64::from(length - base) << len);
        self.bits.put(word, len + extra + 1);
    }
}

/// The shortest match length a length symbol stands for.
fn first_length(symbol: u16) -> u32 {
    match symbol {
        257..=264 => u32::from(symbol) - 254,
        285 => MAX_MATCH,
        _ => {
            let extra = u32::from(symbol - 261) / 4;
            let group_start = [11, 19, 35, 67, 131][extra as usize - 1];
            group_start + (u32::from(symbol - 265) % 4) * (1 << extra)
        }
    }
}

/// Bits packed LSB first into whole bytes, written eight bytes at a time.
struct BitWriter<'a> {
    out: &'a mut [u8],
    /// Where the next eight bytes go.
    at: usize,
    buffer: u64,
    count: u8,
}

impl<'a> BitWriter<'a> {
    /// Writes from the start of `out`, which must be long enough for everything put plus
    /// eight bytes.
    fn new(out: &'a mut [u8]) -> Self {
        BitWriter {
            out,
            at: 0,
            buffer: 0,
            count: 0,
        }
    }

    /// Adds the low `n` (at most 64) bits of `bits`.
    #[inline(always)]
    fn put(&mut self, bits: u64, n: u8) {
        debug_assert!(n == 64 || bits >> n == 0);
        self.buffer |= bits.checked_shl(u32::from(self.count)).unwrap_or(0);
        let total = self.count + n;
        if total >= 64 {
            self.out[self.at..self.at + 8].copy_from_slice(&self.buffer.to_le_bytes());
            self.at += 8;
            // The bits that did not fit in the word just written.
            self.buffer = bits.checked_shr(u32::from(64 - self.count)).unwrap_or(0);
            self.count = total - 64;
        } else {
            self.count = total;
        }
    }

    /// Writes the bits held, padded with zeros to a whole byte; gives the bytes written.
    fn finish(self) -> usize {
        let bytes = usize::from(self.count).div_ceil(8);
        self.out[self.at..self.at + bytes].copy_from_slice(&self.buffer.to_le_bytes()[..bytes]);
        self.at + bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::io::Read;

    /// A zlib stream of `bands`, each encoded on its own.
    fn zlib_of(bands: &[&[u8]]) -> Vec<u8> {
        let mut encoder = BlockEncoder::new();
        let mut out = vec![0x78, 0x01];
        let mut adler = simd_adler32::Adler32::new();
        for band in bands {
            encoder.encode(band, &mut out);
            adler.write(band);
        }
        out.extend_from_slice(&FINAL_BLOCK);
        out.extend_from_slice(&adler.finish().to_be_bytes());
        out
    }

    fn inflate(stream: &[u8]) -> Vec<u8> {
        let mut decoded = Vec::new();
        flate2::read::ZlibDecoder::new(stream)
            .read_to_end(&mut decoded)
            .expect("a valid zlib stream");
        decoded
    }

    #[test]
    fn length_symbols_match_the_rfc() {
        let encoder = BlockEncoder::new();
        for (length, symbol, extra) in [(3, 257, 0), (10, 264, 0), (11, 265, 1), (12, 265, 1)] {
            assert_eq!(encoder.length_symbol[length], (symbol, extra));
        }
        for (length, symbol, extra) in [(13, 266, 1), (19, 269, 2), (227, 284, 5), (257, 284, 5)] {
            assert_eq!(encoder.length_symbol[length], (symbol, extra));
        }
        assert_eq!(encoder.length_symbol[258], (285, 0));
        for length in MIN_MATCH..=MAX_MATCH {
            let (symbol, extra) = encoder.length_symbol[length as usize];
            let base = first_length(symbol);
            assert!(length >= base && length - base < 1 << extra, "{length}");
        }
    }

    #[test]
    fn zero_runs_of_every_length_round_trip() {
        for run in 0..600usize {
            let mut data = vec![7u8; 5];
            data.extend(std::iter::repeat_n(0, run));
            data.push(9);
            assert_eq!(inflate(&zlib_of(&[&data])), data, "run of {run}");
        }
    }

    #[test]
    fn a_constant_band_compresses_and_round_trips() {
        let data = vec![0u8; 100_000];
        let stream = zlib_of(&[&data, &data]);
        assert!(stream.len() < 2_000, "{} bytes", stream.len());
        assert_eq!(inflate(&stream), [data.clone(), data].concat());
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(11), ..ProptestConfig::default() })]

        /// Any bands, split anywhere, inflate back to their concatenation.
        #[test]
        fn bands_round_trip(
            bands in proptest::collection::vec(
                proptest::collection::vec(prop_oneof![3 => Just(0u8), 1 => any::<u8>(), 1 => 0u8..3], 1..3000),
                1..5,
            )
        ) {
            let slices: Vec<&[u8]> = bands.iter().map(|b| b.as_slice()).collect();
            prop_assert_eq!(inflate(&zlib_of(&slices)), bands.concat());
        }
    }
}
