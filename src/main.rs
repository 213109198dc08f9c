//! The `lapclone` command line: a thin wrapper over the library's CLI entry point (feature
//! `cli`), which parses arguments with clap and runs the subcommand. Exit codes: 0 ok,
//! 1 failure, 2 usage.

fn main() {
    std::process::exit(lapclone::run_cli());
}
