//! The `lapclone-bench` command line: parses arguments with clap and runs one benchmark
//! (use a release build). Exit codes: 0 ok, 1 failure, 2 usage.

use clap::Parser;
use lapclone_bench::commands::{self, BenchCommand, UsageError};

#[derive(Parser, Debug)]
#[command(
    name = "lapclone-bench",
    version,
    about = "lapclone's benchmarks and quality study (release builds only give meaningful figures)"
)]
struct Cli {
    #[command(subcommand)]
    which: BenchCommand,
}

fn main() {
    let cli = Cli::parse();
    if let Err(err) = commands::run(cli.which) {
        if let Some(usage) = err.downcast_ref::<UsageError>() {
            eprintln!("lapclone-bench: {usage}");
            std::process::exit(2);
        }
        eprintln!("lapclone-bench: error: {}", commands::describe(&err));
        std::process::exit(1);
    }
}
