//! Reusable per-frame buffers of the raster: takes nothing and gives grow-only storage for
//! triangle setups, the per-pixel triangle ids and depths, coverage, feather distances, the
//! silhouette path and mask, so that a warmed-up frame allocates nothing.

use super::setup::TriangleSetup;

/// Scratch buffers for [`draw_patch`](super::draw_patch); keep one per patch (or per thread)
/// and pass it every frame.
#[derive(Default)]
pub struct RasterScratch {
    pub(crate) setups: Vec<TriangleSetup>,
    pub(crate) ids: Vec<u32>,
    pub(crate) depths: Vec<f32>,
    pub(crate) coverage: Vec<f32>,
    pub(crate) distance: Vec<f32>,
    pub(crate) distance_row: Vec<f32>,
    pub(crate) path_builder: Option<tiny_skia::PathBuilder>,
    pub(crate) mask: Option<tiny_skia::Mask>,
}

impl RasterScratch {
    pub fn new() -> RasterScratch {
        RasterScratch::default()
    }

    /// Sizes the per-pixel buffers for `area` pixels (grow-only capacity).
    pub(crate) fn prepare_pixels(&mut self, area: usize) {
        for buffer in [&mut self.depths, &mut self.coverage, &mut self.distance] {
            buffer.resize(area, 0.0);
        }
        self.ids.resize(area, 0);
    }
}
