//! `lapclone bench …`: benchmarks of each stage (use a release build).

use super::bench_solver::{FactorBenchArgs, SolverBenchArgs};

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub which: BenchCommand,
}

#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Factor, solve and rank-1 switch timings on a Matrix Market Laplacian.
    Solver(SolverBenchArgs),
    /// Analyse, factor, 3-RHS solve and switch timings on built-in disc meshes.
    Factor(FactorBenchArgs),
    /// Meshing timings over synthetic masks from 128² to 2000² (spiral family and others).
    Mesh(super::bench_mesh::MeshBenchArgs),
    /// Deformation timings (rig build, drag step, constraint switches) on disc fixtures.
    Deform(super::bench_deform::DeformBenchArgs),
    /// The paper's Table I and Fig. 5: MVC vs combinatorial vs cotangent against the
    /// pixel-grid reference; `--sweep` writes the density table.
    Paper(super::bench_paper::PaperBenchArgs),
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    match args.which {
        BenchCommand::Solver(args) => super::bench_solver::run_solver(args),
        BenchCommand::Factor(args) => super::bench_solver::run_factor(args),
        BenchCommand::Mesh(args) => super::bench_mesh::run(args),
        BenchCommand::Deform(args) => super::bench_deform::run(args),
        BenchCommand::Paper(args) => super::bench_paper::run(args),
    }
}
