//! From a mask to a patch mesh in the source's frame: takes the source's size, a mask (or
//! polygons) and the mask's offset in the source, and gives the mesh plus the bounding box
//! that anchors (`centre`, `topleft`) refer to.

use glam::DVec2;

use super::{expand_boundary, CloneError, HALF_PIXEL};
use crate::mesh::{
    mesh_mask, mesh_polygons, relax_interior, BitMask, BoundaryPlacement, MeshOptions, MeshResult,
    Polygon,
};

/// A patch mesh in source coordinates, with its mask's bounding box.
#[derive(Clone, Debug)]
pub struct PatchMesh {
    /// The mesh (rest = source coordinates), the mesher's warnings and statistics.
    pub result: MeshResult,
    /// Bounding box of the inside pixels (pixel corners), in source coordinates.
    pub bbox_min: DVec2,
    /// Bottom-right corner of that bounding box; with `bbox_min` it gives the patch centre.
    pub bbox_max: DVec2,
}

impl PatchMesh {
    /// The radius of a drag given without one: a quarter of the bounding box's larger side
    /// (at least a quarter pixel), so a drag moves a region in proportion to the patch.
    pub fn default_drag_radius(&self) -> f64 {
        0.25 * (self.bbox_max - self.bbox_min).max_element().max(1.0)
    }
}

/// Meshes `mask`, whose pixel (0, 0) sits at `offset` in a source of `source_size`.
/// Without an offset the mask must have the source's size. The boundary ends on the outside
/// pixel centres: meshed there ([`BoundaryPlacement::OutsideCentres`]), or meshed on the
/// cracks and moved half a pixel out (`expand_boundary`).
pub fn mesh_from_mask(
    mask: &BitMask,
    offset: Option<DVec2>,
    source_size: (u32, u32),
    options: &MeshOptions,
) -> Result<PatchMesh, CloneError> {
    let mask_size = (mask.width as u32, mask.height as u32);
    if offset.is_none() && mask_size != source_size {
        return Err(CloneError::MaskSize {
            mask: mask_size,
            source_size,
        });
    }
    let offset = offset.unwrap_or(DVec2::ZERO);
    if !offset.is_finite() {
        return Err(CloneError::BadOption(format!(
            "mask offset {offset} is not finite"
        )));
    }
    let mut result = mesh_mask(mask, options)?;
    for p in &mut result.mesh.positions {
        *p += offset;
    }
    finish_mask_mesh(&mut result, options);
    let (min, max) = inside_bbox(mask);
    Ok(PatchMesh {
        result,
        bbox_min: min + offset,
        bbox_max: max + offset,
    })
}

/// What the clone stage does to a fresh mask mesh: puts a crack boundary on the outside pixel
/// centres ([`expand_boundary`]) and relaxes the interior (`options.relax_sweeps`).
pub fn finish_mask_mesh(result: &mut MeshResult, options: &MeshOptions) {
    if result.stats.boundary == BoundaryPlacement::Cracks {
        expand_boundary(&mut result.mesh, HALF_PIXEL);
    }
    relax_interior(
        &mut result.mesh,
        options.relax_sweeps,
        options.min_angle_deg,
    );
}

/// Meshes polygons given in source coordinates (interior relaxed as `options` asks).
pub fn mesh_from_polygons(
    polygons: &[Polygon],
    options: &MeshOptions,
) -> Result<PatchMesh, CloneError> {
    let mut result = mesh_polygons(polygons, options)?;
    relax_interior(
        &mut result.mesh,
        options.relax_sweeps,
        options.min_angle_deg,
    );
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for p in polygons.iter().flat_map(|p| &p.outer) {
        min = min.min(*p);
        max = max.max(*p);
    }
    Ok(PatchMesh {
        result,
        bbox_min: min,
        bbox_max: max,
    })
}

/// Corners of the bounding box of the inside pixels; a zero box at the origin when empty
/// (meshing reports the empty mask before this matters).
fn inside_bbox(mask: &BitMask) -> (DVec2, DVec2) {
    let Some(((x0, y0), (x1, y1))) = mask.inside_bounds() else {
        return (DVec2::ZERO, DVec2::ZERO);
    };
    (
        DVec2::new(x0 as f64, y0 as f64),
        DVec2::new(x1 as f64, y1 as f64),
    )
}
