//! `lapclone repl`: interactive scene editing.

#[derive(clap::Args, Debug)]
pub struct ReplArgs {}

pub fn run(_args: ReplArgs) -> anyhow::Result<()> {
    anyhow::bail!("`lapclone repl` is not implemented yet")
}
