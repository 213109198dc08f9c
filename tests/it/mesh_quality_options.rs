//! The mesh options that trade vertices for clone quality: boundary vertices exactly on the
//! pixel-grid clone's Dirichlet pixel centres (`BoundaryPlacement::OutsideCentres`) and a
//! triangle area bound (`max_area`), on fixed synthetic masks and on proptest masks with a
//! fixed seed.

use std::collections::BTreeSet;

use crate::synth;
use lapclone::clone::mesh_from_mask;
use lapclone::mesh::{mesh_mask, BitMask, BoundaryPlacement, MeshError, MeshOptions};
use proptest::prelude::*;

fn centres_options() -> MeshOptions {
    MeshOptions {
        boundary: BoundaryPlacement::OutsideCentres,
        density: 1.0,
        ..MeshOptions::default()
    }
}

/// Outside pixels with an inside 4-neighbour (the image border counts as outside), as the
/// pixel-grid clone pins them.
fn dirichlet_pixels(mask: &BitMask) -> BTreeSet<(i64, i64)> {
    let mut out = BTreeSet::new();
    for y in 0..mask.height as i64 {
        for x in 0..mask.width as i64 {
            if mask.get(x, y) {
                for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                    if !mask.get(x + dx, y + dy) {
                        out.insert((x + dx, y + dy));
                    }
                }
            }
        }
    }
    out
}

/// Boundary vertices at pixel centres, as pixels; panics on a vertex off every centre.
fn boundary_pixels(mesh: &lapclone::mesh::Mesh) -> BTreeSet<(i64, i64)> {
    mesh.boundary_vertices()
        .map(|v| {
            let p = mesh.positions[v as usize];
            assert_eq!(p - p.floor(), glam::DVec2::splat(0.5), "{p} is off-centre");
            (p.x.floor() as i64, p.y.floor() as i64)
        })
        .collect()
}

#[test]
fn outside_centre_boundaries_are_exactly_the_dirichlet_pixels() {
    let masks = [
        synth::disc(48, 48, 19.0),
        synth::spiral(160, 150),
        synth::two_holes(90, 70),
        synth::annulus(80, 80, 12.0, 35.0),
    ];
    for (k, mask) in masks.iter().enumerate() {
        let result = mesh_mask(mask, &centres_options()).unwrap();
        assert_eq!(
            result.stats.boundary,
            BoundaryPlacement::OutsideCentres,
            "mask {k}"
        );
        assert_eq!(result.stats.off_centre_boundary_vertices, 0, "mask {k}");
        result.mesh.sanity_check().unwrap();
        assert_eq!(
            boundary_pixels(&result.mesh),
            dirichlet_pixels(mask),
            "mask {k}"
        );
        // Every mask pixel centre is inside a triangle: the loops enclose the mask.
        assert_eq!(
            lapclone::mesh::uncovered_mask_pixels(&result.mesh, mask),
            0,
            "mask {k}"
        );
    }
}

#[test]
fn the_clone_stage_keeps_outside_centre_boundaries_where_they_are() {
    let mask = synth::disc(40, 40, 15.0);
    let meshed = mesh_mask(&mask, &centres_options()).unwrap().mesh;
    let patch = mesh_from_mask(&mask, None, (40, 40), &centres_options()).unwrap();
    for v in meshed.boundary_vertices() {
        assert_eq!(
            patch.result.mesh.positions[v as usize],
            meshed.positions[v as usize]
        );
    }
}

#[test]
fn one_pixel_notches_and_holes_mesh_with_a_few_off_centre_vertices() {
    let notched = BitMask::from_fn(30, 30, |x, y| {
        (2..28).contains(&x) && (2..28).contains(&y) && !(x == 14 && y < 12) && (x, y) != (7, 20)
    });
    let result = mesh_mask(&notched, &centres_options()).unwrap();
    result.mesh.sanity_check().unwrap();
    assert_eq!(result.stats.boundary, BoundaryPlacement::OutsideCentres);
    assert_eq!(result.mesh.hole_count(), 1);
    // The notch column (x = 14, y 2..11) is reached from both sides except at its dead end,
    // and the 1-px hole from all four: 2 × 9 + 4 quarter-pixel vertices.
    assert_eq!(result.stats.off_centre_boundary_vertices, 22);
    assert_eq!(
        lapclone::mesh::uncovered_mask_pixels(&result.mesh, &notched),
        0
    );
}

