//! Per-triangle setup, redone every frame: takes one placed triangle with its rest
//! coordinates, membrane and depth and gives (a) its vertices snapped to 1/256-px fixed point,
//! positively oriented, for the exact coverage test and (b) the affine maps from canvas
//! position to barycentric coordinates, rest position, membrane and depth.
//!
//! Coverage uses the snapped vertices (so shared edges are decided identically by both
//! triangles); interpolation uses the unsnapped `f64` positions (so an identity placement
//! samples the source exactly at pixel centres).

use glam::{DVec2, Vec4};

use crate::simd::RowAffine;

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
    /// Rest position (source texel space) and membrane as single-precision affine maps
    /// relative to a pixel centre near the triangle, for shading.
    pub span: SpanSetup,
}

/// Single-precision affine maps for shading, relative to the pixel centre `origin` + ½ near
/// the triangle: offsets from it are small exact integers in f32, so evaluating there costs
/// no precision even far from the canvas origin.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SpanSetup {
    /// Rest x − ½ and rest y − ½ (the sampler's texel-centre shift, folded in), relative to
    /// `membrane.origin`: `[at origin, d/dx, d/dy]`.
    pub texel_x: [f32; 3],
    pub texel_y: [f32; 3],
    pub membrane: MembraneSpan,
    /// `Some(s)` when the triangle is its rest triangle moved by the whole pixels `s`
    /// ([`whole_pixel_shift`]): the texel maps are then exactly `pixel − s`, so every sample
    /// is a source texel, which the eight-lane shader reads directly.
    pub shift: Option<[i32; 2]>,
}

/// The membrane part of [`SpanSetup`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct MembraneSpan {
    pub origin: [i32; 2],
    /// Membrane (RGB, alpha lane 0) at the origin and its steps along x and y.
    pub maps: [Vec4; 3],
}

/// A triangle's barycentric gradients and the pixel centre near vertex `a` that the span
/// maps are based at. Only differences from `a` enter, so a patch moved by whole pixels
/// gets bit-identical span maps.
struct LocalFrame {
    g1: DVec2,
    g2: DVec2,
    origin: [i32; 2],
    /// Origin centre − a.
    offset: DVec2,
}

impl LocalFrame {
    /// `usable`: the gradients are wanted (else zero, for triangles never drawn).
    fn new([a, b, c]: [DVec2; 3], usable: bool) -> LocalFrame {
        let (e1, e2) = (b - a, c - a);
        let inv = if usable { 1.0 / e1.perp_dot(e2) } else { 0.0 };
        // Barycentric gradients: λ1 = g1·(p − a), λ2 = g2·(p − a).
        let clamp = |v: f64| floor_to_i32(v.clamp(-MAX_COORDINATE, MAX_COORDINATE));
        let origin = [clamp(a.x), clamp(a.y)];
        LocalFrame {
            g1: DVec2::new(e2.y * inv, -e2.x * inv),
            g2: DVec2::new(-e1.y * inv, e1.x * inv),
            origin,
            offset: DVec2::new(f64::from(origin[0]) + 0.5, f64::from(origin[1]) + 0.5) - a,
        }
    }

    /// Gradient of the affine map with these increments along a→b and a→c.
    fn gradient(&self, edge1: f64, edge2: f64) -> DVec2 {
        self.g1 * edge1 + self.g2 * edge2
    }

    fn at_origin(&self, at_a: f64, gradient: DVec2) -> f64 {
        at_a + gradient.dot(self.offset)
    }

