//! `lapclone clone`: one seamless clone of a source patch into a target image.

#[derive(clap::Args, Debug)]
pub struct CloneArgs {}

pub fn run(_args: CloneArgs) -> anyhow::Result<()> {
    anyhow::bail!("`lapclone clone` is not implemented yet")
}
