//! `lapclone render`, `preview` and `check`: scene files to frames.

#[derive(clap::Args, Debug)]
pub struct RenderArgs {}
#[derive(clap::Args, Debug)]
pub struct PreviewArgs {}
#[derive(clap::Args, Debug)]
pub struct CheckArgs {}

pub fn run_render(_args: RenderArgs) -> anyhow::Result<()> {
    anyhow::bail!("`lapclone render` is not implemented yet")
}
pub fn run_preview(_args: PreviewArgs) -> anyhow::Result<()> {
    anyhow::bail!("`lapclone preview` is not implemented yet")
}
pub fn run_check(_args: CheckArgs) -> anyhow::Result<()> {
    anyhow::bail!("`lapclone check` is not implemented yet")
}
