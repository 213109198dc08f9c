//! The mesh data structure shared by every later stage.

use glam::DVec2;

/// Whether a boundary loop bounds a piece from outside or a hole inside it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LoopKind {
    /// Bounds a piece from outside (positive signed area).
    Outer,
    /// Bounds a hole inside a piece (negative signed area).
    Hole,
}

/// One closed boundary loop of the mesh, as vertex indices in order (the closing edge from
/// the last vertex back to the first is implied). Outer loops have positive signed area,
/// holes negative, so the inside is always on the same side of every boundary edge.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryLoop {
    /// Outer boundary or hole.
    pub kind: LoopKind,
    /// Connected piece this loop belongs to.
    pub piece: u32,
    /// Vertex indices in order around the loop.
    pub vertices: Vec<u32>,
}

/// A triangle mesh of a patch in rest (source-image) coordinates.
///
/// Positions are `f64`: the deformation and the solver work in `f64`, and rest positions
/// are also the source-texture coordinates, so there is no reason to round them.
/// Triangles have positive signed area `(b - a) × (c - a) > 0` in these raw coordinates
/// (which, with y pointing down, looks clockwise on screen).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, rest (source-pixel) coordinates.
    pub positions: Vec<DVec2>,
    /// Counter-clockwise vertex triples.
    pub triangles: Vec<[u32; 3]>,
    /// Closed boundary loops: outer rings and holes.
    pub loops: Vec<BoundaryLoop>,
    /// `is_boundary[v]`: v lies on a boundary loop.
    pub is_boundary: Vec<bool>,
    /// `piece[v]`: the connected piece of v (pieces touching at a vertex are one piece).
    pub piece: Vec<u32>,
    /// Number of connected pieces.
    pub piece_count: u32,
}

impl Mesh {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Indices of the vertices on a boundary loop.
    pub fn boundary_vertices(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.positions.len() as u32).filter(|&v| self.is_boundary[v as usize])
    }

    /// Number of hole loops.
    pub fn hole_count(&self) -> usize {
        self.loops
            .iter()
            .filter(|l| l.kind == LoopKind::Hole)
            .count()
    }

    /// Unique undirected edges (i < j), sorted.
    ///
    /// A counting sort by the first vertex, then a sort of each vertex's few neighbours: a
    /// comparison sort of all the triangles' edges cost more than the factorisation it feeds.
    pub fn edges(&self) -> Vec<(u32, u32)> {
        let ordered = |a: u32, b: u32| (a.min(b), a.max(b));
        let corners = |t: &[u32; 3]| {
            [
                ordered(t[0], t[1]),
                ordered(t[1], t[2]),
                ordered(t[2], t[0]),
            ]
        };
        // Sized by the largest index used, so a mesh whose triangles name vertices it lacks
        // still gets its edges (its sanity check reports the fault).
        let buckets = self
            .triangles
            .iter()
            .flatten()
            .max()
            .map_or(0, |&v| v as usize + 1);
        let mut start = vec![0usize; buckets + 1];
        for (a, _) in self.triangles.iter().flat_map(corners) {
            start[a as usize + 1] += 1;
        }
        for v in 0..buckets {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        let mut seconds = vec![0u32; start[buckets]];
        for (a, b) in self.triangles.iter().flat_map(corners) {
            seconds[next[a as usize]] = b;
            next[a as usize] += 1;
        }
        let mut edges = Vec::with_capacity(seconds.len() / 2 + buckets);
        for a in 0..buckets {
            let neighbours = &mut seconds[start[a]..start[a + 1]];
            neighbours.sort_unstable();
            let mut last = None;
            for &b in neighbours.iter() {
                if last != Some(b) {
                    edges.push((a as u32, b));
                    last = Some(b);
                }
            }
        }
        edges
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures;

    /// The counting sort gives what sorting and deduplicating every triangle edge gives.
    #[test]
    fn edges_match_the_sorted_deduplicated_triangle_edges() {
        let mut fan = fixtures::disc(5);
        // A hub: one vertex in every triangle of a 300-triangle fan.
        let hub = fan.positions.len() as u32;
        fan.positions.push(glam::DVec2::ZERO);
        let rim: Vec<u32> = (0..300).map(|k| hub + 1 + k).collect();
        fan.positions
            .extend((0..300).map(|k| glam::DVec2::new(f64::from(k), 1.0)));
        fan.triangles
            .extend(rim.windows(2).map(|w| [w[1], hub, w[0]]));
        for mesh in [
            fixtures::grid(6, 4),
            fixtures::disc(7),
            fan,
            Mesh::default(),
        ] {
            let mut expected: Vec<(u32, u32)> = mesh
                .triangles
                .iter()
                .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                .map(|(a, b)| (a.min(b), a.max(b)))
                .collect();
            expected.sort_unstable();
            expected.dedup();
            assert_eq!(mesh.edges(), expected);
        }
    }
}
