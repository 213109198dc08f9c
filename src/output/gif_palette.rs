//! The one palette of a GIF and the mapping of pixels onto it: takes RGBA8 sample frames,
//! gives a [`Palette`] of at most 255 opaque colours (index `len()` is reserved for
//! transparency) and a [`PaletteMap`] that turns pixels into indices.
//!
//! The palette is built once per animation (symbolic step): when the sample frames hold at
//! most 255 distinct opaque colours those are the palette, exactly (sorted, so the order is
//! deterministic); otherwise NeuQuant (`color_quant`, sampling factor 10) quantises a
//! deterministic stride sample of their opaque pixels. Mapping (per frame) is an exact
//! nearest-colour search (squared RGB distance, ties to the lower index) cached in a lazily
//! filled 2²⁴-entry table, so each distinct colour is searched once per [`PaletteMap`].
//! Optional ordered dithering (8×8 Bayer) offsets a pixel by a position-dependent amount
//! before the lookup, so the index is still a pure function of (pixel, position).

use std::collections::BTreeSet;

/// Pixels with alpha below this are transparent in a GIF (1-bit alpha).
pub const ALPHA_THRESHOLD: u8 = 128;

/// At most this many pixels train NeuQuant; more are strided down deterministically.
const NEUQUANT_SAMPLE: usize = 1 << 18;

/// Colours available to a GIF frame besides the transparent index.
pub const MAX_COLOURS: usize = 255;

/// Half the range of the ordered-dither offset added to each channel.
const DITHER_AMPLITUDE: f32 = 8.0;

/// An ordered list of at most `MAX_COLOURS` (255) opaque RGB colours.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Palette {
    colours: Vec<[u8; 3]>,
}

impl Palette {
    /// The palette for frames like `samples` (RGBA8, any number of frames of any size).
    pub fn from_samples(samples: &[&[u8]]) -> Palette {
        if let Some(colours) = exact_colours(samples) {
            return Palette { colours };
        }
        let sample = strided_opaque_sample(samples);
        let quant = color_quant::NeuQuant::new(10, MAX_COLOURS, &sample);
        let colours = quant
            .color_map_rgb()
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        Palette { colours }
    }

    pub fn colours(&self) -> &[[u8; 3]] {
        &self.colours
    }

    /// The reserved transparent index (one past the last colour).
    pub fn transparent_index(&self) -> u8 {
        // invariant: at most MAX_COLOURS (255) colours, so the index fits a u8.
        self.colours.len() as u8
    }

    /// The GIF colour table: the colours then black for the transparent index.
    pub fn gif_table(&self) -> Vec<u8> {
        let mut table: Vec<u8> = self.colours.iter().flatten().copied().collect();
        table.extend_from_slice(&[0, 0, 0]);
        table
    }

    /// Checks the size bound.
    pub fn sanity_check(&self) -> Result<(), String> {
        if self.colours.len() > MAX_COLOURS {
            return Err(format!("{} colours > {MAX_COLOURS}", self.colours.len()));
        }
        Ok(())
    }

    fn nearest(&self, rgb: [u8; 3]) -> u8 {
        let mut best = (u32::MAX, 0usize);
        for (i, c) in self.colours.iter().enumerate() {
            let d = (0..3)
                .map(|k| {
                    let e = rgb[k] as i32 - c[k] as i32;
                    (e * e) as u32
                })
                .sum::<u32>();
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1 as u8
    }
}

/// The sorted distinct opaque colours of `samples`, or `None` if there are more than 255.
fn exact_colours(samples: &[&[u8]]) -> Option<Vec<[u8; 3]>> {
    let mut seen = BTreeSet::new();
    let mut last = None;
    for pixel in samples.iter().flat_map(|s| s.chunks_exact(4)) {
        if pixel[3] < ALPHA_THRESHOLD {
            continue;
        }
        let rgb = [pixel[0], pixel[1], pixel[2]];
        if last == Some(rgb) {
            continue; // runs of one colour are common; skip the set lookup
        }
        last = Some(rgb);
        seen.insert(rgb);
        if seen.len() > MAX_COLOURS {
            return None;
        }
    }
    Some(seen.into_iter().collect())
}

/// Every k-th opaque pixel of `samples` (alpha forced to 255), at most [`NEUQUANT_SAMPLE`].
fn strided_opaque_sample(samples: &[&[u8]]) -> Vec<u8> {
    let opaque = || {
        samples
            .iter()
            .flat_map(|s| s.chunks_exact(4))
            .filter(|p| p[3] >= ALPHA_THRESHOLD)
    };
    let count = opaque().count();
    let stride = count.div_ceil(NEUQUANT_SAMPLE).max(1);
    opaque()
        .step_by(stride)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect()
}

/// 8×8 Bayer matrix, values 0..64.
const BAYER8: [[u8; 8]; 8] = [
    [0, 32, 8, 40, 2, 34, 10, 42],
    [48, 16, 56, 24, 50, 18, 58, 26],
    [12, 44, 4, 36, 14, 46, 6, 38],
    [60, 28, 52, 20, 62, 30, 54, 22],
    [3, 35, 11, 43, 1, 33, 9, 41],
    [51, 19, 59, 27, 49, 17, 57, 25],
    [15, 47, 7, 39, 13, 45, 5, 37],
    [63, 31, 55, 23, 61, 29, 53, 21],
];

/// Pixel → palette index, exact nearest colour, cached. One per thread.
pub struct PaletteMap {
    palette: Palette,
    /// index + 1 per 24-bit colour; 0 = not looked up yet.
    cache: Vec<u8>,
    dither: Option<[[i16; 8]; 8]>,
}

impl PaletteMap {
    pub fn new(palette: Palette, dither: bool) -> PaletteMap {
        let dither = dither.then(|| {
            BAYER8.map(|row| {
                row.map(|b| {
                    (((b as f32 + 0.5) / 64.0 - 0.5) * 2.0 * DITHER_AMPLITUDE).round() as i16
                })
            })
        });
        PaletteMap {
            palette,
            // Zeroed allocation: pages are only touched for colours that occur.
            cache: vec![0; 1 << 24],
            dither,
        }
    }

    pub fn palette(&self) -> &Palette {
        &self.palette
    }

    /// The index for an RGBA pixel at (x, y).
    #[inline]
    pub fn index(&mut self, pixel: &[u8], x: usize, y: usize) -> u8 {
        if pixel[3] < ALPHA_THRESHOLD {
            return self.palette.transparent_index();
        }
        let mut rgb = [pixel[0], pixel[1], pixel[2]];
        if let Some(offsets) = &self.dither {
            let offset = offsets[y & 7][x & 7];
            rgb = rgb.map(|c| (c as i16 + offset).clamp(0, 255) as u8);
        }
        let key = (rgb[0] as usize) << 16 | (rgb[1] as usize) << 8 | rgb[2] as usize;
        match self.cache[key] {
            0 => {
                let found = self.palette.nearest(rgb);
                self.cache[key] = found + 1;
                found
            }
            cached => cached - 1,
        }
    }
}
