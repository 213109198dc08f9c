//! Errors of the raster stage: takes malformed patch input and gives a typed error naming the
//! offending array and index.

/// Why a patch cannot be drawn.
// Each variant's `#[error]` text says what it is and names its fields.
#[allow(missing_docs)]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RasterError {
    #[error("{what} has {actual} entries, expected {expected}")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        actual: usize,
    },
    #[error("triangle {triangle} refers to vertex {vertex}, but there are only {vertex_count}")]
    TriangleIndex {
        triangle: usize,
        vertex: u32,
        vertex_count: usize,
    },
    #[error("boundary loop {boundary_loop} refers to vertex {vertex}, but there are only {vertex_count}")]
    LoopIndex {
        boundary_loop: usize,
        vertex: u32,
        vertex_count: usize,
    },
    #[error("candidate vertex {vertex} is out of range (there are {vertex_count})")]
    CandidateIndex { vertex: u32, vertex_count: usize },
    #[error("{what}[{index}] is not finite")]
    NonFinite { what: &'static str, index: usize },
    #[error("feather must lie in [0, {max}], got {0:?}", max = crate::limits::MAX_FEATHER)]
    Feather(f32),
    #[error(
        "with its feather the patch needs {width}×{height} px examined, more than the limit of \
         {max} px (`limits::MAX_RASTER_PIXELS`): lower the feather, or keep the patch nearer \
         the canvas",
        max = crate::limits::MAX_RASTER_PIXELS
    )]
    WorkTooLarge { width: usize, height: usize },
}
