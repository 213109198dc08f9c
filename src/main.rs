//! The `lapclone` command line: parses arguments with clap and hands each subcommand to its
//! file under `src/cli/`. Exit codes: 0 ok, 1 failure, 2 usage.

mod cli;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => {}
        Err(err) => {
            if let Some(usage) = err.downcast_ref::<cli::UsageError>() {
                eprintln!("lapclone: {usage}");
                std::process::exit(2);
            }
            eprintln!("lapclone: error: {}", cli::describe(&err));
            std::process::exit(1);
        }
    }
}
