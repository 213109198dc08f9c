//! The outline of a placed patch's folds: takes the placed triangles and the winding of the
//! boundary loops, and gives the closed contours that bound the inverted triangles as a
//! region, each wound like a non-inverted triangle (see [`coverage`](super::coverage), which
//! adds them twice to the silhouette path).
//!
//! Why contours instead of the triangles: adjacent inverted triangles traverse their shared
//! edge in opposite directions, so those edges cancel in the winding number. Dropping them
//! leaves the same winding number at every point (it is linear in the edges) with a fraction
//! of the edges: an interactive drag folds a few hundred small triangles, and tiny-skia's
//! scan conversion pays for every edge on every sub-scanline it crosses. It also keeps the
//! inside of a fold free of span breaks, so its coverage is full there.
//!
//! Deterministic: edges are sorted by value and chained in that order.

use super::Patch;

/// Grow-only buffers and the contours of the last [`FoldOutline::build`].
#[derive(Default, Debug)]
pub(crate) struct FoldOutline {
    /// Directed edges `[from, to]`: first those of every inverted triangle, then (after
    /// cancelling) what is left, sorted by `from`.
    edges: Vec<[u32; 2]>,
    used: Vec<bool>,
    /// The contours' vertices, one after the other; each contour closes on its first vertex.
    vertices: Vec<u32>,
    /// Where each contour starts in `vertices`, plus the end.
    starts: Vec<usize>,
}

impl FoldOutline {
    /// The contours of `patch`'s inverted triangles (placed area < 0), wound like a
    /// non-inverted triangle relative to loops of rest orientation `loop_orientation`.
    pub fn build(&mut self, patch: &Patch, loop_orientation: f64) {
        self.edges.clear();
        for tri in patch.triangles {
            let [a, b, c] = tri.map(|v| patch.placed[v as usize]);
            if (b - a).perp_dot(c - a) < 0.0 {
                let [p, q, r] = wound(tri, loop_orientation < 0.0);
                self.edges.extend([[p, q], [q, r], [r, p]]);
            }
        }
        self.cancel_opposite_edges();
        self.chain();
    }

    /// No contour.
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.starts.clear();
    }

    /// The contours, each a closed polygon of vertex indices.
    pub fn contours(&self) -> impl Iterator<Item = &[u32]> {
        self.starts.windows(2).map(|w| &self.vertices[w[0]..w[1]])
    }

    /// Keeps, for each undirected edge, its net count of traversals in one direction.
    fn cancel_opposite_edges(&mut self) {
        let key = |&[p, q]: &[u32; 2]| (p.min(q), p.max(q));
        self.edges.sort_unstable_by_key(key);
        let mut kept = 0;
        let mut group = 0;
        while group < self.edges.len() {
            let k = key(&self.edges[group]);
            let end = group + self.edges[group..].partition_point(|e| key(e) == k);
            // Net traversals from the smaller vertex to the larger.
            let net: i64 = self.edges[group..end]
                .iter()
                .map(|&[p, q]| if p < q { 1 } else { -1 })
                .sum();
            let (low, high) = k;
            let edge = if net > 0 { [low, high] } else { [high, low] };
            for _ in 0..net.unsigned_abs() {
                self.edges[kept] = edge;
                kept += 1;
            }
            group = end;
        }
        self.edges.truncate(kept);
        self.edges.sort_unstable();
    }

    /// Chains the kept edges into closed contours. Every vertex has as many kept edges in as
    /// out (the edges are the boundary of a sum of triangles), so a walk can only stop where
    /// it started.
    fn chain(&mut self) {
        self.used.clear();
        self.used.resize(self.edges.len(), false);
        self.vertices.clear();
        self.starts.clear();
        self.starts.push(0);
        let mut cursor_from = 0;
        while let Some(first) = (cursor_from..self.edges.len()).find(|&e| !self.used[e]) {
            cursor_from = first + 1;
            let origin = self.edges[first][0];
            let mut edge = first;
            loop {
                self.used[edge] = true;
                let [from, to] = self.edges[edge];
                self.vertices.push(from);
                if to == origin {
                    break;
                }
                match self.unused_edge_from(to) {
                    Some(next) => edge = next,
                    // Unbalanced input cannot come from triangles; end the contour anyway
                    // (the path closes it).
                    None => break,
                }
            }
            self.starts.push(self.vertices.len());
        }
    }

    fn unused_edge_from(&self, vertex: u32) -> Option<usize> {
        let first = self.edges.partition_point(|e| e[0] < vertex);
        (first..self.edges.len())
            .take_while(|&e| self.edges[e][0] == vertex)
            .find(|&e| !self.used[e])
    }
}

