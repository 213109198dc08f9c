//! The boundary samplers (nearest, hat, mean) over hand-made square meshes.

use glam::DVec2;
use lapclone::clone::{BoundaryData, BoundarySampler};
use lapclone::mesh::{BoundaryLoop, LoopKind, Mesh};

/// A square of side `side` with boundary vertices every `spacing` px and one inner vertex.
fn square(side: f64, spacing: usize) -> Mesh {
    let per_side = (side as usize) / spacing;
    let mut positions = Vec::new();
    let corners = [
        DVec2::ZERO,
        DVec2::new(side, 0.0),
        DVec2::new(side, side),
        DVec2::new(0.0, side),
    ];
    for k in 0..4 {
        for i in 0..per_side {
            let t = i as f64 / per_side as f64;
            positions.push(corners[k].lerp(corners[(k + 1) % 4], t));
        }
    }
    let n = positions.len() as u32;
    positions.push(DVec2::splat(side / 2.0));
    let triangles = (0..n).map(|i| [i, (i + 1) % n, n]).collect();
    let mut is_boundary = vec![true; n as usize];
    is_boundary.push(false);
    Mesh {
        positions,
        triangles,
        loops: vec![BoundaryLoop {
            kind: LoopKind::Outer,
            piece: 0,
            vertices: (0..n).collect(),
        }],
        is_boundary,
        piece: vec![0; n as usize + 1],
        piece_count: 1,
    }
}

fn sampled(mesh: &Mesh, kind: BoundaryData, f: impl Fn(DVec2) -> f32) -> Vec<f32> {
    let sampler = BoundarySampler::new(mesh, kind);
    let mut values = vec![[0.0; 3]; sampler.boundary_vertices().len()];
    sampler.sample(&mesh.positions, |p| [f(p); 3], &mut values);
    values.iter().map(|v| v[0]).collect()
}

/// The hat average by a fine midpoint rule over the vertex's two edges.
fn hat_average_reference(mesh: &Mesh, v: u32, f: &impl Fn(DVec2) -> f32) -> f64 {
    let vertices = &mesh.loops[0].vertices;
    let i = vertices.iter().position(|&u| u == v).expect("on the loop");
    let n = vertices.len();
    let p = mesh.positions[v as usize];
    let (mut sum, mut mass) = (0.0, 0.0);
    for neighbour in [vertices[(i + 1) % n], vertices[(i + n - 1) % n]] {
        let q = mesh.positions[neighbour as usize];
        let steps = 20_000;
        let ds = (q - p).length() / steps as f64;
        for k in 0..steps {
            let t = (k as f64 + 0.5) / steps as f64;
            sum += (1.0 - t) * f64::from(f(p.lerp(q, t))) * ds;
            mass += (1.0 - t) * ds;
        }
    }
    sum / mass
}

#[test]
fn vertex_data_is_the_sample_at_the_vertex() {
    let mesh = square(12.0, 3);
    let f = |p: DVec2| (p.x * 0.7 + p.y * p.y * 0.01).sin() as f32;
    let values = sampled(&mesh, BoundaryData::Vertex, f);
    for (value, v) in values.iter().zip(mesh.boundary_vertices()) {
        assert_eq!(*value, f(mesh.positions[v as usize]));
    }
}

#[test]
fn a_hat_average_keeps_constant_and_evenly_spaced_linear_data() {
    let mesh = square(12.0, 3);
    for value in sampled(&mesh, BoundaryData::HatAverage, |_| 0.25) {
        assert!((value - 0.25).abs() < 1e-6, "{value}");
    }
    // Linear data along a straight side averages to the vertex's own value (the hat is
    // symmetric there); the corners bend, so only side vertices are compared.
    let f = |p: DVec2| (0.1 + 0.03 * p.x + 0.02 * p.y) as f32;
    let values = sampled(&mesh, BoundaryData::HatAverage, f);
    for (value, v) in values.iter().zip(mesh.boundary_vertices()) {
        if v % 4 != 0 {
            let exact = f(mesh.positions[v as usize]);
            assert!(
                (value - exact).abs() < 1e-6,
                "vertex {v}: {value} vs {exact}"
            );
        }
    }
}

/// A diamond through pixel centres (x.5, y.5) whose edges are pixel diagonals.
fn diamond(steps: usize) -> Mesh {
    let mut mesh = square(4.0, 1);
    let directions = [(1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)];
    let mut p = DVec2::new(0.5, 7.5);
    let mut positions = Vec::new();
    for (dx, dy) in directions {
        for _ in 0..steps {
            positions.push(p);
            p += DVec2::new(dx, dy);
        }
    }
    let n = positions.len() as u32;
    positions.push(DVec2::new(0.5 + steps as f64, 7.5));
    mesh.triangles = (0..n).map(|i| [i, n, (i + 1) % n]).collect();
    mesh.loops[0].vertices = (0..n).collect();
    mesh.is_boundary = (0..=n).map(|v| v < n).collect();
    mesh.piece = vec![0; n as usize + 1];
    mesh.positions = positions;
    mesh
}

#[test]
fn a_hat_average_over_pixel_long_and_diagonal_edges_is_the_vertex_sample() {
    let f = |p: DVec2| (p.x * 1.3).sin() as f32 * (p.y * 0.9).cos() as f32;
    for mesh in [square(12.0, 1), diamond(5)] {
        let hat = sampled(&mesh, BoundaryData::HatAverage, f);
        let vertex = sampled(&mesh, BoundaryData::Vertex, f);
        for (h, v) in hat.iter().zip(&vertex) {
            assert!((h - v).abs() < 1e-6, "{h} vs {v}");
        }
    }
}

#[test]
fn a_hat_average_matches_fine_integration_of_smooth_data() {
    // The trapezoid rule (4 px edges in three 4/3 px steps) against a 20 000-point
    // midpoint rule. Its error is about h²/12 · |(f φ)''| ≤ (16/9)/12 · 0.16 ≈ 0.024 for
    // this data; a wrong weight or a dropped sample is off by 0.1 or more.
    let mesh = square(24.0, 4);
    let f = |p: DVec2| (p.x * 0.35).sin() as f32 + (p.y * 0.2).cos() as f32;
    let values = sampled(&mesh, BoundaryData::HatAverage, f);
    for (value, v) in values.iter().zip(mesh.boundary_vertices()) {
        let reference = hat_average_reference(&mesh, v, &f);
        assert!(
            (f64::from(*value) - reference).abs() < 0.03,
            "vertex {v}: {value} vs {reference}"
        );
    }
}

#[test]
fn a_hat_average_smooths_pixel_noise_that_a_vertex_sample_keeps() {
    // Alternating ±1 at pixel centres along the boundary: the vertex sample keeps its
    // full amplitude, the average over the hat's six samples cancels most of it.
    let mesh = square(24.0, 3);
    let f = |p: DVec2| {
        if (p.x + p.y).round() as i64 % 2 == 0 {
            1.0
        } else {
            -1.0
        }
    };
    let largest = |values: Vec<f32>| values.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    assert_eq!(largest(sampled(&mesh, BoundaryData::Vertex, f)), 1.0);
    assert!(largest(sampled(&mesh, BoundaryData::HatAverage, f)) < 0.5);
}
