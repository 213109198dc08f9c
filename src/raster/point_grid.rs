//! A uniform grid over a set of points: takes placed positions and gives, for any box, the
//! points whose cells it overlaps, in a fixed order (cells row by row, points of a cell in the
//! order given). Rebuilt per call into reusable buffers; the coverage query and the clone
//! stage's beneath query bucket their candidate vertices with it.
//!
//! About four cells per point: candidates line up along curves (a mesh boundary), so an
//! occupied cell holds a few, and a small triangle's box spans one or two cells. The second
//! bound keeps a box that is flat (points on a line) at about 4n cells per side, so never more
//! than about 12n cells.

use glam::DVec2;

/// Reusable buffers of a point grid.
#[derive(Default, Debug)]
pub struct PointGrid {
    /// Per cell (and one past the last): the first of its points in `cell_points`.
    cell_start: Vec<u32>,
    /// Point indices (into the list given to [`build`](Self::build)), grouped by cell.
    cell_points: Vec<u32>,
    /// Per point: its cell.
    cell_of_point: Vec<u32>,
    /// The points' bounding box.
    min: DVec2,
    max: DVec2,
    inverse_cell: f64,
    columns: usize,
    rows: usize,
}

impl PointGrid {
    /// Buckets `points` (at least one); the grid covers their bounding box.
    pub fn build(&mut self, points: impl Iterator<Item = DVec2> + Clone) {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        let mut count = 0usize;
        for p in points.clone() {
            (min, max) = (min.min(p), max.max(p));
            count += 1;
        }
        (self.min, self.max) = (min, max);
        let extent = (max - min).max(DVec2::splat(1e-9));
        let slots = 4.0 * count as f64;
        let cell = ((extent.x * extent.y) / slots)
            .sqrt()
            .max(extent.max_element() / slots)
            .max(1e-9);
        self.columns = ((extent.x / cell).ceil() as usize).clamp(1, 4096);
        self.rows = ((extent.y / cell).ceil() as usize).clamp(1, 4096);
        self.inverse_cell = 1.0 / (extent.x / self.columns as f64).max(extent.y / self.rows as f64);
        let cells = self.columns * self.rows;
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        self.cell_of_point.clear();
        for p in points {
            let (c, r) = self.cell_of(p);
            // Cells are at most 4096² < 2³², so the index fits u32.
            let cell = (r * self.columns + c) as u32;
            self.cell_of_point.push(cell);
            self.cell_start[cell as usize + 1] += 1;
        }
        for i in 0..cells {
            self.cell_start[i + 1] += self.cell_start[i];
        }
        // Counting sort: `cell_start[cell]` serves as the cell's cursor, so afterwards each
        // entry holds the next cell's start, and shifting by one cell restores the starts.
        self.cell_points.clear();
        self.cell_points.resize(count, 0);
        for (k, &cell) in self.cell_of_point.iter().enumerate() {
            let cursor = &mut self.cell_start[cell as usize];
            self.cell_points[*cursor as usize] = k as u32;
            *cursor += 1;
        }
        self.cell_start.copy_within(0..cells, 1);
        self.cell_start[0] = 0;
    }

    /// Calls `visit` with the index of every point in a cell that the box `min..max` overlaps,
    /// unless the box cannot hold a point strictly inside it.
    pub fn near_box(&self, min: DVec2, max: DVec2, mut visit: impl FnMut(usize)) {
        let overlaps = max.x > self.min.x && max.y > self.min.y;
        if !(overlaps && min.x < self.max.x && min.y < self.max.y) {
            return;
        }
        // A point strictly inside the box falls in a cell between the box corners' cells: the
        // cell map is monotone.
        let ((c0, r0), (c1, r1)) = (self.cell_of(min), self.cell_of(max));
        for r in r0..=r1 {
            let row = r * self.columns;
            let range = self.cell_start[row + c0] as usize..self.cell_start[row + c1 + 1] as usize;
            for &k in &self.cell_points[range] {
                visit(k as usize);
            }
        }
    }

    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.min) * self.inverse_cell;
        let c = (q.x.max(0.0) as usize).min(self.columns - 1);
        let r = (q.y.max(0.0) as usize).min(self.rows - 1);
        (c, r)
    }
}
