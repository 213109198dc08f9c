//! Rank-1 constraint switching: updated factors against fresh factorisations, and the guards.

use crate::mesh_fixtures as fixtures;
use lapclone::solve::{
    laplacian, LaplacianKind, PenaltyFactor, PenaltyOptions, SolveError, SymmetricCsc,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

use crate::checks;
use checks::{rel_diff, Rng};

/// Relative difference between the updated factor's solutions and a fresh factorisation's.
fn compare_with_fresh(
    l: &SymmetricCsc,
    f: &mut PenaltyFactor,
    opts: &PenaltyOptions,
    seed: u64,
) -> f64 {
    let n = l.n;
    let mut fresh = PenaltyFactor::new(l, opts).unwrap();
    fresh.set_constrained(f.constrained()).unwrap();
    // set_constrained may update rather than refactor; force a real fresh factorisation.
    fresh.refactor().unwrap();
    let mut rng = Rng(seed);
    let k = 3;
    let b: Vec<f64> = (0..n * k).map(|_| rng.next() * 2.0 - 1.0).collect();
    let (mut x_updated, mut x_fresh) = (b.clone(), b.clone());
    f.solve_in_place(&mut x_updated, k);
    fresh.solve_in_place(&mut x_fresh, k);
    let mut dirichlet_updated: Vec<f64> = b.iter().map(|v| v * 100.0).collect();
    let mut dirichlet_fresh = dirichlet_updated.clone();
    f.solve_dirichlet(&mut dirichlet_updated, k);
    fresh.solve_dirichlet(&mut dirichlet_fresh, k);
    rel_diff(&x_updated, &x_fresh).max(rel_diff(&dirichlet_updated, &dirichlet_fresh))
}

#[test]
fn ten_thousand_random_switches_match_a_fresh_factorisation() {
    let mesh = fixtures::disc(10);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let n = l.n;
    let opts = PenaltyOptions::default();
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    // Start from the boundary constrained, as the cloning stage does.
    f.set_constrained(&mesh.is_boundary).unwrap();
    let mut rng = Rng(2024);
    let (mut updates, mut downdates) = (0, 0);
    for step in 0..10_000 {
        let v = rng.below(n);
        let stats = f.switch(&[(v, !f.is_constrained(v))]).unwrap();
        updates += stats.updates;
        downdates += stats.downdates;
        if step % 2500 == 2499 {
            let diff = compare_with_fresh(&l, &mut f, &opts, step as u64);
            assert!(diff <= 1e-9, "after {step} switches: {diff}");
        }
    }
    assert_eq!(updates + downdates, 10_000);
    let diff = compare_with_fresh(&l, &mut f, &opts, 7);
    eprintln!("relative difference to a fresh factorisation after 10k switches: {diff:e}");
    assert!(diff <= 1e-9, "final: {diff}");
    // Refactorisations must stay the exception, not the rule.
    assert!(
        f.refactor_count() < 1000,
        "guard refactored {} times",
        f.refactor_count()
    );
    eprintln!("refactors after 10k switches: {}", f.refactor_count());
}

#[test]
fn batches_apply_updates_before_downdates_and_match_fresh() {
    let mesh = fixtures::grid(12, 9);
    let l = laplacian(&mesh, LaplacianKind::Cotangent);
    let n = l.n;
    let opts = PenaltyOptions::default();
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    f.set_constrained(&mesh.is_boundary).unwrap();
    let mut rng = Rng(31);
    for round in 0..200 {
        let changes: Vec<(usize, bool)> = (0..1 + rng.below(6))
            .map(|_| (rng.below(n), rng.next() < 0.5))
            .collect();
        let before = f.constrained_count();
        let stats = f.switch(&changes).unwrap();
        let after = f.constrained_count();
        assert_eq!(
            after as isize - before as isize,
            stats.updates as isize - stats.downdates as isize
        );
        // The last mention of a vertex wins.
        for &(v, _) in &changes {
            let last = changes.iter().rev().find(|c| c.0 == v).unwrap().1;
            assert_eq!(f.is_constrained(v), last, "round {round}");
        }
    }
    assert!(compare_with_fresh(&l, &mut f, &opts, 3) <= 1e-9);
}

#[test]
fn guard_refactors_when_the_last_constraint_of_a_piece_is_released() {
    let mesh = fixtures::grid(4, 4);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let opts = PenaltyOptions::default();
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    let stats = f.switch(&[(7, true)]).unwrap();
    assert!(!stats.refactored);
    // Releasing the only constraint sends a pivot from ≈ α down to ≈ ε: cancellation would
    // leave garbage, so the pivot guard must rebuild the factor.
    let stats = f.switch(&[(7, false)]).unwrap();
    assert!(stats.refactored, "pivot guard did not fire");
    assert_eq!(f.refactor_count(), 1);
    let mut zero = vec![0.0; l.n];
    f.solve_in_place(&mut zero, 1);
    assert!(zero.iter().all(|&x| x == 0.0));
    assert!(compare_with_fresh(&l, &mut f, &opts, 1) <= 1e-9);
}

#[test]
fn drift_guard_fires_once_the_budget_is_spent() {
    let mesh = fixtures::disc(6);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    // Every downdate adds at least one unit roundoff (≈ 1.1e-16) to the estimate.
    let opts = PenaltyOptions {
        drift_budget: 1e-15,
        ..Default::default()
    };
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    f.set_constrained(&mesh.is_boundary).unwrap();
    let interior = (0..l.n).find(|&v| !mesh.is_boundary[v]).unwrap();
    let refactors_before = f.refactor_count();
    let mut fired_after = None;
    for round in 1..=20 {
        f.switch(&[(interior, true)]).unwrap();
        let stats = f.switch(&[(interior, false)]).unwrap();
        if stats.refactored {
            fired_after = Some(round);
            break;
        }
        assert!(f.drift_estimate() > 0.0);
    }
    let fired_after = fired_after.expect("drift guard never fired");
    assert!(
        fired_after > 1,
        "fired on the first downdate: budget not accumulated"
    );
    assert_eq!(f.drift_estimate(), 0.0);
    assert_eq!(f.refactor_count(), refactors_before + 1);
}

/// A factor built with constraints on solves like one built without and switched: the
/// same constrained set, solutions within 1e-12 of a fresh refactor's; it then switches on
/// from there like any other factor.
#[test]
fn factors_built_constrained_match_factors_switched_on() {
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let mesh = fixtures::disc(9);
        let l = laplacian(&mesh, kind);
        let opts = PenaltyOptions::default();
        let mut built = PenaltyFactor::with_constrained(&l, &opts, &mesh.is_boundary).unwrap();
        let boundary = mesh.is_boundary.iter().filter(|&&b| b).count();
        assert_eq!(built.constrained(), &mesh.is_boundary[..]);
        assert_eq!(built.constrained_count(), boundary);
        assert_eq!(built.refactor_count(), 0);
        // Nothing to switch: the constrained set is already the wanted one.
        let stats = built.set_constrained(&mesh.is_boundary).unwrap();
        assert_eq!((stats.updates, stats.downdates), (0, 0));
        assert!(compare_with_fresh(&l, &mut built, &opts, 5) <= 1e-12);
        let mut rng = Rng(77);
        for _ in 0..200 {
            let v = rng.below(l.n);
            built.switch(&[(v, !built.is_constrained(v))]).unwrap();
        }
        assert!(compare_with_fresh(&l, &mut built, &opts, 6) <= 1e-9);
    }
    let l = laplacian(&fixtures::grid(2, 2), LaplacianKind::Combinatorial);
    assert!(matches!(
        PenaltyFactor::with_constrained(&l, &PenaltyOptions::default(), &[true]),
        Err(SolveError::WrongLength { got: 1, .. })
    ));
}

