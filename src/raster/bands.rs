//! Row bands for shading on several threads: takes the canvas rows of a rectangle and gives
//! bands of [`ROWS_PER_BAND`] rows that the threads take in turn until none is left, each
//! with its own slice of the canvas. Rows shade independently, so the pixels are the same for
//! any split. Bands are taken rather than halves handed out because a worker may start late
//! or share its core with other work: the others do not wait for a fixed half it holds.

use std::sync::Mutex;

use super::PixelRect;

/// Rows per band.
const ROWS_PER_BAND: usize = 40;

/// A band: its canvas rows and the canvas from its first row on.
type Band<'a, T> = (PixelRect, &'a mut [[T; 4]]);

/// The bands not taken yet.
pub(crate) struct Bands<'a, T> {
    left: Mutex<std::vec::IntoIter<Band<'a, T>>>,
}

impl<'a, T> Bands<'a, T> {
    /// Cuts `rows` into bands; `canvas` holds the canvas rows from `rows.y0` on, `width`
    /// pixels wide.
    pub fn new(rows: PixelRect, width: usize, mut canvas: &'a mut [[T; 4]]) -> Self {
        let mut bands = Vec::with_capacity(rows.height().div_ceil(ROWS_PER_BAND));
        let mut y0 = rows.y0;
        while y0 < rows.y1 {
            let y1 = (y0 + ROWS_PER_BAND as i32).min(rows.y1);
            let len = ((y1 - y0) as usize * width).min(canvas.len());
            let (band, rest) = std::mem::take(&mut canvas).split_at_mut(len);
            canvas = rest;
            bands.push((PixelRect { y0, y1, ..rows }, band));
            y0 = y1;
        }
        Bands {
            left: Mutex::new(bands.into_iter()),
        }
    }

    /// Runs `shade` on bands not taken yet until none is left; `shade` gets a band and the
    /// canvas from its first row on and gives (centre hits, pixels written), summed here.
    pub fn shade(&self, shade: impl Fn(PixelRect, &mut [[T; 4]]) -> (usize, usize)) -> (usize, usize) {
        let mut sum = (0, 0);
        // A poisoned lock means another thread panicked, which its join reports.
        while let Some((rows, band)) = self.left.lock().ok().and_then(|mut left| left.next()) {
            let (hits, written) = shade(rows, band);
            sum = (sum.0 + hits, sum.1 + written);
        }
        sum
    }
}
