//! PNG images encoded in independent row bands: takes an image's header and a way to fill
//! any row with its PNG samples, gives the PNG bytes. Rows are Up-filtered and each band of
//! about 64 KiB is one self-contained deflate block (`deflate_block`), so a band's bytes
//! depend only on its own rows and the row above. That buys two things: bands can be
//! encoded on any threads in any order, and a band whose rows did not change since the last
//! frame can be reused as it is ([`EncodedBand`]). The bytes are a pure function of the
//! pixels, so they are identical however the work was split.

mod container;
mod deflate_block;
mod huffman;

use std::io::Write;
use std::sync::atomic::{AtomicUsize, Ordering};

pub use container::{write_png, PngStream};
pub use huffman::{canonical_codes, code_lengths};
use deflate_block::BlockEncoder;

/// A band aims at about this many bytes of filtered rows.
const BAND_BYTES: usize = 64 * 1024;
/// PNG's Up filter: each byte minus the one above it.
const FILTER_UP: u8 = 2;

/// The colour types lapclone writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PngColor {
    Grey,
    GreyAlpha,
    Rgb,
    Rgba,
}

impl PngColor {
    fn channels(self) -> usize {
        match self {
            PngColor::Grey => 1,
            PngColor::GreyAlpha => 2,
            PngColor::Rgb => 3,
            PngColor::Rgba => 4,
        }
    }

    /// The IHDR colour type.
    fn code(self) -> u8 {
        match self {
            PngColor::Grey => 0,
            PngColor::GreyAlpha => 4,
            PngColor::Rgb => 2,
            PngColor::Rgba => 6,
        }
    }
}

/// What the IHDR chunk says, and the band layout that follows from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PngHeader {
    pub width: u32,
    pub height: u32,
    pub color: PngColor,
    pub sixteen_bit: bool,
}

impl PngHeader {
    /// Bytes of samples in one row (without the filter byte).
    pub fn row_bytes(&self) -> usize {
        self.width as usize * self.color.channels() * if self.sixteen_bit { 2 } else { 1 }
    }

    /// Rows per band: a function of the row size only, so bands line up across frames.
    pub fn rows_per_band(&self) -> u32 {
        let rows = BAND_BYTES / (self.row_bytes() + 1);
        (rows.max(1) as u32).min(self.height)
    }

    pub fn band_count(&self) -> usize {
        self.height.div_ceil(self.rows_per_band()) as usize
    }

    /// The rows of band `band`.
    pub fn band_rows(&self, band: usize) -> std::ops::Range<u32> {
        let per = self.rows_per_band();
        let start = band as u32 * per;
        start..(start + per).min(self.height)
    }
}

/// One band's deflate block and the Adler-32 of the filtered bytes it holds.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EncodedBand {
    pub bytes: Vec<u8>,
    pub adler: u32,
    /// Filtered bytes the block inflates to.
    pub filtered_len: usize,
}

/// Encodes bands; keeps its buffers between calls.
#[derive(Default)]
pub struct BandEncoder {
    block: BlockEncoder,
    filtered: Vec<u8>,
    above: Vec<u8>,
    row: Vec<u8>,
}

impl BandEncoder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Encodes band `band` of `header` into `into` (its buffer reused); `fill_row(y, buf)`
    /// writes row `y`'s samples into `buf` (`header.row_bytes()` long).
    pub fn encode_band(
        &mut self,
        header: &PngHeader,
        band: usize,
        mut fill_row: impl FnMut(u32, &mut [u8]),
        into: &mut EncodedBand,
    ) {
        let rows = header.band_rows(band);
        let row_bytes = header.row_bytes();
        self.above.clear();
        self.above.resize(row_bytes, 0);
        self.row.resize(row_bytes, 0);
        if rows.start > 0 {
            fill_row(rows.start - 1, &mut self.above);
        }
        self.filtered.resize(rows.len() * (row_bytes + 1), 0);
        for (y, filtered) in rows.zip(self.filtered.chunks_exact_mut(row_bytes + 1)) {
            fill_row(y, &mut self.row);
            filtered[0] = FILTER_UP;
            for ((out, &b), &a) in filtered[1..].iter_mut().zip(&self.row).zip(&self.above) {
                *out = b.wrapping_sub(a);
            }
            std::mem::swap(&mut self.row, &mut self.above);
        }
        into.bytes.clear();
        self.block.encode(&self.filtered, &mut into.bytes);
        into.adler = simd_adler32::adler32(&self.filtered.as_slice());
        into.filtered_len = self.filtered.len();
    }

    /// The whole image on this thread, each band written as soon as it is encoded.
    pub fn encode_image(
        &mut self,
        header: &PngHeader,
        mut fill_row: impl FnMut(u32, &mut [u8]),
        out: impl Write,
    ) -> std::io::Result<()> {
        let mut stream = PngStream::start(header, out)?;
        let mut band = EncodedBand::default();
        for index in 0..header.band_count() {
            self.encode_band(header, index, &mut fill_row, &mut band);
            stream.band(&band)?;
        }
        stream.finish().map(drop)
    }
}

/// The whole image with its bands encoded on `threads` scoped threads while the caller's
/// thread writes them out in order (on the caller's thread alone for one); the bytes are the
/// same for any thread count.
pub fn encode_image_parallel(
    header: &PngHeader,
    fill_row: impl Fn(u32, &mut [u8]) + Sync,
    threads: usize,
    out: impl Write,
) -> std::io::Result<()> {
    if threads <= 1 {
        return BandEncoder::new().encode_image(header, fill_row, out);
    }
    let count = header.band_count();
    let next = AtomicUsize::new(0);
    let mut stream = PngStream::start(header, out)?;
    std::thread::scope(|scope| {
        let (sender, bands) = std::sync::mpsc::sync_channel(2 * threads);
        for _ in 0..threads {
            let (sender, next, fill_row) = (sender.clone(), &next, &fill_row);
            scope.spawn(move || {
                let mut encoder = BandEncoder::new();
                loop {
                    let index = next.fetch_add(1, Ordering::Relaxed);
                    let mut band = EncodedBand::default();
                    if index >= count {
                        return;
                    }
                    encoder.encode_band(header, index, fill_row, &mut band);
                    if sender.send((index, band)).is_err() {
                        return; // the writer failed and is gone
                    }
                }
            });
        }
        drop(sender);
        // Bands arrive in any order; each is written once the ones above it are.
        let mut waiting = std::collections::BTreeMap::new();
        let mut wanted = 0;
        for (index, band) in bands {
            waiting.insert(index, band);
            while let Some(band) = waiting.remove(&wanted) {
                stream.band(&band)?;
                wanted += 1;
            }
        }
        Ok::<_, std::io::Error>(())
    })?;
    stream.finish().map(drop)
}
