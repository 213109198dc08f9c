//! Interior relaxation for the combinatorial Laplacian: takes a mesh and moves each interior
//! vertex towards the mean of its neighbours (boundary vertices stay), giving the same
//! triangles at new positions.
//!
//! Why: the combinatorial Laplacian reproduces a linear function f at vertex i exactly when
//! Σ_j (x_j − x_i) = 0 over its neighbours, because then Σ_j (f_j − f_i) = ∇f · Σ_j (x_j −
//! x_i) = 0. A graded refinement mesh breaks this everywhere (docs/quality.md: no linear
//! precision), so the combinatorial membrane drifts from the harmonic one. Gauss–Seidel
//! sweeps towards that fixed point (Tutte's barycentric embedding) shrink the defect without
//! adding a vertex, so re-clone cost does not change.
//!
//! A move that would leave one of the vertex's triangles with less than a tenth of its
//! area before the move is skipped, so triangles never fold. Sweeps run in vertex order:
//! deterministic.

use glam::DVec2;

use super::Mesh;

/// Smallest fraction of its area a triangle may keep when a corner moves.
const MIN_AREA_RATIO: f64 = 0.1;

/// Runs `sweeps` Gauss–Seidel sweeps; gives how many vertex moves were skipped to keep
/// triangles from folding.
pub fn relax_interior(mesh: &mut Mesh, sweeps: usize) -> usize {
    if sweeps == 0 {
        return 0;
    }
    let n = mesh.vertex_count();
    let (neighbour_start, neighbours) = neighbour_lists(mesh);
    let (triangle_start, incident) = incident_triangles(mesh);
    let mut skipped = 0;
    for _ in 0..sweeps {
        for v in (0..n).filter(|&v| !mesh.is_boundary[v]) {
            let around = &neighbours[neighbour_start[v]..neighbour_start[v + 1]];
            if around.is_empty() {
                continue;
            }
            let sum: DVec2 = around.iter().map(|&u| mesh.positions[u as usize]).sum();
            let target = sum / around.len() as f64;
            let triangles = &incident[triangle_start[v]..triangle_start[v + 1]];
            if keeps_triangles(mesh, v, target, triangles) {
                mesh.positions[v] = target;
            } else {
                skipped += 1;
            }
        }
    }
    skipped
}

/// Whether moving `v` to `target` keeps each of its triangles above the area ratio.
fn keeps_triangles(mesh: &Mesh, v: usize, target: DVec2, triangles: &[u32]) -> bool {
    triangles.iter().all(|&t| {
        let corners = mesh.triangles[t as usize];
        let p = corners.map(|c| mesh.positions[c as usize]);
        let moved = corners.map(|c| {
            if c as usize == v {
                target
            } else {
                mesh.positions[c as usize]
            }
        });
        let area = |q: [DVec2; 3]| (q[1] - q[0]).perp_dot(q[2] - q[0]);
        area(moved) > MIN_AREA_RATIO * area(p)
    })
}

/// Sorted, deduplicated neighbours of every vertex, in compressed rows.
fn neighbour_lists(mesh: &Mesh) -> (Vec<usize>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| {
            [(0, 1), (1, 2), (2, 0)]
                .into_iter()
                .flat_map(move |(a, b)| [(t[a], t[b]), (t[b], t[a])])
        })
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    rows(mesh.vertex_count(), pairs)
}

/// Triangles incident to every vertex, in compressed rows.
fn incident_triangles(mesh: &Mesh) -> (Vec<usize>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .enumerate()
        .flat_map(|(t, corners)| corners.map(|c| (c, t as u32)))
        .collect();
    pairs.sort_unstable();
    rows(mesh.vertex_count(), pairs)
}

/// Compressed rows from sorted (row, value) pairs.
fn rows(count: usize, pairs: Vec<(u32, u32)>) -> (Vec<usize>, Vec<u32>) {
    let mut start = vec![0usize; count + 1];
    for &(row, _) in &pairs {
        start[row as usize + 1] += 1;
    }
    for i in 0..count {
        start[i + 1] += start[i];
    }
    (start, pairs.into_iter().map(|(_, value)| value).collect())
}