fn area(mesh: &lapclone::mesh::Mesh, t: &[u32; 3]) -> f64 {
    let p = t.map(|v| mesh.positions[v as usize]);
    0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0])
}

/// The bound holds for every triangle of a crack-boundary mesh; the outside-centres
/// boundary (the default) never splits its edges, so refinement skips a large triangle whose
/// circumcentre would encroach one: there it holds for every triangle off the boundary.
#[test]
fn max_area_bounds_every_triangle_and_adds_vertices() {
    let mask = synth::disc(120, 120, 50.0);
    for boundary in [BoundaryPlacement::Cracks, BoundaryPlacement::OutsideCentres] {
        let defaults = MeshOptions {
            boundary,
            ..MeshOptions::default()
        };
        let free = mesh_mask(&mask, &defaults).unwrap();
        let largest_free = free
            .mesh
            .triangles
            .iter()
            .map(|t| area(&free.mesh, t))
            .fold(0.0, f64::max);
        for bound in [40.0, 10.0, 2.5] {
            assert!(largest_free > bound, "the bound {bound} must bite");
            let options = MeshOptions {
                max_area: Some(bound),
                ..defaults.clone()
            };
            let bounded = mesh_mask(&mask, &options).unwrap();
            assert!(bounded.stats.refinement_complete);
            bounded.mesh.sanity_check().unwrap();
            let on_boundary = |t: &[u32; 3]| {
                t.iter()
                    .filter(|&&v| bounded.mesh.is_boundary[v as usize])
                    .count()
            };
            for t in &bounded.mesh.triangles {
                let a = area(&bounded.mesh, t);
                assert!(a > 0.0, "{boundary:?}: area {a}");
                if boundary == BoundaryPlacement::Cracks || on_boundary(t) == 0 {
                    assert!(a <= bound, "{boundary:?}: area {a} above {bound}");
                }
            }
            assert!(bounded.mesh.vertex_count() > free.mesh.vertex_count());
        }
    }
}

#[test]
fn bad_max_areas_are_refused() {
    for bad in [0.0, 0.1, -4.0, f64::NAN, f64::INFINITY] {
        let options = MeshOptions {
            max_area: Some(bad),
            ..MeshOptions::default()
        };
        let error = mesh_mask(&synth::disc(20, 20, 8.0), &options).unwrap_err();
        assert!(
            matches!(&error, MeshError::InvalidOption(text) if text.contains("max_area")),
            "{error}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 24,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x0ce4_77e5),
        ..ProptestConfig::default()
    })]
    /// Random blob masks: the centre path meshes (or falls back to cracks with a warning),
    /// stays sane and covers every mask pixel; vertices on centres are Dirichlet pixels.
    #[test]
    fn random_masks_mesh_on_or_near_the_dirichlet_pixels(seed in 0u64..10_000) {
        let mask = synth::blobs(48, 40, seed);
        let Ok(result) = mesh_mask(&mask, &centres_options()) else {
            return Ok(());
        };
        result.mesh.sanity_check().unwrap();
        if result.stats.boundary == BoundaryPlacement::OutsideCentres {
            let dirichlet = dirichlet_pixels(&mask);
            let mut off_centre = 0;
            for v in result.mesh.boundary_vertices() {
                let p = result.mesh.positions[v as usize];
                if p - p.floor() == glam::DVec2::splat(0.5) {
                    prop_assert!(dirichlet.contains(&(p.x.floor() as i64, p.y.floor() as i64)));
                } else {
                    off_centre += 1;
                }
            }
            // Only the quarter-pixel points: refinement never splits a boundary edge.
            prop_assert_eq!(off_centre, result.stats.off_centre_boundary_vertices);
            prop_assert_eq!(lapclone::mesh::uncovered_mask_pixels(&result.mesh, &mask), 0);
        } else {
            prop_assert!(!result.warnings.is_empty());
        }
    }
}