#[test]
fn bad_switch_input_is_an_error_and_changes_nothing() {
    let l = laplacian(&fixtures::grid(2, 2), LaplacianKind::Combinatorial);
    let mut f = PenaltyFactor::new(&l, &PenaltyOptions::default()).unwrap();
    assert!(matches!(
        f.switch(&[(0, true), (99, true)]),
        Err(SolveError::VertexOutOfRange { vertex: 99, .. })
    ));
    assert_eq!(f.constrained_count(), 0);
    assert!(matches!(
        f.set_constrained(&[true]),
        Err(SolveError::WrongLength { .. })
    ));
    let bad = PenaltyOptions {
        alpha: Some(-1.0),
        ..Default::default()
    };
    assert!(matches!(
        PenaltyFactor::new(&l, &bad),
        Err(SolveError::BadAlpha(_))
    ));
}

proptest! {
    #![proptest_config(Config { rng_seed: RngSeed::Fixed(0x5017E), cases: 24, failure_persistence: None, ..Config::default() })]
    #[test]
    fn random_switch_sequences_match_fresh(
        cols in 1usize..9, rows in 1usize..9, cotangent in any::<bool>(),
        switches in prop::collection::vec((0usize..100, any::<bool>()), 1..120),
    ) {
        let mesh = fixtures::grid(cols, rows);
        let kind = if cotangent { LaplacianKind::Cotangent } else { LaplacianKind::Combinatorial };
        let l = laplacian(&mesh, kind);
        let opts = PenaltyOptions::default();
        let mut f = PenaltyFactor::new(&l, &opts).unwrap();
        for chunk in switches.chunks(3) {
            let changes: Vec<(usize, bool)> = chunk.iter().map(|&(v, on)| (v % l.n, on)).collect();
            f.switch(&changes).unwrap();
        }
        prop_assert!(compare_with_fresh(&l, &mut f, &opts, 11) <= 1e-9);
    }
}

