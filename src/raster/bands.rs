//! Row bands: takes the per-triangle setups and the canvas rows to shade and gives a partition
//! of those rows into bands of a few dozen rows, each with the ascending list of triangles
//! that may own a pixel centre in the band or in its apron.
//!
//! Why bands: the per-pixel triangle ids, depths and coverage of one band fit in the L2
//! cache, so a frame streams only the source and the canvas through memory instead of
//! several full-size per-pixel buffers; and bands are independent, so threads can take them
//! in any order without changing a single pixel. The apron holds the rows the fringe lookup
//! of [`shade`](super::shade) reads beyond the band (its neighbour radius).

/// Rows above and below a band whose triangle ids the band's shading reads.
pub(crate) const APRON: i32 = 2;

/// The centre rows of a triangle that owns no pixel (not drawable).
pub(crate) const NO_ROWS: (i64, i64) = (0, 0);

/// Pixels per band to aim for (ids + depths + coverage of a band stay well inside L2).
pub(crate) const BAND_PIXELS: usize = 32 * 1024;

/// The bands of one frame, rebuilt per frame into grow-only storage.
#[derive(Default)]
pub(crate) struct Bands {
    first_row: i32,
    last_row: i32,
    height: i32,
    starts: Vec<u32>,
    triangles: Vec<u32>,
    /// Per triangle: its first and last band (`lo > hi`: none), found once per frame.
    ranges: Vec<(u32, u32)>,
}

impl Bands {
    /// Splits rows `[first_row, last_row)` of a `width`-pixel-wide region into bands of about
    /// `band_pixels` pixels (8 to 64 rows; any height gives the same pixels) and bins every
    /// triangle into the bands whose rows or apron its centre rows (`[top, bottom)`, per
    /// triangle: `centre_rows` of a drawable one, [`NO_ROWS`] otherwise) may reach.
    pub fn build(
        &mut self,
        centre_rows: &[(i64, i64)],
        (first_row, last_row): (i32, i32),
        width: usize,
        band_pixels: usize,
    ) {
        self.first_row = first_row;
        self.last_row = last_row.max(first_row);
        self.height = (band_pixels / width.max(1)).clamp(8, 64) as i32;
        let count = self.count();
        let mut ranges = std::mem::take(&mut self.ranges);
        ranges.clear();
        // Bands are at most canvas rows, so their indices fit u32.
        ranges.extend(centre_rows.iter().map(|&rows| {
            self.band_range(rows, count)
                .map_or((1, 0), |(lo, hi)| (lo as u32, hi as u32))
        }));
        self.starts.clear();
        self.starts.resize(count + 1, 0);
        for &(lo, hi) in &ranges {
            for band in lo..=hi {
                self.starts[band as usize + 1] += 1;
            }
        }
        for band in 0..count {
            self.starts[band + 1] += self.starts[band];
        }
        self.triangles.clear();
        self.triangles.resize(self.starts[count] as usize, 0);
        // `starts[band]` serves as the band's fill cursor, then is shifted back.
        for (index, &(lo, hi)) in ranges.iter().enumerate() {
            for band in lo as usize..=hi as usize {
                self.triangles[self.starts[band] as usize] = index as u32;
                self.starts[band] += 1;
            }
        }
        self.ranges = ranges;
        for band in (1..=count).rev() {
            self.starts[band] = self.starts[band - 1];
        }
        if let Some(first) = self.starts.first_mut() {
            *first = 0;
        }
    }

    /// Rows per band (the last band may be shorter).
    pub fn height(&self) -> i32 {
        self.height
    }

    pub fn count(&self) -> usize {
        let rows = (self.last_row - self.first_row).max(0);
        ((rows + self.height - 1) / self.height.max(1)) as usize
    }

    /// The canvas rows `[y0, y1)` of `band`.
    pub fn rows(&self, band: usize) -> (i32, i32) {
        let y0 = self.first_row + band as i32 * self.height;
        (y0, (y0 + self.height).min(self.last_row))
    }

    /// The triangles of `band`, ascending.
    pub fn triangles(&self, band: usize) -> &[u32] {
        &self.triangles[self.starts[band] as usize..self.starts[band + 1] as usize]
    }

    /// The bands (of `count`) whose rows ± [`APRON`] meet the centre rows `[top, bottom)`.
    fn band_range(&self, (top, bottom): (i64, i64), count: usize) -> Option<(usize, usize)> {
        if count == 0 {
            return None;
        }
        let (apron, first, last_row) = (
            i64::from(APRON),
            i64::from(self.first_row),
            i64::from(self.last_row),
        );
        if top >= last_row + apron || bottom <= first - apron {
            return None;
        }
        let reach_top = top - i64::from(APRON) - i64::from(self.first_row);
        let reach_bottom = bottom - 1 + i64::from(APRON) - i64::from(self.first_row);
        // Rows above the first band clamp to band 0, rows far below to the last band, so an
        // unsigned 32-bit division gives the floor (heights are 8 to 64, never 0).
        let height = self.height.max(1) as u32;
        let band_of = |reach: i64| (reach.clamp(0, i64::from(u32::MAX)) as u32 / height) as usize;
        let (lo, hi) = (band_of(reach_top), band_of(reach_bottom).min(count - 1));
        (top < bottom && lo <= hi).then_some((lo, hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::setup::TriangleSetup;
    use crate::raster::triangles::centre_rows;
    use glam::DVec2;

    fn rows_of(setups: &[TriangleSetup]) -> Vec<(i64, i64)> {
        setups
            .iter()
            .map(|s| if s.drawable { centre_rows(s) } else { NO_ROWS })
            .collect()
    }

    fn triangle(y0: f64, y1: f64) -> TriangleSetup {
        let corners = [
            DVec2::new(0.0, y0),
            DVec2::new(10.0, y0),
            DVec2::new(0.0, y1),
        ];
        TriangleSetup::new(corners, corners, [[0.0; 3]; 3], [0.0; 3])
    }

    #[test]
    fn every_band_lists_exactly_the_triangles_reaching_its_rows_and_apron() {
        let setups: Vec<TriangleSetup> = (0..60)
            .map(|k| {
                let top = -20.0 + f64::from(k) * 7.3;
                triangle(top, top + 1.0 + f64::from(k % 9) * 5.1)
            })
            .collect();
        let mut bands = Bands::default();
        bands.build(&rows_of(&setups), (3, 301), 2000, BAND_PIXELS);
        assert_eq!(bands.height(), 16);
        assert_eq!(bands.count(), 19);
        assert_eq!(bands.rows(18), (291, 301));
        for band in 0..bands.count() {
            let (y0, y1) = bands.rows(band);
            let expected: Vec<u32> = (0..setups.len() as u32)
                .filter(|&k| {
                    let (top, bottom) = centre_rows(&setups[k as usize]);
                    top < bottom && top < i64::from(y1 + APRON) && bottom > i64::from(y0 - APRON)
                })
                .collect();
            assert_eq!(bands.triangles(band), expected.as_slice(), "band {band}");
        }
    }

    #[test]
    fn no_rows_no_bands() {
        let mut bands = Bands::default();
        bands.build(&rows_of(&[triangle(0.0, 5.0)]), (10, 10), 100, BAND_PIXELS);
        assert_eq!(bands.count(), 0);
    }
}
