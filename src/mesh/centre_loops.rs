//! Boundary loops through the mask's Dirichlet pixels: takes crack loops (pixel corners,
//! inside on the left) and gives, per loop, the closed polyline through the centres of the
//! outside pixels across each crack edge, in crack order.
//!
//! Why: the exact pixel-grid clone (Pérez et al.) pins the membrane at the centres of the
//! outside 4-neighbours of the mask. A mesh whose boundary vertices are exactly those centres
//! samples `target − source` at them without mixing pixels, so its boundary data *is* the
//! reference's (docs/quality.md). Each crack edge has one outside pixel; consecutive edges
//! that share it give one vertex, and a staircase becomes a diagonal through the centres.
//!
//! An outside pixel reached from two separate runs of one or more loops (a 1-px-wide notch or
//! gap, a 1-px hole) would make the loop retrace itself or collapse. Such edges get a point a
//! quarter pixel outside their crack instead, which keeps the loops apart; those few
//! vertices sample mixed pixels.

use glam::DVec2;

use super::contour::CrackLoop;
use super::simplify::Segment;

/// How far outside its crack a vertex of a shared outside pixel sits, px.
const SHARED_OFFSET: f64 = 0.25;

/// One crack edge: its midpoint, its unit outward normal and its outside pixel.
#[derive(Clone, Copy)]
struct Edge {
    midpoint: DVec2,
    outward: DVec2,
    pixel: (i64, i64),
}

/// Whether loops thinned to `spacing` keep every centre (the longest step between
/// neighbouring centres is √2 px).
fn keeps_every_centre(spacing: f64) -> bool {
    spacing <= std::f64::consts::SQRT_2 + 1e-9
}

/// Largest distance of a dropped centre from the chord that replaces it, px.
const THIN_TOLERANCE: f64 = 0.5;

/// Keeps every centre when `spacing` ≤ √2 (the longest step between neighbouring centres);
/// otherwise drops centres greedily while the chord stays at most `spacing` long and within
/// [`THIN_TOLERANCE`] of the dropped ones. Points with `keep` set (and the first) stay. Kept
/// points are still centres, so the boundary data stays unmixed. A chord may cut a convex
/// corner pixel (the centre loop touches its corner), but every mask pixel keeps its centre
/// and at least half its square inside (tested), so the patch's anti-aliased edge leaves it
/// at least half opaque.
fn thin_loop(lp: &KeptLoop, spacing: f64) -> Vec<DVec2> {
    let (points, keep) = (&lp.points, &lp.keep);
    let n = points.len();
    if keeps_every_centre(spacing) || n <= 3 {
        return points.to_vec();
    }
    let mut out = vec![points[0]];
    let (mut from, mut to) = (0, 1);
    while to < n {
        // `to + 1 == n` closes the chord on the first point.
        let end = points[(to + 1) % n];
        let a = points[from];
        let extends = !keep[to]
            && a.distance(end) <= spacing
            && (from + 1..=to).all(|k| Segment::new(a, end).distance(points[k]) <= THIN_TOLERANCE);
        if !extends {
            out.push(points[to]);
            from = to;
        }
        to += 1;
    }
    if out.len() < 3 {
        return points.to_vec();
    }
    out
}

/// A closed loop's points before thinning.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct KeptLoop {
    pub points: Vec<DVec2>,
    /// Thinning must keep the point.
    pub keep: Vec<bool>,
}

impl KeptLoop {
    pub fn push(&mut self, point: DVec2, keep: bool) {
        self.points.push(point);
        self.keep.push(keep);
    }
}

/// Loops through the outside pixel centres, one per crack loop (same order, same
/// orientation), and how many vertices had to fall back to the quarter-pixel offset.
/// With `spacing` above √2 px, centres are dropped where the boundary is straight enough
/// (see `thin_loop`).
pub fn outside_centre_loops(crack: &[CrackLoop], spacing: f64) -> (Vec<Vec<DVec2>>, usize) {
    let (loops, fallbacks) = outside_centre_points(crack);
    let thinned = loops.iter().map(|lp| thin_loop(lp, spacing)).collect();
    (thinned, fallbacks)
}

