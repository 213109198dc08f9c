//! Supernodal factorisation path: faer's supernodal LDLᵀ converted to the column layout the
//! solve and rank-1 kernels read, checked against the simplicial factor, a dense
//! reconstruction and fresh factorisations after switching.

use lapclone::solve::symbolic::{SymbolicFactor, SUPERNODAL_MIN_VERTICES};

use crate::checks;
use crate::mesh_fixtures as fixtures;
use checks::{dense_solve, rel_diff, Rng};
use lapclone::solve::{
    laplacian, FactorMethod, LaplacianKind, PenaltyFactor, PenaltyOptions, SymmetricCsc,
};

const SUPERNODAL: [FactorMethod; 2] = [FactorMethod::Supernodal, FactorMethod::SupernodalRelaxed];

fn options(method: FactorMethod) -> PenaltyOptions {
    PenaltyOptions {
        method,
        ..Default::default()
    }
}

fn factor_with(l: &SymmetricCsc, method: FactorMethod, constrained: &[bool]) -> PenaltyFactor {
    let mut f = PenaltyFactor::new(l, &options(method)).unwrap();
    f.set_constrained(constrained).unwrap();
    // A fresh numeric factorisation, not the rank-1 updates `set_constrained` may have used.
    f.refactor().unwrap();
    f
}

fn solve(f: &mut PenaltyFactor, b: &[f64], k: usize) -> Vec<f64> {
    let mut x = b.to_vec();
    f.solve_in_place(&mut x, k);
    x
}

#[test]
fn fundamental_supernodes_keep_the_simplicial_pattern_and_relaxed_ones_add_zeros() {
    let l = laplacian(&fixtures::disc(8), LaplacianKind::Combinatorial);
    let simplicial = SymbolicFactor::analyse_with(&l, FactorMethod::Simplicial).unwrap();
    let fundamental = SymbolicFactor::analyse_with(&l, FactorMethod::Supernodal).unwrap();
    let relaxed = SymbolicFactor::analyse_with(&l, FactorMethod::SupernodalRelaxed).unwrap();
    assert!(!simplicial.is_supernodal());
    assert_eq!(fundamental.col_ptr(), simplicial.col_ptr());
    assert_eq!(fundamental.row_idx(), simplicial.row_idx());
    // The relaxed test cases below only exercise explicit zeros if there are some.
    assert!(relaxed.nnz_factor() > simplicial.nnz_factor());
}

#[test]
fn supernodal_solves_match_simplicial_and_dense() {
    let mesh = fixtures::disjoint_union(&fixtures::disc(5), &fixtures::grid(6, 4));
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let l = laplacian(&mesh, kind);
        let n = l.n;
        let mut rng = Rng(11);
        let wanted: Vec<bool> = (0..n).map(|_| rng.next() < 0.3).collect();
        let k = 3;
        let b: Vec<f64> = (0..n * k).map(|_| rng.next() * 2.0 - 1.0).collect();
        let mut simplicial = factor_with(&l, FactorMethod::Simplicial, &wanted);
        let reference = solve(&mut simplicial, &b, k);
        let mut a = l.to_dense();
        for (v, row) in a.iter_mut().enumerate() {
            row[v] += simplicial.epsilon() + if wanted[v] { simplicial.alpha() } else { 0.0 };
        }
        for c in 0..k {
            let dense = dense_solve(&a, &b[c * n..(c + 1) * n]);
            let diff = rel_diff(&reference[c * n..(c + 1) * n], &dense);
            assert!(diff <= 1e-10, "simplicial vs dense: {diff}");
        }
        for method in SUPERNODAL {
            let mut f = factor_with(&l, method, &wanted);
            let diff = rel_diff(&solve(&mut f, &b, k), &reference);
            assert!(diff <= 1e-12, "{kind:?} {method:?} vs simplicial: {diff}");
        }
    }
}

#[test]
fn supernodal_unconstrained_piece_gives_a_zero_membrane() {
    let mesh = fixtures::disjoint_union(&fixtures::disc(3), &fixtures::grid(3, 3));
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let n = l.n;
    let first_piece = fixtures::disc(3).vertex_count();
    let wanted: Vec<bool> = (0..n)
        .map(|v| v < first_piece && mesh.is_boundary[v])
        .collect();
    for method in SUPERNODAL {
        let mut f = factor_with(&l, method, &wanted);
        let mut values = vec![1.0; n];
        f.solve_dirichlet(&mut values, 1);
        assert!(
            values[first_piece..].iter().all(|&v| v == 0.0),
            "{method:?}"
        );
        assert!(values[..first_piece]
            .iter()
            .all(|&v| (v - 1.0).abs() <= 1e-6));
    }
}

