//! Builds the graph Laplacian of a [`Mesh`] as a [`SymmetricCsc`]: the paper's combinatorial
//! Laplacian (degree on the diagonal, −1 per edge) or cotangent weights on the rest geometry.
//!
//! Cotangent weights: `w_ij = ½ (cot α_ij + cot β_ij)` summed over the (one or two) triangles
//! sharing edge ij. Obtuse triangles can make a sum negative, which would break the maximum
//! principle (membranes overshooting their boundary values) and can break positive
//! semi-definiteness; a negative edge total is clamped to 0. Triangles with (numerically) zero
//! area contribute nothing instead of an infinite cotangent. Rows always sum to zero.

use glam::DVec2;

use super::SymmetricCsc;
use crate::mesh::Mesh;

/// Which edge weights the Laplacian uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LaplacianKind {
    /// Every edge weighs 1 (the paper): depends on connectivity only.
    #[default]
    Combinatorial,
    /// Cotangent weights on rest positions, negative edge totals clamped to 0.
    Cotangent,
}

impl LaplacianKind {
    /// The name used in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            LaplacianKind::Combinatorial => "combinatorial",
            LaplacianKind::Cotangent => "cotangent",
        }
    }

    /// The kind named `name` (`combinatorial`, `cotangent`).
    pub fn from_name(name: &str) -> Option<Self> {
        [LaplacianKind::Combinatorial, LaplacianKind::Cotangent]
            .into_iter()
            .find(|k| k.name() == name)
    }
}

/// The Laplacian `L = D − W` of the mesh, lower triangle. Vertices without edges get a zero row.
pub fn laplacian(mesh: &Mesh, kind: LaplacianKind) -> SymmetricCsc {
    let n = mesh.vertex_count();
    let weighted_edges: Vec<(u32, u32, f64)> = match kind {
        LaplacianKind::Combinatorial => {
            mesh.edges().into_iter().map(|(i, j)| (i, j, 1.0)).collect()
        }
        LaplacianKind::Cotangent => cotangent_edges(mesh),
    };
    from_sorted_edges(n, &weighted_edges)
}

/// `D − W` in lower CSC straight from edges `(i, j, w)` with i < j < n, sorted and unique:
/// column i is its diagonal, then −w for each edge (i, j) in order — no sort.
fn from_sorted_edges(n: usize, edges: &[(u32, u32, f64)]) -> SymmetricCsc {
    let mut diagonal = vec![0.0; n];
    let mut col_ptr = vec![0usize; n + 1];
    for &(i, j, w) in edges {
        diagonal[i as usize] += w;
        diagonal[j as usize] += w;
        col_ptr[i as usize + 1] += 1;
    }
    for v in 0..n {
        col_ptr[v + 1] += col_ptr[v] + 1;
    }
    let nnz = col_ptr[n];
    let (mut row_idx, mut values) = (Vec::with_capacity(nnz), Vec::with_capacity(nnz));
    let mut rest = edges.iter().peekable();
    for (v, &d) in diagonal.iter().enumerate() {
        row_idx.push(v);
        values.push(d);
        while let Some(&(_, j, w)) = rest.next_if(|e| e.0 as usize == v) {
            row_idx.push(j as usize);
            values.push(-w);
        }
    }
    let csc = SymmetricCsc {
        n,
        col_ptr,
        row_idx,
        values,
    };
    debug_assert!(csc.sanity_check().is_ok());
    csc
}

/// ½ cot of the angle at each corner of the triangle `p`: that triangle's share of the weight
/// of the edge opposite the corner. All 0 when the triangle has (numerically) zero area: its
/// doubled area not above 1e-12 of the longer edge from corner 0, squared, or NaN.
pub(crate) fn half_cotangents(p: [DVec2; 3]) -> [f64; 3] {
    let twice_area = (p[1] - p[0]).perp_dot(p[2] - p[0]).abs();
    let scale = (p[1] - p[0])
        .length_squared()
        .max((p[2] - p[0]).length_squared());
    // NaN-safe: a NaN area counts as degenerate.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(twice_area > 1e-12 * scale) {
        return [0.0; 3];
    }
    std::array::from_fn(|corner| {
        let u = p[(corner + 1) % 3] - p[corner];
        let v = p[(corner + 2) % 3] - p[corner];
        0.5 * (u.dot(v) / twice_area)
    })
}

/// Edges (i < j, sorted) with their clamped cotangent weight.
fn cotangent_edges(mesh: &Mesh) -> Vec<(u32, u32, f64)> {
    let mut half: Vec<(u32, u32, f64)> = Vec::with_capacity(mesh.triangles.len() * 3);
    for t in &mesh.triangles {
        let shares = half_cotangents(t.map(|v| mesh.positions[v as usize]));
        for (corner, share) in shares.into_iter().enumerate() {
            let (a, b) = (t[(corner + 1) % 3], t[(corner + 2) % 3]);
            half.push((a.min(b), a.max(b), share));
        }
    }
    half.sort_by_key(|e| (e.0, e.1));
    let mut edges: Vec<(u32, u32, f64)> = Vec::with_capacity(half.len());
    for (i, j, w) in half {
        match edges.last_mut() {
            Some(last) if last.0 == i && last.1 == j => last.2 += w,
            _ => edges.push((i, j, w)),
        }
    }
    edges.iter_mut().for_each(|e| e.2 = e.2.max(0.0));
    edges
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures;

    /// The reference assembly the direct one replaced: every edge and diagonal as a triplet,
    /// sorted and summed by [`SymmetricCsc::from_triplets`].
    fn from_triplets(n: usize, edges: &[(u32, u32, f64)]) -> SymmetricCsc {
        let mut diagonal = vec![0.0; n];
        let mut triplets = Vec::new();
        for &(i, j, w) in edges {
            triplets.push((j as usize, i as usize, -w));
            diagonal[i as usize] += w;
            diagonal[j as usize] += w;
        }
        triplets.extend(diagonal.iter().enumerate().map(|(v, &d)| (v, v, d)));
        SymmetricCsc::from_triplets(n, &triplets).unwrap()
    }

    #[test]
    fn direct_assembly_matches_triplet_assembly_bit_for_bit() {
        let mut meshes = vec![fixtures::grid(7, 5), fixtures::disc(6)];
        // A vertex no triangle uses gets a zero row.
        let mut isolated = fixtures::grid(3, 2);
        isolated.positions.push(glam::DVec2::new(99.0, 99.0));
        isolated.is_boundary.push(false);
        isolated.piece.push(0);
        meshes.push(isolated);
        for mesh in &meshes {
            let n = mesh.vertex_count();
            let combinatorial: Vec<_> = mesh.edges().iter().map(|&(i, j)| (i, j, 1.0)).collect();
            for edges in [combinatorial, cotangent_edges(mesh)] {
                let direct = from_sorted_edges(n, &edges);
                let reference = from_triplets(n, &edges);
                assert!(direct.sanity_check().is_ok());
                assert_eq!(direct.col_ptr, reference.col_ptr);
                assert_eq!(direct.row_idx, reference.row_idx);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&direct.values), bits(&reference.values));
            }
        }
    }
}
