//! `lapclone-bench solver` and `lapclone-bench factor`: timings of the solve stage —
//! analyse, factor, 3-RHS solve and rank-1 switches — on a Matrix Market Laplacian or on the
//! built-in disc meshes. Release builds only give meaningful figures.

use crate::fixtures;
use crate::matrix_market::{read_constrained_list, read_matrix_market};
use anyhow::Context;
use lapclone::simd::Path;
use lapclone::solve::solve::ldlt_solve_interleaved;
use lapclone::solve::solve_supernodal::{inverse_diagonal, ldlt_solve_supernodal_at};
use lapclone::solve::{
    laplacian, write_matrix_market, FactorMethod, LaplacianKind, PenaltyFactor, PenaltyOptions,
    SymmetricCsc,
};
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct SolverBenchArgs {
    /// Laplacian in Matrix Market coordinate format (as written by `lapclone mesh --laplacian-out`).
    pub matrix: PathBuf,
    /// File with one constrained (0-based) vertex index per line.
    #[arg(long)]
    pub constrained: PathBuf,
    /// Penalty weight (default: relative to the matrix scale).
    #[arg(long, value_parser = super::finite_f64)]
    pub alpha: Option<f64>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Numeric factorisation.
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    pub method: MethodArg,
}

/// `--method` values.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum MethodArg {
    Auto,
    Simplicial,
    Supernodal,
    Relaxed,
}

impl From<MethodArg> for FactorMethod {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Auto => FactorMethod::Auto,
            MethodArg::Simplicial => FactorMethod::Simplicial,
            MethodArg::Supernodal => FactorMethod::Supernodal,
            MethodArg::Relaxed => FactorMethod::SupernodalRelaxed,
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct FactorBenchArgs {
    /// Approximate vertex counts of the disc meshes.
    #[arg(long, value_delimiter = ',', default_values_t = vec![2_034usize, 52_054, 495_037])]
    pub sizes: Vec<usize>,
    /// Use cotangent instead of combinatorial weights.
    #[arg(long)]
    pub cotangent: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Numeric factorisation.
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    pub method: MethodArg,
    /// Also write each Laplacian as `disc_<n>.mtx` and its constrained (boundary) vertices as
    /// `disc_<n>.constrained` into this folder, for `benches/cholmod/reference.py`.
    #[arg(long)]
    pub matrix_out: Option<PathBuf>,
}

/// Timings of one matrix, milliseconds (best of several runs).
#[derive(serde::Serialize, Debug)]
struct Timings {
    n: usize,
    nnz_factor: usize,
    analyze_ms: f64,
    factor_ms: f64,
    /// Dirichlet right-hand sides (zero off the constrained vertices), as the cloning solves.
    solve3_ms: f64,
    /// Dense right-hand sides (every entry non-zero), as CHOLMOD's reference figures.
    solve3_dense_ms: f64,
    /// The supernodal kernel alone (dense right-hand sides already permuted, 3 channels in
    /// rows of 4), compiled for this CPU.
    solve3_kernel_ms: f64,
    /// The same kernel on the portable path (baseline instruction set, same bits).
    solve3_portable_ms: f64,
    /// The column-by-column kernel on the same factor (the pre-supernodal solve), for comparison.
    solve3_column_ms: f64,
    update_ms: f64,
    switch100_ms: f64,
    refactor_ms: f64,
}

const RUNS: usize = 5;

fn best_ms(runs: usize, mut work: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let start = Instant::now();
            work();
            start.elapsed().as_secs_f64() * 1e3
        })
        .fold(f64::INFINITY, f64::min)
}

/// Best of at least `RUNS * 4` runs, more for short work: runs until [`SOLVE_BUDGET_MS`]
/// are spent (at most 5,000), so a sub-millisecond solve on a shared machine gets enough
/// tries to catch an undisturbed one.
fn best_ms_budgeted(mut work: impl FnMut()) -> f64 {
    let started = Instant::now();
    let mut best = f64::INFINITY;
    let mut runs = 0;
    while runs < RUNS * 4
        || (runs < 5_000 && started.elapsed().as_secs_f64() * 1e3 < SOLVE_BUDGET_MS)
    {
        best = best.min(best_ms(1, &mut work));
        runs += 1;
    }
    best
}

