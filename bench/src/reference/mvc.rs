//! Mean-Value-Coordinates cloning (Farbman et al. 2009), the paper's baseline. It takes mesh
//! vertex positions and one outer boundary polygon per piece (vertex indices) and gives, once,
//! the dense mean-value coordinates of every interior vertex w.r.t. its polygon
//! ([`MvcWeights::new`], the "pre-processing" column of the paper's Table I); then, per clone,
//! the membrane `m(x) = Σ_i λ_i(x) · value_i` at interior vertices, boundary vertices keeping
//! their own values ([`MvcWeights::apply`], the "membrane" column). Inside triangles the
//! membrane is linear, like the combinatorial one.
//!
//! Mean-value coordinates are defined w.r.t. a single closed polygon; a patch with holes has
//! no such polygon, so holes are refused with [`MvcError::HasHoles`] rather than faked.
//! No hierarchical boundary sampling: the paper compares with a plain CPU MVC.
//!
//! Coordinates use Floater's `w_i = (tan(α_{i−1}/2) + tan(α_i/2)) / r_i` with signed angles,
//! which stays valid (linear precision, partition of unity) on any simple polygon, not only on
//! star-shaped ones. `tan(α/2)` is evaluated as `A / (r r' + D)` when the dot product `D ≥ 0`
//! and as `(r r' − D) / A` otherwise, so neither form divides by a cancelled difference;
//! points on a boundary vertex or edge get the limit values (a unit vector or linear
//! interpolation along the edge).

use glam::DVec2;
use thiserror::Error;

use lapclone::mesh::{BoundaryLoop, LoopKind, Mesh};

/// Relative size under which a point counts as lying on a polygon vertex or edge.
const ON_BOUNDARY_TOLERANCE: f64 = 1e-14;

/// Why MVC weights could not be built or applied.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MvcError {
    #[error("MVC is undefined on a patch with holes ({holes} hole loop(s)); use the Laplacian")]
    HasHoles { holes: usize },
    #[error("boundary polygon has {count} vertices, at least 3 are needed")]
    TooFewBoundaryVertices { count: usize },
    #[error("vertex index {index} out of range (mesh has {vertex_count} vertices)")]
    VertexOutOfRange { index: u32, vertex_count: usize },
    #[error("vertex {index} appears twice on the boundary")]
    RepeatedBoundaryVertex { index: u32 },
    #[error("vertex {vertex} has a non-finite position")]
    NonFinitePosition { vertex: u32 },
    #[error("boundary polygon has zero area")]
    DegeneratePolygon,
    #[error("piece {piece} has {count} outer loops, MVC needs exactly one per piece")]
    OuterLoopsPerPiece { piece: u32, count: usize },
    #[error("piece array has {got} entries, expected one per vertex ({expected})")]
    PieceLength { expected: usize, got: usize },
    #[error("coordinates of vertex {vertex} sum to {sum} (non-finite or not 1)")]
    BadCoordinates { vertex: u32, sum: f64 },
    #[error("a weight block's table does not match its interior × boundary size")]
    BlockShape,
    #[error("channels must be at least 1")]
    NoChannels,
    #[error("{what} has {got} samples, expected vertices × channels = {expected}")]
    ValuesLength {
        what: &'static str,
        expected: usize,
        got: usize,
    },
}

/// Dense coordinates of the interior vertices of one piece w.r.t. its outer polygon.
#[derive(Clone, Debug)]
pub struct MvcBlock {
    boundary: Vec<u32>,
    interior: Vec<u32>,
    /// Row-major `interior.len() × boundary.len()`.
    weights: Vec<f64>,
}

impl MvcBlock {
    pub fn boundary(&self) -> &[u32] {
        &self.boundary
    }

    pub fn interior(&self) -> &[u32] {
        &self.interior
    }

    /// Coordinates of the `row`-th interior vertex, one per boundary vertex, in polygon order.
    pub fn coordinates(&self, row: usize) -> &[f64] {
        let n = self.boundary.len();
        &self.weights[row * n..(row + 1) * n]
    }
}

/// The MVC pre-processing of a mesh: one [`MvcBlock`] per piece.
#[derive(Clone, Debug)]
pub struct MvcWeights {
    vertex_count: usize,
    blocks: Vec<MvcBlock>,
}