/// Random switches on a supernodal-derived factor (explicit zeros included for the relaxed
/// one) against fresh factorisations.
fn switches_match_fresh(l: &SymmetricCsc, method: FactorMethod, start: &[bool], steps: usize) {
    let n = l.n;
    let mut f = PenaltyFactor::new(l, &options(method)).unwrap();
    f.set_constrained(start).unwrap();
    let mut rng = Rng(method as u64 + 5);
    for step in 0..steps {
        if step % 10 == 9 {
            let batch: Vec<(usize, bool)> =
                (0..8).map(|_| (rng.below(n), rng.next() < 0.5)).collect();
            f.switch(&batch).unwrap();
        } else {
            let v = rng.below(n);
            f.switch(&[(v, !f.is_constrained(v))]).unwrap();
        }
    }
    let mut fresh = factor_with(l, FactorMethod::Simplicial, f.constrained());
    let k = 3;
    let b: Vec<f64> = (0..n * k).map(|_| rng.next() * 2.0 - 1.0).collect();
    let diff = rel_diff(&solve(&mut f, &b, k), &solve(&mut fresh, &b, k));
    assert!(diff <= 1e-9, "{method:?} after {steps} switches: {diff}");
    let mut dirichlet: Vec<f64> = b.iter().map(|v| 100.0 * v).collect();
    let mut dirichlet_fresh = dirichlet.clone();
    f.solve_dirichlet(&mut dirichlet, k);
    fresh.solve_dirichlet(&mut dirichlet_fresh, k);
    let diff = rel_diff(&dirichlet, &dirichlet_fresh);
    assert!(
        diff <= 1e-9,
        "{method:?} Dirichlet after {steps} switches: {diff}"
    );
}

#[test]
fn switching_on_a_supernodal_factor_matches_a_fresh_factorisation() {
    let mesh = fixtures::disc(10);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    for method in SUPERNODAL {
        switches_match_fresh(&l, method, &mesh.is_boundary, 2_000);
    }
}

#[test]
fn auto_goes_supernodal_above_the_crossover_and_switches_stay_exact() {
    let mesh = fixtures::disc_with_vertices(SUPERNODAL_MIN_VERTICES);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    assert!(SymbolicFactor::analyse(&l).unwrap().is_supernodal());
    let small = laplacian(&fixtures::disc(10), LaplacianKind::Combinatorial);
    assert!(!SymbolicFactor::analyse(&small).unwrap().is_supernodal());
    switches_match_fresh(&l, FactorMethod::Auto, &mesh.is_boundary, 300);
}

/// Dirichlet right-hand sides are zero off the constrained vertices, so the forward sweep
/// skips whole supernodes: the result must still be the dense solve of (L + P) x = P b,
/// for a boundary (few constraints, many skipped panels) and for a single vertex.
#[test]
fn sparse_dirichlet_right_hand_sides_match_a_dense_solve() {
    let mesh = fixtures::disc(10);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let n = l.n;
    let mut rng = Rng(23);
    let one_vertex: Vec<bool> = (0..n).map(|v| v == n / 2).collect();
    for wanted in [mesh.is_boundary.clone(), one_vertex] {
        for method in [FactorMethod::Simplicial, FactorMethod::Supernodal] {
            let mut f = factor_with(&l, method, &wanted);
            let mut a = l.to_dense();
            for (v, row) in a.iter_mut().enumerate() {
                row[v] += f.epsilon() + if wanted[v] { f.alpha() } else { 0.0 };
            }
            let k = 3;
            let targets: Vec<f64> = (0..n * k).map(|_| rng.next() * 2.0 - 1.0).collect();
            let mut x = targets.clone();
            f.solve_dirichlet(&mut x, k);
            for c in 0..k {
                let column = &targets[c * n..(c + 1) * n];
                let pb: Vec<f64> = (0..n)
                    .map(|v| {
                        if wanted[v] {
                            f.alpha() * column[v]
                        } else {
                            0.0
                        }
                    })
                    .collect();
                let diff = rel_diff(&x[c * n..(c + 1) * n], &dense_solve(&a, &pb));
                assert!(diff <= 1e-10, "{method:?} channel {c}: {diff}");
            }
        }
    }
}
