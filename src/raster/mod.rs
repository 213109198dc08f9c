//! The raster stage: takes a cloned patch — rest positions (source texture coordinates),
//! placed positions in canvas pixels, triangles, a per-vertex RGB membrane, optional
//! per-vertex depth, the source [`FloatImage`](crate::pixels::FloatImage) and the mesh's
//! boundary loops — and composites it over a [`Canvas`](crate::pixels::Canvas).
//!
//! Rules (see each file for the why):
//! - A pixel belongs to a triangle when its centre is inside the placed triangle, decided
//!   exactly in 1/256-px fixed point with a top-left fill rule, so triangles sharing an edge
//!   leave no cracks and no double hits (`triangles.rs`). Inverted (folded) triangles are drawn.
//! - Overlaps: the larger interpolated depth wins; on equal depth the later triangle wins.
//! - Coverage: the union of all placed triangles, anti-aliased only at its silhouette, filled
//!   by tiny-skia as the boundary loops plus every inverted triangle twice (see `coverage.rs`).
//!   Edge pixels whose centre misses every triangle take their colour by extrapolating the
//!   affine maps of the nearest hit pixel's triangle.
//! - `feather` px ramps the coverage down by distance to the silhouette (`feather.rs`).
//! - Composite: straight-alpha source-over; over an opaque canvas that is
//!   `out = cov·α·patch + (1 − cov·α)·canvas`.
//!
//! [`boundary_layers`] answers, independently of pixels, which boundary vertices lie under
//! the patch's own front layer (the clone stage switches their constraints off) and which
//! lie over a lower layer of it (the clone stage glues them).
//!
//! A draw runs on the calling thread, or with `RasterOptions::threads` shares its parts with
//! the raster's worker pool (`workers.rs`); every pixel depends only on the draw's inputs,
//! never on the thread count.
//!
//! Once-per-mesh vs per-frame: nothing is cached across frames except the buffers in
//! [`RasterScratch`] and [`CoverageGrid`]; a frame re-does the per-triangle setup (cheap) and
//! allocates nothing once the buffers have grown to the patch's size.

mod bands;
mod clip;
mod coverage;
mod covered;
mod draw;
mod error;
mod feather;
mod folds;
pub mod overlay;
mod patch;
mod point_grid;
mod prepare;
mod sampler;
mod scratch;
mod setup;
mod shade;
mod triangles;
mod workers;

pub use crate::pixels::PixelRect;
pub use covered::{
    boundary_layers, covered_boundary_vertices, weights_if_strictly_inside, Beneath, CoverageGrid,
};
pub use point_grid::PointGrid;
pub use draw::{draw_patch, RasterOptions, RasterStats};
pub use workers::MAX_RASTER_THREADS;
pub use error::RasterError;
pub use patch::Patch;
pub use scratch::RasterScratch;
pub use triangles::triangle_pixels;