    /// The texel maps x and y of a triangle with these rest corners, as [`SpanSetup`] holds
    /// them (they share the membrane's origin). A triangle moved by the whole pixels `shift`
    /// maps the centre of pixel `origin` to the texel centre `origin − s`, exactly.
    fn texel_maps(&self, rest: [DVec2; 3], shift: Option<[i32; 2]>) -> [[f32; 3]; 2] {
        if let Some(s) = shift {
            let [x, y] = [0, 1].map(|k| (self.origin[k] - s[k]) as f32);
            return [[x, 1.0, 0.0], [y, 0.0, 1.0]];
        }
        let (r1, r2) = (rest[1] - rest[0], rest[2] - rest[0]);
        let texel = |at_a: f64, edge1: f64, edge2: f64| {
            let gradient = self.gradient(edge1, edge2);
            [
                (self.at_origin(at_a, gradient) - 0.5) as f32,
                gradient.x as f32,
                gradient.y as f32,
            ]
        };
        [texel(rest[0].x, r1.x, r2.x), texel(rest[0].y, r1.y, r2.y)]
    }
}

impl MembraneSpan {
    fn new(frame: &LocalFrame, membrane: [[f32; 3]; 3]) -> MembraneSpan {
        let channel = |c: usize| {
            let m = |k: usize| f64::from(membrane[k][c]);
            let gradient = frame.gradient(m(1) - m(0), m(2) - m(0));
            (frame.at_origin(m(0), gradient), gradient)
        };
        let [r, g, b] = [channel(0), channel(1), channel(2)];
        let lanes =
            |f: &dyn Fn((f64, DVec2)) -> f64| Vec4::new(f(r) as f32, f(g) as f32, f(b) as f32, 0.0);
        MembraneSpan {
            origin: frame.origin,
            maps: [lanes(&|m| m.0), lanes(&|m| m.1.x), lanes(&|m| m.1.y)],
        }
    }

}

/// How far (px) a placed vertex may lie from its rest position moved by whole pixels and
/// still count as moved by them: placements put placed points on a 2⁻¹⁶-px grid
/// (`clone::PLACED_GRID`), so a whole-pixel move leaves each off by at most half of that.
const WHOLE_PIXEL_TOLERANCE: f64 = 1.0 / 65536.0;

/// The whole pixels `s` a placed triangle is its rest triangle moved by, each vertex within
/// [`WHOLE_PIXEL_TOLERANCE`]. Sampling `pixel − s` exactly instead of the placed map moves a
/// sample by at most that, and keeps a pasted patch's texels unresampled (the promise of a
/// whole-pixel placement), wherever the mesh's vertices lie between grid points.
pub(crate) fn whole_pixel_shift(placed: [DVec2; 3], rest: [DVec2; 3]) -> Option<[i32; 2]> {
    let s = (placed[0] - rest[0]).round();
    // With placed points within 2²⁰ px (drawable), `pixel − s` then stays below 2²⁴, where
    // the f32 texel maps hold it exactly.
    let limit = f64::from(1 << 22);
    if !s.is_finite() || s.abs().max_element() > limit {
        return None;
    }
    let close = placed
        .iter()
        .zip(&rest)
        .all(|(&p, &r)| (p - r - s).abs().max_element() <= WHOLE_PIXEL_TOLERANCE);
    close.then_some([s.x as i32, s.y as i32])
}

/// `⌊v⌋` for `|v| ≤ MAX_COORDINATE` (NaN gives 0), without the libm call `f64::floor`
/// becomes on baseline x86_64.
#[inline]
fn floor_to_i32(v: f64) -> i32 {
    let truncated = v as i32;
    truncated - i32::from(f64::from(truncated) > v)
}

/// A placed vertex snapped to the fixed-point grid, and whether it is in range. Snapped once
/// per vertex and frame (not once per triangle corner).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SnappedVertex {
    pub fixed: [i64; 2],
    pub in_range: bool,
}

impl SnappedVertex {
    #[inline]
    pub fn new(p: DVec2) -> SnappedVertex {
        SnappedVertex {
            fixed: snap(p),
            in_range: p.abs().max_element() <= MAX_COORDINATE,
        }
    }
}

impl TriangleSetup {
    pub fn new(
        placed: [DVec2; 3],
        rest: [DVec2; 3],
        membrane: [[f32; 3]; 3],
        depth: [f32; 3],
    ) -> TriangleSetup {
        let snapped = placed.map(SnappedVertex::new);
        TriangleSetup::from_snapped(placed, snapped, rest, membrane, depth)
    }