impl MvcWeights {
    /// One simple polygon `boundary` (vertex indices in order, either orientation); every
    /// vertex not on it is interior.
    pub fn new(positions: &[DVec2], boundary: &[u32]) -> Result<Self, MvcError> {
        let on_boundary = boundary_flags(positions.len(), boundary)?;
        let interior: Vec<u32> = (0..positions.len() as u32)
            .filter(|&v| !on_boundary[v as usize])
            .collect();
        Ok(Self {
            vertex_count: positions.len(),
            blocks: vec![build_block(positions, boundary, interior)?],
        })
    }

    /// Mesh loops with a per-vertex piece id: one block per outer loop, whose interior is the
    /// off-boundary vertices of that loop's piece. Any hole loop is refused.
    pub fn from_loops(
        positions: &[DVec2],
        loops: &[BoundaryLoop],
        piece_of_vertex: &[u32],
    ) -> Result<Self, MvcError> {
        let holes = loops.iter().filter(|l| l.kind == LoopKind::Hole).count();
        if holes > 0 {
            return Err(MvcError::HasHoles { holes });
        }
        if piece_of_vertex.len() != positions.len() {
            return Err(MvcError::PieceLength {
                expected: positions.len(),
                got: piece_of_vertex.len(),
            });
        }
        let mut on_boundary = vec![false; positions.len()];
        for l in loops {
            for (v, &b) in boundary_flags(positions.len(), &l.vertices)?
                .iter()
                .enumerate()
            {
                on_boundary[v] |= b;
            }
        }
        let blocks = loops
            .iter()
            .map(|l| {
                let count = loops.iter().filter(|o| o.piece == l.piece).count();
                if count != 1 {
                    return Err(MvcError::OuterLoopsPerPiece {
                        piece: l.piece,
                        count,
                    });
                }
                let interior = (0..positions.len() as u32)
                    .filter(|&v| !on_boundary[v as usize] && piece_of_vertex[v as usize] == l.piece)
                    .collect();
                build_block(positions, &l.vertices, interior)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            vertex_count: positions.len(),
            blocks,
        })
    }

    /// [`from_loops`](Self::from_loops) on a [`Mesh`].
    pub fn from_mesh(mesh: &Mesh) -> Result<Self, MvcError> {
        Self::from_loops(&mesh.positions, &mesh.loops, &mesh.piece)
    }

    /// Checks shapes, index ranges and that every interior vertex's coordinates are finite
    /// and sum to 1 (to 1e-9): the partition of unity MVC guarantees inside a simple polygon.
    pub fn sanity_check(&self) -> Result<(), MvcError> {
        for block in &self.blocks {
            if block.weights.len() != block.interior.len() * block.boundary.len() {
                return Err(MvcError::BlockShape);
            }
            for &index in block.boundary.iter().chain(&block.interior) {
                if index as usize >= self.vertex_count {
                    return Err(MvcError::VertexOutOfRange {
                        index,
                        vertex_count: self.vertex_count,
                    });
                }
            }
            for (row, &vertex) in block.interior.iter().enumerate() {
                let sum: f64 = block.coordinates(row).iter().sum();
                if !sum.is_finite() || (sum - 1.0).abs() > 1e-9 {
                    return Err(MvcError::BadCoordinates { vertex, sum });
                }
            }
        }
        Ok(())
    }

    pub fn blocks(&self) -> &[MvcBlock] {
        &self.blocks
    }

    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Stored coordinates (interior × boundary, summed over pieces).
    pub fn weight_count(&self) -> usize {
        self.blocks.iter().map(|b| b.weights.len()).sum()
    }

    /// The membrane: `values` and `out` are per vertex, `channels` interleaved
    /// (`v * channels + c`). Only boundary entries of `values` are read; boundary entries of
    /// `out` get their own value, interior entries `Σ λ_i value_i`. Vertices on no block are
    /// left untouched. Allocates nothing.
    pub fn apply<T: Copy + Into<f64>>(
        &self,
        values: &[T],
        channels: usize,
        out: &mut [f64],
    ) -> Result<(), MvcError> {
        if channels == 0 {
            return Err(MvcError::NoChannels);
        }
        let expected = self.vertex_count * channels;
        for (what, got) in [("values", values.len()), ("out", out.len())] {
            if got != expected {
                return Err(MvcError::ValuesLength {
                    what,
                    expected,
                    got,
                });
            }
        }
        for block in &self.blocks {
            apply_block(block, values, channels, out);
        }
        Ok(())
    }
}

