//! Factorisation, solve and Laplacian tests for the solve stage, against dense references.

use crate::mesh_fixtures as fixtures;
use lapclone::mesh::Mesh;
use lapclone::solve::{laplacian, LaplacianKind, PenaltyFactor, PenaltyOptions, SymmetricCsc};

use crate::checks;
use checks::{dense_solve, rel_diff, Rng};

/// The penalised matrix `L + P + εI` as a dense matrix.
fn penalised_dense(l: &SymmetricCsc, f: &PenaltyFactor) -> Vec<Vec<f64>> {
    let mut a = l.to_dense();
    for (v, row) in a.iter_mut().enumerate() {
        row[v] += f.epsilon() + if f.is_constrained(v) { f.alpha() } else { 0.0 };
    }
    a
}

fn check_against_dense(mesh: &Mesh, kind: LaplacianKind, seed: u64) {
    let l = laplacian(mesh, kind);
    l.sanity_check().unwrap();
    let n = l.n;
    let mut f = PenaltyFactor::new(&l, &PenaltyOptions::default()).unwrap();
    let mut rng = Rng(seed);
    let wanted: Vec<bool> = (0..n).map(|_| rng.next() < 0.3).collect();
    f.set_constrained(&wanted).unwrap();
    let k = 3;
    let b: Vec<f64> = (0..n * k).map(|_| rng.next() * 2.0 - 1.0).collect();
    let mut x = b.clone();
    f.solve_in_place(&mut x, k);
    let a = penalised_dense(&l, &f);
    for c in 0..k {
        let (xc, bc) = (&x[c * n..(c + 1) * n], &b[c * n..(c + 1) * n]);
        let reference = dense_solve(&a, bc);
        assert!(
            rel_diff(xc, &reference) <= 1e-10,
            "column {c}: {}",
            rel_diff(xc, &reference)
        );
        // Normwise relative residual ‖Ax − b‖ / (‖A‖‖x‖ + ‖b‖) (∞-norms): the scale-free
        // measure for a matrix whose penalty rows are 1e8 times larger than the others.
        let mut ax = vec![0.0; n];
        l.mul_vec(xc, &mut ax);
        let dense_l = l.to_dense();
        let residual = (0..n)
            .map(|v| (ax[v] + (a[v][v] - dense_l[v][v]) * xc[v] - bc[v]).abs())
            .fold(0.0, f64::max);
        let norm_a = a
            .iter()
            .map(|row| row.iter().map(|x| x.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let norm = |x: &[f64]| x.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let rel = residual / (norm_a * norm(xc) + norm(bc));
        assert!(rel <= 1e-10, "residual {rel}");
    }
}

#[test]
fn factor_matches_dense_solve_on_small_meshes() {
    for (i, mesh) in [
        fixtures::grid(6, 5),
        fixtures::disc(4),
        fixtures::grid(1, 1),
    ]
    .iter()
    .enumerate()
    {
        for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
            check_against_dense(mesh, kind, 17 + i as u64);
        }
    }
}

#[test]
fn every_k_from_one_to_six_matches_single_rhs_solves() {
    let l = laplacian(&fixtures::disc(5), LaplacianKind::Combinatorial);
    let n = l.n;
    let mut f = PenaltyFactor::new(&l, &PenaltyOptions::default()).unwrap();
    let boundary: Vec<bool> = fixtures::disc(5).is_boundary.clone();
    f.set_constrained(&boundary).unwrap();
    let mut rng = Rng(5);
    for k in 1..=6 {
        let b: Vec<f64> = (0..n * k).map(|_| rng.next()).collect();
        let mut together = b.clone();
        f.solve_in_place(&mut together, k);
        for c in 0..k {
            let mut single = b[c * n..(c + 1) * n].to_vec();
            f.solve_in_place(&mut single, 1);
            assert!(rel_diff(&together[c * n..(c + 1) * n], &single) <= 1e-14);
        }
    }
}

#[test]
fn combinatorial_laplacian_is_degree_minus_adjacency() {
    let mesh = fixtures::disc(3);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let dense = l.to_dense();
    let edges = mesh.edges();
    for (v, row) in dense.iter().enumerate() {
        let sum: f64 = row.iter().sum();
        assert_eq!(sum, 0.0, "row {v} sums to {sum}");
        let degree = edges
            .iter()
            .filter(|e| e.0 as usize == v || e.1 as usize == v)
            .count();
        assert_eq!(row[v], degree as f64);
    }
    for &(i, j) in &edges {
        assert_eq!(dense[i as usize][j as usize], -1.0);
    }
}

#[test]
fn cotangent_laplacian_matches_hand_computation() {
    // Right isosceles triangle: 90° at vertex 0, 45° at 1 and 2. cot 90° = 0, cot 45° = 1.
    let mut mesh = fixtures::grid(1, 1);
    mesh.positions.truncate(3);
    mesh.positions = vec![
        glam::DVec2::new(0.0, 0.0),
        glam::DVec2::new(1.0, 0.0),
        glam::DVec2::new(0.0, 1.0),
    ];
    mesh.triangles = vec![[0, 1, 2]];
    mesh.is_boundary = vec![true; 3];
    mesh.piece = vec![0; 3];
    mesh.loops[0].vertices = vec![0, 1, 2];
    let l = laplacian(&mesh, LaplacianKind::Cotangent).to_dense();
    let expected = [[1.0, -0.5, -0.5], [-0.5, 0.5, 0.0], [-0.5, 0.0, 0.5]];
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (l[i][j] - expected[i][j]).abs() <= 1e-15,
                "({i},{j}) = {}",
                l[i][j]
            );
        }
    }
    // Obtuse apex: the edge opposite it gets a negative cotangent, clamped to 0.
    mesh.positions = vec![
        glam::DVec2::new(0.0, 0.0),
        glam::DVec2::new(4.0, 0.0),
        glam::DVec2::new(2.0, 0.5),
    ];
    let l = laplacian(&mesh, LaplacianKind::Cotangent).to_dense();
    assert_eq!(l[0][1], 0.0);
    let cot_base = 2.0 / 0.5; // cot of the base angles = adjacent / opposite
    assert!((l[0][2] + 0.5 * cot_base).abs() <= 1e-12);
    for row in &l {
        assert!(row.iter().sum::<f64>().abs() <= 1e-12);
    }
}

