//! The raster input: takes borrowed slices describing one placed, cloned patch and gives a
//! validated [`Patch`] (lengths agree, indices in range, numbers finite).

use glam::DVec2;

use super::RasterError;
use crate::mesh::BoundaryLoop;
use crate::pixels::FloatImage;

/// One cloned patch, ready to draw.
#[derive(Clone, Copy, Debug)]
pub struct Patch<'a> {
    /// Rest positions = source texture coordinates (pixel coordinates of `source`).
    pub rest: &'a [DVec2],
    /// Placed positions in canvas pixels (transformed and deformed).
    pub placed: &'a [DVec2],
    /// Triangles; positive area at rest, any orientation once placed.
    pub triangles: &'a [[u32; 3]],
    /// Per-vertex RGB offsets added to the source colour.
    pub membrane: &'a [[f32; 3]],
    /// Per-vertex depth (larger = in front); `None` draws later triangles over earlier ones.
    pub depth: Option<&'a [f32]>,
    /// All boundary loops of the mesh (outer and holes), for the anti-aliased silhouette.
    /// Empty: the silhouette is filled from every triangle instead (correct, slower).
    pub loops: &'a [BoundaryLoop],
    pub source: &'a FloatImage,
}

impl Patch<'_> {
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }

    /// Checks lengths, indices and finiteness; O(vertices + triangles + loop vertices).
    pub fn validate(&self) -> Result<(), RasterError> {
        self.validate_geometry()?;
        self.validate_membrane(self.membrane)
    }

    /// [`validate`](Self::validate) without the membrane.
    pub(crate) fn validate_geometry(&self) -> Result<(), RasterError> {
        let n = self.rest.len();
        check_len("placed", n, self.placed.len())?;
        if let Some(depth) = self.depth {
            check_len("depth", n, depth.len())?;
            if let Some(index) = depth.iter().position(|d| !d.is_finite()) {
                return Err(RasterError::NonFinite {
                    what: "depth",
                    index,
                });
            }
        }
        check_finite_points("rest", self.rest)?;
        check_finite_points("placed", self.placed)?;
        for (triangle, tri) in self.triangles.iter().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(RasterError::TriangleIndex {
                    triangle,
                    vertex,
                    vertex_count: n,
                });
            }
        }
        for (boundary_loop, l) in self.loops.iter().enumerate() {
            if let Some(&vertex) = l.vertices.iter().find(|&&v| v as usize >= n) {
                return Err(RasterError::LoopIndex {
                    boundary_loop,
                    vertex,
                    vertex_count: n,
                });
            }
        }
        Ok(())
    }

    /// Checks that `membrane` fits this patch: one finite RGB offset per vertex.
    pub(crate) fn validate_membrane(&self, membrane: &[[f32; 3]]) -> Result<(), RasterError> {
        check_len("membrane", self.rest.len(), membrane.len())?;
        match membrane
            .iter()
            .position(|m| m.iter().any(|v| !v.is_finite()))
        {
            Some(index) => Err(RasterError::NonFinite {
                what: "membrane",
                index,
            }),
            None => Ok(()),
        }
    }
}

fn check_len(what: &'static str, expected: usize, actual: usize) -> Result<(), RasterError> {
    if expected == actual {
        Ok(())
    } else {
        Err(RasterError::LengthMismatch {
            what,
            expected,
            actual,
        })
    }
}

fn check_finite_points(what: &'static str, points: &[DVec2]) -> Result<(), RasterError> {
    match points.iter().position(|p| !p.is_finite()) {
        Some(index) => Err(RasterError::NonFinite { what, index }),
        None => Ok(()),
    }
}