fn apply_block<T: Copy + Into<f64>>(block: &MvcBlock, values: &[T], k: usize, out: &mut [f64]) {
    for &b in &block.boundary {
        let b = b as usize * k;
        for c in 0..k {
            out[b + c] = values[b + c].into();
        }
    }
    for (row, &v) in block.interior.iter().enumerate() {
        let target = &mut out[v as usize * k..(v as usize + 1) * k];
        target.fill(0.0);
        for (&lambda, &b) in block.coordinates(row).iter().zip(&block.boundary) {
            let source = &values[b as usize * k..(b as usize + 1) * k];
            for (t, &s) in target.iter_mut().zip(source) {
                *t += lambda * s.into();
            }
        }
    }
}

/// Validates a polygon's indices and returns the per-vertex "is on it" flags.
fn boundary_flags(vertex_count: usize, boundary: &[u32]) -> Result<Vec<bool>, MvcError> {
    if boundary.len() < 3 {
        return Err(MvcError::TooFewBoundaryVertices {
            count: boundary.len(),
        });
    }
    let mut flags = vec![false; vertex_count];
    for &index in boundary {
        let slot = flags
            .get_mut(index as usize)
            .ok_or(MvcError::VertexOutOfRange {
                index,
                vertex_count,
            })?;
        if *slot {
            return Err(MvcError::RepeatedBoundaryVertex { index });
        }
        *slot = true;
    }
    Ok(flags)
}

fn build_block(
    positions: &[DVec2],
    boundary: &[u32],
    interior: Vec<u32>,
) -> Result<MvcBlock, MvcError> {
    for &v in boundary.iter().chain(&interior) {
        if !positions[v as usize].is_finite() {
            return Err(MvcError::NonFinitePosition { vertex: v });
        }
    }
    let polygon: Vec<DVec2> = boundary.iter().map(|&v| positions[v as usize]).collect();
    if signed_area(&polygon) == 0.0 {
        return Err(MvcError::DegeneratePolygon);
    }
    let n = polygon.len();
    let mut weights = vec![0.0; interior.len() * n];
    for (row, &v) in interior.iter().enumerate() {
        mean_value_coordinates(
            positions[v as usize],
            &polygon,
            &mut weights[row * n..(row + 1) * n],
        )?;
    }
    Ok(MvcBlock {
        boundary: boundary.to_vec(),
        interior,
        weights,
    })
}

fn signed_area(polygon: &[DVec2]) -> f64 {
    let n = polygon.len();
    (0..n)
        .map(|i| polygon[i].perp_dot(polygon[(i + 1) % n]))
        .sum::<f64>()
        * 0.5
}

/// Mean-value coordinates of `x` w.r.t. the closed `polygon` (at least 3 vertices, simple,
/// either orientation) into `out` (`polygon.len()` entries, summing to 1). Points on a polygon
/// vertex or edge get the limit values. Allocates nothing.
pub fn mean_value_coordinates(
    x: DVec2,
    polygon: &[DVec2],
    out: &mut [f64],
) -> Result<(), MvcError> {
    let n = polygon.len();
    if n < 3 {
        return Err(MvcError::TooFewBoundaryVertices { count: n });
    }
    if out.len() != n {
        return Err(MvcError::ValuesLength {
            what: "coordinates",
            expected: n,
            got: out.len(),
        });
    }
    let scale = polygon
        .iter()
        .map(|p| (*p - x).length())
        .fold(0.0_f64, f64::max);
    let tiny = ON_BOUNDARY_TOLERANCE * scale;
    if let Some(i) = (0..n).find(|&i| (polygon[i] - x).length() <= tiny) {
        out.fill(0.0);
        out[i] = 1.0;
        return Ok(());
    }
    // First pass: out[i] = tan(α_i / 2) for the edge (i, i+1).
    for i in 0..n {
        let j = (i + 1) % n;
        let (d0, d1) = (polygon[i] - x, polygon[j] - x);
        let (r0, r1) = (d0.length(), d1.length());
        let (area, dot) = (d0.perp_dot(d1), d0.dot(d1));
        if dot < 0.0 && area.abs() <= ON_BOUNDARY_TOLERANCE * r0 * r1 {
            out.fill(0.0);
            out[i] = r1 / (r0 + r1);
            out[j] = r0 / (r0 + r1);
            return Ok(());
        }
        out[i] = if dot >= 0.0 {
            area / (r0 * r1 + dot)
        } else {
            (r0 * r1 - dot) / area
        };
    }
    // Second pass: w_i = (t_{i−1} + t_i) / r_i, then normalise.
    let mut previous_tan = out[n - 1];
    let mut total = 0.0;
    for i in 0..n {
        let tan = out[i];
        out[i] = (previous_tan + tan) / (polygon[i] - x).length();
        total += out[i];
        previous_tan = tan;
    }
    for w in out.iter_mut() {
        *w /= total;
    }
    Ok(())
}
