//! Puts a mask mesh's boundary where the exact clone fixes its values: takes a mesh whose
//! boundary runs along pixel cracks and moves every boundary vertex half a pixel outward,
//! onto the outside pixel centres.
//!
//! Why: the exact pixel-grid Poisson clone (Pérez et al.) leaves every mask pixel free and
//! fixes the membrane at the outside 4-neighbours' centres, half a pixel beyond the crack.
//! A mesh whose boundary sits on the crack fixes it half a pixel too far in, where bilinear
//! sampling averages an inside and an outside pixel. Moving the boundary out makes the two
//! agree at the seam (docs/quality.md) while keeping the values at the vertices themselves, so
//! linear data is still reproduced exactly by the cotangent Laplacian.
//!
//! A vertex whose move would invert or flatten one of its triangles stays where it is.

use glam::DVec2;

use crate::mesh::Mesh;

/// Distance from a crack to the outside pixel centre, in pixels.
pub const HALF_PIXEL: f64 = 0.5;

/// Moves boundary vertices `by` pixels outward (see the module doc); gives how many moved.
pub fn expand_boundary(mesh: &mut Mesh, by: f64) -> usize {
    let targets = outward_targets(mesh, by);
    let mut moved: Vec<bool> = targets.iter().map(Option::is_some).collect();
    let rest = mesh.positions.clone();
    for (v, target) in targets.iter().enumerate() {
        if let Some(p) = target {
            mesh.positions[v] = *p;
        }
    }
    // Undo moves that spoil a triangle or collapse a loop (a hole 1 px wide shrinks to a
    // segment or a point); undoing can only help the neighbours, so this ends.
    loop {
        let mut spoilt: Vec<u32> = Vec::new();
        for t in &mesh.triangles {
            if !is_healthy(
                t.map(|v| mesh.positions[v as usize]),
                t.map(|v| rest[v as usize]),
            ) {
                spoilt.extend_from_slice(t);
            }
        }
        for lp in &mesh.loops {
            let area = |p: &[DVec2]| loop_area(lp.vertices.iter().map(|&v| p[v as usize]));
            let rest_area = area(&rest);
            // Same orientation, and not squashed below a tenth of its rest area.
            if area(&mesh.positions) * rest_area.signum() <= 0.1 * rest_area.abs() {
                spoilt.extend_from_slice(&lp.vertices);
            }
        }
        let mut undone = false;
        for v in spoilt {
            if moved[v as usize] {
                moved[v as usize] = false;
                mesh.positions[v as usize] = rest[v as usize];
                undone = true;
            }
        }
        if !undone {
            break;
        }
    }
    moved.iter().filter(|&&m| m).count()
}

/// Twice the signed area of a closed loop (shoelace).
fn loop_area(points: impl Iterator<Item = DVec2> + Clone) -> f64 {
    let first = points.clone().next().unwrap_or_default();
    let mut previous = first;
    let mut twice = 0.0;
    for p in points.skip(1).chain(std::iter::once(first)) {
        twice += previous.perp_dot(p);
        previous = p;
    }
    twice
}

/// Where each boundary vertex on exactly one loop would go.
fn outward_targets(mesh: &Mesh, by: f64) -> Vec<Option<DVec2>> {
    let n = mesh.vertex_count();
    let mut loops_through = vec![0u8; n];
    let mut target: Vec<Option<DVec2>> = vec![None; n];
    for lp in &mesh.loops {
        let k = lp.vertices.len();
        for (i, &v) in lp.vertices.iter().enumerate() {
            loops_through[v as usize] = loops_through[v as usize].saturating_add(1);
            let prev = mesh.positions[lp.vertices[(i + k - 1) % k] as usize];
            let next = mesh.positions[lp.vertices[(i + 1) % k] as usize];
            let chord = next - prev;
            // Inside lies left of the loop direction, so outward is the chord turned right.
            let outward = DVec2::new(chord.y, -chord.x).normalize_or_zero();
            target[v as usize] = Some(mesh.positions[v as usize] + outward * by);
        }
    }
    for (v, t) in target.iter_mut().enumerate() {
        // A vertex shared by two loops (pieces touching at a corner) has no single outside.
        if loops_through[v] != 1 {
            *t = None;
        }
    }
    target
}

/// Positive area, and not squashed below a tenth of its rest area.
fn is_healthy(moved: [DVec2; 3], rest: [DVec2; 3]) -> bool {
    let area = |p: [DVec2; 3]| (p[1] - p[0]).perp_dot(p[2] - p[0]);
    area(moved) > 0.1 * area(rest)
}