/// Time budget of [`best_ms_budgeted`].
const SOLVE_BUDGET_MS: f64 = 300.0;

fn measure(
    l: &SymmetricCsc,
    constrained: &[usize],
    alpha: Option<f64>,
    method: FactorMethod,
) -> anyhow::Result<Timings> {
    let opts = PenaltyOptions {
        alpha,
        method,
        ..Default::default()
    };
    let runs = if l.n > 200_000 { 2 } else { RUNS };
    let analyze_ms = best_ms(runs, || {
        let _ = lapclone::solve::symbolic::SymbolicFactor::analyse_with(l, method);
    });
    let mut factor = PenaltyFactor::new(l, &opts)?;
    let mut wanted = vec![false; l.n];
    constrained.iter().for_each(|&v| wanted[v] = true);
    factor.set_constrained(&wanted)?;
    let mut failure = None;
    let factor_ms = best_ms(runs, || {
        if let Err(e) = factor.refactor() {
            failure = Some(e);
        }
    });
    if let Some(e) = failure {
        return Err(e.into());
    }
    let rhs: Vec<f64> = (0..3 * l.n)
        .map(|i| ((i * 7919) % 1000) as f64 / 1000.0)
        .collect();
    let mut work = rhs.clone();
    let solve3_ms = best_ms_budgeted(|| {
        work.copy_from_slice(&rhs);
        factor.solve_dirichlet(&mut work, 3);
    });
    let solve3_dense_ms = best_ms_budgeted(|| {
        work.copy_from_slice(&rhs);
        factor.solve_in_place(&mut work, 3);
    });
    let kernels = kernel_ms(&factor, &rhs);
    let (update_ms, switch100_ms) = switch_ms(&mut factor, constrained, runs);
    Ok(Timings {
        n: l.n,
        nnz_factor: factor.nnz_factor(),
        analyze_ms,
        factor_ms,
        solve3_ms,
        solve3_dense_ms,
        solve3_kernel_ms: kernels.vector,
        solve3_portable_ms: kernels.portable,
        solve3_column_ms: kernels.column,
        update_ms,
        switch100_ms,
        refactor_ms: factor_ms,
    })
}

/// Best-of times, ms, of one constraint switch (a downdate plus the update restoring it,
/// halved) and of 100 switched off and back on (halved).
fn switch_ms(factor: &mut PenaltyFactor, constrained: &[usize], runs: usize) -> (f64, f64) {
    let probe = constrained.get(constrained.len() / 2).copied().unwrap_or(0);
    let update_ms = best_ms(RUNS * 4, || {
        let _ = factor.switch(&[(probe, !factor.is_constrained(probe))]);
        let _ = factor.switch(&[(probe, !factor.is_constrained(probe))]);
    }) / 2.0;
    let hundred: Vec<usize> = constrained
        .iter()
        .step_by((constrained.len() / 100).max(1))
        .take(100)
        .copied()
        .collect();
    let switch100_ms = best_ms(runs, || {
        for &v in &hundred {
            let _ = factor.switch(&[(v, false)]);
        }
        for &v in &hundred {
            let _ = factor.switch(&[(v, true)]);
        }
    }) / 2.0;
    (update_ms, switch100_ms)
}

/// Best-of timings of the solve kernels, ms.
struct KernelTimings {
    vector: f64,
    portable: f64,
    column: f64,
}

/// Best-of timings of the solve kernels on `factor` (3 right-hand sides, already in factor
/// order): the supernodal one on either [`Path`], and the column one it replaced.
fn kernel_ms(factor: &PenaltyFactor, rhs: &[f64]) -> KernelTimings {
    let symbolic = factor.symbolic();
    let values = factor.factor_values();
    let n = symbolic.n();
    let mut inv_diagonal = vec![0.0; n];
    inverse_diagonal(symbolic, values, &mut inv_diagonal);
    let rows: Vec<f64> = (0..4 * n)
        .map(|i| {
            if i % 4 == 3 {
                0.0
            } else {
                rhs[i / 4 * 3 + i % 4]
            }
        })
        .collect();
    let mut x = rows.clone();
    let mut sweeps = |path: Path| {
        best_ms_budgeted(|| {
            x.copy_from_slice(&rows);
            ldlt_solve_supernodal_at(path, symbolic, values, &inv_diagonal, &mut x, 4);
        })
    };
    let (vector, portable) = (sweeps(Path::Vector), sweeps(Path::Portable));
    let mut x = rhs.to_vec();
    let column = best_ms_budgeted(|| {
        x.copy_from_slice(rhs);
        ldlt_solve_interleaved(symbolic.col_ptr(), symbolic.row_idx(), values, &mut x, 3);
    });
    KernelTimings {
        vector,
        portable,
        column,
    }
}