    /// [`new`](Self::new) with the corners already snapped (`snapped[k]` is
    /// `SnappedVertex::new(placed[k])`).
    #[inline]
    pub fn from_snapped(
        placed: [DVec2; 3],
        snapped: [SnappedVertex; 3],
        rest: [DVec2; 3],
        membrane: [[f32; 3]; 3],
        depth: [f32; 3],
    ) -> TriangleSetup {
        let [a, b, c] = placed;
        let e1 = b - a;
        let e2 = c - a;
        let det = e1.perp_dot(e2);
        let mut fixed = snapped.map(|s| s.fixed);
        // Out-of-range (or NaN) vertices snap to saturated values whose edge function would
        // overflow i64: test the range first and never evaluate it for them.
        let in_range = snapped.iter().all(|s| s.in_range);
        let fixed_area = if in_range {
            edge_function(fixed[0], fixed[1], fixed[2])
        } else {
            0
        };
        if fixed_area < 0 {
            fixed.swap(1, 2);
        }
        let drawable = in_range && fixed_area != 0 && det != 0.0 && det.is_finite();
        let frame = LocalFrame::new(placed, drawable);
        let shift = if drawable {
            whole_pixel_shift(placed, rest)
        } else {
            None
        };
        let [texel_x, texel_y] = frame.texel_maps(rest, shift);
        let affine = |at_a: f64, edge1: f64, edge2: f64| {
            let gradient = frame.gradient(edge1, edge2);
            [at_a - gradient.dot(a), gradient.x, gradient.y]
        };
        TriangleSetup {
            span: SpanSetup {
                texel_x,
                texel_y,
                membrane: MembraneSpan::new(&frame, membrane),
                shift,
            },
            fixed,
            drawable,
            depth_affine: affine(
                f64::from(depth[0]),
                f64::from(depth[1]) - f64::from(depth[0]),
                f64::from(depth[2]) - f64::from(depth[0]),
            ),
        }
    }

    /// Depth at the centre of pixel (x, y) and its step per pixel along the row: a span
    /// evaluates `first + step · k` in f32 (exact f64 at the span's start, so no error
    /// accumulates across the canvas; along a span it is far below any depth gap that
    /// matters, and the same for every thread count).
    #[inline]
    pub fn depth_along_row(&self, x: i32, y: i32) -> (f32, f32) {
        let d = &self.depth_affine;
        let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
        ((d[0] + d[1] * cx + d[2] * cy) as f32, d[1] as f32)
    }
}

impl SpanSetup {
    /// The source position (texel space) and membrane at pixel `(x, y)`'s centre.
    #[inline(always)]
    pub fn at_pixel(&self, x: i32, y: i32) -> (f32, f32, Vec4) {
        self.along_row(y).at(x)
    }

    /// The maps along row `y`: each map's `d/dy · dy` term taken once for the row.
    #[inline(always)]
    pub fn along_row(&self, y: i32) -> RowMaps {
        let dy = (y - self.membrane.origin[1]) as f32;
        let [m_origin, m_x, m_y] = self.membrane.maps;
        RowMaps {
            origin_x: self.membrane.origin[0],
            texel_x: [self.texel_x[0], self.texel_x[1], self.texel_x[2] * dy],
            texel_y: [self.texel_y[0], self.texel_y[1], self.texel_y[2] * dy],
            membrane: [m_origin, m_x, m_y * dy],
        }
    }
}

/// A triangle's maps along one canvas row ([`SpanSetup::along_row`]): at pixel `x` each is
/// `(at origin + d/dx · dx) + (d/dy · dy)`, the same operations in the same order as
/// evaluating the whole map at the pixel, with the row's term computed once.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowMaps {
    origin_x: i32,
    /// `[at origin, d/dx, d/dy · dy]`.
    texel_x: [f32; 3],
    texel_y: [f32; 3],
    membrane: [Vec4; 3],
}

