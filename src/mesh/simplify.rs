//! Boundary sampling, the two separate knobs: [`simplify_loop`] (geometry: closed-loop
//! Douglas–Peucker with fixed anchors and a collapse guard) and [`subdivide_loop`] (seam
//! quality: split every edge to at most `density` pixels). Both take and give closed
//! polylines as point lists (closing edge implied).

use glam::DVec2;

/// A simplified loop and the largest distance from a dropped input point to the segment
/// that replaced it (the loop's Hausdorff deviation, since input edges are straight).
#[derive(Clone, Debug, PartialEq)]
pub struct Simplified {
    pub points: Vec<DVec2>,
    pub max_deviation: f64,
}

/// Twice the signed area of a closed polyline.
pub fn doubled_signed_area(points: &[DVec2]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| points[i].perp_dot(points[(i + 1) % n]))
        .sum()
}

/// A segment with the parts of the point distance that do not depend on the point: the one
/// point-to-segment distance of the mesher, its coverage check and the renderer's warnings.
pub(crate) struct Segment {
    a: DVec2,
    ab: DVec2,
    len2: f64,
}

impl Segment {
    pub(crate) fn new(a: DVec2, b: DVec2) -> Self {
        let ab = b - a;
        Segment {
            a,
            ab,
            len2: ab.length_squared(),
        }
    }

    /// Distance from `p` to the segment (to `a` when the segment is a point).
    pub(crate) fn distance(&self, p: DVec2) -> f64 {
        if self.len2 == 0.0 {
            return p.distance(self.a);
        }
        let t = ((p - self.a).dot(self.ab) / self.len2).clamp(0.0, 1.0);
        p.distance(self.a + self.ab * t)
    }
}

/// Douglas–Peucker on a closed loop. Points with `anchor[i]` set are always kept; the first
/// point and the point farthest from it are kept too. Guard: if the result would have fewer
/// than 3 points or less than half the original |area|, the loop is returned unchanged.
pub fn simplify_loop(points: &[DVec2], anchor: &[bool], tolerance: f64) -> Simplified {
    let n = points.len();
    let unchanged = Simplified {
        points: points.to_vec(),
        max_deviation: 0.0,
    };
    if n <= 3 || tolerance <= 0.0 {
        return unchanged;
    }
    let mut keep = anchor.to_vec();
    keep[0] = true;
    let farthest = (1..n)
        .max_by(|&i, &j| {
            points[i]
                .distance_squared(points[0])
                .total_cmp(&points[j].distance_squared(points[0]))
        })
        .unwrap_or(1);
    keep[farthest] = true;
    let kept_anchors: Vec<usize> = (0..n).filter(|&i| keep[i]).collect();
    let mut max_deviation = 0.0f64;
    let mut stack = Vec::new();
    for (k, &from) in kept_anchors.iter().enumerate() {
        let to = kept_anchors[(k + 1) % kept_anchors.len()];
        let to_unwrapped = if to <= from { to + n } else { to };
        stack.push((from, to_unwrapped));
        while let Some((a, b)) = stack.pop() {
            if b - a < 2 {
                continue;
            }
            // Indices run up to 2n (the loop unrolled once): wrap without a division.
            let wrap = |i: usize| if i < n { i } else { i - n };
            let segment = Segment::new(points[wrap(a)], points[wrap(b)]);
            let (worst, distance) = (a + 1..b)
                .map(|i| (i, segment.distance(points[wrap(i)])))
                .max_by(|x, y| x.1.total_cmp(&y.1))
                .unwrap_or((a, 0.0));
            if distance > tolerance {
                keep[wrap(worst)] = true;
                stack.push((worst, b));
                stack.push((a, worst));
            } else {
                max_deviation = max_deviation.max(distance);
            }
        }
    }
    let simplified: Vec<DVec2> = (0..n).filter(|&i| keep[i]).map(|i| points[i]).collect();
    let original_area = doubled_signed_area(points).abs();
    if simplified.len() < 3 || doubled_signed_area(&simplified).abs() < 0.5 * original_area {
        return unchanged;
    }
    Simplified {
        points: simplified,
        max_deviation,
    }
}

/// How many points [`subdivide_loop`] would give (as a float: a loop reaching 1e308 px would
/// overflow any integer), so callers can refuse before allocating.
pub fn subdivided_len(points: &[DVec2], density: f64) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| {
            (points[i].distance(points[(i + 1) % n]) / density)
                .ceil()
                .max(1.0)
        })
        .sum()
}

/// Splits every edge of a closed loop into the fewest equal parts no longer than `density`.
pub fn subdivide_loop(points: &[DVec2], density: f64, out: &mut Vec<DVec2>) {
    out.clear();
    let n = points.len();
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        let parts = (a.distance(b) / density).ceil().max(1.0) as usize;
        out.push(a);
        out.extend((1..parts).map(|k| a.lerp(b, k as f64 / parts as f64)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn staircase(steps: usize) -> Vec<DVec2> {
        // A right triangle whose hypotenuse is a 1-px staircase.
        let mut pts = vec![DVec2::new(0.0, 0.0)];
        for i in 0..steps {
            pts.push(DVec2::new(i as f64 + 1.0, i as f64));
            pts.push(DVec2::new(i as f64 + 1.0, i as f64 + 1.0));
        }
        pts.push(DVec2::new(0.0, steps as f64));
        pts
    }

    #[test]
    fn staircase_collapses_to_a_triangle_within_tolerance() {
        let pts = staircase(20);
        let anchors = vec![false; pts.len()];
        let s = simplify_loop(&pts, &anchors, 0.9);
        assert!(s.points.len() < 8, "{}", s.points.len());
        assert!(
            s.max_deviation <= 0.9 && s.max_deviation > 0.5,
            "{}",
            s.max_deviation
        );
        // Every input point is within the tolerance of the simplified loop.
        let m = s.points.len();
        for p in &pts {
            let d = (0..m)
                .map(|i| Segment::new(s.points[i], s.points[(i + 1) % m]).distance(*p))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= 0.9 + 1e-12);
        }
    }

    #[test]
    fn anchors_survive() {
        let pts = staircase(10);
        let mut anchors = vec![false; pts.len()];
        anchors[7] = true;
        let s = simplify_loop(&pts, &anchors, 0.9);
        assert!(s.points.contains(&pts[7]));
    }

    #[test]
    fn guard_keeps_a_loop_that_would_collapse() {
        // A 1×1 square: DP with a 2 px tolerance would leave 2 points.
        let pts = vec![
            DVec2::ZERO,
            DVec2::X,
            DVec2::ONE,
            DVec2::Y,
            DVec2::new(0.0, 0.5),
        ];
        let s = simplify_loop(&pts, &[false; 5], 2.0);
        assert_eq!(s.points, pts);
        assert_eq!(s.max_deviation, 0.0);
    }

    #[test]
    fn subdivision_respects_density_and_keeps_corners() {
        let pts = vec![DVec2::ZERO, DVec2::new(10.0, 0.0), DVec2::new(10.0, 3.0)];
        let mut out = Vec::new();
        subdivide_loop(&pts, 2.0, &mut out);
        let n = out.len();
        for i in 0..n {
            assert!(out[i].distance(out[(i + 1) % n]) <= 2.0 + 1e-12);
        }
        for p in &pts {
            assert!(out.contains(p));
        }
        // 10 → 5 parts, 3 → 2 parts, hypotenuse √109 ≈ 10.44 → 6 parts.
        assert_eq!(n, 5 + 2 + 6);
    }
}
