//! Supernodal solve: the supernode partition detected from the factor pattern, and the
//! panel kernel against the column kernel it replaced (≤ 1e-12 relative), for factors with
//! and without relaxed supernodes, every channel count and both SIMD paths (which must agree
//! bit for bit); random meshes
//! and right-hand sides by proptest with a fixed seed.

use crate::mesh_fixtures as fixtures;
use lapclone::mesh::Mesh;
use lapclone::solve::solve::ldlt_solve_interleaved;
use lapclone::solve::solve_supernodal::{inverse_diagonal, lanes_for, ldlt_solve_supernodal_at};
use lapclone::solve::symbolic::SymbolicFactor;
use lapclone::solve::{laplacian, FactorMethod, LaplacianKind, PenaltyFactor, PenaltyOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

use crate::checks;
use checks::{mixed_mesh as mesh, rel_diff, simd_levels as levels, METHODS};

fn factor(mesh: &Mesh, method: FactorMethod, constrained_every: usize) -> PenaltyFactor {
    let l = laplacian(mesh, LaplacianKind::Cotangent);
    let opts = PenaltyOptions {
        method,
        ..Default::default()
    };
    let mut f = PenaltyFactor::new(&l, &opts).unwrap();
    let wanted: Vec<bool> = (0..l.n)
        .map(|v| mesh.is_boundary[v] || v % constrained_every == 0)
        .collect();
    f.set_constrained(&wanted).unwrap();
    f
}

/// Detection agrees with the definition, column by column: a supernode is a maximal run in
/// which each column is the previous one minus its diagonal.
fn check_partition(symbolic: &SymbolicFactor) {
    let (cp, ri) = (symbolic.col_ptr(), symbolic.row_idx());
    let column = |j: usize| &ri[cp[j] as usize..cp[j + 1] as usize];
    let partition = symbolic.supernodes();
    partition.sanity_check(cp, ri).unwrap();
    let n = symbolic.n();
    let mut starts = vec![0u32];
    for j in 1..n {
        if column(j) != &column(j - 1)[1..] {
            starts.push(j as u32);
        }
    }
    starts.push(n as u32);
    assert_eq!(partition.begins(), &starts[..]);
    for s in 0..partition.count() {
        assert_eq!(partition.panel_rows(s), column(partition.columns(s).start));
    }
    let tallest = (0..partition.count())
        .map(|s| partition.panel_rows(s).len())
        .max()
        .unwrap_or(0);
    assert_eq!(partition.max_height(), tallest);
}

/// Supernodal solve (every supported level) of `channels` right-hand sides vs the column
/// kernel on the same factor.
fn check_against_column_kernel(f: &PenaltyFactor, channels: usize, seed: u64) {
    let symbolic = f.symbolic();
    let values = f.factor_values();
    let n = symbolic.n();
    let mut inv = vec![0.0; n];
    inverse_diagonal(symbolic, values, &mut inv);
    let mut state = seed;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let b: Vec<f64> = (0..n * channels).map(|_| next()).collect();
    let mut reference = b.clone();
    ldlt_solve_interleaved(
        symbolic.col_ptr(),
        symbolic.row_idx(),
        values,
        &mut reference,
        channels,
    );
    let lanes = lanes_for(channels);
    let mut bits: Vec<Vec<u64>> = Vec::new();
    for level in levels() {
        let mut x = vec![0.0; n * lanes];
        for i in 0..n {
            x[i * lanes..i * lanes + channels]
                .copy_from_slice(&b[i * channels..(i + 1) * channels]);
        }
        ldlt_solve_supernodal_at(level, symbolic, values, &inv, &mut x, lanes);
        let solved: Vec<f64> = (0..n * channels)
            .map(|k| x[k / channels * lanes + k % channels])
            .collect();
        bits.push(x.iter().map(|v| v.to_bits()).collect());
        let diff = rel_diff(&solved, &reference);
        assert!(
            diff <= 1e-12,
            "{level:?}, {channels} channels, {} supernodes: {diff:e}",
            symbolic.supernodes().count()
        );
    }
    assert!(
        bits.windows(2).all(|w| w[0] == w[1]),
        "the vector and portable paths must give the same bits"
    );
}

#[test]
fn partition_matches_the_pattern_for_every_factor_kind() {
    for kind in 0..3 {
        let m = mesh(kind, 9);
        let l = laplacian(&m, LaplacianKind::Combinatorial);
        for method in METHODS {
            check_partition(&SymbolicFactor::analyse_with(&l, method).unwrap());
        }
    }
}

#[test]
fn relaxed_factors_have_wider_supernodes_with_explicit_zeros() {
    let l = laplacian(&fixtures::disc(12), LaplacianKind::Combinatorial);
    let fundamental = SymbolicFactor::analyse_with(&l, FactorMethod::Supernodal).unwrap();
    let relaxed = SymbolicFactor::analyse_with(&l, FactorMethod::SupernodalRelaxed).unwrap();
    // Otherwise the relaxed cases below would not exercise stored zeros inside panels.
    assert!(relaxed.supernodes().count() < fundamental.supernodes().count());
    assert!(relaxed.nnz_factor() > fundamental.nnz_factor());
    let widest = |s: &SymbolicFactor| {
        (0..s.supernodes().count())
            .map(|k| s.supernodes().columns(k).len())
            .max()
            .unwrap()
    };
    // Wider than one forward/backward block, so the block loop is exercised.
    assert!(widest(&fundamental) > 8);
}

#[test]
fn supernodal_solve_matches_the_column_kernel_on_fixed_meshes() {
    for method in METHODS {
        let f = factor(&fixtures::disc(14), method, 7);
        for channels in 1..=4 {
            check_against_column_kernel(&f, channels, channels as u64 + 1);
        }
    }
}

proptest! {
    #![proptest_config(Config {
        cases: 24,
        rng_seed: RngSeed::Fixed(0x0005_eed3),
        failure_persistence: None,
        ..Config::default()
    })]

    #[test]
    fn supernodal_solve_matches_the_column_kernel(
        kind in 0u8..3,
        size in 2usize..12,
        method in 0usize..3,
        constrained_every in 2usize..9,
        channels in 1usize..=4,
        seed in any::<u64>(),
    ) {
        let m = mesh(kind, size);
        let f = factor(&m, METHODS[method], constrained_every);
        check_partition(f.symbolic());
        check_against_column_kernel(&f, channels, seed);
    }
}

