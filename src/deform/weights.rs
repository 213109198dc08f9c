//! Per-triangle edge-weight shares: takes a mesh and a [`LaplacianKind`] and gives, for every
//! triangle, the share `w^t` of each of its three edges' Laplacian weight, plus the Laplacian
//! assembled from exactly those shares (so the divergence right-hand side built from them is
//! consistent with the factored matrix; see the rules in [`deform`](super)).
//!
//! Edge k of triangle `[a, b, c]` runs from corner k to corner k+1 (ab, bc, ca); for cotangent
//! weights its share is ½ cot of the angle at the third corner, from the solver's own
//! `half_cotangents` (so [`solve::laplacian`](fn@crate::solve::laplacian) has the same
//! weights), and an edge whose total
//! is negative gets share 0 in every triangle (the solver's clamp to 0).

use crate::mesh::Mesh;
use crate::solve::laplacian::half_cotangents;
use crate::solve::{LaplacianKind, SymmetricCsc};

/// `shares[t][k]`: triangle t's share of the weight of its edge k (corner k → corner k+1).
pub fn edge_shares(mesh: &Mesh, kind: LaplacianKind) -> Vec<[f64; 3]> {
    let mut shares: Vec<[f64; 3]> = match kind {
        LaplacianKind::Combinatorial => vec![[1.0; 3]; mesh.triangles.len()],
        LaplacianKind::Cotangent => mesh
            .triangles
            .iter()
            .map(|t| {
                // Edge k is opposite corner k + 2.
                let h = half_cotangents(t.map(|v| mesh.positions[v as usize]));
                [h[2], h[0], h[1]]
            })
            .collect(),
    };
    // Sum per undirected edge, then rescale (combinatorial) or clamp (cotangent) each share.
    let mut edge_refs: Vec<(u32, u32, usize, usize)> = Vec::with_capacity(3 * shares.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edge_refs.push((a.min(b), a.max(b), t, k));
        }
    }
    edge_refs.sort_unstable();
    for group in edge_refs.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let total: f64 = group.iter().map(|&(_, _, t, k)| shares[t][k]).sum();
        let count = group.len() as f64;
        for &(_, _, t, k) in group {
            shares[t][k] = match kind {
                LaplacianKind::Combinatorial => 1.0 / count,
                LaplacianKind::Cotangent if total < 0.0 => 0.0,
                LaplacianKind::Cotangent => shares[t][k],
            };
        }
    }
    shares
}

/// The Laplacian `Σ_t L_t` (lower triangle) built from the shares.
pub fn assemble_laplacian(n: usize, triangles: &[[u32; 3]], shares: &[[f64; 3]]) -> SymmetricCsc {
    let mut triplets = Vec::with_capacity(6 * triangles.len() + n);
    for (tri, share) in triangles.iter().zip(shares) {
        for k in 0..3 {
            let (a, b, w) = (tri[k] as usize, tri[(k + 1) % 3] as usize, share[k]);
            triplets.push((a, b, -w));
            triplets.push((a, a, w));
            triplets.push((b, b, w));
        }
    }
    // invariant: the rig validated indices < n, and shares are finite (degenerate triangles
    // get 0, others a finite cotangent).
    let matrix = SymmetricCsc::from_triplets(n, &triplets);
    // invariant: indices come from the mesh, shares are finite
    matrix.expect("finite shares")
}