/// Σ_j (x_j − x_i) over the neighbours of every interior vertex: the combinatorial
/// Laplacian's defect on linear functions.
/// The smallest angle of any triangle, degrees.
fn smallest_angle(mesh: &lapclone::mesh::Mesh) -> f64 {
    let mut smallest = f64::INFINITY;
    for t in &mesh.triangles {
        let q = t.map(|c| mesh.positions[c as usize]);
        for k in 0..3 {
            let (a, b) = (q[(k + 1) % 3] - q[k], q[(k + 2) % 3] - q[k]);
            smallest = smallest.min(a.angle_to(b).abs().to_degrees());
        }
    }
    smallest
}

/// Whether each vertex is on the boundary or shares a triangle with a boundary vertex
/// (relaxation leaves these where they are).
fn boundary_or_ring(mesh: &lapclone::mesh::Mesh) -> Vec<bool> {
    let mut stays = mesh.is_boundary.clone();
    for t in &mesh.triangles {
        if t.iter().any(|&c| mesh.is_boundary[c as usize]) {
            for &c in t {
                stays[c as usize] = true;
            }
        }
    }
    stays
}

/// Σ |Σ_j (x_j − x_i)| over the vertices relaxation may move.
fn first_moment_defect(mesh: &lapclone::mesh::Mesh) -> f64 {
    let n = mesh.vertex_count();
    let mut sum = vec![glam::DVec2::ZERO; n];
    for (a, b) in mesh.edges() {
        let d = mesh.positions[b as usize] - mesh.positions[a as usize];
        sum[a as usize] += d;
        sum[b as usize] -= d;
    }
    let stays = boundary_or_ring(mesh);
    (0..n)
        .filter(|&v| !stays[v])
        .map(|v| sum[v].length())
        .sum::<f64>()
}

#[test]
fn relaxation_keeps_the_boundary_and_its_ring_and_the_triangles_and_shrinks_the_linear_defect() {
    for mask in [
        synth::annulus(160, 160, 20.0, 70.0),
        synth::two_holes(180, 140),
        synth::disc(120, 120, 50.0),
    ] {
        let before = mesh_mask(&mask, &MeshOptions::default()).unwrap().mesh;
        let stays = boundary_or_ring(&before);
        assert!(
            stays.iter().any(|s| !s),
            "the mask has vertices off the ring"
        );
        let mut after = before.clone();
        lapclone::mesh::relax_interior(&mut after, 5, 25.0);
        after.sanity_check().unwrap();
        let (was, is) = (smallest_angle(&before), smallest_angle(&after));
        assert!(is >= was.min(25.0) - 1e-9, "smallest angle {was}° → {is}°");
        assert_eq!(after.triangles, before.triangles);
        for v in (0..before.vertex_count()).filter(|&v| stays[v]) {
            assert_eq!(after.positions[v], before.positions[v]);
        }
        for t in &after.triangles {
            assert!(area(&after, t) > 0.0);
        }
        let (was, is) = (first_moment_defect(&before), first_moment_defect(&after));
        assert!(is < 0.5 * was, "defect {was} → {is}");
        // Deterministic: the same sweeps give the same bits.
        let mut again = before.clone();
        lapclone::mesh::relax_interior(&mut again, 5, 25.0);
        assert_eq!(again.positions, after.positions);
    }
}

#[test]
fn the_seam_quality_preset_is_valid_and_relaxes_in_the_clone_stage() {
    let options = MeshOptions::seam_quality();
    options.validate().unwrap();
    let mask = synth::disc(40, 40, 15.0);
    let raw = mesh_mask(&mask, &options).unwrap().mesh;
    let patch = mesh_from_mask(&mask, None, (40, 40), &options).unwrap();
    let mut relaxed = raw.clone();
    lapclone::mesh::relax_interior(&mut relaxed, options.relax_sweeps, options.min_angle_deg);
    assert_eq!(patch.result.mesh.positions, relaxed.positions);
    assert_ne!(relaxed.positions, raw.positions);
    let too_many = MeshOptions {
        relax_sweeps: lapclone::mesh::MAX_RELAX_SWEEPS + 1,
        ..MeshOptions::default()
    };
    assert!(mesh_mask(&mask, &too_many).is_err());
}
