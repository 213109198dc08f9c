//! Deformation over sequences of frames: incremental constraint switching against fresh rigs,
//! no inverted triangles for moderate drags (proptest, fixed seed), and the shares-built
//! Laplacian against the solver's.

use crate::mesh_fixtures as fixtures;
use glam::DVec2;
use lapclone::deform::{DeformRig, Deformed, Handle, Pin};
use lapclone::mesh::Mesh;
use lapclone::solve::{laplacian, LaplacianKind};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn disc_px(rings: usize, spacing: f64) -> Mesh {
    let mut mesh = fixtures::disc(rings);
    for p in &mut mesh.positions {
        *p = *p * spacing + DVec2::new(100.0, 80.0);
    }
    mesh
}

fn h(x0: f64, y0: f64, x1: f64, y1: f64, r: f64) -> Handle {
    Handle::drag(DVec2::new(x0, y0), DVec2::new(x1, y1), r)
}

/// Frames of an editing session: a drag in progress, a second handle, pins added and
/// removed, a radius change, a handle removed, a pivot and a rotation override, no handle.
fn session() -> Vec<(Vec<Handle>, Vec<Pin>)> {
    let pin = |x, y| Pin(DVec2::new(x, y));
    vec![
        (vec![h(130.0, 80.0, 130.0, 80.0, 15.0)], vec![]),
        (vec![h(130.0, 80.0, 134.0, 83.0, 15.0)], vec![]),
        (vec![h(130.0, 80.0, 138.0, 86.0, 15.0)], vec![]),
        (
            vec![
                h(130.0, 80.0, 138.0, 86.0, 15.0),
                h(75.0, 70.0, 70.0, 64.0, 12.0),
            ],
            vec![],
        ),
        (
            vec![
                h(130.0, 80.0, 138.0, 86.0, 15.0),
                h(75.0, 70.0, 70.0, 64.0, 12.0),
            ],
            vec![pin(125.0, 88.0)],
        ),
        (
            vec![
                h(130.0, 80.0, 138.0, 86.0, 22.0),
                h(75.0, 70.0, 72.0, 60.0, 12.0),
            ],
            vec![pin(125.0, 88.0), pin(90.0, 70.0)],
        ),
        (vec![h(75.0, 70.0, 72.0, 60.0, 12.0)], vec![pin(90.0, 70.0)]),
        (
            vec![Handle {
                pivot: Some(DVec2::new(80.0, 80.0)),
                ..h(100.0, 100.0, 104.0, 96.0, 18.0)
            }],
            vec![],
        ),
        (
            vec![Handle {
                rotation_deg: Some(25.0),
                ..h(100.0, 100.0, 102.0, 101.0, 18.0)
            }],
            vec![pin(100.0, 80.0)],
        ),
        (vec![], vec![pin(100.0, 80.0)]),
        (vec![h(112.0, 64.0, 115.0, 60.0, 9.0)], vec![]),
    ]
}

fn max_relative(a: &Deformed, b: &Deformed) -> f64 {
    let scale = b.positions.iter().map(|p| p.length()).fold(0.0, f64::max);
    a.positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
        / scale
}

#[test]
fn incremental_switching_matches_fresh_rigs() {
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let mesh = disc_px(14, 4.0);
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let (mut out, mut fresh_out) = (Deformed::default(), Deformed::default());
        let mut total_switches = 0;
        for (frame, (handles, pins)) in session().iter().enumerate() {
            let stats = rig.deform(handles, pins, &mut out).unwrap();
            total_switches += stats.switches();
            let mut fresh = DeformRig::new(&mesh, kind).unwrap();
            fresh.deform(handles, pins, &mut fresh_out).unwrap();
            let diff = max_relative(&out, &fresh_out);
            assert!(
                diff <= 1e-9,
                "{kind:?} frame {frame}: relative difference {diff}"
            );
            assert_eq!(out.depth, fresh_out.depth, "{kind:?} frame {frame}: depth");
            if stats.solved {
                assert_eq!(
                    rig.constrained(),
                    fresh.constrained(),
                    "{kind:?} frame {frame}"
                );
            }
            if frame == 1 || frame == 2 {
                assert_eq!(
                    stats.switches(),
                    0,
                    "moving p1 only changes the right-hand side"
                );
            }
        }
        assert!(total_switches > 0);
    }
}

#[test]
fn deforming_the_same_frame_twice_is_bitwise_identical() {
    let mesh = disc_px(10, 4.0);
    let mut rig = DeformRig::new(&mesh, LaplacianKind::Cotangent).unwrap();
    let (mut first, mut second) = (Deformed::default(), Deformed::default());
    let frames = session();
    rig.deform(&frames[4].0, &frames[4].1, &mut first).unwrap();
    rig.deform(&frames[4].0, &frames[4].1, &mut second).unwrap();
    assert_eq!(first, second);
}

#[test]
fn shares_build_the_solvers_laplacian() {
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        // A sheared grid has obtuse triangles, so cotangent weights get clamped somewhere.
        let mut mesh = fixtures::grid(9, 7);
        for p in &mut mesh.positions {
            p.x += 0.9 * p.y;
        }
        let rig = DeformRig::new(&mesh, kind).unwrap();
        let (ours, theirs) = (
            rig.laplacian().to_dense(),
            laplacian(&mesh, kind).to_dense(),
        );
        for (row_a, row_b) in ours.iter().zip(&theirs) {
            for (a, b) in row_a.iter().zip(row_b) {
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                    "{kind:?}: {a} vs {b}"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(Config {
        rng_seed: RngSeed::Fixed(0x0def_0123),
        cases: 48,
        ..Config::default()
    })]

    /// Moderate drags on a disc of radius 48 px with 4 px edges: one or two handles, radius
    /// 10–24 px, drag length up to min(0.4 r, 8 px) (two edges), p0 at least 12 px from the
    /// pivot (so θ stays below ≈ 40°) and two handles' p0 farther apart than their radii
    /// summed (handles pulling neighbouring vertices apart are not a moderate drag).
    #[test]
    fn moderate_drags_invert_no_triangle(
        kind_is_cot in any::<bool>(),
        handles in prop::collection::vec(
            (12.0..44.0f64, 0.0..std::f64::consts::TAU, 10.0..24.0f64, 0.0..std::f64::consts::TAU, 0.0..1.0f64),
            1..=2,
        ),
    ) {
        let mesh = disc_px(12, 4.0);
        let kind = if kind_is_cot { LaplacianKind::Cotangent } else { LaplacianKind::Combinatorial };
        let centre = DVec2::new(100.0, 80.0);
        let handles: Vec<Handle> = handles
            .iter()
            .map(|&(rho, phi, radius, dir, frac)| {
                let p0 = centre + DVec2::from_angle(phi) * rho;
                let len = (0.4 * radius).min(8.0) * frac;
                Handle::drag(p0, p0 + DVec2::from_angle(dir) * len, radius)
            })
            .collect();
        if let [a, b] = &handles[..] {
            prop_assume!(a.from.distance(b.from) > a.radius + b.radius);
        }
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let mut out = Deformed::default();
        rig.deform(&handles, &[], &mut out).unwrap();
        prop_assert_eq!(out.inverted_triangles(&mesh), 0, "{:?}", handles);
    }
}
