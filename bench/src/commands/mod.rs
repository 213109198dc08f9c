//! `lapclone-bench …`: takes a parsed subcommand and runs that benchmark of a stage (use a
//! release build), printing a table or JSON. The argument helpers are the `lapclone` CLI's
//! own, so shared flags parse and fail alike.

pub mod bench_browser;
pub mod bench_clone;
pub mod bench_deform;
pub mod bench_follow;
pub mod bench_mesh;
pub mod bench_opencv;
pub mod bench_paper;
pub mod bench_render;
pub mod bench_solver;
pub mod bench_track;
pub mod bench_view;
pub mod child_run;

pub use lapclone::cli::{describe, finite_f64, mesh_args, UsageError};

use bench_solver::{FactorBenchArgs, SolverBenchArgs};

/// One benchmark.
#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Factor, solve and rank-1 switch timings on a Matrix Market Laplacian.
    Solver(SolverBenchArgs),
    /// Analyse, factor, 3-RHS solve and switch timings on built-in disc meshes.
    Factor(FactorBenchArgs),
    /// Meshing timings over synthetic masks from 128² to 2000² (spiral family and others).
    Mesh(bench_mesh::MeshBenchArgs),
    /// Deformation timings (rig build, drag step, constraint switches) on disc fixtures.
    Deform(bench_deform::DeformBenchArgs),
    /// A 1920×1080 scene with two deforming patches: per-frame compute and PNG encoding.
    Render(bench_render::RenderBenchArgs),
    /// End-to-end clone timings: the paper's spiral (first clone, reclone) and a deform frame.
    Clone(bench_clone::CloneBenchArgs),
    /// The paper's Table I and Fig. 5: MVC vs combinatorial vs cotangent against the
    /// pixel-grid reference; `--sweep` writes the density table.
    Paper(bench_paper::PaperBenchArgs),
    /// Whole processes of the release `lapclone` binary against OpenCV and ffmpeg: a 1920×1080
    /// scene to PNG files against an OpenCV loop and to MP4 against PNG, and a 6000×5000
    /// clone against seamlessClone, with its peak memory.
    Opencv(bench_opencv::OpencvBenchArgs),
    /// Point tracking: 1920×1080 PNG footage against decoding alone and an OpenCV
    /// calcOpticalFlowPyrLK loop, and the tracked path's error beside OpenCV's.
    Track(bench_track::TrackBenchArgs),
    /// A 1920×1080 scene following a track against the same scene with its keys written
    /// out: whole `lapclone render` processes, interleaved.
    Follow(bench_follow::FollowBenchArgs),
    /// The live view's drag on 1920×1080 scenes (the cat; the horse folding over itself):
    /// pointer message in → changed pixels out, through the release `lapclone repl --view`.
    View(bench_view::ViewBenchArgs),
    /// The live view's drag in headless chromium on the same scenes, pointer moves at 60 Hz
    /// by default: pointer event → pixels painted (the page's own timing), updates painted
    /// per second and where the time went.
    Browser(bench_browser::BrowserBenchArgs),
}

/// Runs one benchmark.
pub fn run(which: BenchCommand) -> anyhow::Result<()> {
    match which {
        BenchCommand::Solver(args) => bench_solver::run_solver(args),
        BenchCommand::Factor(args) => bench_solver::run_factor(args),
        BenchCommand::Mesh(args) => bench_mesh::run(args),
        BenchCommand::Deform(args) => bench_deform::run(args),
        BenchCommand::Render(args) => bench_render::run(args),
        BenchCommand::Clone(args) => bench_clone::run(args),
        BenchCommand::Paper(args) => bench_paper::run(args),
        BenchCommand::Opencv(args) => bench_opencv::run(args),
        BenchCommand::Track(args) => bench_track::run(args),
        BenchCommand::Follow(args) => bench_follow::run(args),
        BenchCommand::View(args) => bench_view::run(args),
        BenchCommand::Browser(args) => bench_browser::run(args),
    }
}
