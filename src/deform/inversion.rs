//! Inversion check: takes a [`Deformed`] and the mesh it came from and counts triangles whose
//! deformed signed area is `≤ 0` (rest triangles are positive, so these folded over).

use super::Deformed;
use crate::mesh::Mesh;

impl Deformed {
    /// Triangles of `mesh` with non-positive signed area at the deformed positions.
    pub fn inverted_triangles(&self, mesh: &Mesh) -> usize {
        mesh.triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|v| self.positions[v as usize]);
                (b - a).perp_dot(c - a) <= 0.0
            })
            .count()
    }
}
