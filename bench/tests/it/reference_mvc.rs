//! MVC baseline: linear precision and partition of unity on convex and star-shaped polygons,
//! exact barycentric coordinates on triangles, boundary limits, the weights/apply split on a
//! mesh, and the refusal of holes.

use glam::DVec2;
use lapclone::mesh::{BoundaryLoop, LoopKind, Mesh};
use lapclone_bench::reference::{mean_value_coordinates, MvcError, MvcWeights};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use std::f64::consts::TAU;

const TOLERANCE: f64 = 1e-9;

fn coordinates(x: DVec2, polygon: &[DVec2]) -> Vec<f64> {
    let mut out = vec![f64::NAN; polygon.len()];
    mean_value_coordinates(x, polygon, &mut out).unwrap();
    out
}

/// max over {Σλ − 1, Σλ p − x}: both vanish for exact linear precision.
fn linear_precision_error(x: DVec2, polygon: &[DVec2], lambda: &[f64]) -> f64 {
    let sum: f64 = lambda.iter().sum();
    let reproduced: DVec2 = polygon.iter().zip(lambda).map(|(p, l)| *p * *l).sum();
    (sum - 1.0).abs().max((reproduced - x).abs().max_element())
}

fn star_polygon(n: usize, wobble: f64) -> Vec<DVec2> {
    (0..n)
        .map(|i| {
            let t = TAU * i as f64 / n as f64;
            let r = 10.0 + wobble * (5.0 * t).sin();
            DVec2::new(50.0 + r * t.cos(), 40.0 + r * t.sin())
        })
        .collect()
}

#[test]
fn triangle_coordinates_are_barycentric() {
    let tri = [
        DVec2::new(1.0, 2.0),
        DVec2::new(9.0, 3.0),
        DVec2::new(4.0, 8.0),
    ];
    let x = DVec2::new(4.5, 4.0);
    let lambda = coordinates(x, &tri);
    let area = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    let total = area(tri[0], tri[1], tri[2]);
    let expected = [
        area(x, tri[1], tri[2]) / total,
        area(tri[0], x, tri[2]) / total,
        area(tri[0], tri[1], x) / total,
    ];
    for (l, e) in lambda.iter().zip(expected) {
        assert!((l - e).abs() <= TOLERANCE, "{lambda:?} vs {expected:?}");
    }
}

#[test]
fn square_centre_gets_equal_weights_in_both_orientations() {
    let mut square = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 2.0),
        DVec2::new(0.0, 2.0),
    ];
    for _ in 0..2 {
        let lambda = coordinates(DVec2::new(1.0, 1.0), &square);
        assert!(
            lambda.iter().all(|l| (l - 0.25).abs() <= TOLERANCE),
            "{lambda:?}"
        );
        square.reverse();
    }
}

#[test]
fn star_shaped_concave_polygon_has_linear_precision() {
    let polygon = star_polygon(60, 3.0);
    let mut worst = 0.0f64;
    let mut negative = 0;
    for i in 0..60 {
        for s in [0.05, 0.4, 0.75, 0.95] {
            let t = TAU * (i as f64 + 0.37) / 60.0;
            let r = s * (10.0 - 3.0);
            let x = DVec2::new(50.0 + r * t.cos(), 40.0 + r * t.sin());
            let lambda = coordinates(x, &polygon);
            worst = worst.max(linear_precision_error(x, &polygon, &lambda));
            negative += lambda.iter().filter(|&&l| l < 0.0).count();
        }
    }
    assert!(worst <= TOLERANCE, "worst {worst}");
    // The signed-angle formula really is exercised: concavity gives negative coordinates.
    assert!(negative > 0);
}

#[test]
fn points_on_the_boundary_get_the_limit_values() {
    let square = [
        DVec2::new(0.0, 0.0),
        DVec2::new(4.0, 0.0),
        DVec2::new(4.0, 4.0),
        DVec2::new(0.0, 4.0),
    ];
    assert_eq!(
        coordinates(DVec2::new(4.0, 4.0), &square),
        vec![0.0, 0.0, 1.0, 0.0]
    );
    let on_edge = coordinates(DVec2::new(4.0, 1.0), &square);
    assert!((on_edge[1] - 0.75).abs() <= TOLERANCE && (on_edge[2] - 0.25).abs() <= TOLERANCE);
    // Just inside the edge the coordinates tend to the same limit.
    let near = coordinates(DVec2::new(4.0 - 1e-9, 1.0), &square);
    assert!(
        on_edge
            .iter()
            .zip(&near)
            .all(|(a, b)| (a - b).abs() <= 1e-6),
        "{near:?}"
    );
}

