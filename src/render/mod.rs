//! Rendering scenes: takes a [`Scene`](crate::scene::Scene) and a frame index (or a time) and
//! gives the composited frame as a [`Canvas`](crate::pixels::Canvas).
//!
//! Once per scene ([`Renderer::new`]): load images, mesh every patch, assemble and factor its
//! cloning Laplacian and, for patches with handles or pins, factor its deformation Laplacian. Per frame:
//! evaluate the timeline at t = i / fps, reset the canvas to the background, then for each
//! patch back to front: deformation solve (rank-1 switches only), visibility switches,
//! membrane solve, raster — each patch clones onto the composite of the layers below it; a
//! layer with opacity below 1 is then blended over a copy of the pixels below it, and a
//! layer with opacity 0 is not drawn.
//! After an edit ([`Renderer::set_scene`]) only new or changed patches are built again.

mod error;
mod layer;
mod opacity;
mod point_warnings;
mod renderer;
mod source_warnings;

pub use error::RenderError;
pub use renderer::{DrawnRegion, FrameStats, PlacedMesh, Renderer, SceneUpdate};
