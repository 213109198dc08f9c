//! Deformation: identity, rigid whole-patch drags, locality, handle accuracy and depth.

use crate::mesh_fixtures as fixtures;
use glam::DVec2;
use lapclone::deform::{DeformOptions, DeformRig, Deformed, Handle, Pin};
use lapclone::mesh::Mesh;
use lapclone::solve::LaplacianKind;

const KINDS: [LaplacianKind; 2] = [LaplacianKind::Combinatorial, LaplacianKind::Cotangent];

/// A hexagonal disc of the given rings, scaled to pixel units and moved off the origin.
fn disc_px(rings: usize, spacing: f64) -> Mesh {
    let mut mesh = fixtures::disc(rings);
    for p in &mut mesh.positions {
        *p = *p * spacing + DVec2::new(100.0, 80.0);
    }
    mesh
}

fn max_distance(a: &[DVec2], b: &[DVec2]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

#[test]
fn no_handle_copies_rest_and_solves_nothing() {
    for kind in KINDS {
        let mesh = disc_px(8, 4.0);
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let mut out = Deformed::default();
        let stats = rig
            .deform(&[], &[Pin(DVec2::new(100.0, 80.0))], &mut out)
            .unwrap();
        assert!(!stats.solved);
        assert_eq!(out.positions, mesh.positions);
        assert!(out.depth.iter().all(|&d| d == 0.0));
    }
}

#[test]
fn solve_path_without_handle_is_identity() {
    for kind in KINDS {
        let mesh = disc_px(8, 4.0);
        let options = DeformOptions {
            solve_without_handles: true,
            ..Default::default()
        };
        let mut rig = DeformRig::with_options(&mesh, kind, options).unwrap();
        let mut out = Deformed::default();
        let stats = rig.deform(&[], &[], &mut out).unwrap();
        assert!(stats.solved);
        assert_eq!(
            stats.constrained,
            mesh.vertex_count(),
            "no handle: every vertex is far field"
        );
        let err = max_distance(&out.positions, &mesh.positions);
        assert!(err <= 1e-6, "{kind:?}: {err}");
    }
}

#[test]
fn handle_that_does_not_move_is_identity() {
    for kind in KINDS {
        let mesh = disc_px(10, 4.0);
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let mut out = Deformed::default();
        let p0 = DVec2::new(115.0, 70.0);
        for radius in [5.0, 20.0, 1e4] {
            let stats = rig
                .deform(&[Handle::drag(p0, p0, radius)], &[], &mut out)
                .unwrap();
            assert!(stats.solved);
            let err = max_distance(&out.positions, &mesh.positions);
            assert!(err <= 1e-6, "{kind:?} r {radius}: {err}");
        }
    }
}

/// Least-squares similarity `q ≈ s R p + t`: returns (scale, angle, max residual).
fn fit_similarity(p: &[DVec2], q: &[DVec2]) -> (f64, f64, f64) {
    let n = p.len() as f64;
    let (pc, qc) = (p.iter().sum::<DVec2>() / n, q.iter().sum::<DVec2>() / n);
    let (mut a, mut b, mut var) = (0.0, 0.0, 0.0);
    for (pi, qi) in p.iter().zip(q) {
        let (u, v) = (*pi - pc, *qi - qc);
        a += u.dot(v);
        b += u.perp_dot(v);
        var += u.length_squared();
    }
    let angle = b.atan2(a);
    let scale = (a * a + b * b).sqrt() / var;
    let rotation = DVec2::from_angle(angle) * scale;
    let residual = p
        .iter()
        .zip(q)
        .map(|(pi, qi)| (qc + rotation.rotate(*pi - pc)).distance(*qi))
        .fold(0.0, f64::max);
    (scale, angle, residual)
}

/// A radius ≫ the patch makes every g ≈ 1: the fields rotate rigidly by θ and the handle
/// vertex translates, so the result is a rigid motion. The only non-rigid part is θ's
/// variation over the patch, `θ · d²/(2σ²) ≤ 0.35 · 2·(50 px)²/(2·(5000 px)²) ≈ 7e-5` rad,
/// i.e. ≲ 4e-3 px over a 50 px radius: tolerance 1e-2 px.
#[test]
fn whole_patch_drag_is_a_rigid_motion() {
    for kind in KINDS {
        let mesh = disc_px(10, 5.0);
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let o = rig.rest_centroid();
        assert!(
            o.distance(DVec2::new(100.0, 80.0)) < 1e-9,
            "centroid of a symmetric disc"
        );
        let p0 = o + DVec2::new(30.0, -10.0);
        let p1 =
            o + DVec2::from_angle(20f64.to_radians()).rotate(p0 - o) * 1.1 + DVec2::new(0.0, -3.0);
        let theta = (p0 - o).perp_dot(p1 - o).atan2((p0 - o).dot(p1 - o));
        assert!(theta.abs() > 0.2);
        let mut out = Deformed::default();
        rig.deform(&[Handle::drag(p0, p1, 1e4)], &[], &mut out)
            .unwrap();
        let (scale, angle, residual) = fit_similarity(&mesh.positions, &out.positions);
        assert!(residual <= 1e-2, "{kind:?}: residual {residual} px");
        assert!((scale - 1.0).abs() <= 1e-4, "{kind:?}: scale {scale}");
        assert!(
            (angle - theta).abs() <= 1e-4,
            "{kind:?}: angle {angle} vs {theta}"
        );
        assert_eq!(out.inverted_triangles(&mesh), 0);
    }
}

#[test]
fn rotation_override_replaces_the_derived_angle() {
    let mesh = disc_px(8, 5.0);
    let mut rig = DeformRig::new(&mesh, LaplacianKind::Combinatorial).unwrap();
    let p0 = DVec2::new(120.0, 80.0);
    let handle = Handle {
        rotation_deg: Some(-35.0),
        ..Handle::drag(p0, p0, 1e4)
    };
    let mut out = Deformed::default();
    rig.deform(&[handle], &[], &mut out).unwrap();
    let (_, angle, residual) = fit_similarity(&mesh.positions, &out.positions);
    assert!(residual <= 1e-2, "residual {residual}");
    assert!(
        (angle - (-35f64).to_radians()).abs() <= 1e-4,
        "angle {angle}"
    );
}

#[test]
fn local_drag_leaves_the_far_field_at_rest_and_moves_the_handle_vertex() {
    for kind in KINDS {
        let mesh = disc_px(20, 4.0);
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let (p0, p1, radius) = (DVec2::new(140.0, 80.0), DVec2::new(146.0, 86.0), 10.0);
        let mut out = Deformed::default();
        rig.deform(&[Handle::drag(p0, p1, radius)], &[], &mut out)
            .unwrap();
        let sigma: f64 = radius / 2.0;
        let mut far = 0;
        for (rest, moved) in mesh.positions.iter().zip(&out.positions) {
            let g = (-rest.distance_squared(p0) / (2.0 * sigma * sigma)).exp();
            if g < 1e-3 {
                far += 1;
                assert!(
                    rest.distance(*moved) <= 0.5,
                    "{kind:?}: far vertex {rest} moved to {moved}"
                );
            }
        }
        assert!(
            far > mesh.vertex_count() / 2,
            "most of the disc is far field"
        );
        let h = rig.nearest_vertex(p0);
        let miss = out.positions[h].distance(mesh.positions[h] + (p1 - p0));
        assert!(
            miss <= 1e-6 * p1.length(),
            "{kind:?}: handle vertex misses p1 by {miss}"
        );
        assert_eq!(out.inverted_triangles(&mesh), 0);
    }
}

#[test]
fn every_handle_vertex_lands_on_its_target() {
    for kind in KINDS {
        let mesh = disc_px(16, 4.0);
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        // p0 exactly on a vertex, so the handle vertex's target p_h + (p1 − p0) is p1.
        let on_vertex = |p: DVec2| mesh.positions[rig.nearest_vertex(p)];
        let handles = [
            Handle::drag(
                on_vertex(DVec2::new(132.0, 80.0)),
                DVec2::new(135.0, 70.0),
                15.0,
            ),
            Handle::drag(
                on_vertex(DVec2::new(60.0, 80.0)),
                DVec2::new(66.0, 87.0),
                12.0,
            ),
        ];
        let pins = [Pin(DVec2::new(100.0, 80.0))];
        let mut out = Deformed::default();
        rig.deform(&handles, &pins, &mut out).unwrap();
        for h in &handles {
            let v = rig.nearest_vertex(h.from);
            assert_eq!(mesh.positions[v], h.from, "p0 chosen on a vertex");
            let miss = out.positions[v].distance(h.to);
            assert!(miss <= 1e-6 * h.to.length(), "{kind:?}: {miss}");
        }
        let pinned = rig.nearest_vertex(pins[0].0);
        assert!(out.positions[pinned].distance(mesh.positions[pinned]) <= 1e-6 * 100.0);
    }
}

#[test]
fn dragged_region_comes_in_front_and_depth_follows_handles() {
    let mesh = disc_px(16, 4.0);
    let mut rig = DeformRig::new(&mesh, LaplacianKind::Combinatorial).unwrap();
    let (a, b) = (DVec2::new(130.0, 80.0), DVec2::new(70.0, 80.0));
    let front = Handle::drag(a, a + DVec2::new(5.0, 0.0), 12.0);
    let behind = Handle {
        depth: Some(-2.0),
        ..Handle::drag(b, b + DVec2::new(0.0, 5.0), 12.0)
    };
    let pin = Pin(DVec2::new(100.0, 112.0));
    let mut out = Deformed::default();
    rig.deform(&[front, behind], &[pin], &mut out).unwrap();
    let depth_at = |p: DVec2| out.depth[rig.nearest_vertex(p)];
    // The documented formula, vertex by vertex (σ = r/2).
    let g = |p: DVec2, h: &Handle| {
        (-p.distance_squared(h.from) / (2.0 * (h.radius / 2.0).powi(2))).exp()
    };
    let pinned = rig.nearest_vertex(pin.0);
    for (v, p) in mesh
        .positions
        .iter()
        .enumerate()
        .filter(|&(v, _)| v != pinned)
    {
        let expected = 1.0 * g(*p, &front) - 2.0 * g(*p, &behind);
        assert!(
            (f64::from(out.depth[v]) - expected).abs() <= 1e-6,
            "vertex {v}"
        );
    }
    let (near_a, near_b, centre) = (depth_at(a), depth_at(b), depth_at(DVec2::new(100.0, 80.0)));
    assert!(
        (near_a - 1.0).abs() < 0.06,
        "default depth 1 at p0: {near_a}"
    );
    assert!(
        (near_b + 2.0).abs() < 0.12,
        "explicit depth at p0: {near_b}"
    );
    assert!(
        near_a > centre && centre > near_b,
        "{near_a} > {centre} > {near_b}"
    );
    assert!(
        centre.abs() < 1e-2,
        "undragged middle stays at depth ≈ 0: {centre}"
    );
    assert_eq!(depth_at(pin.0), 0.0, "pinned vertex depth");
    // Depth falls off monotonically with rest distance from p0 along a ray.
    let ray: Vec<f32> = (0..8)
        .map(|k| depth_at(a + DVec2::new(0.0, 3.0 * k as f64)))
        .collect();
    assert!(ray.windows(2).all(|w| w[0] >= w[1]), "{ray:?}");
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let mesh = disc_px(4, 4.0);
    let mut rig = DeformRig::new(&mesh, LaplacianKind::Combinatorial).unwrap();
    let mut out = Deformed::default();
    let p = DVec2::new(100.0, 80.0);
    for bad in [
        Handle::drag(p, p, 0.0),
        Handle::drag(p, p, f64::NAN),
        Handle::drag(DVec2::new(f64::INFINITY, 0.0), p, 5.0),
        Handle {
            rotation_deg: Some(f64::NAN),
            ..Handle::drag(p, p, 5.0)
        },
    ] {
        assert!(rig.deform(&[bad], &[], &mut out).is_err());
    }
    assert!(rig
        .deform(&[], &[Pin(DVec2::new(f64::NAN, 1.0))], &mut out)
        .is_err());
    assert!(out.positions.is_empty(), "no partial output on error");
    assert!(DeformRig::new(&Mesh::default(), LaplacianKind::Combinatorial).is_err());
    let mut broken = mesh.clone();
    broken.triangles[0][1] = 10_000;
    assert!(DeformRig::new(&broken, LaplacianKind::Cotangent).is_err());
}
