//! The `lapclone` command line: a thin wrapper over the library's CLI entry point (feature
//! `cli`), which parses arguments with clap and runs the subcommand. Exit codes: 0 ok,
//! 1 failure, 2 usage.

#![forbid(unsafe_code)]

/// The system allocator, counting the bytes in use (no limit of its own): scene evaluation
/// checks its memory budget against the count.
#[global_allocator]
static ALLOCATOR: cap::Cap<std::alloc::System> = cap::Cap::new(std::alloc::System, usize::MAX);

fn main() {
    lapclone::set_allocation_probe(|| ALLOCATOR.allocated());
    std::process::exit(lapclone::run_cli());
}
