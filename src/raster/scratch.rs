//! Reusable per-frame buffers of the raster: takes nothing and gives grow-only storage for
//! triangle setups, the row bands, each worker's per-pixel triangle ids, depths and coverage,
//! feather distances, the silhouette path and mask, so that a warmed-up frame allocates
//! nothing.

use super::bands::{Bands, BAND_PIXELS};
use super::coverage::Silhouette;
use super::folds::FoldOutline;
use super::replay::{LazySpans, Replay};
use super::setup::{LocalFrame, SnappedVertex, TriangleSetup};

/// Scratch buffers for [`draw_patch`](super::draw_patch); keep one per patch (or per thread)
/// and pass it every frame.
pub struct RasterScratch {
    pub(crate) setups: Vec<TriangleSetup>,
    /// Per-triangle frames of setups whose membrane maps are added after the solve.
    pub(crate) frames: Vec<LocalFrame>,
    /// Per triangle: the canvas rows its pixel centres may reach (what the bands bin).
    pub(crate) centre_rows: Vec<(i64, i64)>,
    /// Placed vertices snapped to the fixed-point grid.
    pub(crate) snapped: Vec<SnappedVertex>,
    pub(crate) bands: Bands,
    pub(crate) workers: Vec<BandScratch>,
    /// The feathered coverage of the whole work rectangle.
    pub(crate) coverage: Vec<f32>,
    pub(crate) distance: Vec<f32>,
    pub(crate) distance_row: Vec<f32>,
    /// The anti-aliased silhouette's strips.
    pub(crate) silhouette: Silhouette,
    /// The outline of the inverted triangles, for the silhouette.
    pub(crate) folds: FoldOutline,
    /// Pixels per row band (tests vary it to prove it changes nothing).
    pub(crate) band_pixels: usize,
    pub(crate) replay: Replay,
    /// Per-thread membrane maps of a replayed draw.
    pub(crate) replay_spans: [LazySpans; 2],
    /// The membrane a recording draw prepares with (all zero; see `record.rs`).
    pub(crate) zero_membrane: Vec<[f32; 3]>,
}

impl Default for RasterScratch {
    fn default() -> Self {
        RasterScratch {
            setups: Vec::new(),
            frames: Vec::new(),
            centre_rows: Vec::new(),
            snapped: Vec::new(),
            bands: Bands::default(),
            workers: Vec::new(),
            coverage: Vec::new(),
            distance: Vec::new(),
            distance_row: Vec::new(),
            silhouette: Silhouette::default(),
            folds: FoldOutline::default(),
            band_pixels: BAND_PIXELS,
            replay: Replay::default(),
            replay_spans: Default::default(),
            zero_membrane: Vec::new(),
        }
    }
}

impl RasterScratch {
    pub fn new() -> RasterScratch {
        RasterScratch::default()
    }
}

/// One worker's per-pixel buffers over a band (or, feathered, the whole work rectangle).
#[derive(Default)]
pub(crate) struct BandScratch {
    pub ids: Vec<u32>,
    pub depths: Vec<f32>,
    /// Pixel-centre coverage when not anti-aliasing.
    pub coverage: Vec<u8>,
}

impl BandScratch {
    /// Sizes the buffers for `area` pixels (grow-only capacity).
    pub fn prepare(&mut self, area: usize, use_depth: bool) {
        self.ids.resize(area, 0);
        if use_depth {
            self.depths.resize(area, 0.0);
        }
    }
}