#[test]
fn constrained_values_are_honoured() {
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let mesh = fixtures::disc(12);
        let l = laplacian(&mesh, kind);
        let n = l.n;
        let mut f = PenaltyFactor::new(&l, &PenaltyOptions::default()).unwrap();
        f.set_constrained(&mesh.is_boundary).unwrap();
        let mut rng = Rng(99);
        let k = 3;
        let targets: Vec<f64> = (0..n * k).map(|_| 255.0 * rng.next()).collect();
        let mut values = targets.clone();
        f.solve_dirichlet(&mut values, k);
        let range = 255.0;
        for c in 0..k {
            for v in (0..n).filter(|&v| mesh.is_boundary[v]) {
                let err = (values[c * n + v] - targets[c * n + v]).abs();
                assert!(err <= 1e-6 * range, "vertex {v}: error {err}");
            }
            // Maximum principle (combinatorial weights are positive; clamped cotangents too).
            for v in 0..n {
                assert!(values[c * n + v] >= -1e-6 && values[c * n + v] <= range + 1e-6);
            }
        }
    }
}

#[test]
fn unconstrained_piece_gives_zero_membrane() {
    let a = fixtures::disc(4);
    let mesh = fixtures::disjoint_union(&a, &fixtures::grid(5, 4));
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let n = l.n;
    let mut f = PenaltyFactor::new(&l, &PenaltyOptions::default()).unwrap();
    // Nothing constrained at all: zero right-hand side → exactly zero.
    let mut zero = vec![0.0; n * 2];
    f.solve_in_place(&mut zero, 2);
    assert!(zero.iter().all(|&x| x == 0.0));
    // Only the disc's boundary constrained: the grid piece stays zero, the disc takes values.
    let wanted: Vec<bool> = (0..n)
        .map(|v| v < a.vertex_count() && mesh.is_boundary[v])
        .collect();
    f.set_constrained(&wanted).unwrap();
    let mut values: Vec<f64> = (0..n)
        .map(|v| if wanted[v] { 7.0 } else { 123.0 })
        .collect();
    f.solve_dirichlet(&mut values, 1);
    for (v, &value) in values.iter().enumerate() {
        let expected = if v < a.vertex_count() { 7.0 } else { 0.0 };
        assert!(
            (value - expected).abs() <= 1e-6 * 7.0,
            "vertex {v}: {value}"
        );
    }
}

#[test]
fn one_and_three_vertex_meshes() {
    let opts = PenaltyOptions::default();
    let one = Mesh {
        positions: vec![glam::DVec2::new(0.5, 0.5)],
        is_boundary: vec![true],
        piece: vec![0],
        piece_count: 1,
        ..Default::default()
    };
    let l = laplacian(&one, LaplacianKind::Combinatorial);
    assert_eq!((l.n, l.nnz(), l.values[0]), (1, 1, 0.0));
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    let mut x = vec![0.0];
    f.solve_in_place(&mut x, 1);
    assert_eq!(x, [0.0]);
    f.switch(&[(0, true)]).unwrap();
    let mut x = vec![3.5];
    f.solve_dirichlet(&mut x, 1);
    assert!((x[0] - 3.5).abs() <= 1e-12);
    f.switch(&[(0, false)]).unwrap();
    assert_eq!(f.constrained_count(), 0);

    let mut three = fixtures::grid(1, 1);
    three.positions.truncate(3);
    three.triangles = vec![[0, 1, 2]];
    three.is_boundary.truncate(3);
    three.piece.truncate(3);
    three.loops[0].vertices = vec![0, 1, 2];
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let l = laplacian(&three, kind);
        let mut f = PenaltyFactor::new(&l, &opts).unwrap();
        f.switch(&[(0, true), (2, true)]).unwrap();
        let mut x = vec![1.0, 0.0, 3.0];
        f.solve_dirichlet(&mut x, 1);
        assert!((x[0] - 1.0).abs() <= 1e-6 && (x[2] - 3.0).abs() <= 1e-6);
        // Vertex 1 is the weighted average of its neighbours.
        let d = l.to_dense();
        let avg = -(d[1][0] * x[0] + d[1][2] * x[2]) / d[1][1];
        assert!((x[1] - avg).abs() <= 1e-6, "{} vs {avg}", x[1]);
    }
}
