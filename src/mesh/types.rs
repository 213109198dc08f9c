//! The mesh data structure shared by every later stage.

use glam::DVec2;

/// Whether a boundary loop bounds a piece from outside or a hole inside it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LoopKind {
    Outer,
    Hole,
}

/// One closed boundary loop of the mesh, as vertex indices in order (the closing edge from
/// the last vertex back to the first is implied). Outer loops have positive signed area,
/// holes negative, so the inside is always on the same side of every boundary edge.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryLoop {
    pub kind: LoopKind,
    /// Connected piece this loop belongs to.
    pub piece: u32,
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
    pub positions: Vec<DVec2>,
    pub triangles: Vec<[u32; 3]>,
    pub loops: Vec<BoundaryLoop>,
    /// `is_boundary[v]`: v lies on a boundary loop.
    pub is_boundary: Vec<bool>,
    /// `piece[v]`: the connected piece of v (pieces touching at a vertex are one piece).
    pub piece: Vec<u32>,
    pub piece_count: u32,
}

impl Mesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn boundary_vertices(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.positions.len() as u32).filter(|&v| self.is_boundary[v as usize])
    }

    pub fn hole_count(&self) -> usize {
        self.loops
            .iter()
            .filter(|l| l.kind == LoopKind::Hole)
            .count()
    }

    /// Unique undirected edges (i < j), sorted.
    pub fn edges(&self) -> Vec<(u32, u32)> {
        let mut edges: Vec<(u32, u32)> = self
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        edges
    }
}
