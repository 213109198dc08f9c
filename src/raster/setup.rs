//! Per-triangle setup, redone every frame: takes one placed triangle with its rest
//! coordinates, membrane and depth and gives (a) its vertices snapped to 1/256-px fixed point,
//! positively oriented, for the exact coverage test and (b) the affine maps from canvas
//! position to barycentric coordinates, rest position, membrane and depth.
//!
//! Coverage uses the snapped vertices (so shared edges are decided identically by both
//! triangles); interpolation uses the unsnapped `f64` positions (so an identity placement
//! samples the source exactly at pixel centres).

use glam::DVec2;

/// Fixed-point subpixel resolution (1/256 px).
pub(crate) const SUBPIXEL_BITS: u32 = 8;
pub(crate) const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// Vertices farther than this from the origin (in px) are not drawn: it keeps the i64 edge
/// functions exact (|coordinate| · 256 ≤ 2^28, products ≤ 2^58).
pub(crate) const MAX_COORDINATE: f64 = (1u64 << 20) as f64;

/// Everything the per-pixel loops need to know about one triangle.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TriangleSetup {
    /// Snapped vertices, reordered so the signed area is positive.
    pub fixed: [[i64; 2]; 3],
    /// Whether the placed triangle is drawable (non-degenerate, in range).
    pub drawable: bool,
    /// Depth as an affine function of the canvas position: `[constant, d/dx, d/dy]`.
    pub depth_affine: [f64; 3],
    /// Signed placed area ×2 (negative: inverted).
    pub signed_area2: f64,
    /// Rest x and y as affine functions of the canvas position: `[constant, d/dx, d/dy]`.
    pub rest_x: [f64; 3],
    pub rest_y: [f64; 3],
    /// Membrane channels as affine functions of the canvas position: `[constant, d/dx, d/dy]`.
    pub membrane_affine: [[f32; 3]; 3],
}

/// Barycentric-derived values at one canvas position.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Interpolated {
    pub rest: DVec2,
    pub membrane: [f32; 3],
}

impl TriangleSetup {
    pub fn new(
        placed: [DVec2; 3],
        rest: [DVec2; 3],
        membrane: [[f32; 3]; 3],
        depth: [f32; 3],
    ) -> TriangleSetup {
        let [a, b, c] = placed;
        let e1 = b - a;
        let e2 = c - a;
        let det = e1.perp_dot(e2);
        let mut fixed = placed.map(snap);
        // Out-of-range (or NaN) vertices snap to saturated values whose edge function would
        // overflow i64: test the range first and never evaluate it for them.
        let in_range = placed
            .iter()
            .all(|p| p.abs().max_element() <= MAX_COORDINATE);
        let fixed_area = if in_range {
            edge_function(fixed[0], fixed[1], fixed[2])
        } else {
            0
        };
        if fixed_area < 0 {
            fixed.swap(1, 2);
        }
        let drawable = in_range && fixed_area != 0 && det != 0.0 && det.is_finite();
        let inv = if drawable { 1.0 / det } else { 0.0 };
        // Barycentric gradients: λ1 = g1·(p − a), λ2 = g2·(p − a).
        let g1 = DVec2::new(e2.y * inv, -e2.x * inv);
        let g2 = DVec2::new(-e1.y * inv, e1.x * inv);
        let affine = |at_a: f64, edge1: f64, edge2: f64| {
            let gradient = g1 * edge1 + g2 * edge2;
            [at_a - gradient.dot(a), gradient.x, gradient.y]
        };
        let (r1, r2) = (rest[1] - rest[0], rest[2] - rest[0]);
        let membrane_affine = [0, 1, 2].map(|c| {
            let m = |k: usize| f64::from(membrane[k][c]);
            affine(m(0), m(1) - m(0), m(2) - m(0)).map(|v| v as f32)
        });
        TriangleSetup {
            rest_x: affine(rest[0].x, r1.x, r2.x),
            rest_y: affine(rest[0].y, r1.y, r2.y),
            membrane_affine,
            fixed,
            drawable,
            depth_affine: affine(
                f64::from(depth[0]),
                f64::from(depth[1]) - f64::from(depth[0]),
                f64::from(depth[2]) - f64::from(depth[0]),
            ),
            signed_area2: det,
        }
    }

    #[inline]
    pub fn depth_at(&self, x: f64, y: f64) -> f32 {
        let d = &self.depth_affine;
        (d[0] + d[1] * x + d[2] * y) as f32
    }

    /// Rest position and membrane at a canvas position (extrapolated outside the triangle).
    #[inline(always)]
    pub fn interpolate(&self, x: f64, y: f64) -> Interpolated {
        let rest = DVec2::new(
            self.rest_x[0] + self.rest_x[1] * x + self.rest_x[2] * y,
            self.rest_y[0] + self.rest_y[1] * x + self.rest_y[2] * y,
        );
        let (xf, yf) = (x as f32, y as f32);
        let membrane = self.membrane_affine.map(|m| m[0] + m[1] * xf + m[2] * yf);
        Interpolated { rest, membrane }
    }
}

/// Rounds a position to the 1/256-px grid.
#[inline]
pub(crate) fn snap(p: DVec2) -> [i64; 2] {
    let s = SUBPIXEL as f64;
    [round_to_i64(p.x * s), round_to_i64(p.y * s)]
}

/// `value.round() as i64` (half away from zero, saturating, NaN → 0) without the libm call
/// `f64::round` becomes on baseline x86_64: below 2^52 the fraction `value − trunc(value)`
/// is exact; above, values are integers and the fraction is 0 (or the cast saturated).
#[inline]
fn round_to_i64(value: f64) -> i64 {
    let truncated = value as i64;
    let fraction = value - truncated as f64;
    if fraction >= 0.5 {
        truncated.saturating_add(1)
    } else if fraction <= -0.5 {
        truncated.saturating_sub(1)
    } else {
        truncated
    }
}

/// (b − a) × (p − a) in fixed point; positive when p is left of a→b in raw coordinates
/// (the inside of a positively oriented triangle).
#[inline]
pub(crate) fn edge_function(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn far_or_nan_vertices_are_not_drawable_and_never_overflow() {
        let far = [1e300, -1e300, 1e7, f64::NAN, f64::INFINITY];
        for value in far {
            let placed = [
                DVec2::new(0.0, 0.0),
                DVec2::new(value, 1.0),
                DVec2::new(3.0, value),
            ];
            let rest = [DVec2::ZERO, DVec2::X, DVec2::Y];
            let setup = TriangleSetup::new(placed, rest, [[0.0; 3]; 3], [0.0; 3]);
            assert!(!setup.drawable, "{value}");
        }
    }

    #[test]
    fn rounding_matches_f64_round() {
        let special = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            9007199254740993.0,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            9.223372036854776e18,
        ];
        for v in special {
            assert_eq!(round_to_i64(v), v.round() as i64, "{v}");
        }
        use proptest::prelude::*;
        use proptest::test_runner::{Config, RngSeed, TestRunner};
        let config = Config {
            rng_seed: RngSeed::Fixed(0x0d5e),
            cases: 20_000,
            ..Config::default()
        };
        let strategy = prop_oneof![
            -1e6f64..1e6,
            (-4_000_000i64..4_000_000).prop_map(|k| k as f64 * 0.25),
            any::<f64>(),
        ];
        TestRunner::new(config)
            .run(&strategy, |v| {
                prop_assert_eq!(round_to_i64(v), v.round() as i64, "{}", v);
                Ok(())
            })
            .unwrap();
    }
}
