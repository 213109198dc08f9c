//! `expand_boundary` moves the boundary half a pixel out and keeps every triangle
//! positive.

use crate::synth;
use glam::DVec2;
use lapclone::clone::{expand_boundary, HALF_PIXEL};
use lapclone::mesh::{mesh_mask, BitMask, MeshOptions};

fn square_mask() -> BitMask {
    BitMask::from_fn(12, 12, |x, y| (2..10).contains(&x) && (2..10).contains(&y))
}

#[test]
fn boundary_moves_half_a_pixel_out_and_triangles_stay_positive() {
    let mut mesh = mesh_mask(&square_mask(), &MeshOptions::default())
        .unwrap()
        .mesh;
    let before = mesh.clone();
    let moved = expand_boundary(&mut mesh, HALF_PIXEL);
    assert_eq!(moved, mesh.boundary_vertices().count());
    mesh.sanity_check().unwrap();
    for v in before.boundary_vertices() {
        let (a, b) = (before.positions[v as usize], mesh.positions[v as usize]);
        assert!(((a - b).length() - 0.5).abs() < 1e-12);
        // Outward: away from the square's centre (6, 6).
        assert!((b - DVec2::splat(6.0)).length() > (a - DVec2::splat(6.0)).length());
    }
    for v in 0..mesh.vertex_count() {
        if !mesh.is_boundary[v] {
            assert_eq!(mesh.positions[v], before.positions[v]);
        }
    }
}

/// Found by tests/fuzz_mesh.rs: with a fine density the edges of a 1-px-wide hole are
/// subdivided, every hole vertex moved onto the hole's centre lines, and the hole loop
/// was left with zero area (the mesh failed its sanity check).
#[test]
fn one_pixel_wide_holes_do_not_collapse() {
    let fuzz_mask = ["###.", "#.##", "###.", "##.#"];
    let found = BitMask::from_fn(4, 4, |x, y| fuzz_mask[y].as_bytes()[x] == b'#');
    let slot = BitMask::from_fn(10, 11, |x, y| {
        (1..9).contains(&x) && (1..10).contains(&y) && !((3..7).contains(&x) && y == 4)
    });
    for mask in [found, slot] {
        for density in [0.3, 0.5, 1.0, 3.0] {
            let options = MeshOptions {
                density,
                ..MeshOptions::default()
            };
            let mut mesh = mesh_mask(&mask, &options).unwrap().mesh;
            assert_eq!(mesh.hole_count(), 1);
            expand_boundary(&mut mesh, HALF_PIXEL);
            mesh.sanity_check()
                .unwrap_or_else(|e| panic!("density {density}: {e}"));
        }
    }
}

#[test]
fn thin_and_spiky_masks_keep_every_triangle_positive() {
    for mask in [
        synth::comb(120, 90, 6, 4),
        synth::spiral(160, 150),
        synth::line(64, 40, 30),
    ] {
        let Ok(result) = mesh_mask(&mask, &MeshOptions::default()) else {
            continue;
        };
        let mut mesh = result.mesh;
        expand_boundary(&mut mesh, HALF_PIXEL);
        for t in &mesh.triangles {
            let p = t.map(|v| mesh.positions[v as usize]);
            assert!((p[1] - p[0]).perp_dot(p[2] - p[0]) > 0.0);
        }
    }
}