impl RowMaps {
    /// The source position (texel space) and membrane at the row's pixel `x`.
    #[inline(always)]
    pub fn at(&self, x: i32) -> (f32, f32, Vec4) {
        let dx = (x - self.origin_x) as f32;
        let at = |m: &[f32; 3]| m[0] + m[1] * dx + m[2];
        (at(&self.texel_x), at(&self.texel_y), self.membrane_at(x))
    }

    /// The maps as the eight-lane shader takes them, and the column they are based at.
    #[inline(always)]
    pub fn affine(&self) -> (RowAffine, i32) {
        let maps = RowAffine {
            texel_x: self.texel_x,
            texel_y: self.texel_y,
            membrane: self.membrane.map(|m| m.to_array()),
        };
        (maps, self.origin_x)
    }

    /// The membrane alone at the row's pixel `x`.
    #[inline(always)]
    pub fn membrane_at(&self, x: i32) -> Vec4 {
        let dx = (x - self.origin_x) as f32;
        let [m_origin, m_x, m_row] = self.membrane;
        m_origin + m_x * dx + m_row
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
    fn floor_to_i32_is_floor_over_the_coordinate_range() {
        let mut values = vec![
            0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.999, -2.999, 1e-300, -1e-300,
        ];
        values.extend([MAX_COORDINATE, -MAX_COORDINATE, MAX_COORDINATE - 0.25]);
        values.extend((0..2000).map(|k| (f64::from(k) - 1000.0) * 0.37 + 1e-9 * f64::from(k)));
        for v in values {
            assert_eq!(floor_to_i32(v), v.floor() as i32, "{v}");
        }
        assert_eq!(floor_to_i32(f64::NAN), 0);
    }

    /// A triangle placed as a placement places it (on the 2⁻¹⁶-px grid) is a whole-pixel
    /// shift exactly when the move is whole pixels; its texel maps then give `pixel − s`.
    #[test]
    fn only_whole_pixel_moves_are_shifts() {
        let grid = |p: DVec2| (p * 65536.0).round() / 65536.0;
        let rest = [
            DVec2::new(10.123_456_7, 20.987_654_3),
            DVec2::new(13.3, 20.1),
            DVec2::new(11.71, 24.02),
        ];
        let (mut shifts, mut others) = (0, 0);
        for (k, dx) in [-37.0, -1.0, 0.0, 2.0, 500.0, 0.5, 3.25, 1.0 + 1e-3].iter().enumerate() {
            let dy = [4.0, -3.0, 0.0, 7.0, 1.0, -2.5, 0.0, 2.0][k];
            let move_by = DVec2::new(*dx, dy);
            let placed = rest.map(|r| grid(r + move_by));
            let setup = TriangleSetup::new(placed, rest, [[0.0; 3]; 3], [0.0; 3]);
            let whole = move_by.fract() == DVec2::ZERO;
            if whole {
                shifts += 1;
                assert_eq!(setup.span.shift, Some([*dx as i32, dy as i32]), "{move_by}");
                let maps = setup.span.along_row(30);
                for x in 40..60 {
                    let (tx, ty, _) = maps.at(x);
                    assert_eq!([tx, ty], [(x as f64 - dx) as f32, (30.0 - dy) as f32]);
                }
            } else {
                others += 1;
                assert_eq!(setup.span.shift, None, "{move_by}");
            }
        }
        // Scaled or turned by a hair more than the grid: not a shift.
        for placed in [
            rest.map(|r| grid(r * 1.000_01)),
            rest.map(|r| grid(DVec2::from_angle(1e-5).rotate(r))),
        ] {
            others += 1;
            assert_eq!(TriangleSetup::new(placed, rest, [[0.0; 3]; 3], [0.0; 3]).span.shift, None);
        }
        assert_eq!((shifts, others), (5, 5));
    }

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