/// Every outside pixel centre of each crack loop (quarter-pixel points where a centre is
/// shared, marked to be kept), before thinning, and how many points fell back.
fn outside_centre_points(crack: &[CrackLoop]) -> (Vec<KeptLoop>, usize) {
    let loops: Vec<(Vec<Edge>, Vec<Run>)> = crack
        .iter()
        .map(|c| {
            let edges = unit_edges(c);
            let runs = runs_of(&edges);
            (edges, runs)
        })
        .collect();
    // Pixels reached by more than one run, sorted (a hash set cost 2 M instructions on the
    // 400² spiral, more than the rest of this function).
    let mut reached: Vec<(i64, i64)> = (loops.iter())
        .flat_map(|(edges, runs)| runs.iter().map(|r| edges[r.first].pixel))
        .collect();
    reached.sort_unstable();
    let shared: Vec<(i64, i64)> = reached
        .windows(2)
        .filter(|w| w[0] == w[1])
        .map(|w| w[0])
        .collect();
    let mut fallbacks = 0;
    let loops = loops
        .iter()
        .map(|(edges, runs)| {
            // A loop around a single outside pixel (a 1-px hole) has one run.
            let collapsed = runs.len() < 3;
            let mut out = KeptLoop::default();
            for run in runs {
                let pixel = edges[run.first].pixel;
                if !collapsed && shared.binary_search(&pixel).is_err() {
                    out.push(
                        DVec2::new(pixel.0 as f64 + 0.5, pixel.1 as f64 + 0.5),
                        false,
                    );
                } else {
                    fallbacks += run.len;
                    for k in 0..run.len {
                        let e = &edges[(run.first + k) % edges.len()];
                        out.push(e.midpoint + e.outward * SHARED_OFFSET, true);
                    }
                }
            }
            out
        })
        .collect();
    (loops, fallbacks)
}

/// The unit crack edges of a loop, from its corner list.
fn unit_edges(crack: &CrackLoop) -> Vec<Edge> {
    let n = crack.points.len();
    let mut edges = Vec::new();
    for i in 0..n {
        let (a, b) = (crack.points[i], crack.points[(i + 1) % n]);
        let steps = (b - a).abs().max_element().round() as usize;
        if steps == 0 {
            continue;
        }
        let direction = (b - a) / steps as f64;
        // Inside is on the left of the direction in the crack tracer's convention
        // (y down: left of (dx, dy) is (−dy, dx)), so outside is (dy, −dx).
        let outward = DVec2::new(direction.y, -direction.x);
        for k in 0..steps {
            let midpoint = a + direction * (k as f64 + 0.5);
            let centre = midpoint + outward * 0.5;
            edges.push(Edge {
                midpoint,
                outward,
                pixel: (centre.x.floor() as i64, centre.y.floor() as i64),
            });
        }
    }
    edges
}

/// A cyclic run of a loop's edges: `len` edges from `first`, wrapping past the end.
#[derive(Clone, Copy)]
struct Run {
    first: usize,
    len: usize,
}

/// Maximal cyclic runs of consecutive edges with the same outside pixel, starting at the
/// first edge that begins one (so no run is split across the wrap).
fn runs_of(edges: &[Edge]) -> Vec<Run> {
    let n = edges.len();
    let starts_run = |i: usize| edges[i].pixel != edges[(i + n - 1) % n].pixel;
    let Some(offset) = (0..n).find(|&i| starts_run(i)) else {
        return if n == 0 {
            Vec::new()
        } else {
            vec![Run { first: 0, len: n }]
        };
    };
    let mut runs: Vec<Run> = Vec::new();
    for i in (offset..n + offset).map(|i| i % n) {
        match runs.last_mut() {
            Some(run) if !starts_run(i) => run.len += 1,
            _ => runs.push(Run { first: i, len: 1 }),
        }
    }
    runs
}
