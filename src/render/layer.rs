//! One patch of a scene as the renderer keeps it: takes the patch description once (mesh,
//! cloning factor, deformation rig) and, per frame, its evaluated state, and clones it onto
//! the canvas.

use glam::DVec2;

use super::RenderError;
use crate::clone::{
    mesh_from_mask, mesh_from_polygons, CloneOptions, CloneStats, PatchCloner, PatchMesh,
    Placement,
};
use crate::deform::{DeformRig, DeformStats, Deformed, Handle, Pin};
use crate::mesh::{BitMask, MeshOptions, Polygon};
use crate::pixels::{Canvas, FloatImage};
use crate::scene::{Patch, PatchState, Shape};

/// Mask pixels at or above this luminance (or alpha) are inside.
const MASK_THRESHOLD: f32 = 0.5;

/// Everything kept between frames for one patch.
pub(super) struct Layer {
    pub name: String,
    cloner: PatchCloner,
    /// The rest point a placement's position refers to (bounding-box centre).
    pivot: DVec2,
    /// Built only for patches that deform at some time.
    rig: Option<DeformRig>,
    deformed: Deformed,
    handles: Vec<Handle>,
    pins: Vec<Pin>,
}

impl Layer {
    pub fn new(patch: &Patch, source: FloatImage) -> Result<Self, RenderError> {
        let clone_error = |source| RenderError::Clone {
            patch: patch.name.clone(),
            source,
        };
        let mut mesh_options = MeshOptions::default();
        if let Some(density) = patch.density {
            mesh_options.density = density;
        }
        let patch_mesh = mesh_patch(patch, &source, &mesh_options)?;
        let pivot = (patch_mesh.bbox_min + patch_mesh.bbox_max) * 0.5;
        let options = CloneOptions {
            laplacian: patch.laplacian,
            mode: patch.mode,
            feather: patch.feather as f32,
        };
        let cloner = PatchCloner::new(source, patch_mesh.result.mesh, &options).map_err(clone_error)?;
        let deforms = !patch.handles.is_empty() || !patch.pins.is_empty();
        let rig = if deforms {
            let rig = DeformRig::new(cloner.mesh(), patch.laplacian).map_err(|source| {
                RenderError::Deform {
                    patch: patch.name.clone(),
                    source,
                }
            })?;
            Some(rig)
        } else {
            None
        };
        Ok(Self {
            name: patch.name.clone(),
            cloner,
            pivot,
            rig,
            deformed: Deformed::default(),
            handles: Vec::new(),
            pins: Vec::new(),
        })
    }

    /// Clones this patch, in its state at this frame, onto `canvas`.
    pub fn draw(
        &mut self,
        state: &PatchState,
        canvas: &mut Canvas,
    ) -> Result<(CloneStats, DeformStats), RenderError> {
        let placement = Placement {
            pivot: self.pivot,
            at: state.position.unwrap_or(self.pivot),
            scale: state.scale,
            rotation_deg: state.rotation,
        };
        let deform_stats = self.deform(state)?;
        let result = match &self.rig {
            Some(_) => self.cloner.clone_deformed(
                canvas,
                &placement,
                &self.deformed.positions,
                Some(&self.deformed.depth),
            ),
            None => self.cloner.clone_onto(canvas, &placement),
        };
        let clone_stats = result.map_err(|source| RenderError::Clone {
            patch: self.name.clone(),
            source,
        })?;
        Ok((clone_stats, deform_stats))
    }

    fn deform(&mut self, state: &PatchState) -> Result<DeformStats, RenderError> {
        let Some(rig) = &mut self.rig else {
            return Ok(DeformStats::default());
        };
        self.handles.clear();
        self.handles.extend(state.handles.iter().map(|h| Handle {
            from: h.from,
            to: h.to,
            radius: h.radius,
            pivot: h.pivot,
            rotation_deg: h.rotation,
            depth: h.depth.map(|d| d as f32),
        }));
        self.pins.clear();
        self.pins.extend(state.pins.iter().map(|&p| Pin(p)));
        rig.deform(&self.handles, &self.pins, &mut self.deformed)
            .map_err(|source| RenderError::Deform {
                patch: self.name.clone(),
                source,
            })
    }

    pub fn vertex_count(&self) -> usize {
        self.cloner.mesh().vertex_count()
    }
}

fn mesh_patch(
    patch: &Patch,
    source: &FloatImage,
    options: &MeshOptions,
) -> Result<PatchMesh, RenderError> {
    let clone_error = |source| RenderError::Clone {
        patch: patch.name.clone(),
        source,
    };
    match &patch.shape {
        Shape::Mask(path) => {
            let mask = BitMask::load(path, MASK_THRESHOLD).map_err(|source| RenderError::Mask {
                patch: patch.name.clone(),
                path: path.clone(),
                source,
            })?;
            mesh_from_mask(&mask, None, (source.width(), source.height()), options)
                .map_err(clone_error)
        }
        Shape::Polygons(polygons) => {
            let polygons: Vec<Polygon> = polygons
                .iter()
                .map(|p| Polygon {
                    outer: p.outer.clone(),
                    holes: p.holes.clone(),
                })
                .collect();
            mesh_from_polygons(&polygons, options).map_err(clone_error)
        }
    }
}
