//! From a mask to a patch mesh in the source's frame: takes the source's size, a mask (or
//! polygons) and the mask's offset in the source, and gives the mesh plus the bounding box
//! that anchors (`centre`, `topleft`) refer to.

use glam::DVec2;

use super::{expand_boundary, CloneError, HALF_PIXEL};
use crate::util::number_text;
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
    let bbox = inside_bbox(mask);
    // An empty mask is the mesher's error to give ("no inside pixels").
    let past = bbox.and_then(|(min, max)| reach_past(min + offset, max + offset, source_size));
    let (min, max) = bbox.unwrap_or_default();
    if past.is_some_and(f64::is_infinite) {
        return Err(CloneError::BadOption(format!(
            "the mask at offset ({}, {}) lies entirely outside the {}×{} source",
            number_text(offset.x),
            number_text(offset.y),
            source_size.0,
            source_size.1
        )));
    }
    let mut result = mesh_mask(mask, options)?;
    if let Some(past) = past.filter(|&p| p > PAST_EDGE_TOLERANCE) {
        result.warnings.push(format!(
            "the mask at offset ({}, {}) reaches {} px past the edge of the {}×{} source; the pixels there repeat the edge",
            number_text(offset.x),
            number_text(offset.y),
            number_text((past * 10.0).round() / 10.0),
            source_size.0,
            source_size.1
        ));
    }
    for p in &mut result.mesh.positions {
        *p += offset;
    }
    finish_mask_mesh(&mut result, options);
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

/// How far past a patch may reach beyond its source's edge unremarked, px: a polygon drawn
/// along the image's border may sit on pixel centres or edges.
pub const PAST_EDGE_TOLERANCE: f64 = 1.0;

/// How far (px) the box `min`..`max` (source coordinates) reaches past a `size` source's
/// rectangle, when it does; infinite when it misses the rectangle entirely. The pixels a
/// patch takes from past the edge repeat the edge (sampling is clamped).
pub fn reach_past(min: DVec2, max: DVec2, (width, height): (u32, u32)) -> Option<f64> {
    let size = DVec2::new(f64::from(width), f64::from(height));
    if max.x <= 0.0 || max.y <= 0.0 || min.x >= size.x || min.y >= size.y {
        return Some(f64::INFINITY);
    }
    let past = (-min).max(max - size).max_element();
    (past > 0.0).then_some(past)
}

/// Corners of the bounding box of the inside pixels; `None` for an empty mask (meshing
/// reports it).
fn inside_bbox(mask: &BitMask) -> Option<(DVec2, DVec2)> {
    let ((x0, y0), (x1, y1)) = mask.inside_bounds()?;
    Some((
        DVec2::new(x0 as f64, y0 as f64),
        DVec2::new(x1 as f64, y1 as f64),
    ))
}
