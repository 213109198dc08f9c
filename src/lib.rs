//! lapclone: seamless image cloning and deformation with the combinatorial Laplacian
//! (Cuadros-Vargas, Nonato, Pascucci). The library takes masks, images and scene files in
//! and gives meshes, factored Laplacians, membranes, deformed meshes and rendered frames
//! out; the `lapclone` binary is a thin CLI over it.
//!
//! The modules follow the pipeline: [`mesh`] → [`solve`] → [`clone`] / [`deform`] →
//! [`raster`], driven per frame by [`scene`]. [`pixels`] holds the float image type shared by
//! all stages; [`reference`](mod@reference) holds the pixel-grid and MVC baselines used by tests and benches;
//! [`limits`] the documented resource limits every input is checked against.

/// Declares the pipeline's stage modules: private in the library, public (and undocumented)
/// with the `internals` feature, which lapclone's own tests and `lapclone-bench` use.
macro_rules! stage_modules {
    ($($name:ident),* $(,)?) => {$(
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        pub mod $name;
        // Without `internals`, what only the tests and benchmarks reach is unused here.
        #[cfg(not(feature = "internals"))]
        #[allow(dead_code, unused_imports)]
        mod $name;
    )*};
}

stage_modules!(
    clone, deform, limits, mesh, output, pixels, raster, render, scene, script, solve, util,
);

// The CLI's files name library items as `lapclone::…`, as any other user would.
extern crate self as lapclone;

#[cfg(all(feature = "cli", feature = "internals"))]
#[doc(hidden)]
pub mod cli;
#[cfg(all(feature = "cli", not(feature = "internals")))]
mod cli;

/// The `lapclone` program: parses `std::env::args`, runs the subcommand, reports an error on
/// stderr and gives the exit code (0 ok, 1 failure, 2 usage). Only `src/main.rs` calls it.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub fn run_cli() -> i32 {
    use clap::Parser as _;
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => 0,
        Err(err) => {
            if let Some(usage) = err.downcast_ref::<cli::UsageError>() {
                eprintln!("lapclone: {usage}");
                return 2;
            }
            eprintln!("lapclone: error: {}", cli::describe(&err));
            1
        }
    }
}
