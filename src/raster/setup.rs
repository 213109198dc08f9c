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
    /// Placed position of vertex 0 (original order).
    pub origin: DVec2,
    /// Inverse of the placed edge matrix [b − a, c − a]: position offset → (λ1, λ2).
    pub to_barycentric: [[f64; 2]; 2],
    pub rest_origin: DVec2,
    pub rest_edge1: DVec2,
    pub rest_edge2: DVec2,
    pub membrane_origin: [f32; 3],
    pub membrane_edge1: [f32; 3],
    pub membrane_edge2: [f32; 3],
    pub depth_origin: f32,
    pub depth_edge1: f32,
    pub depth_edge2: f32,
    /// Signed placed area ×2 (negative: inverted).
    pub signed_area2: f64,
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
        let fixed_area = edge_function(fixed[0], fixed[1], fixed[2]);
        if fixed_area < 0 {
            fixed.swap(1, 2);
        }
        let in_range = placed
            .iter()
            .all(|p| p.abs().max_element() <= MAX_COORDINATE);
        let drawable = in_range && fixed_area != 0 && det != 0.0 && det.is_finite();
        let inv = if drawable { 1.0 / det } else { 0.0 };
        let sub = |x: [f32; 3], y: [f32; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
        TriangleSetup {
            fixed,
            drawable,
            origin: a,
            to_barycentric: [[e2.y * inv, -e2.x * inv], [-e1.y * inv, e1.x * inv]],
            rest_origin: rest[0],
            rest_edge1: rest[1] - rest[0],
            rest_edge2: rest[2] - rest[0],
            membrane_origin: membrane[0],
            membrane_edge1: sub(membrane[1], membrane[0]),
            membrane_edge2: sub(membrane[2], membrane[0]),
            depth_origin: depth[0],
            depth_edge1: depth[1] - depth[0],
            depth_edge2: depth[2] - depth[0],
            signed_area2: det,
        }
    }

    #[inline]
    pub fn barycentric(&self, position: DVec2) -> (f64, f64) {
        let q = position - self.origin;
        let m = &self.to_barycentric;
        (m[0][0] * q.x + m[0][1] * q.y, m[1][0] * q.x + m[1][1] * q.y)
    }

    #[inline]
    pub fn depth_at(&self, position: DVec2) -> f32 {
        let (l1, l2) = self.barycentric(position);
        self.depth_origin + l1 as f32 * self.depth_edge1 + l2 as f32 * self.depth_edge2
    }

    #[inline]
    pub fn interpolate(&self, position: DVec2) -> Interpolated {
        let (l1, l2) = self.barycentric(position);
        let rest = self.rest_origin + l1 * self.rest_edge1 + l2 * self.rest_edge2;
        let (f1, f2) = (l1 as f32, l2 as f32);
        let mut membrane = self.membrane_origin;
        for (c, m) in membrane.iter_mut().enumerate() {
            *m += f1 * self.membrane_edge1[c] + f2 * self.membrane_edge2[c];
        }
        Interpolated { rest, membrane }
    }
}

/// Rounds a position to the 1/256-px grid.
#[inline]
pub(crate) fn snap(p: DVec2) -> [i64; 2] {
    let s = SUBPIXEL as f64;
    [(p.x * s).round() as i64, (p.y * s).round() as i64]
}

/// (b − a) × (p − a) in fixed point; positive when p is left of a→b in raw coordinates
/// (the inside of a positively oriented triangle).
#[inline]
pub(crate) fn edge_function(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}
