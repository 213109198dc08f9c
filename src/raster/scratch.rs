//! Reusable per-frame buffers of the raster: takes nothing and gives grow-only storage for
//! triangle setups, the per-pixel triangle ids, depths and coverage of the work rectangle,
//! feather distances and the silhouette's paths and masks, so that a warmed-up frame
//! allocates nothing.

use super::coverage::Silhouette;
use super::folds::FoldOutline;
use super::setup::{SnappedVertex, TriangleSetup};
use super::triangles::TriangleBins;

/// Scratch buffers for [`draw_patch`](super::draw_patch); the caller keeps one (per patch,
/// or per thread) and passes it every frame.
#[derive(Default)]
pub struct RasterScratch {
    pub(crate) setups: Vec<TriangleSetup>,
    /// Placed vertices snapped to the fixed-point grid.
    pub(crate) snapped: Vec<SnappedVertex>,
    /// Per work pixel: the triangle owning its centre.
    pub(crate) ids: Vec<u32>,
    /// Per work pixel: the owner's depth (drawn with depth only).
    pub(crate) depths: Vec<f32>,
    /// The triangles of each row band, for drawing the ids band by band.
    pub(crate) bins: TriangleBins,
    /// Pixel-centre coverage when not anti-aliasing.
    pub(crate) centres: Vec<u8>,
    /// The feathered coverage of the work rectangle.
    pub(crate) feathered: Vec<f32>,
    pub(crate) distance: Vec<f32>,
    pub(crate) distance_row: Vec<f32>,
    /// The anti-aliased silhouette's strips.
    pub(crate) silhouette: Silhouette,
    /// The outline of the inverted triangles, for the silhouette.
    pub(crate) folds: FoldOutline,
}

impl RasterScratch {
    pub fn new() -> RasterScratch {
        RasterScratch::default()
    }
}
