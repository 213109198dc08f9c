//! Two-thread solve schedule: the split passes its race-freedom check on random meshes;
//! the scheduled sweeps match the column kernel (≤ 1e-12 relative) at every SIMD level, and
//! give the same bits for 1, 2 and 3 threads; a [`PenaltyFactor`] with a schedule matches one
//! without; only large factors get one by default. Random meshes by proptest, fixed seed.

use lapclone::mesh::Mesh;
use lapclone::solve::schedule::SolveSchedule;
use lapclone::solve::solve::ldlt_solve_interleaved;
use lapclone::solve::solve_supernodal::{inverse_diagonal, lanes_for, ldlt_solve_scheduled_at};
use lapclone::solve::symbolic::SymbolicFactor;
use lapclone::solve::{
    fixtures, laplacian, FactorMethod, LaplacianKind, PenaltyFactor, PenaltyOptions, SchedulePolicy,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

use crate::checks;
use checks::{mixed_mesh as mesh, rel_diff, simd_levels as levels, METHODS};

fn factor(mesh: &Mesh, method: FactorMethod, schedule: SchedulePolicy) -> PenaltyFactor {
    let l = laplacian(mesh, LaplacianKind::Combinatorial);
    let opts = PenaltyOptions {
        method,
        schedule,
        ..Default::default()
    };
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    let wanted: Vec<bool> = (0..l.n)
        .map(|v| mesh.is_boundary[v] || v % 11 == 0)
        .collect();
    f.set_constrained(&wanted).unwrap();
    f
}

fn random_rows(len: usize, seed: u64) -> Vec<f64> {
    let mut state = seed;
    (0..len)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

/// The scheduled kernel against the column kernel, at every level and thread count; the
/// thread counts must agree bit for bit and leave the spill zero.
fn check_scheduled_kernel(f: &PenaltyFactor, channels: usize, seed: u64) {
    let symbolic = f.symbolic();
    assert!(
        symbolic.schedule().is_some(),
        "the factor must have a schedule"
    );
    let values = f.factor_values();
    let n = symbolic.n();
    let mut inv = vec![0.0; n];
    inverse_diagonal(symbolic, values, &mut inv);
    let b = random_rows(n * channels, seed);
    let mut reference = b.clone();
    ldlt_solve_interleaved(
        symbolic.col_ptr(),
        symbolic.row_idx(),
        values,
        &mut reference,
        channels,
    );
    let lanes = lanes_for(channels);
    for level in levels() {
        let mut first: Option<Vec<f64>> = None;
        for threads in [1, 2, 3] {
            let mut x = vec![0.0; n * lanes];
            for i in 0..n {
                x[i * lanes..i * lanes + channels]
                    .copy_from_slice(&b[i * channels..(i + 1) * channels]);
            }
            let mut spill = vec![0.0; n * lanes];
            ldlt_solve_scheduled_at(
                level, symbolic, values, &inv, &mut x, lanes, &mut spill, threads,
            );
            assert!(spill.iter().all(|&v| v == 0.0), "spill left non-zero");
            let solved: Vec<f64> = (0..n * channels)
                .map(|k| x[k / channels * lanes + k % channels])
                .collect();
            let diff = rel_diff(&solved, &reference);
            assert!(diff <= 1e-12, "{level:?}, {threads} threads: {diff:e}");
            match &first {
                None => first = Some(x),
                Some(one_thread) => assert!(
                    one_thread
                        .iter()
                        .zip(&x)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{level:?}: {threads} threads differ from 1"
                ),
            }
        }
    }
}

proptest! {
    #![proptest_config(Config {
        cases: 24,
        rng_seed: RngSeed::Fixed(0x5c4e_d01e),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn splits_of_random_meshes_pass_the_race_check(
        kind in 0u8..3,
        size in 1usize..14,
        method in 0usize..3,
    ) {
        let l = laplacian(&mesh(kind, size), LaplacianKind::Combinatorial);
        let symbolic = SymbolicFactor::analyse_with(&l, METHODS[method]).unwrap();
        let partition = symbolic.supernodes();
        let schedule = SolveSchedule::split(partition);
        schedule.sanity_check(partition).unwrap();
        let total: u64 = (0..partition.count())
            .map(|s| {
                let (w, h) = (partition.columns(s).len() as u64, partition.panel_rows(s).len() as u64);
                w * h - w * (w - 1) / 2
            })
            .sum();
        prop_assert_eq!(schedule.work().iter().sum::<u64>(), total);
    }

    #[test]
    fn scheduled_solves_match_the_column_kernel_for_every_thread_count(
        kind in 0u8..3,
        size in 3usize..14,
        method in 0usize..3,
        channels in 1usize..=4,
        seed in any::<u64>(),
    ) {
        let f = factor(&mesh(kind, size), METHODS[method], SchedulePolicy::Always);
        check_scheduled_kernel(&f, channels, seed);
    }
}

#[test]
fn a_wide_disc_splits_evenly() {
    let l = laplacian(&fixtures::disc(30), LaplacianKind::Combinatorial);
    let symbolic = SymbolicFactor::analyse_with(&l, FactorMethod::SupernodalRelaxed).unwrap();
    let [a, b, top] = SolveSchedule::split(symbolic.supernodes()).work();
    // Without a real split the threaded sweeps would not be exercised at all.
    assert!(a > 0 && b > 0, "{a} {b} {top}");
    assert!(a.max(b) + top < (a + b + top) * 3 / 4, "{a} {b} {top}");
}

#[test]
fn penalty_factors_with_and_without_a_schedule_agree() {
    // Odd and even vertex counts: two threads permute half of the rows each.
    for (m, method) in [0, 1, 2]
        .into_iter()
        .flat_map(|kind| METHODS.map(|method| (mesh(kind, 15), method)))
    {
        let mut split = factor(&m, method, SchedulePolicy::Always);
        let mut whole = factor(&m, method, SchedulePolicy::Never);
        assert!(whole.symbolic().schedule().is_none());
        let n = split.n();
        let b = random_rows(n * 3, 7);
        let (mut x, mut y) = (b.clone(), b.clone());
        split.solve_dirichlet(&mut x, 3);
        whole.solve_dirichlet(&mut y, 3);
        assert!(rel_diff(&x, &y) <= 1e-12, "{method:?}, n = {n}");
        let (mut x, mut y) = (b.clone(), b.clone());
        split.solve_in_place(&mut x, 3);
        whole.solve_in_place(&mut y, 3);
        assert!(rel_diff(&x, &y) <= 1e-12, "{method:?}");
        let mut one_thread = b.clone();
        split.set_solve_threads(1);
        split.solve_in_place(&mut one_thread, 3);
        assert_eq!(
            one_thread, x,
            "{method:?}: thread counts must agree bit for bit"
        );
    }
}

#[test]
fn only_large_factors_get_a_schedule_by_default() {
    let small = laplacian(
        &fixtures::disc_with_vertices(2_000),
        LaplacianKind::Combinatorial,
    );
    assert!(SymbolicFactor::analyse(&small)
        .unwrap()
        .schedule()
        .is_none());
    let large = laplacian(
        &fixtures::disc_with_vertices(20_000),
        LaplacianKind::Combinatorial,
    );
    let symbolic = SymbolicFactor::analyse(&large).unwrap();
    let schedule = symbolic
        .schedule()
        .expect("a 20k-vertex disc is worth two threads");
    schedule.sanity_check(symbolic.supernodes()).unwrap();
}
