//! Errors of the clone stage.

use crate::mesh::MeshError;
use crate::pixels::PixelError;
use crate::raster::RasterError;
use crate::solve::SolveError;

/// Why meshing a patch, building a cloner or cloning failed.
#[derive(Debug, thiserror::Error)]
pub enum CloneError {
    /// Meshing the patch failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The sparse solver failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Reading or writing an image failed.
    #[error(transparent)]
    Pixels(#[from] PixelError),
    /// The raster failed.
    #[error(transparent)]
    Raster(#[from] RasterError),
    /// A [`CloneOptions`](super::CloneOptions) value is out of range.
    #[error("{0}")]
    BadOption(String),
    /// The mask's size differs from the source's and no offset was given.
    #[error("mask is {}×{} but the source is {}×{}: give the mask's offset in the source", mask.0, mask.1, source_size.0, source_size.1)]
    MaskSize {
        /// Mask columns and rows.
        mask: (u32, u32),
        /// Source columns and rows.
        source_size: (u32, u32),
    },
    /// The placement is not finite or its scale not positive.
    #[error("placement must be finite with a positive scale: {0}")]
    BadPlacement(String),
    /// A deformed position list does not match the mesh (given, vertices).
    #[error("{0} positions given for a mesh of {1} vertices")]
    VertexCountMismatch(usize, usize),
}
