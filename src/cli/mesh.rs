//! `lapclone mesh`: mask → mesh, with an optional picture, JSON stats and Laplacian export.

use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct MeshArgs {
    /// Mask image (any format the `image` crate reads).
    pub mask: PathBuf,
    /// Maximum boundary edge length in pixels (seam quality knob).
    #[arg(long, value_parser = super::finite_f64)]
    pub density: Option<f64>,
    /// Minimum angle for refinement, degrees.
    #[arg(long = "min-angle", value_parser = super::finite_f64)]
    pub min_angle: Option<f64>,
    /// Vertex budget.
    #[arg(long = "max-vertices")]
    pub max_vertices: Option<usize>,
    /// Inside threshold in [0, 1] (alpha if the image has alpha, else luminance).
    #[arg(long, value_parser = super::finite_f64)]
    pub threshold: Option<f64>,
    /// Draw the mesh over the mask into this PNG.
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Print one JSON object with mesh statistics on stdout.
    #[arg(long)]
    pub stats: bool,
    /// Write the combinatorial Laplacian (Matrix Market) and `<file>.boundary`.
    #[arg(long = "laplacian-out")]
    pub laplacian_out: Option<PathBuf>,
}

pub fn run(_args: MeshArgs) -> anyhow::Result<()> {
    anyhow::bail!("`lapclone mesh` is not implemented yet")
}
