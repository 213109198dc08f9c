//! Patch meshing (paper §II-A): takes a mask (image or polygons) and gives an adaptive,
//! boundary-conforming triangle [`Mesh`] — dense at the boundary, coarse inside — with holes
//! and several pieces.
//!
//! Coordinates are pixel coordinates of the mask/source image, x to the right, y down; pixel
//! (i, j) covers the square [i, i+1] × [j, j+1], so its centre is (i + 0.5, j + 0.5) and the
//! crack boundary runs along integer coordinates.

mod types;

pub use types::{BoundaryLoop, LoopKind, Mesh};
