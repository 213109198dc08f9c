//! Errors of the clone stage.

use crate::mesh::MeshError;
use crate::pixels::PixelError;
use crate::raster::RasterError;
use crate::solve::SolveError;

#[derive(Debug, thiserror::Error)]
pub enum CloneError {
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Pixels(#[from] PixelError),
    #[error(transparent)]
    Raster(#[from] RasterError),
    #[error("{0}")]
    BadOption(String),
    #[error("placement must be finite with a positive scale: {0}")]
    BadPlacement(String),
    #[error("{0} positions given for a mesh of {1} vertices")]
    VertexCountMismatch(usize, usize),
}