/// `tri` as given (`keep`) or with its winding reversed.
pub(crate) fn wound(tri: &[u32; 3], keep: bool) -> [u32; 3] {
    if keep {
        *tri
    } else {
        [tri[0], tri[2], tri[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixels::{FloatImage, PixelFormat};
    use glam::DVec2;

    /// A `columns` × `rows` grid of unit cells, two triangles each, positive at rest.
    fn grid(columns: u32, rows: u32) -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let at = |i: u32, j: u32| j * (columns + 1) + i;
        let rest = (0..=rows)
            .flat_map(|j| (0..=columns).map(move |i| DVec2::new(f64::from(i), f64::from(j))))
            .collect::<Vec<_>>();
        let mut triangles = Vec::new();
        for j in 0..rows {
            for i in 0..columns {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
                for tri in [[a, b, d], [a, d, c]] {
                    let [p, q, r] = tri.map(|v| rest[v as usize]);
                    let positive = (q - p).perp_dot(r - p) > 0.0;
                    triangles.push(if positive {
                        tri
                    } else {
                        [tri[0], tri[2], tri[1]]
                    });
                }
            }
        }
        (rest, triangles)
    }

    /// The winding number of the closed polygon `points` around `p`.
    fn winding(points: impl Iterator<Item = DVec2> + Clone, p: DVec2) -> i32 {
        let next = points.clone().cycle().skip(1);
        points
            .zip(next)
            .map(|(a, b)| {
                let side = (b - a).perp_dot(p - a);
                match (a.y <= p.y, b.y <= p.y) {
                    (true, false) if side > 0.0 => 1,
                    (false, true) if side < 0.0 => -1,
                    _ => 0,
                }
            })
            .sum()
    }

    /// Deterministic values in [0, 1).
    fn noise(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn the_outline_winds_like_the_inverted_triangles_it_replaces() {
        let (rest, triangles) = grid(9, 7);
        let source = FloatImage::from_fn(1, 1, PixelFormat::RGBA8, |_, _| [0.0; 4]).unwrap();
        let mut outline = FoldOutline::default();
        for seed in 0..40 {
            let mut random = noise(seed);
            // Large random moves invert many triangles, in clusters and alone.
            let placed: Vec<DVec2> = rest
                .iter()
                .map(|&p| p + 2.4 * DVec2::new(random() - 0.5, random() - 0.5))
                .collect();
            let patch = Patch {
                rest: &rest,
                placed: &placed,
                triangles: &triangles,
                membrane: &[],
                depth: None,
                loops: &[],
                source: &source,
            };
            for orientation in [1.0, -1.0] {
                outline.build(&patch, orientation);
                let inverted: Vec<[u32; 3]> = triangles
                    .iter()
                    .filter(|t| {
                        let [a, b, c] = t.map(|v| placed[v as usize]);
                        (b - a).perp_dot(c - a) < 0.0
                    })
                    .map(|t| wound(t, orientation < 0.0))
                    .collect();
                let edges: usize = outline.contours().map(<[u32]>::len).sum();
                assert!(edges <= 3 * inverted.len(), "seed {seed}");
                let at = |v: &u32| placed[*v as usize];
                for _ in 0..200 {
                    let p = DVec2::new(random() * 11.0 - 1.0, random() * 9.0 - 1.0);
                    let by_triangles: i32 =
                        inverted.iter().map(|t| winding(t.iter().map(at), p)).sum();
                    let by_outline: i32 = outline
                        .contours()
                        .map(|c| winding(c.iter().map(at), p))
                        .sum();
                    assert_eq!(by_outline, by_triangles, "seed {seed}, point {p}");
                }
            }
        }
    }

    #[test]
    fn a_wholly_inverted_patch_is_one_contour_along_its_border() {
        let (rest, triangles) = grid(5, 4);
        let source = FloatImage::from_fn(1, 1, PixelFormat::RGBA8, |_, _| [0.0; 4]).unwrap();
        let mirrored: Vec<DVec2> = rest.iter().map(|p| DVec2::new(-p.x, p.y)).collect();
        let patch = Patch {
            rest: &rest,
            placed: &mirrored,
            triangles: &triangles,
            membrane: &[],
            depth: None,
            loops: &[],
            source: &source,
        };
        let mut outline = FoldOutline::default();
        outline.build(&patch, 1.0);
        let contours: Vec<&[u32]> = outline.contours().collect();
        assert_eq!(contours.len(), 1);
        assert_eq!(contours[0].len(), 2 * (5 + 4), "the border's vertices");
        outline.clear();
        assert_eq!(outline.contours().count(), 0);
    }
}
