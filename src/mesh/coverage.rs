//! Mask-aware check of a mesh: [`uncovered_mask_pixels`] counts inside pixels whose centre
//! is neither in a triangle nor within 0.5 px of the mesh.

use glam::DVec2;

use super::simplify::Segment;
use super::{BitMask, Mesh};

/// How far outside the mesh a mask pixel centre may lie and still count as covered.
pub const COVERAGE_TOLERANCE_PX: f64 = 0.5;

/// Number of inside pixels of `mask` whose centre lies farther than 0.5 px from the mesh.
pub fn uncovered_mask_pixels(mesh: &Mesh, mask: &BitMask) -> usize {
    let covered = covered_centres(mesh, mask.width, mask.height);
    let segments = BoundaryGrid::new(mesh);
    let mut uncovered = 0;
    for y in 0..mask.height {
        for x in 0..mask.width {
            if mask.get(x as i64, y as i64) && !covered[y * mask.width + x] {
                let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                if !segments.any_within(centre, COVERAGE_TOLERANCE_PX) {
                    uncovered += 1;
                }
            }
        }
    }
    uncovered
}

/// Flags every pixel whose centre lies in a (closed) triangle of the mesh.
fn covered_centres(mesh: &Mesh, width: usize, height: usize) -> Vec<bool> {
    let mut covered = vec![false; width * height];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        let x0 = (lo.x - 0.5).ceil().max(0.0) as usize;
        let y0 = (lo.y - 0.5).ceil().max(0.0) as usize;
        let x1 = ((hi.x - 0.5).floor() as i64).min(width as i64 - 1);
        let y1 = ((hi.y - 0.5).floor() as i64).min(height as i64 - 1);
        let eps = 1e-9 * (b - a).perp_dot(c - a);
        for y in y0 as i64..=y1 {
            for x in x0 as i64..=x1 {
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let inside = (b - a).perp_dot(p - a) >= -eps
                    && (c - b).perp_dot(p - b) >= -eps
                    && (a - c).perp_dot(p - c) >= -eps;
                if inside {
                    covered[y as usize * width + x as usize] = true;
                }
            }
        }
    }
    covered
}

/// Boundary segments bucketed on a coarse grid for near-point queries.
struct BoundaryGrid {
    cell: f64,
    cols: usize,
    rows: usize,
    origin: DVec2,
    buckets: Vec<Vec<(DVec2, DVec2)>>,
}

impl BoundaryGrid {
    fn new(mesh: &Mesh) -> Self {
        let cell = 4.0;
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in &mesh.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if mesh.positions.is_empty() {
            lo = DVec2::ZERO;
            hi = DVec2::ZERO;
        }
        let cols = ((hi.x - lo.x) / cell).floor() as usize + 1;
        let rows = ((hi.y - lo.y) / cell).floor() as usize + 1;
        let mut grid = Self {
            cell,
            cols,
            rows,
            origin: lo,
            buckets: vec![Vec::new(); cols * rows],
        };
        for lp in &mesh.loops {
            let n = lp.vertices.len();
            for i in 0..n {
                let a = mesh.positions[lp.vertices[i] as usize];
                let b = mesh.positions[lp.vertices[(i + 1) % n] as usize];
                let (c0, r0) = grid.cell_of(a.min(b));
                let (c1, r1) = grid.cell_of(a.max(b));
                for r in r0..=r1 {
                    for c in c0..=c1 {
                        grid.buckets[r * cols + c].push((a, b));
                    }
                }
            }
        }
        grid
    }

    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let c = ((p.x - self.origin.x) / self.cell)
            .floor()
            .clamp(0.0, (self.cols - 1) as f64) as usize;
        let r = ((p.y - self.origin.y) / self.cell)
            .floor()
            .clamp(0.0, (self.rows - 1) as f64) as usize;
        (c, r)
    }

    fn any_within(&self, p: DVec2, radius: f64) -> bool {
        let (c0, r0) = self.cell_of(p - DVec2::splat(radius));
        let (c1, r1) = self.cell_of(p + DVec2::splat(radius));
        (r0..=r1).any(|r| {
            (c0..=c1).any(|c| {
                self.buckets[r * self.cols + c]
                    .iter()
                    .any(|&(a, b)| Segment::new(a, b).distance(p) <= radius + 1e-12)
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::triangulate::assemble_mesh;
    use super::*;

    fn rect_mesh(x0: f64, y0: f64, x1: f64, y1: f64) -> Mesh {
        let p = vec![
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ];
        assemble_mesh(p, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn exact_cover_has_no_uncovered_pixels() {
        let mask = BitMask::from_fn(6, 5, |x, y| (1..5).contains(&x) && (1..4).contains(&y));
        let mesh = rect_mesh(1.0, 1.0, 5.0, 4.0);
        assert_eq!(uncovered_mask_pixels(&mesh, &mask), 0);
    }

    #[test]
    fn shrunken_mesh_leaves_a_column_uncovered() {
        let mask = BitMask::from_fn(6, 5, |x, y| (1..5).contains(&x) && (1..4).contains(&y));
        // 0.4 px short: column 4's centres (x = 4.5) are 0.1 px away → covered by tolerance.
        assert_eq!(
            uncovered_mask_pixels(&rect_mesh(1.0, 1.0, 4.6, 4.0), &mask),
            0
        );
        // 1.2 px short: column 4 is 0.7 px away → 3 uncovered pixels.
        assert_eq!(
            uncovered_mask_pixels(&rect_mesh(1.0, 1.0, 3.8, 4.0), &mask),
            3
        );
    }
}
