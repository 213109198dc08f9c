//! Patch meshing (paper §II-A): takes a mask (image or polygons) and gives an adaptive,
//! boundary-conforming triangle [`Mesh`] — dense at the boundary, coarse inside — with holes
//! and several pieces.
//!
//! Coordinates are pixel coordinates of the mask/source image, x to the right, y down; pixel
//! (i, j) covers the square [i, i+1] × [j, j+1], so its centre is (i + 0.5, j + 0.5) and the
//! crack boundary runs along integer coordinates.
//!
//! Pipeline ([`mesh_mask`](fn@mesh_mask)): [`BitMask`] → small pieces dropped → crack loops
//! (`contour`) → loops through the outside pixel centres, thinned to `density` (`centre_loops`,
//! the default [`BoundaryPlacement::OutsideCentres`]) or, with [`BoundaryPlacement::Cracks`],
//! Douglas–Peucker + subdivision to `density` (`simplify`) → spade CDT + refinement
//! (`triangulate`) → [`Mesh`], verified by [`Mesh::sanity_check`]. Every mask is meshed
//! whole, on the calling thread. [`relax_interior`] evens out the interior for the
//! combinatorial Laplacian (the clone stage applies it). Mask-aware checks are in
//! `coverage`.

mod bitmask;
mod centre_loops;
mod contour;
mod coverage;
mod error;
// Test meshes and masks; the integration tests and benchmarks include the same files.
#[cfg(test)]
#[path = "../../tests/common/mesh_fixtures.rs"]
pub mod fixtures;
mod mesh_mask;
mod options;
mod relax;
mod sanity;
mod simplify;
#[cfg(test)]
#[path = "../../tests/common/synth_masks.rs"]
pub mod synth;
mod triangulate;
mod types;

pub use bitmask::{BitMask, MASK_THRESHOLD};
pub use centre_loops::outside_centre_loops;
pub use contour::{for_each_edge_pixel, label_pieces, trace_crack_loops, CrackLoop};
pub use coverage::uncovered_mask_pixels;
pub use error::{MeshError, SanityError};
pub use mesh_mask::{mesh_mask, mesh_polygons, Polygon};
pub use options::{
    min_angle_deg, BoundaryPlacement, MeshOptions, MeshResult, MeshStats, MAX_RELAX_SWEEPS,
};
pub use relax::relax_interior;
pub use simplify::doubled_signed_area;
pub(crate) use simplify::Segment;
pub use triangulate::{assemble_mesh, Refinement};
pub use types::{BoundaryLoop, LoopKind, Mesh};
