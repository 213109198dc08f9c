//! Exact triangle coverage with a depth test: takes the per-triangle setups and the work
//! rectangle and gives, per work pixel, the index of the triangle drawn there (or
//! [`NO_TRIANGLE`]).
//!
//! A pixel belongs to a triangle when its centre is strictly inside the snapped, positively
//! oriented triangle, or exactly on a *top-left* edge (inner normal pointing right, or a
//! horizontal edge with the inside below, y down). A shared edge is traversed in opposite
//! directions by its two triangles, so exactly one of them owns the centres on it, and the
//! integer edge functions make that decision exact. Triangles are drawn row band by row
//! band ([`TriangleBins`]), each band's in index order, and win a pixel when their
//! interpolated depth is ≥ the stored one, so on equal depth the later triangle wins. Bands
//! may be drawn on several threads: a pixel meets the same triangles in the same order.

use glam::DVec2;

use super::setup::{edge_function, TriangleSetup, SUBPIXEL};
use super::PixelRect;

pub(crate) const NO_TRIANGLE: u32 = u32::MAX;

/// Rows of the work rectangle drawn together. The triangles are binned by the bands their
/// rows reach; each band's ids and depths (about 150 kB for a 600-px-wide patch) are cleared
/// and drawn while they stay in cache, and bands are what several threads take in turn. A
/// pixel still meets its triangles in index order, so the ids are the same for any split.
const BAND_ROWS: usize = 32;

/// Grow-only storage for the triangles of each band, kept in the raster scratch.
#[derive(Default)]
pub(crate) struct TriangleBins {
    /// Where each band's triangles start in `indices` (one more entry than bands).
    starts: Vec<usize>,
    /// Triangle indices, band after band, ascending within each.
    indices: Vec<u32>,
}

/// One band's rows and its part of the ids and depths (empty without depth).
pub(crate) struct Band<'a> {
    index: usize,
    rows: PixelRect,
    ids: &'a mut [u32],
    depths: &'a mut [f32],
}

/// Fills `ids` (and `depths` when `use_depth`) over `rect`, both `rect.area()` long, drawing
/// every drawable triangle of `setups` (on equal depth the later triangle wins).
pub(crate) fn rasterise_triangles(
    setups: &[TriangleSetup],
    rect: PixelRect,
    use_depth: bool,
    (ids, depths): (&mut [u32], &mut [f32]),
    bins: &mut TriangleBins,
) {
    bins.fill(setups, rect);
    for band in bands(rect, ids, depths, use_depth) {
        bins.rasterise(setups, band);
    }
}

/// The bands of `rect` (top to bottom, [`BAND_ROWS`] rows each, the last one shorter) with
/// their parts of `ids` and, when `use_depth`, `depths`.
pub(crate) fn bands<'a>(
    rect: PixelRect,
    ids: &'a mut [u32],
    depths: &'a mut [f32],
    use_depth: bool,
) -> impl Iterator<Item = Band<'a>> {
    let cells = BAND_ROWS * rect.width().max(1);
    let depths = depths[..if use_depth { ids.len() } else { 0 }].chunks_mut(cells);
    let depths = depths.map(Some).chain(std::iter::repeat_with(|| None));
    let rows = (rect.y0..rect.y1).step_by(BAND_ROWS).map(move |y0| PixelRect {
        y0,
        y1: rect.y1.min(y0 + BAND_ROWS as i32),
        ..rect
    });
    let parts = ids.chunks_mut(cells).zip(depths).zip(rows).enumerate();
    parts.map(|(index, ((ids, depths), rows))| Band {
        index,
        rows,
        ids,
        depths: depths.unwrap_or_default(),
    })
}

