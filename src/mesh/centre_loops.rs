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

use std::collections::HashMap;

use glam::DVec2;

use super::contour::CrackLoop;

/// How far outside its crack a vertex of a shared outside pixel sits, px.
const SHARED_OFFSET: f64 = 0.25;

/// One crack edge: its midpoint, its unit outward normal and its outside pixel.
#[derive(Clone, Copy)]
struct Edge {
    midpoint: DVec2,
    outward: DVec2,
    pixel: (i64, i64),
}

/// Largest distance of a dropped centre from the chord that replaces it, px: mask pixel
/// centres lie at least √½ px inside the centre loop, so they stay inside.
const THIN_TOLERANCE: f64 = 0.5;

/// Keeps every centre when `spacing` ≤ √2 (the longest step between neighbouring centres);
/// otherwise drops centres greedily while the chord stays at most `spacing` long and within
/// [`THIN_TOLERANCE`] of the dropped ones. Points with `keep` set (and the first) stay.
/// Kept points are still centres, so the boundary data stays unmixed.
fn thin_loop(points: &[DVec2], keep: &[bool], spacing: f64) -> Vec<DVec2> {
    let n = points.len();
    if spacing <= std::f64::consts::SQRT_2 + 1e-9 || n <= 3 {
        return points.to_vec();
    }
    let mut out = vec![points[0]];
    let (mut from, mut to) = (0, 1);
    while to < n {
        // `to + 1 == n` closes the chord on the first point.
        let end = points[(to + 1) % n];
        let extends = !keep[to]
            && points[from].distance(end) <= spacing
            && (from + 1..=to)
                .all(|k| distance_to_segment(points[k], points[from], end) <= THIN_TOLERANCE);
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

fn distance_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Loops through the outside pixel centres, one per crack loop (same order, same
/// orientation), and how many vertices had to fall back to the quarter-pixel offset.
/// With `spacing` above √2 px, centres are dropped where the boundary is straight enough
/// (see `thin_loop`).
pub fn outside_centre_loops(crack: &[CrackLoop], spacing: f64) -> (Vec<Vec<DVec2>>, usize) {
    let runs: Vec<Vec<Vec<Edge>>> = crack.iter().map(|c| runs_of(&unit_edges(c))).collect();
    let mut seen: HashMap<(i64, i64), u32> = HashMap::new();
    for lp in &runs {
        for run in lp {
            *seen.entry(run[0].pixel).or_default() += 1;
        }
    }
    let mut fallbacks = 0;
    let loops = runs
        .iter()
        .map(|lp| {
            // A loop around a single outside pixel (a 1-px hole) has one run.
            let collapsed = lp.len() < 3;
            let mut points = Vec::with_capacity(lp.len());
            let mut keep = Vec::with_capacity(lp.len());
            for run in lp {
                if !collapsed && seen[&run[0].pixel] == 1 {
                    let (x, y) = run[0].pixel;
                    points.push(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                    keep.push(false);
                } else {
                    fallbacks += run.len();
                    points.extend(run.iter().map(|e| e.midpoint + e.outward * SHARED_OFFSET));
                    keep.extend(run.iter().map(|_| true));
                }
            }
            thin_loop(&points, &keep, spacing)
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

/// Maximal cyclic runs of consecutive edges with the same outside pixel.
fn runs_of(edges: &[Edge]) -> Vec<Vec<Edge>> {
    let mut runs: Vec<Vec<Edge>> = Vec::new();
    for &e in edges {
        match runs.last_mut() {
            Some(run) if run[0].pixel == e.pixel => run.push(e),
            _ => runs.push(vec![e]),
        }
    }
    if runs.len() > 1 && runs[0][0].pixel == runs[runs.len() - 1][0].pixel {
        let last = runs.pop().unwrap_or_default();
        runs[0].splice(0..0, last);
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{trace_crack_loops, BitMask};

    fn centres(mask: &BitMask) -> (Vec<Vec<DVec2>>, usize) {
        outside_centre_loops(&trace_crack_loops(mask), 1.0)
    }

    #[test]
    fn a_rectangle_gives_its_outside_ring_without_corners() {
        let mask = BitMask::from_fn(8, 7, |x, y| (2..5).contains(&x) && (2..4).contains(&y));
        let (loops, fallbacks) = centres(&mask);
        assert_eq!((loops.len(), fallbacks), (1, 0));
        // 3 above, 3 below, 2 left, 2 right: the 4-neighbours, not the diagonal corners.
        assert_eq!(loops[0].len(), 10);
        for p in &loops[0] {
            let pixel = (p.x.floor() as i64, p.y.floor() as i64);
            assert_eq!(p.fract(), DVec2::splat(0.5));
            assert!(!mask.get(pixel.0, pixel.1));
            let touches = [(-1, 0), (1, 0), (0, -1), (0, 1)]
                .iter()
                .any(|(dx, dy)| mask.get(pixel.0 + dx, pixel.1 + dy));
            assert!(touches, "{p} is not a 4-neighbour of the mask");
        }
        assert!(crate::mesh::doubled_signed_area(&loops[0]) > 0.0);
    }

    #[test]
    fn a_one_pixel_notch_and_hole_fall_back_to_quarter_pixel_points() {
        let notch = BitMask::from_fn(9, 9, |x, y| {
            (1..8).contains(&x) && (1..8).contains(&y) && !(x == 4 && y < 5)
        });
        let (loops, fallbacks) = centres(&notch);
        assert!(fallbacks > 0);
        let mut all: Vec<(i64, i64)> = loops[0]
            .iter()
            .map(|p| ((p.x * 4.0) as i64, (p.y * 4.0) as i64))
            .collect();
        let n = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), n, "a vertex repeats");
        let hole = BitMask::from_fn(5, 5, |x, y| {
            (1..4).contains(&x) && (1..4).contains(&y) && (x, y) != (2, 2)
        });
        let (loops, fallbacks) = centres(&hole);
        assert_eq!((loops.len(), fallbacks), (2, 4));
        assert!(loops.iter().all(|l| l.len() >= 3));
    }
}
