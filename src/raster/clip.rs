//! Polygon clipping to a rectangle: takes a closed polygon (f64 points) and an axis-aligned
//! rectangle and gives the polygon clipped to it (Sutherland–Hodgman, one pass per side).
//!
//! Why: the silhouette's strips ([`coverage`](super::coverage)) hand tiny-skia paths that
//! already lie inside their mask, so tiny-skia never runs its own clipper, whose results
//! depend on the mask's size (grow-only, so on earlier frames). Clipping a closed loop to a
//! convex region keeps the winding number of every point inside the region: the parts cut
//! away are replaced by runs along the region's border, outside its interior.

use glam::DVec2;

/// A closed rectangle `[x0, x1] × [y0, y1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ClipRect {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

#[cfg(test)]
impl ClipRect {
    /// Whether `p` lies in the rectangle (border included).
    pub fn contains(&self, p: DVec2) -> bool {
        p.x >= self.x0 && p.x <= self.x1 && p.y >= self.y0 && p.y <= self.y1
    }
}

/// One side of the rectangle: a coordinate axis, the bound and which side is kept.
#[derive(Clone, Copy)]
struct Side {
    vertical: bool,
    bound: f64,
    keep_above: bool,
}

impl Side {
    fn inside(&self, p: DVec2) -> bool {
        let value = if self.vertical { p.x } else { p.y };
        if self.keep_above {
            value >= self.bound
        } else {
            value <= self.bound
        }
    }

    /// Where p→q crosses the side's line (p and q on opposite sides). The crossing is
    /// computed from the endpoint with the smaller coordinate along the axis, so an edge
    /// and its reverse give the same point.
    fn crossing(&self, p: DVec2, q: DVec2) -> DVec2 {
        let along = |v: DVec2| if self.vertical { v.x } else { v.y };
        let (a, b) = if along(p) <= along(q) { (p, q) } else { (q, p) };
        let t = (self.bound - along(a)) / (along(b) - along(a));
        let point = a + (b - a) * t;
        if self.vertical {
            DVec2::new(self.bound, point.y)
        } else {
            DVec2::new(point.x, self.bound)
        }
    }
}

/// Clips the closed polygon `points` to `rect` into `out` (cleared first; empty when nothing
/// is left). `spare` is scratch space; both keep their capacity between calls.
pub(crate) fn clip_polygon(
    points: impl Iterator<Item = DVec2>,
    rect: &ClipRect,
    out: &mut Vec<DVec2>,
    spare: &mut Vec<DVec2>,
) {
    out.clear();
    out.extend(points);
    // Every point a pass makes lies on a segment between the input's points, so inside their
    // box: a side that the box lies on the kept side of keeps every point, in order, and its
    // pass is skipped (the same output, without the copy). Strips cut the silhouette's loops
    // only at their top and bottom, and most triangles not at all.
    let (min, max, nan) = out.iter().fold(
        (
            DVec2::splat(f64::INFINITY),
            DVec2::splat(f64::NEG_INFINITY),
            false,
        ),
        |(min, max, nan), &p| (min.min(p), max.max(p), nan || p.is_nan()),
    );
    // A NaN point is outside every side, and the box (which skips NaN) would not show it.
    let kept = |inside: bool| inside && !nan;
    let sides = [
        (true, rect.x0, true, kept(min.x >= rect.x0)),
        (true, rect.x1, false, kept(max.x <= rect.x1)),
        (false, rect.y0, true, kept(min.y >= rect.y0)),
        (false, rect.y1, false, kept(max.y <= rect.y1)),
    ];
    for (vertical, bound, keep_above, all_kept) in sides {
        if out.is_empty() {
            return;
        }
        if !all_kept {
            let side = Side {
                vertical,
                bound,
                keep_above,
            };
            clip_to_side(out, spare, side);
        }
    }
}