#[test]
fn penalty_solves_match_the_column_kernel_for_up_to_six_channels() {
    for method in METHODS {
        let mut f = factor(&fixtures::disc(10), method, 5);
        let n = f.n();
        let symbolic = f.symbolic();
        let values = f.factor_values().to_vec();
        let k = 6;
        let b: Vec<f64> = (0..n * k)
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.5)
            .collect();
        // Reference: permute, column kernel per channel, permute back.
        let fwd = symbolic.perm_fwd().to_vec();
        let mut reference = vec![0.0; n * k];
        for c in 0..k {
            let mut y: Vec<f64> = fwd.iter().map(|&v| b[c * n + v as usize]).collect();
            ldlt_solve_interleaved(symbolic.col_ptr(), symbolic.row_idx(), &values, &mut y, 1);
            for (pos, &v) in fwd.iter().enumerate() {
                reference[c * n + v as usize] = y[pos];
            }
        }
        let mut x = b.clone();
        f.solve_in_place(&mut x, k);
        assert!(rel_diff(&x, &reference) <= 1e-12, "{method:?}");
    }
}

#[test]
fn dirichlet_ignores_unconstrained_inputs_even_nan() {
    let mesh = fixtures::disc(8);
    let mut f = factor(&mesh, FactorMethod::Auto, 6);
    let n = f.n();
    let k = 3;
    let targets: Vec<f64> = (0..n * k).map(|i| (i % 17) as f64).collect();
    let mut with_zeros = targets.clone();
    let mut with_nan = targets.clone();
    for v in 0..n {
        if !f.is_constrained(v) {
            for c in 0..k {
                with_zeros[c * n + v] = 0.0;
                with_nan[c * n + v] = f64::NAN;
            }
        }
    }
    f.solve_dirichlet(&mut with_zeros, k);
    f.solve_dirichlet(&mut with_nan, k);
    assert!(with_nan.iter().all(|v| v.is_finite()));
    assert_eq!(with_zeros, with_nan);
    for v in (0..n).filter(|&v| f.is_constrained(v)) {
        for c in 0..k {
            assert!((with_zeros[c * n + v] - targets[c * n + v]).abs() <= 1e-6);
        }
    }
}

#[test]
fn repeated_solves_are_bit_identical() {
    let mesh = fixtures::grid(20, 14);
    let mut f = factor(&mesh, FactorMethod::SupernodalRelaxed, 4);
    let n = f.n();
    let b: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut first = b.clone();
    f.solve_dirichlet(&mut first, 3);
    for _ in 0..3 {
        let mut again = b.clone();
        f.solve_dirichlet(&mut again, 3);
        assert!(first
            .iter()
            .zip(&again)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
