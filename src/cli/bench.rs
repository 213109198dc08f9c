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
    /// A 1920×1080 scene with two deforming patches: per-frame compute and PNG encoding.
    Render(super::bench_render::RenderBenchArgs),
    /// End-to-end clone timings: the paper's spiral (first clone, reclone) and a deform frame.
    Clone(super::bench_clone::CloneBenchArgs),
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
        BenchCommand::Render(args) => super::bench_render::run(args),
        BenchCommand::Clone(args) => super::bench_clone::run(args),
        BenchCommand::Paper(args) => super::bench_paper::run(args),
    }
}
