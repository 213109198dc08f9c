//! Where the membrane reads target − source for a boundary vertex: takes the mesh's boundary
//! loops and gives, per boundary vertex, its loop neighbours and the point half a pixel
//! outside the patch, at rest and once placed.
//!
//! Why half a pixel out: a boundary vertex sits on the crack between an inside and an outside
//! pixel, where bilinear sampling averages the two. The exact (pixel-grid) Poisson clone fixes
//! the membrane at the outside neighbours' centres, half a pixel further out, so reading there
//! makes the mesh membrane agree with it at the seam (measured: +6 dB PSNR with cotangent
//! weights on photographs, see docs/quality.md). The offset follows the placed boundary, so it
//! stays half a source pixel, scaled, rotated and deformed with the patch.

use glam::DVec2;

use crate::mesh::Mesh;

/// Distance from the crack to the outside pixel centre, in source pixels.
pub const PROBE_OFFSET: f64 = 0.5;

/// Loop neighbours of one boundary vertex (`None` where the vertex is on two loops, e.g. a
/// corner where two pieces touch: there is no single outward direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Neighbours {
    pub prev: u32,
    pub next: u32,
}

/// Neighbours of each vertex in `boundary` (same order).
pub(crate) fn loop_neighbours(mesh: &Mesh, boundary: &[u32]) -> Vec<Option<Neighbours>> {
    let n = mesh.vertex_count();
    let mut found: Vec<Option<Neighbours>> = vec![None; n];
    let mut seen = vec![0u8; n];
    for lp in &mesh.loops {
        let k = lp.vertices.len();
        for (i, &v) in lp.vertices.iter().enumerate() {
            seen[v as usize] = seen[v as usize].saturating_add(1);
            found[v as usize] = Some(Neighbours {
                prev: lp.vertices[(i + k - 1) % k],
                next: lp.vertices[(i + 1) % k],
            });
        }
    }
    boundary
        .iter()
        .map(|&v| (seen[v as usize] == 1).then_some(found[v as usize]).flatten())
        .collect()
}

/// The point `PROBE_OFFSET` source pixels outside the patch at vertex `v`, given where its
/// loop neighbours are (`positions`) and the rest geometry (for the local scale).
pub(crate) fn outside_probe(
    v: u32,
    neighbours: Option<Neighbours>,
    positions: &[DVec2],
    rest: &[DVec2],
) -> DVec2 {
    let p = positions[v as usize];
    let Some(nb) = neighbours else {
        return p;
    };
    let (prev, next) = (positions[nb.prev as usize], positions[nb.next as usize]);
    let chord = next - prev;
    let rest_chord = (rest[nb.next as usize] - rest[nb.prev as usize]).length();
    let length = chord.length();
    if !(length > 1e-12 && rest_chord > 1e-12) {
        return p;
    }
    // The inside lies left of the loop direction (positive-area outer loops, negative-area
    // holes), so the outward normal is the chord turned right: (dy, −dx).
    let outward = DVec2::new(chord.y, -chord.x) / length;
    p + outward * (PROBE_OFFSET * length / rest_chord)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{BoundaryLoop, LoopKind};

    fn square(scale: f64) -> (Mesh, Vec<DVec2>) {
        let rest = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(4.0, 4.0),
            DVec2::new(0.0, 4.0),
        ];
        let mesh = Mesh {
            positions: rest.clone(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            loops: vec![BoundaryLoop {
                kind: LoopKind::Outer,
                piece: 0,
                vertices: vec![0, 1, 2, 3],
            }],
            is_boundary: vec![true; 4],
            piece: vec![0; 4],
            piece_count: 1,
        };
        let placed = rest.iter().map(|&p| p * scale).collect();
        (mesh, placed)
    }

    #[test]
    fn probe_points_away_from_the_inside_by_half_a_scaled_pixel() {
        for scale in [1.0, 2.0] {
            let (mesh, placed) = square(scale);
            let boundary: Vec<u32> = mesh.boundary_vertices().collect();
            let nb = loop_neighbours(&mesh, &boundary);
            let probe = outside_probe(1, nb[1], &placed, &mesh.positions);
            // Corner (4, 0): outward is the diagonal (1, −1)/√2.
            let expected = placed[1] + DVec2::new(1.0, -1.0).normalize() * 0.5 * scale;
            assert!((probe - expected).length() < 1e-12, "{probe} vs {expected}");
            // The probe must be outside the square.
            assert!(probe.x > placed[1].x && probe.y < placed[1].y);
        }
    }

    #[test]
    fn vertex_on_two_loops_is_probed_in_place() {
        let (mut mesh, placed) = square(1.0);
        mesh.loops.push(BoundaryLoop {
            kind: LoopKind::Outer,
            piece: 1,
            vertices: vec![1, 2, 3],
        });
        let boundary: Vec<u32> = mesh.boundary_vertices().collect();
        let nb = loop_neighbours(&mesh, &boundary);
        assert!(nb[1].is_none());
        assert_eq!(outside_probe(1, nb[1], &placed, &mesh.positions), placed[1]);
    }
}
