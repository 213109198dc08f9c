//! `Mesh::sanity_check`: takes a [`Mesh`] and verifies every structural invariant that does
//! not need the mask (the mask-aware checks live in `coverage`): finite positions, indices in
//! range, every triangle of positive signed area, each directed edge in at most one triangle
//! (so undirected edges are shared by ≤ 2 consistently oriented triangles), no unused
//! vertex, boundary loops that are exactly the closed chains of boundary edges with the right
//! orientation, per-vertex flags and piece ids that agree with the triangles, and
//! V − E + F = pieces − holes.

use super::triangulate::{boundary_edges, label_pieces};
use super::{LoopKind, Mesh, SanityError};

impl Mesh {
    /// Verifies the mesh invariants; returns the first violation found.
    pub fn sanity_check(&self) -> Result<(), SanityError> {
        self.check_arrays()?;
        self.check_triangles()?;
        self.check_loops()?;
        self.check_pieces()?;
        self.check_euler()
    }

    fn check_arrays(&self) -> Result<(), SanityError> {
        let n = self.positions.len();
        if self.is_boundary.len() != n || self.piece.len() != n {
            return Err(SanityError::LengthMismatch {
                positions: n,
                is_boundary: self.is_boundary.len(),
                piece: self.piece.len(),
            });
        }
        match self.positions.iter().position(|p| !p.is_finite()) {
            Some(v) => Err(SanityError::NonFinitePosition { vertex: v as u32 }),
            None => Ok(()),
        }
    }

    fn check_triangles(&self) -> Result<(), SanityError> {
        let n = self.positions.len();
        let mut used = vec![false; n];
        for (index, t) in self.triangles.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= n) {
                return Err(SanityError::IndexOutOfRange {
                    triangle: index,
                    vertex: v,
                });
            }
            let [a, b, c] = t.map(|v| self.positions[v as usize]);
            let area = 0.5 * (b - a).perp_dot(c - a);
            if area.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(SanityError::NotPositive {
                    triangle: index,
                    area,
                });
            }
            for &v in t {
                used[v as usize] = true;
            }
        }
        if let Some(v) = used.iter().position(|&u| !u) {
            return Err(SanityError::IsolatedVertex { vertex: v as u32 });
        }
        let mut directed: Vec<(u32, u32)> = self
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        directed.sort_unstable();
        match directed.windows(2).find(|w| w[0] == w[1]) {
            Some(w) => Err(SanityError::EdgeOverShared {
                a: w[0].0,
                b: w[0].1,
            }),
            None => Ok(()),
        }
    }

    fn check_loops(&self) -> Result<(), SanityError> {
        let boundary = boundary_edges(&self.triangles);
        let mut seen = vec![false; boundary.len()];
        let mut listed = 0usize;
        let mut on_loop = vec![false; self.positions.len()];
        for (loop_index, lp) in self.loops.iter().enumerate() {
            let len = lp.vertices.len();
            if len < 3 {
                return Err(SanityError::ShortLoop { loop_index, len });
            }
            for i in 0..len {
                let (a, b) = (lp.vertices[i], lp.vertices[(i + 1) % len]);
                match boundary.binary_search(&(a, b)) {
                    Ok(k) if !seen[k] => seen[k] = true,
                    _ => return Err(SanityError::LoopEdgeNotBoundary { loop_index, a, b }),
                }
                on_loop[a as usize] = true;
                if self.piece[a as usize] != lp.piece {
                    return Err(SanityError::PieceMismatch { vertex: a });
                }
            }
            listed += len;
            let points: Vec<_> = lp
                .vertices
                .iter()
                .map(|&v| self.positions[v as usize])
                .collect();
            let area = 0.5 * super::simplify::doubled_signed_area(&points);
            let (ok, kind) = match lp.kind {
                LoopKind::Outer => (area > 0.0, "outer"),
                LoopKind::Hole => (area < 0.0, "hole"),
            };
            if !ok {
                return Err(SanityError::LoopOrientation {
                    loop_index,
                    kind,
                    area,
                });
            }
        }
        if listed != boundary.len() {
            return Err(SanityError::BoundaryEdgeCount {
                listed,
                actual: boundary.len(),
            });
        }
        match (0..self.positions.len()).find(|&v| on_loop[v] != self.is_boundary[v]) {
            Some(v) => Err(SanityError::BoundaryFlag { vertex: v as u32 }),
            None => Ok(()),
        }
    }

    fn check_pieces(&self) -> Result<(), SanityError> {
        let (labels, count) = label_pieces(self.positions.len(), &self.triangles);
        if count != self.piece_count {
            return Err(SanityError::PieceCount {
                listed: self.piece_count,
                actual: count,
            });
        }
        // piece must be a relabelling of the connectivity labels: a bijection between ids.
        let mut map = vec![u32::MAX; count as usize];
        let mut back = vec![u32::MAX; count as usize];
        for (v, (&mine, &truth)) in self.piece.iter().zip(&labels).enumerate() {
            if mine >= count {
                return Err(SanityError::PieceMismatch { vertex: v as u32 });
            }
            let fwd_ok = map[truth as usize] == u32::MAX || map[truth as usize] == mine;
            let back_ok = back[mine as usize] == u32::MAX || back[mine as usize] == truth;
            if !fwd_ok || !back_ok {
                return Err(SanityError::PieceMismatch { vertex: v as u32 });
            }
            map[truth as usize] = mine;
            back[mine as usize] = truth;
        }
        Ok(())
    }

    fn check_euler(&self) -> Result<(), SanityError> {
        let v = self.positions.len() as i64;
        let e = self.edges().len() as i64;
        let f = self.triangles.len() as i64;
        let expected = self.piece_count as i64 - self.hole_count() as i64;
        if v - e + f != expected {
            return Err(SanityError::Euler {
                actual: v - e + f,
                expected,
            });
        }
        Ok(())
    }
}