impl TriangleBins {
    /// Bins the drawable triangles of `setups` by the bands of `rect` their pixel rows reach
    /// (a counting sort, so each band keeps them in index order).
    pub fn fill(&mut self, setups: &[TriangleSetup], rect: PixelRect) {
        let bands = rect.height().div_ceil(BAND_ROWS);
        self.starts.clear();
        self.starts.resize(bands + 1, 0);
        let reaches = || setups.iter().enumerate().filter_map(|(i, s)| band_reach(i, s, rect));
        for (_, first, last) in reaches() {
            self.starts[first..=last].iter_mut().for_each(|n| *n += 1);
        }
        let mut total = 0;
        for start in &mut self.starts {
            (*start, total) = (total, total + *start);
        }
        self.indices.clear();
        self.indices.resize(total, 0);
        // `starts[b]` walks through band b while it fills, ending at band b + 1's start;
        // shifting them back by one band restores the starts.
        for (index, first, last) in reaches() {
            for band in first..=last {
                self.indices[self.starts[band]] = index;
                self.starts[band] += 1;
            }
        }
        self.starts.rotate_right(1);
        self.starts[0] = 0;
    }

    /// Clears `band`'s ids (and depths) and draws its triangles into them.
    pub fn rasterise(&self, setups: &[TriangleSetup], band: Band) {
        band.ids.fill(NO_TRIANGLE);
        band.depths.fill(f32::NEG_INFINITY);
        let use_depth = !band.depths.is_empty();
        for &index in &self.indices[self.starts[band.index]..self.starts[band.index + 1]] {
            let setup = &setups[index as usize];
            rasterise_one(setup, index, band.rows, use_depth, band.ids, band.depths);
        }
    }
}

/// The index of a drawable triangle and the first and last band of `rect` whose rows its
/// pixel centres may reach (its fixed-point bounds), or `None` when it reaches none.
fn band_reach(index: usize, setup: &TriangleSetup, rect: PixelRect) -> Option<(u32, usize, usize)> {
    if !setup.drawable {
        return None;
    }
    let ys = setup.fixed.map(|p| p[1]);
    let (y0, y1) = centre_range(ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]));
    let y0 = y0.max(i64::from(rect.y0));
    let y1 = y1.min(i64::from(rect.y1));
    (y0 < y1).then(|| {
        let band = |y: i64| (y - i64::from(rect.y0)) as usize / BAND_ROWS;
        (index as u32, band(y0), band(y1 - 1))
    })
}

/// Whether the edge a→b of a positively oriented triangle is a top or left edge.
#[inline]
fn is_top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0 || (dy == 0 && dx > 0)
}

/// Pixel range whose centres may lie in [lo, hi] (fixed point): i + ½ ∈ [lo, hi].
#[inline]
fn centre_range(lo: i64, hi: i64) -> (i64, i64) {
    let half = SUBPIXEL / 2;
    let first = (lo - half).div_euclid(SUBPIXEL) + i64::from((lo - half).rem_euclid(SUBPIXEL) != 0);
    let last = (hi - half).div_euclid(SUBPIXEL);
    (first, last + 1)
}

fn rasterise_one(
    setup: &TriangleSetup,
    index: u32,
    work: PixelRect,
    use_depth: bool,
    ids: &mut [u32],
    depths: &mut [f32],
) {
    let width = work.width();
    scan_spans(setup.fixed, work, |y, x0, x1| {
        let row = (y - work.y0) as usize * width;
        let cells = row + (x0 - work.x0) as usize..row + (x1 - work.x0) as usize;
        if !use_depth {
            ids[cells].fill(index);
            return;
        }
        let depth_at = setup.depth_along_row(x0, y);
        depth_test_span(index, depth_at, &mut ids[cells.clone()], &mut depths[cells]);
    });
}

/// The depth test along one span: pixel k gets depth `first + step·k` and takes the
/// triangle when that is ≥ the stored depth (never when it is NaN). Written without a
/// branch per pixel: whether a triangle wins flips along a fold, and the mispredictions
/// cost more than the selects; groups of eight vectorise.
#[inline]
fn depth_test_span(index: u32, (first, step): (f32, f32), ids: &mut [u32], depths: &mut [f32]) {
    const LANES: usize = 8;
    let mut id_groups = ids.chunks_exact_mut(LANES);
    let mut depth_groups = depths.chunks_exact_mut(LANES);
    let mut k = 0usize;
    for (ids, stored) in (&mut id_groups).zip(&mut depth_groups) {
        for lane in 0..LANES {
            depth_test_pixel(index, first + step * (k + lane) as i32 as f32, &mut ids[lane], &mut stored[lane]);
        }
        k += LANES;
    }
    let tail = id_groups.into_remainder().iter_mut();
    for (id, stored) in tail.zip(depth_groups.into_remainder()) {
        depth_test_pixel(index, first + step * k as i32 as f32, id, stored);
        k += 1;
    }
}

