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
    #[error("mask is {}×{} but the source is {}×{}: give the mask's offset in the source", mask.0, mask.1, source_size.0, source_size.1)]
    MaskSize {
        mask: (u32, u32),
        source_size: (u32, u32),
    },
    #[error("placement must be finite with a positive scale: {0}")]
    BadPlacement(String),
    #[error("{0} positions given for a mesh of {1} vertices")]
    VertexCountMismatch(usize, usize),
}