fn convex_polygon(angles: &[f64], rx: f64, ry: f64) -> Vec<DVec2> {
    let mut sorted = angles.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup_by(|a, b| (*a - *b).abs() < 1e-3);
    sorted
        .iter()
        .map(|t| DVec2::new(rx * t.cos(), ry * t.sin()))
        .collect()
}

proptest! {
    #![proptest_config(Config {
        rng_seed: RngSeed::Fixed(0x0c0_0008),
        cases: 200,
        ..Config::default()
    })]
    #[test]
    fn convex_polygons_have_linear_precision_and_positive_weights(
        angles in proptest::collection::vec(0.0f64..TAU, 3..40),
        rx in 1.0f64..500.0,
        ry in 1.0f64..500.0,
        mix in proptest::collection::vec(0.001f64..1.0, 3),
        corner in 0usize..40,
    ) {
        let polygon = convex_polygon(&angles, rx, ry);
        prop_assume!(polygon.len() >= 3);
        // A strictly interior point: a positive combination of three vertices.
        let n = polygon.len();
        let picks = [corner % n, (corner + n / 3 + 1) % n, (corner + 2 * n / 3 + 2) % n];
        let total: f64 = mix.iter().sum();
        let x: DVec2 = picks.iter().zip(&mix).map(|(&i, &m)| polygon[i] * (m / total)).sum();
        let lambda = coordinates(x, &polygon);
        prop_assert!(linear_precision_error(x, &polygon, &lambda) <= TOLERANCE * rx.max(ry));
        prop_assert!(lambda.iter().all(|&l| l >= -1e-12), "{:?}", lambda);
    }
}

proptest! {
    #![proptest_config(Config {
        rng_seed: RngSeed::Fixed(0x57a2_0008),
        cases: 200,
        ..Config::default()
    })]
    #[test]
    fn star_shaped_polygons_have_linear_precision(
        radii in proptest::collection::vec(0.7f64..1.3, 5..50),
        scale in 1.0f64..300.0,
        direction in 0.0f64..TAU,
        depth in 0.0f64..0.65,
    ) {
        let n = radii.len();
        let polygon: Vec<DVec2> = radii
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let t = TAU * i as f64 / n as f64;
                DVec2::new(t.cos(), t.sin()) * (r * scale)
            })
            .collect();
        // Every ray from the origin leaves the polygon beyond 0.7·cos(π/5)·scale > 0.56·scale.
        let x = DVec2::new(direction.cos(), direction.sin()) * (depth * 0.85 * scale);
        let lambda = coordinates(x, &polygon);
        prop_assert!(linear_precision_error(x, &polygon, &lambda) <= TOLERANCE * scale);
    }
}

/// A fan of positions: the star polygon as boundary plus interior points.
fn star_positions() -> (Vec<DVec2>, Vec<u32>) {
    let mut positions = star_polygon(40, 2.0);
    let boundary: Vec<u32> = (0..40).collect();
    for i in 0..30 {
        let t = TAU * i as f64 / 30.0;
        let r = 1.0 + (i % 7) as f64;
        positions.push(DVec2::new(50.0 + r * t.cos(), 40.0 + r * t.sin()));
    }
    (positions, boundary)
}

#[test]
fn apply_reproduces_affine_boundary_data_per_channel() {
    let (positions, boundary) = star_positions();
    let weights = MvcWeights::new(&positions, &boundary).unwrap();
    weights.sanity_check().unwrap();
    assert_eq!(weights.weight_count(), 30 * 40);
    let affine = |p: DVec2, c: usize| [0.2 * p.x - 0.1 * p.y + 1.0, -0.03 * p.x + 0.5][c];
    let mut values = vec![f32::NAN; positions.len() * 2]; // interior inputs must not be read
    for &b in &boundary {
        for c in 0..2 {
            values[b as usize * 2 + c] = affine(positions[b as usize], c) as f32;
        }
    }
    let mut out = vec![0.0; positions.len() * 2];
    weights.apply(&values, 2, &mut out).unwrap();
    for (v, p) in positions.iter().enumerate() {
        for c in 0..2 {
            // f32 inputs: compare against the f32-rounded affine function's precision.
            assert!(
                (out[v * 2 + c] - affine(*p, c)).abs() <= 1e-5,
                "vertex {v} channel {c}"
            );
        }
    }
}

