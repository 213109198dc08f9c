//! Error types of the meshing stage: [`MeshError`] for everything `mesh_mask` /
//! `mesh_polygons` / the writers can fail on, [`SanityError`] for a mesh that breaks one of
//! the invariants `Mesh::sanity_check` verifies.

use std::path::PathBuf;

/// Why meshing (or reading a mask, or writing a mesh file) failed.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The mask image cannot be read or decoded.
    #[error("cannot read mask {path}")]
    MaskRead {
        /// The mask file.
        path: PathBuf,
        /// The decoder's error.
        #[source]
        source: image::ImageError,
    },
    /// The mask exceeds a resource limit.
    #[error("mask {path}: {source}")]
    MaskTooLarge {
        /// The mask file.
        path: PathBuf,
        /// Which limit.
        #[source]
        source: crate::limits::LimitError,
    },
    /// No pixel of the mask is inside.
    #[error("mask has no inside pixels")]
    EmptyMask,
    /// Every piece of the mask is below `min_piece_area`.
    #[error(
        "every piece of the mask is smaller than the minimum piece area ({min_piece_area} px²), \
         so nothing is left to mesh: make the mask's pieces larger"
    )]
    AllPiecesTooSmall {
        /// The option's value, px².
        min_piece_area: f64,
    },
    /// A [`MeshOptions`](super::MeshOptions) value is out of range.
    #[error("invalid mesh option: {0}")]
    InvalidOption(String),
    /// A polygon is unusable (too few points, not finite, out of range).
    #[error("polygon {polygon}: {reason}")]
    InvalidPolygon {
        /// Position of the polygon in the list.
        polygon: usize,
        /// What is wrong.
        reason: String,
    },
    /// The polygon list is empty.
    #[error("no polygons to mesh")]
    NoPolygons,
    /// Boundary loops (of polygons) cross each other.
    #[error(
        "boundary loops cross each other ({conflicts} conflicting edges); loops must not intersect"
    )]
    IntersectingBoundary {
        /// Edges that cross another loop.
        conflicts: usize,
    },
    /// `max_vertices` is below what the boundary alone needs.
    #[error(
        "vertex budget of {max_vertices} is below the {needed} boundary vertices this mask needs; \
         raise the density (the longest boundary edge, px), use a mask with a shorter outline, \
         or raise the budget where it is set (max_vertices; `lapclone mesh --max-vertices`)"
    )]
    VertexBudget {
        /// The budget.
        max_vertices: usize,
        /// Boundary vertices needed.
        needed: usize,
    },
    /// The mask's boundary is too long for the vertex budget.
    #[error(
        "the mask's boundary has {edges} pixel edges, more than the {max_edges} the vertex \
         budget allows (16 per vertex, at least 2^20); use a smoother mask, or raise the budget \
         where it is set (max_vertices; `lapclone mesh --max-vertices`)"
    )]
    BoundaryTooLong {
        /// Pixel edges on the mask's boundary.
        edges: usize,
        /// The most the budget allows.
        max_edges: usize,
    },
    /// The triangulator failed.
    #[error("triangulation failed: {0}")]
    Triangulation(String),
    /// The mesh broke an invariant.
    #[error("the mesh failed its sanity check")]
    Sanity(#[from] SanityError),
}

/// The first broken invariant `Mesh::sanity_check` found.
// Each variant's `#[error]` text says what it is and names its fields.
#[allow(missing_docs)]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SanityError {
    #[error("per-vertex arrays have lengths {is_boundary} (is_boundary) and {piece} (piece) for {positions} positions")]
    LengthMismatch {
        positions: usize,
        is_boundary: usize,
        piece: usize,
    },
    #[error("vertex {vertex} has a non-finite position")]
    NonFinitePosition { vertex: u32 },
    #[error("triangle {triangle} refers to vertex {vertex}, out of range")]
    IndexOutOfRange { triangle: usize, vertex: u32 },
    #[error("triangle {triangle} has signed area {area} (must be > 0, counter-clockwise in raw coordinates)")]
    NotPositive { triangle: usize, area: f64 },
    #[error("directed edge {a}→{b} appears in more than one triangle (edge over-shared or orientation flipped)")]
    EdgeOverShared { a: u32, b: u32 },
    #[error("vertex {vertex} is used by no triangle")]
    IsolatedVertex { vertex: u32 },
    #[error("boundary loop {loop_index} has edge {a}→{b}, which is not a boundary edge of the triangles")]
    LoopEdgeNotBoundary { loop_index: usize, a: u32, b: u32 },
    #[error("the loops list {listed} boundary edges but the triangles have {actual}")]
    BoundaryEdgeCount { listed: usize, actual: usize },
    #[error("boundary loop {loop_index} has {len} vertices (needs at least 3)")]
    ShortLoop { loop_index: usize, len: usize },
    #[error("boundary loop {loop_index} is marked {kind} but its signed area is {area}")]
    LoopOrientation {
        loop_index: usize,
        kind: &'static str,
        area: f64,
    },
    #[error("is_boundary[{vertex}] disagrees with the boundary loops")]
    BoundaryFlag { vertex: u32 },
    #[error("piece ids disagree with the triangle connectivity at vertex {vertex}")]
    PieceMismatch { vertex: u32 },
    #[error("piece_count is {listed} but the triangles form {actual} connected pieces")]
    PieceCount { listed: u32, actual: u32 },
    #[error("Euler characteristic V − E + F = {actual}, expected pieces − holes = {expected}")]
    Euler { actual: i64, expected: i64 },
}