/// One pixel of [`depth_test_span`], as selects.
#[inline(always)]
fn depth_test_pixel(index: u32, depth: f32, id: &mut u32, stored: &mut f32) {
    let wins = depth >= *stored;
    let keep = u32::from(wins).wrapping_sub(1);
    *id = (index & !keep) | (*id & keep);
    *stored = f32::from_bits((depth.to_bits() & !keep) | (stored.to_bits() & keep));
}

/// Calls `visit(x, y)` for every pixel of `clip` whose centre the placed triangle owns under
/// the raster's fill rule (either orientation; nothing for degenerate triangles or vertices
/// beyond ±2^20 px). This is exactly the coverage [`draw_patch`](super::draw_patch) uses.
pub fn triangle_pixels(corners: [DVec2; 3], clip: PixelRect, mut visit: impl FnMut(i32, i32)) {
    let setup = TriangleSetup::new(corners, corners, [[0.0; 3]; 3], [0.0; 3]);
    if setup.drawable {
        scan_spans(setup.fixed, clip, |y, x0, x1| {
            (x0..x1).for_each(|x| visit(x, y))
        });
    }
}

/// Scans a positively oriented fixed-point triangle over `clip`, calling `visit(y, x0, x1)`
/// with each non-empty row span `[x0, x1)` of owned pixel centres.
fn scan_spans(fixed: [[i64; 2]; 3], clip: PixelRect, mut visit: impl FnMut(i32, i32, i32)) {
    let [a, b, c] = fixed;
    let (x0, x1) = centre_range(a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]));
    let (y0, y1) = centre_range(a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
    let x0 = x0.max(i64::from(clip.x0));
    let x1 = x1.min(i64::from(clip.x1));
    let y0 = y0.max(i64::from(clip.y0));
    let y1 = y1.min(i64::from(clip.y1));
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    // Edge k is opposite vertex k; a top-left edge also owns the centres exactly on it, which
    // with integer values is "w + 1 > 0" instead of "w > 0".
    let edges = [(b, c), (c, a), (a, b)];
    let bias = edges.map(|(p, q)| i64::from(is_top_left(p, q)));
    let step_x = edges.map(|(p, q)| -(q[1] - p[1]) * SUBPIXEL);
    let step_y = edges.map(|(p, q)| (q[0] - p[0]) * SUBPIXEL);
    let centre = |i: i64| i * SUBPIXEL + SUBPIXEL / 2;
    let start = [centre(x0), centre(y0)];
    let mut row_w = [0i64; 3];
    for k in 0..3 {
        row_w[k] = edge_function(edges[k].0, edges[k].1, start) + bias[k];
    }
    // Each edge's bound on the span is ⌊−w / |step_x|⌋, and −w steps by −step_y per row:
    // walked exactly with a remainder instead of three 64-bit divisions per row.
    let mut bounds: [FloorWalk; 3] =
        std::array::from_fn(|k| FloorWalk::new(-row_w[k], step_x[k].abs().max(1), -step_y[k]));
    let len = x1 - x0;
    for y in y0..y1 {
        let (mut lo, mut hi) = (0, len);
        for k in 0..3 {
            match step_x[k].signum() {
                1 => lo = lo.max(bounds[k].quotient + 1),
                -1 => hi = hi.min(-bounds[k].quotient),
                _ if row_w[k] <= 0 => hi = 0,
                _ => {}
            }
        }
        debug_assert_eq!(
            if lo < hi { (lo, hi) } else { (0, 0) },
            row_span(row_w, step_x, len)
        );
        if lo < hi {
            // All lie inside `clip`, whose bounds are i32.
            visit(y as i32, (x0 + lo) as i32, (x0 + hi) as i32);
        }
        for k in 0..3 {
            row_w[k] += step_y[k];
            bounds[k].advance();
        }
    }
}

