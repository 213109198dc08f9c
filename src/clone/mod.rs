//! Seamless cloning (paper §II-C): takes a source image, a patch mesh in the source's frame
//! and where to put it, and gives the patch composited seamlessly onto a canvas.
//!
//! [`PatchCloner`] owns everything that is built once per patch — the mesh, the factored
//! Laplacian, the source samples at the boundary, raster scratch — so re-cloning after a
//! move or a deformation costs only constraint switches, one multi-RHS back-substitution
//! and the raster.

mod boundary_data;
mod cloner;
mod error;
mod expand;
mod glue;
mod membrane;
mod patch_mesh;
mod placement;

pub use crate::raster::Beneath;
pub use boundary_data::{BoundaryData, BoundarySampler, HAT_SAMPLE_SPACING};
pub use cloner::{CloneMode, CloneOptions, CloneStats, PatchCloner};
pub use error::CloneError;
pub use expand::{expand_boundary, HALF_PIXEL};
pub use glue::{Glue, GlueFrame, GlueStats, GluedVertex, GLUE_TOLERANCE, MAX_GLUE_ITERATIONS};
pub use membrane::{MembraneSolver, MembraneStats, MEMBRANE_CHANNELS};
pub use patch_mesh::{
    finish_mask_mesh, mesh_from_mask, mesh_from_polygons, reach_past, PatchMesh, PAST_EDGE_TOLERANCE,
};
pub use placement::{Anchor, Placement, PLACED_GRID};
