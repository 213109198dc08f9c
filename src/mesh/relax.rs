//! Interior relaxation for the combinatorial Laplacian: takes a mesh and moves each interior
//! vertex that has no boundary neighbour towards the mean of its neighbours, giving the same
//! triangles at new positions.
//!
//! Why: the combinatorial Laplacian reproduces a linear function f at vertex i exactly when
//! Σ_j (x_j − x_i) = 0 over its neighbours, because then Σ_j (f_j − f_i) = ∇f · Σ_j (x_j −
//! x_i) = 0. A graded refinement mesh breaks this everywhere (docs/quality.md: no linear
//! precision), so the combinatorial membrane drifts from the harmonic one. Gauss–Seidel
//! sweeps towards that fixed point (Tutte's barycentric embedding) shrink the defect without
//! adding a vertex, so re-clone cost does not change.
//!
//! The boundary and its first ring of interior vertices stay: the triangles along the boundary
//! decide how the membrane meets the target, and pulling the ring towards the dense boundary
//! made the seam step 3–7 % larger (docs/quality.md), while moving the rest gains most of the
//! accuracy.
//!
//! A move must keep each of the vertex's triangles above a tenth of its area before the move
//! (so triangles never fold) and must not make the smallest angle around the vertex smaller
//! than the angle bound asked for, or than it already was if that is smaller (so relaxing keeps
//! the refinement's angle guarantee). A move that fails is halved, twice at most, then skipped.
//! Sweeps run in vertex order: deterministic.

use glam::DVec2;

use super::Mesh;

/// Smallest fraction of its area a triangle may keep when a corner moves.
const MIN_AREA_RATIO: f64 = 0.1;

/// Halvings tried when a full move towards the neighbours' mean fails a guard.
const MOVE_HALVINGS: usize = 2;

/// Runs `sweeps` Gauss–Seidel sweeps that keep every angle at or above `min_angle_deg` (or
/// where it already was); gives how many vertex moves were skipped.
pub fn relax_interior(mesh: &mut Mesh, sweeps: usize, min_angle_deg: f64) -> usize {
    if sweeps == 0 {
        return 0;
    }
    let fans = InteriorFans::of(mesh);
    // A triangle's smallest angle is at most 60°, where sin² grows with the angle.
    let bound = min_angle_deg.clamp(0.0, 60.0).to_radians().sin().powi(2);
    let mut doubled_areas = Vec::with_capacity(16);
    let mut skipped = 0;
    for _ in 0..sweeps {
        for (k, &v) in fans.vertices.iter().enumerate() {
            let fan = &fans.corners[fans.start[k]..fans.start[k + 1]];
            let moved = !fan.is_empty()
                && move_towards_mean(&mut mesh.positions, v, fan, bound, &mut doubled_areas);
            skipped += usize::from(!moved);
        }
    }
    skipped
}

/// Moves `v` towards the mean of its neighbours, or part of the way, if some move passes
/// both guards (areas, and `bound` or the smallest sin² around `v` already); gives whether
/// it moved. `doubled_areas` is scratch.
fn move_towards_mean(
    positions: &mut [DVec2],
    v: u32,
    fan: &[[u32; 2]],
    bound: f64,
    doubled_areas: &mut Vec<f64>,
) -> bool {
    let here = positions[v as usize];
    doubled_areas.clear();
    let mut smallest = f64::INFINITY;
    let mut sum = DVec2::ZERO;
    for &[a, b] in fan {
        let (pa, pb) = (positions[a as usize], positions[b as usize]);
        let (area, sine) = doubled_area_and_smallest_sine(here, pa, pb);
        doubled_areas.push(area);
        smallest = smallest.min(sine);
        sum += pa + pb;
    }
    // Each neighbour of a closed fan is a corner of exactly two of its triangles.
    let mut target = sum / (2 * fan.len()) as f64;
    let allowed = smallest.min(bound);
    for _ in 0..=MOVE_HALVINGS {
        let keeps = fan
            .iter()
            .zip(doubled_areas.iter())
            .all(|(&[a, b], &before)| {
                let (pa, pb) = (positions[a as usize], positions[b as usize]);
                let (area, sine) = doubled_area_and_smallest_sine(target, pa, pb);
                area > MIN_AREA_RATIO * before && sine >= allowed
            });
        if keeps {
            positions[v as usize] = target;
            return true;
        }
        target = (target + here) * 0.5;
    }
    false
}

/// Twice the area of the triangle (v, a, b) and the squared sine of its smallest angle.
fn doubled_area_and_smallest_sine(v: DVec2, a: DVec2, b: DVec2) -> (f64, f64) {
    let area = (a - v).perp_dot(b - v);
    let lengths = [
        (a - v).length_squared(),
        (b - v).length_squared(),
        (b - a).length_squared(),
    ];
    // The smallest angle faces the shortest side; 2·area = the other two sides · its sine.
    let shortest = lengths[0].min(lengths[1]).min(lengths[2]);
    let product = lengths[0] * lengths[1] * lengths[2] / shortest;
    (area, area * area / product)
}

/// The triangles around every vertex that relaxation moves (interior, no boundary neighbour),
/// as the other two corners in the triangle's order (so (v, a, b) turns the mesh's way), in
/// compressed rows.
struct InteriorFans {
    vertices: Vec<u32>,
    start: Vec<usize>,
    corners: Vec<[u32; 2]>,
}

impl InteriorFans {
    /// Counting sort of the triangles' corners: linear time.
    fn of(mesh: &Mesh) -> Self {
        let n = mesh.vertex_count();
        // A vertex sharing a triangle with a boundary vertex is on the boundary or its ring.
        let mut stays = mesh.is_boundary.clone();
        for t in &mesh.triangles {
            if t.iter().any(|&c| mesh.is_boundary[c as usize]) {
                for &c in t {
                    stays[c as usize] = true;
                }
            }
        }
        let vertices: Vec<u32> = (0..n as u32).filter(|&v| !stays[v as usize]).collect();
        let mut row_of = vec![u32::MAX; n];
        for (k, &v) in vertices.iter().enumerate() {
            row_of[v as usize] = k as u32;
        }
        let mut start = vec![0usize; vertices.len() + 1];
        for t in &mesh.triangles {
            for &c in t {
                let row = row_of[c as usize];
                if row != u32::MAX {
                    start[row as usize + 1] += 1;
                }
            }
        }
        for k in 0..vertices.len() {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut corners = vec![[0u32; 2]; start[vertices.len()]];
        for t in &mesh.triangles {
            for i in 0..3 {
                let row = row_of[t[i] as usize];
                if row != u32::MAX {
                    let slot = &mut fill[row as usize];
                    corners[*slot] = [t[(i + 1) % 3], t[(i + 2) % 3]];
                    *slot += 1;
                }
            }
        }
        Self {
            vertices,
            start,
            corners,
        }
    }
}
