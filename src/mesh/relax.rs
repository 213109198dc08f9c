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
    let (triangle_start, incident) = incident_triangles(mesh);
    let (neighbour_start, neighbours) = neighbour_lists(mesh, &triangle_start, &incident);
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

/// Sorted, deduplicated neighbours of every vertex, in compressed rows, read off the
/// incident triangles (linear time; only the short per-vertex lists are sorted).
fn neighbour_lists(
    mesh: &Mesh,
    triangle_start: &[usize],
    incident: &[u32],
) -> (Vec<usize>, Vec<u32>) {
    let n = mesh.vertex_count();
    let mut start = Vec::with_capacity(n + 1);
    let mut neighbours = Vec::with_capacity(2 * incident.len());
    start.push(0);
    for v in 0..n {
        let row = neighbours.len();
        for &t in &incident[triangle_start[v]..triangle_start[v + 1]] {
            let corners = mesh.triangles[t as usize];
            neighbours.extend(corners.iter().copied().filter(|&c| c as usize != v));
        }
        neighbours[row..].sort_unstable();
        let mut kept = row;
        for k in row..neighbours.len() {
            if k == row || neighbours[k] != neighbours[kept - 1] {
                neighbours[kept] = neighbours[k];
                kept += 1;
            }
        }
        neighbours.truncate(kept);
        start.push(neighbours.len());
    }
    (start, neighbours)
}

/// Triangles incident to every vertex, in compressed rows (counting sort: linear time).
fn incident_triangles(mesh: &Mesh) -> (Vec<usize>, Vec<u32>) {
    let n = mesh.vertex_count();
    let mut start = vec![0usize; n + 1];
    for t in &mesh.triangles {
        for &c in t {
            start[c as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut incident = vec![0u32; start[n]];
    for (index, t) in mesh.triangles.iter().enumerate() {
        for &c in t {
            incident[fill[c as usize]] = index as u32;
            fill[c as usize] += 1;
        }
    }
    (start, incident)
}