/// `⌊N / d⌋` along the arithmetic progression `N, N + D, N + 2D, …` (`d > 0`), stepped
/// exactly with a remainder instead of a division per term.
#[derive(Clone, Copy)]
struct FloorWalk {
    quotient: i64,
    remainder: i64,
    divisor: i64,
    quotient_step: i64,
    remainder_step: i64,
}

impl FloorWalk {
    fn new(numerator: i64, divisor: i64, step: i64) -> Self {
        Self {
            quotient: numerator.div_euclid(divisor),
            remainder: numerator.rem_euclid(divisor),
            divisor,
            quotient_step: step.div_euclid(divisor),
            remainder_step: step.rem_euclid(divisor),
        }
    }

    /// On to the next term: `0 ≤ remainder < divisor` holds again after one carry.
    #[inline]
    fn advance(&mut self) {
        self.quotient += self.quotient_step;
        self.remainder += self.remainder_step;
        if self.remainder >= self.divisor {
            self.remainder -= self.divisor;
            self.quotient += 1;
        }
    }
}

/// The exact range `[lo, hi)` of steps `t ∈ [0, len)` with `w[k] + t·step[k] > 0` for all
/// three edges: each edge bounds t from one side by an exact integer division, so the span
/// is precisely the set of pixels the per-pixel test would accept. The reference for
/// [`scan_spans`]' division-free walk (checked against it in debug builds).
#[inline]
fn row_span(w: [i64; 3], step: [i64; 3], len: i64) -> (i64, i64) {
    let (mut lo, mut hi) = (0, len);
    for k in 0..3 {
        let (w, s) = (w[k], step[k]);
        if s > 0 {
            // t > −w / s  ⇔  t ≥ ⌊−w / s⌋ + 1.
            lo = lo.max((-w).div_euclid(s) + 1);
        } else if s < 0 {
            // t < w / |s|  ⇔  t < ⌈w / |s|⌉ = −⌊−w / |s|⌋.
            hi = hi.min(-(-w).div_euclid(-s));
        } else if w <= 0 {
            return (0, 0);
        }
    }
    if lo < hi {
        (lo, hi)
    } else {
        (0, 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunked_depth_test_matches_the_pixel_loop() {
        // Spans of every length up to 40 over stored depths that the span's ramp crosses,
        // ties included, and a NaN ramp (never wins).
        for len in 0..=40usize {
            for (first, step) in [
                (0.25f32, 0.125f32),
                (3.0, -0.25),
                (1.0, 0.0),
                (f32::NAN, 1.0),
            ] {
                let stored: Vec<f32> = (0..len).map(|k| [0.5, 1.0, -1.0, 2.75][k % 4]).collect();
                let old_ids: Vec<u32> = (0..len as u32).collect();
                let (mut ids, mut depths) = (old_ids.clone(), stored.clone());
                depth_test_span(99, (first, step), &mut ids, &mut depths);
                for k in 0..len {
                    let depth = first + step * k as f32;
                    let wins = depth >= stored[k];
                    assert_eq!(ids[k], if wins { 99 } else { old_ids[k] }, "{len} {k}");
                    let expected = if wins { depth } else { stored[k] };
                    assert_eq!(depths[k].to_bits(), expected.to_bits(), "{len} {k}");
                }
            }
        }
    }

    /// Triangles drawn band by band give the ids and depths of drawing each over the whole
    /// rectangle in index order: random triangles with depth ramps (folds, ties), inside,
    /// across and outside rectangles whose heights are not whole bands.
    #[test]
    fn banded_ids_match_drawing_each_triangle_over_the_rectangle() {
        let mut state = 0xba4d_u64;
        let mut next = |lo: f64, hi: f64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
        };
        let mut drawn = 0;
        for case in 0..60 {
            let rect = PixelRect {
                x0: next(-20.0, 20.0) as i32,
                y0: next(-20.0, 20.0) as i32,
                x1: next(40.0, 120.0) as i32,
                y1: next(25.0, 200.0) as i32,
            };
            let setups: Vec<TriangleSetup> = (0..150)
                .map(|_| {
                    let (cx, cy) = (next(-40.0, 140.0), next(-40.0, 220.0));
                    let size = next(1.0, 60.0);
                    let corner = |next: &mut dyn FnMut(f64, f64) -> f64| {
                        DVec2::new(cx + next(-size, size), cy + next(-size, size))
                    };
                    let placed = [corner(&mut next), corner(&mut next), corner(&mut next)];
                    let depth = [next(-1.0, 1.0), next(-1.0, 1.0), next(-1.0, 1.0)];
                    let depth = depth.map(|d| if case % 3 == 0 { 0.0 } else { d as f32 });
                    TriangleSetup::new(placed, placed, [[0.0; 3]; 3], depth)
                })
                .collect();
            for use_depth in [false, true] {
                let area = rect.area();
                let (mut ids, mut depths) = (vec![7; area], vec![3.0; area]);
                let depths_used = if use_depth { &mut depths[..] } else { &mut [][..] };
                let mut bins = TriangleBins::default();
                rasterise_triangles(&setups, rect, use_depth, (&mut ids, depths_used), &mut bins);
                let (mut want_ids, mut want_depths) = (vec![NO_TRIANGLE; area], vec![f32::NEG_INFINITY; area]);
                for (index, setup) in setups.iter().enumerate().filter(|(_, s)| s.drawable) {
                    let buffers = (&mut want_ids[..], &mut want_depths[..]);
                    rasterise_one(setup, index as u32, rect, use_depth, buffers.0, buffers.1);
                }
                assert_eq!(ids, want_ids, "case {case}, depth {use_depth}");
                if use_depth {
                    assert_eq!(depths, want_depths, "case {case}");
                }
                drawn += ids.iter().filter(|&&id| id != NO_TRIANGLE).count();
            }
        }
        assert!(drawn > 100_000, "{drawn} pixels drawn");
    }

    #[test]
    fn centre_range_includes_exact_centres() {
        // Centres at 0.5 (=128) and 1.5 (=384).
        assert_eq!(centre_range(128, 384), (0, 2));
        assert_eq!(centre_range(129, 383), (1, 1));
        assert_eq!(centre_range(-128, 128), (-1, 1));
    }

    #[test]
    fn floor_walks_match_division_at_every_term() {
        let mut state = 0xf100_u64;
        let mut next = |range: i64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 20) as i64 % (2 * range + 1) - range
        };
        for _ in 0..2000 {
            let (start, step) = (next(1 << 40), next(1 << 30));
            let divisor = next(1 << 20).abs().max(1);
            let mut walk = FloorWalk::new(start, divisor, step);
            for term in 0..50 {
                let n = start + term * step;
                assert_eq!(
                    walk.quotient,
                    n.div_euclid(divisor),
                    "{start} {step} {divisor} {term}"
                );
                walk.advance();
            }
        }
    }

    /// The per-pixel edge test the spans replace.
    fn brute_span(w: [i64; 3], step: [i64; 3], len: i64) -> Vec<i64> {
        (0..len)
            .filter(|&t| (0..3).all(|k| w[k] + t * step[k] > 0))
            .collect()
    }

    #[test]
    fn row_spans_match_the_per_pixel_edge_test() {
        use proptest::prelude::*;
        use proptest::test_runner::{Config, RngSeed, TestRunner};
        let config = Config {
            rng_seed: RngSeed::Fixed(0x5a4e),
            cases: 4000,
            ..Config::default()
        };
        let value = -3000i64..3000;
        let step = prop_oneof![Just(0i64), -700i64..700, Just(256), Just(-256)];
        let strategy = (
            [value.clone(), value.clone(), value],
            [step.clone(), step.clone(), step],
            0i64..40,
        );
        TestRunner::new(config)
            .run(&strategy, |(w, step, len)| {
                let (lo, hi) = row_span(w, step, len);
                let span: Vec<i64> = (lo..hi).collect();
                prop_assert_eq!(span, brute_span(w, step, len));
                Ok(())
            })
            .unwrap();
    }
}