/// The batch guard refactors exactly when the summed path costs of the real switches exceed
/// the refactorisation estimate — small batches update, a whole-mesh batch refactors — and
/// either way the result matches a fresh factorisation.
#[test]
fn batch_guard_compares_path_costs_with_the_refactor_cost() {
    let mesh = fixtures::disc(12);
    let l = laplacian(&mesh, LaplacianKind::Combinatorial);
    let n = l.n;
    let opts = PenaltyOptions::default();
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    f.set_constrained(&mesh.is_boundary).unwrap();
    let interior: Vec<usize> = (0..n).filter(|&v| !mesh.is_boundary[v]).collect();
    let (mut updated, mut refactored) = (0, 0);
    for size in [1, 2, 4, 8, 16, 32, 64, 128, interior.len()] {
        let batch: Vec<(usize, bool)> = interior.iter().take(size).map(|&v| (v, true)).collect();
        let sym = f.symbolic();
        let cost: f64 = batch
            .iter()
            .map(|&(v, _)| sym.switch_cost(sym.position_of(v)))
            .sum();
        let expect_refactor = cost > sym.refactor_cost();
        let before = f.refactor_count();
        let stats = f.switch(&batch).unwrap();
        assert_eq!(stats.refactored, expect_refactor, "batch of {size}");
        assert_eq!(f.refactor_count(), before + usize::from(expect_refactor));
        if expect_refactor {
            refactored += 1;
        } else {
            updated += 1;
        }
        assert!(compare_with_fresh(&l, &mut f, &opts, size as u64) <= 1e-9);
        // Back to the boundary only (downdates; may refactor by the same rule).
        let release: Vec<(usize, bool)> = batch.iter().map(|&(v, _)| (v, false)).collect();
        f.switch(&release).unwrap();
    }
    assert!(
        updated >= 3 && refactored >= 1,
        "{updated} updated, {refactored} refactored"
    );
}
