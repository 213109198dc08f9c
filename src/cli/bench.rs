//! `lapclone bench …`: benchmarks of each stage (use a release build).

use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub which: BenchCommand,
}

#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Factor, solve and rank-1 switch timings on a Matrix Market Laplacian.
    Solver(SolverBenchArgs),
    /// Deformation timings (rig build, drag step, constraint switches) on disc fixtures.
    Deform(super::bench_deform::DeformBenchArgs),
}

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
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    match args.which {
        BenchCommand::Solver(_) => anyhow::bail!("`lapclone bench solver` is not implemented yet"),
        BenchCommand::Deform(args) => super::bench_deform::run(args),
    }
}