#[test]
fn holes_are_refused_and_pieces_use_their_own_loop() {
    let (mut positions, _) = star_positions();
    let hole = BoundaryLoop {
        kind: LoopKind::Hole,
        piece: 0,
        vertices: vec![40, 41, 42],
    };
    let outer = BoundaryLoop {
        kind: LoopKind::Outer,
        piece: 0,
        vertices: (0..40).collect(),
    };
    let piece = vec![0u32; positions.len()];
    assert_eq!(
        MvcWeights::from_loops(&positions, &[outer.clone(), hole], &piece).unwrap_err(),
        MvcError::HasHoles { holes: 1 }
    );

    // A second piece: a triangle far away holding one interior vertex.
    let base = positions.len() as u32;
    positions.extend([
        DVec2::new(200.0, 0.0),
        DVec2::new(230.0, 0.0),
        DVec2::new(200.0, 30.0),
        DVec2::new(210.0, 10.0),
    ]);
    let second = BoundaryLoop {
        kind: LoopKind::Outer,
        piece: 1,
        vertices: vec![base, base + 1, base + 2],
    };
    let mut mesh = Mesh {
        positions: positions.clone(),
        loops: vec![outer, second],
        ..Mesh::default()
    };
    mesh.piece = (0..positions.len() as u32)
        .map(|v| u32::from(v >= base))
        .collect();
    let weights = MvcWeights::from_mesh(&mesh).unwrap();
    weights.sanity_check().unwrap();
    assert_eq!(weights.blocks().len(), 2);
    assert_eq!(weights.blocks()[1].interior(), &[base + 3]);
    let lambda = weights.blocks()[1].coordinates(0);
    assert!((lambda[0] - 1.0 / 3.0).abs() <= TOLERANCE);
    assert!((lambda[1] - 1.0 / 3.0).abs() <= TOLERANCE);
}

#[test]
fn malformed_input_is_a_typed_error() {
    let (positions, _) = star_positions();
    assert_eq!(
        MvcWeights::new(&positions, &[0, 1]).unwrap_err(),
        MvcError::TooFewBoundaryVertices { count: 2 }
    );
    assert_eq!(
        MvcWeights::new(&positions, &[0, 1, 1]).unwrap_err(),
        MvcError::RepeatedBoundaryVertex { index: 1 }
    );
    assert!(matches!(
        MvcWeights::new(&positions, &[0, 1, 999]),
        Err(MvcError::VertexOutOfRange { index: 999, .. })
    ));
    let mut short = [0.0; 2];
    assert!(mean_value_coordinates(DVec2::ZERO, &positions[..3], &mut short).is_err());
    assert!(mean_value_coordinates(DVec2::ZERO, &positions[..2], &mut short).is_err());
    let collinear = [DVec2::ZERO, DVec2::X, DVec2::X * 2.0, DVec2::new(0.5, 0.0)];
    assert_eq!(
        MvcWeights::new(&collinear, &[0, 1, 2]).unwrap_err(),
        MvcError::DegeneratePolygon
    );
    let mut bad = positions.clone();
    bad[45] = DVec2::new(f64::NAN, 0.0);
    assert_eq!(
        MvcWeights::new(&bad, &(0..40).collect::<Vec<_>>()).unwrap_err(),
        MvcError::NonFinitePosition { vertex: 45 }
    );
    let weights = MvcWeights::new(&positions, &(0..40).collect::<Vec<_>>()).unwrap();
    let mut out = vec![0.0; positions.len()];
    assert!(matches!(
        weights.apply(&[0.0f64; 3], 1, &mut out),
        Err(MvcError::ValuesLength { what: "values", .. })
    ));
}
