//! `min_angle_deg` against a reference over random meshes.

use glam::DVec2;
use lapclone::mesh::{min_angle_deg, Mesh};
use proptest::prelude::*;

fn reference_min_angle_deg(mesh: &Mesh) -> f64 {
    let mut smallest = std::f64::consts::PI;
    for t in &mesh.triangles {
        let p = t.map(|v| mesh.positions[v as usize]);
        for k in 0..3 {
            let (u, w) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            smallest = smallest.min(u.perp_dot(w).abs().atan2(u.dot(w)));
        }
    }
    smallest.to_degrees()
}

fn soup(points: &[(f64, f64)]) -> Mesh {
    let positions: Vec<DVec2> = points.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
    let triangles = (0..positions.len() as u32 / 3)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    Mesh {
        positions,
        triangles,
        ..Default::default()
    }
}

#[test]
fn right_isosceles_and_degenerate_triangles() {
    let right = soup(&[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]);
    assert!((min_angle_deg(&right) - 45.0).abs() < 1e-12);
    let degenerate = soup(&[
        (0.0, 0.0),
        (1.0, 0.0),
        (0.0, 1.0),
        (2.0, 2.0),
        (2.0, 2.0),
        (3.0, 2.0),
    ]);
    assert_eq!(min_angle_deg(&degenerate), 0.0);
    assert_eq!(min_angle_deg(&Mesh::default()), 180.0);
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 200,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed_a17e),
        ..ProptestConfig::default()
    })]
    #[test]
    fn matches_the_three_angle_formula(
        points in proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 3..60)
    ) {
        let mut points = points;
        points.truncate(points.len() / 3 * 3);
        let mesh = soup(&points);
        let (fast, exact) = (min_angle_deg(&mesh), reference_min_angle_deg(&mesh));
        prop_assert!((fast - exact).abs() < 1e-9, "{fast} vs {exact}");
    }
}