fn print(rows: &[Timings], json: bool) -> anyhow::Result<()> {
    if json {
        let text = if rows.len() == 1 {
            serde_json::to_string(&rows[0])?
        } else {
            serde_json::to_string(rows)?
        };
        println!("{text}");
        return Ok(());
    }
    println!(
        "{:>9} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11} {:>13}",
        "n",
        "nnz(L)",
        "analyse ms",
        "factor ms",
        "solve3 ms",
        "dense3 ms",
        "kernel ms",
        "portable ms",
        "column ms",
        "switch ms",
        "100 switch ms"
    );
    for t in rows {
        println!(
            "{:>9} {:>11} {:>11.3} {:>11.3} {:>11.4} {:>11.4} {:>11.4} {:>11.4} {:>11.4} {:>11.4} {:>13.3}",
            t.n,
            t.nnz_factor,
            t.analyze_ms,
            t.factor_ms,
            t.solve3_ms,
            t.solve3_dense_ms,
            t.solve3_kernel_ms,
            t.solve3_portable_ms,
            t.solve3_column_ms,
            t.update_ms,
            t.switch100_ms
        );
    }
    println!(
        "solve3 = PenaltyFactor::solve_dirichlet, 3 channels (permutations included); dense3 = \
         solve_in_place with a dense right-hand side; kernel = the supernodal sweeps alone \
         (compiled for this CPU); portable = the same sweeps at the baseline instruction set; \
         column = the column-by-column sweeps they replaced"
    );
    Ok(())
}

pub fn run_solver(args: SolverBenchArgs) -> anyhow::Result<()> {
    let l = read_matrix_market(&args.matrix)?;
    let constrained = read_constrained_list(&args.constrained, l.n)?;
    if constrained.is_empty() {
        return Err(super::UsageError(format!(
            "{}: no constrained vertex listed",
            args.constrained.display()
        ))
        .into());
    }
    let timings =
        measure(&l, &constrained, args.alpha, args.method.into()).context("benchmark failed")?;
    print(&[timings], args.json)
}

pub fn run_factor(args: FactorBenchArgs) -> anyhow::Result<()> {
    let kind = if args.cotangent {
        LaplacianKind::Cotangent
    } else {
        LaplacianKind::Combinatorial
    };
    let mut rows = Vec::new();
    for &size in &args.sizes {
        let mesh = fixtures::disc_with_vertices(size);
        let l = laplacian(&mesh, kind);
        let boundary: Vec<usize> = (0..l.n).filter(|&v| mesh.is_boundary[v]).collect();
        if let Some(folder) = &args.matrix_out {
            write_disc(folder, &l, &boundary)?;
        }
        rows.push(measure(&l, &boundary, None, args.method.into())?);
    }
    print(&rows, args.json)
}

/// `disc_<n>.mtx` and `disc_<n>.constrained` (one 0-based index per line) in `folder`.
fn write_disc(
    folder: &std::path::Path,
    l: &SymmetricCsc,
    constrained: &[usize],
) -> anyhow::Result<()> {
    std::fs::create_dir_all(folder).with_context(|| format!("creating {}", folder.display()))?;
    let stem = folder.join(format!("disc_{}", l.n));
    write_matrix_market(&stem.with_extension("mtx"), l, "")?;
    let list: String = constrained.iter().map(|v| format!("{v}\n")).collect();
    let path = stem.with_extension("constrained");
    std::fs::write(&path, list).with_context(|| format!("writing {}", path.display()))
}