/// One Sutherland–Hodgman pass: `out` clipped to `side`'s kept half-plane.
fn clip_to_side(out: &mut Vec<DVec2>, spare: &mut Vec<DVec2>, side: Side) {
    spare.clear();
    let Some(&last) = out.last() else {
        return;
    };
    let mut previous = last;
    for &point in out.iter() {
        match (side.inside(previous), side.inside(point)) {
            (true, true) => spare.push(point),
            (true, false) => spare.push(side.crossing(previous, point)),
            (false, true) => {
                spare.push(side.crossing(previous, point));
                spare.push(point);
            }
            (false, false) => {}
        }
        previous = point;
    }
    std::mem::swap(out, spare);
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Winding number of a closed polygon around `p` (crossing count, signed).
    fn winding(polygon: &[DVec2], p: DVec2) -> i32 {
        let mut w = 0;
        for k in 0..polygon.len() {
            let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            let side = (b - a).perp_dot(p - a);
            if a.y <= p.y && b.y > p.y && side > 0.0 {
                w += 1;
            } else if a.y > p.y && b.y <= p.y && side < 0.0 {
                w -= 1;
            }
        }
        w
    }

    fn clip(polygon: &[DVec2], rect: &ClipRect) -> Vec<DVec2> {
        let (mut out, mut spare) = (Vec::new(), Vec::new());
        clip_polygon(polygon.iter().copied(), rect, &mut out, &mut spare);
        out
    }

    #[test]
    fn a_polygon_inside_is_kept_and_one_outside_vanishes() {
        let rect = ClipRect {
            x0: 0.0,
            y0: 0.0,
            x1: 10.0,
            y1: 10.0,
        };
        let inside = [
            DVec2::new(1.0, 1.0),
            DVec2::new(5.0, 2.0),
            DVec2::new(3.0, 7.0),
        ];
        assert_eq!(clip(&inside, &rect), inside.to_vec());
        let outside = inside.map(|p| p + DVec2::new(20.0, 0.0));
        assert!(clip(&outside, &rect).is_empty());
        let straddling = [
            DVec2::new(-5.0, 5.0),
            DVec2::new(5.0, -5.0),
            DVec2::new(15.0, 5.0),
            DVec2::new(5.0, 15.0),
        ];
        let clipped = clip(&straddling, &rect);
        assert!(clipped.iter().all(|&p| rect.contains(p)), "{clipped:?}");
    }

    /// Every side's pass, none skipped.
    fn clip_every_side(polygon: &[DVec2], rect: &ClipRect) -> Vec<DVec2> {
        let (mut out, mut spare) = (polygon.to_vec(), Vec::new());
        for (vertical, bound, keep_above) in [
            (true, rect.x0, true),
            (true, rect.x1, false),
            (false, rect.y0, true),
            (false, rect.y1, false),
        ] {
            let side = Side {
                vertical,
                bound,
                keep_above,
            };
            clip_to_side(&mut out, &mut spare, side);
        }
        out
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, rng_seed: proptest::test_runner::RngSeed::Fixed(0xC11F), ..ProptestConfig::default() })]

        /// Skipping the passes whose side the polygon's box lies inside gives the points of
        /// all four passes, bit for bit (the polygons reach inside, across and past the
        /// rectangle).
        #[test]
        fn skipped_passes_change_no_point(
            points in prop::collection::vec((-20.0f64..60.0, -20.0f64..60.0), 3..12),
            x0 in -10.0f64..30.0, y0 in -10.0f64..30.0, w in 0.5f64..40.0, h in 0.5f64..40.0,
        ) {
            let polygon: Vec<DVec2> = points.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
            let rect = ClipRect { x0, y0, x1: x0 + w, y1: y0 + h };
            let clipped = clip(&polygon, &rect);
            let reference = clip_every_side(&polygon, &rect);
            prop_assert_eq!(
                clipped.iter().map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>(),
                reference.iter().map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>()
            );
        }

        /// Self-intersecting random loops: every point strictly inside the rectangle keeps
        /// its winding number, and every clipped vertex lies in the rectangle.
        #[test]
        fn clipping_keeps_the_winding_number_inside_the_rectangle(
            raw in prop::collection::vec((-30.0f64..30.0, -30.0f64..30.0), 3..12),
            probes in prop::collection::vec((-9.9f64..9.9, -4.9f64..4.9), 40),
        ) {
            let polygon: Vec<DVec2> = raw.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
            let rect = ClipRect { x0: -10.0, y0: -5.0, x1: 10.0, y1: 5.0 };
            let clipped = clip(&polygon, &rect);
            prop_assert!(clipped.iter().all(|&p| rect.contains(p)));
            for (x, y) in probes {
                // Offsets keep probes off the (finitely many) vertex rows of either polygon.
                let p = DVec2::new(x + 1e-7, y + 3e-7);
                let expected = winding(&polygon, p);
                let got = if clipped.is_empty() { 0 } else { winding(&clipped, p) };
                prop_assert_eq!(got, expected, "probe {:?}", p);
            }
        }
    }
}
