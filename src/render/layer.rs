//! One patch of a scene as the renderer keeps it: takes the patch description once (mesh,
//! cloning factor, deformation rig) and, per frame, its evaluated state, and clones it onto
//! the canvas.

use glam::DVec2;

use super::RenderError;
use crate::clone::{
    mesh_from_mask, mesh_from_polygons, reach_past, CloneOptions, CloneStats, PatchCloner, PatchMesh, Placement,
};
use crate::deform::{DeformRig, DeformStats, Deformed, Handle, Pin};
use crate::mesh::{BitMask, Mesh, MeshOptions, Polygon, MASK_THRESHOLD};
use crate::pixels::{Canvas, FloatImage, Footage, FootageReader};
use crate::scene::{
    BoundaryData, BoundaryPlacement, CloneMode, LaplacianKind, Patch, PatchState, Shape,
};

/// The patch settings a layer's mesh, cloning factor and rig are built from: a layer can be
/// kept for a new version of its patch exactly when these are equal.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct LayerSettings {
    source: std::path::PathBuf,
    footage: Option<Footage>,
    shape: Shape,
    density: Option<f64>,
    laplacian: LaplacianKind,
    mode: CloneMode,
    feather: f64,
    boundary_data: BoundaryData,
    boundary: BoundaryPlacement,
}

impl LayerSettings {
    pub fn of(patch: &Patch) -> Self {
        LayerSettings {
            source: patch.source.clone(),
            footage: patch.footage.clone(),
            shape: patch.shape.clone(),
            density: patch.density,
            laplacian: patch.laplacian,
            mode: patch.mode,
            feather: patch.feather,
            boundary_data: patch.boundary_data,
            boundary: patch.boundary,
        }
    }
}

/// Whether a patch deforms at some time (and so needs a rig).
pub(super) fn deforms(patch: &Patch) -> bool {
    !patch.handles.is_empty() || !patch.pins.is_empty()
}

/// Everything kept between frames for one patch.
pub(super) struct Layer {
    pub name: String,
    pub settings: LayerSettings,
    cloner: PatchCloner,
    /// The rest point a placement's position refers to (bounding-box centre).
    pivot: DVec2,
    /// Built only once the patch deforms at some time; kept (unused) if it stops deforming.
    rig: Option<DeformRig>,
    /// Whether the current version of the patch deforms (uses `rig`).
    deforms: bool,
    deformed: Deformed,
    handles: Vec<Handle>,
    pins: Vec<Pin>,
    /// An animated source's frames, and the frame index the cloner holds.
    footage: Option<(FootageReader, u64)>,
}

impl Layer {
    /// `source` is the patch's source image (an animated source's first frame); `fps` the
    /// scene's, which picks an animated source's frames.
    pub fn new(patch: &Patch, source: FloatImage, fps: f64) -> Result<Self, RenderError> {
        let clone_error = |source| RenderError::Clone {
            patch: patch.name.clone(),
            source,
        };
        let mut mesh_options = MeshOptions {
            boundary: patch.boundary,
            ..MeshOptions::default()
        };
        if let Some(density) = patch.density {
            mesh_options.density = density;
        }
        let patch_mesh = mesh_patch(patch, &source, &mesh_options)?;
        let pivot = (patch_mesh.bbox_min + patch_mesh.bbox_max) * 0.5;
        let options = CloneOptions {
            laplacian: patch.laplacian,
            mode: patch.mode,
            feather: patch.feather as f32,
            boundary_data: patch.boundary_data,
        };
        let cloner =
            PatchCloner::new(source, patch_mesh.result.mesh, &options).map_err(clone_error)?;
        let deforms = deforms(patch);
        let rig = if deforms {
            Some(build_rig(patch, cloner.mesh())?)
        } else {
            None
        };
        Ok(Self {
            name: patch.name.clone(),
            settings: LayerSettings::of(patch),
            cloner,
            pivot,
            rig,
            deforms,
            deformed: Deformed::default(),
            handles: Vec::new(),
            pins: Vec::new(),
            footage: patch
                .footage
                .clone()
                .map(|f| (FootageReader::new(f, fps), 0)),
        })
    }

    /// Moves an animated source to scene frame `index` (nothing for a still source).
    pub fn seek_source(&mut self, index: u64) -> Result<(), RenderError> {
        let Some((reader, held)) = self.footage.as_mut() else {
            return Ok(());
        };
        if *held == index {
            return Ok(());
        }
        let image = reader
            .frame(index)
            .map_err(|e| RenderError::footage(Some(&self.name), e))?;
        self.cloner.set_source(image.clone());
        *held = index;
        Ok(())
    }

    /// Factorisations of this layer's cloning Laplacian so far.
    pub fn factorisations(&self) -> usize {
        self.cloner.factorisations()
    }

    /// The canvas-independent part of cloning this patch, in its state at this frame:
    /// deformation, placement and self-occlusion. Layers of one frame may prepare in parallel.
    pub fn prepare(&mut self, state: &PatchState) -> Result<DeformStats, RenderError> {
        let placement = Placement {
            pivot: self.pivot,
            at: state.position.unwrap_or(self.pivot),
            scale: state.scale,
            rotation_deg: state.rotation,
        };
        let deform_stats = self.deform(state)?;
        let result = if self.deforms() {
            self.cloner.prepare_deformed(
                &placement,
                &self.deformed.positions,
                Some(&self.deformed.depth),
            )
        } else {
            self.cloner.prepare_rigid(&placement)
        };
        result.map_err(|source| self.clone_error(source))?;
        Ok(deform_stats)
    }

    /// After [`prepare`](Self::prepare): clones onto `canvas` (the composite of the layers
    /// below), shading on `raster_threads` threads.
    pub fn composite(
        &mut self,
        canvas: &mut Canvas,
        raster_threads: usize,
    ) -> Result<CloneStats, RenderError> {
        self.cloner.set_raster_threads(raster_threads);
        let depth = self.deforms().then_some(&self.deformed.depth[..]);
        let result = self.cloner.clone_prepared(canvas, depth);
        result.map_err(|source| self.clone_error(source))
    }

    /// Whether this layer deforms in the current version of its patch.
    pub fn deforms(&self) -> bool {
        self.rig.is_some() && self.deforms
    }

    fn clone_error(&self, source: crate::clone::CloneError) -> RenderError {
        RenderError::Clone {
            patch: self.name.clone(),
            source,
        }
    }

    fn deform(&mut self, state: &PatchState) -> Result<DeformStats, RenderError> {
        let Some(rig) = self.rig.as_mut().filter(|_| self.deforms) else {
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

    /// A rig this layer still needs for `patch` (a patch that gains its first handle or pin),
    /// built without touching the layer so a failure leaves it as it was.
    pub fn missing_rig(&self, patch: &Patch) -> Result<Option<DeformRig>, RenderError> {
        if deforms(patch) && self.rig.is_none() {
            build_rig(patch, self.cloner.mesh()).map(Some)
        } else {
            Ok(None)
        }
    }

    /// Takes the new version of its patch (same [`LayerSettings`]) and, if given, its new rig.
    pub fn update(&mut self, patch: &Patch, rig: Option<DeformRig>) {
        patch.name.clone_into(&mut self.name);
        if rig.is_some() {
            self.rig = rig;
        }
        self.deforms = deforms(patch);
    }

    /// The source image's width and height.
    pub fn source_size(&self) -> (u32, u32) {
        let source = self.cloner.source();
        (source.width(), source.height())
    }

    pub fn has_rig(&self) -> bool {
        self.rig.is_some()
    }

    pub fn settings_source(&self) -> &std::path::Path {
        &self.settings.source
    }

    pub fn source(&self) -> &FloatImage {
        self.cloner.source()
    }

    pub fn mesh(&self) -> &Mesh {
        self.cloner.mesh()
    }

    /// Canvas positions of the vertices in the last drawn frame.
    /// The rest point a placement's position refers to (bounding-box centre).
    pub fn pivot(&self) -> DVec2 {
        self.pivot
    }

    pub fn placed(&self) -> &[DVec2] {
        self.cloner.placed()
    }

    pub fn vertex_count(&self) -> usize {
        self.cloner.mesh().vertex_count()
    }
}

fn build_rig(patch: &Patch, mesh: &Mesh) -> Result<DeformRig, RenderError> {
    DeformRig::new(mesh, patch.laplacian).map_err(|source| RenderError::Deform {
        patch: patch.name.clone(),
        source,
    })
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
            let mask_error = |source| RenderError::Mask {
                patch: patch.name.clone(),
                path: path.clone(),
                source: Box::new(source),
            };
            let mask = BitMask::load(path, MASK_THRESHOLD).map_err(mask_error)?;
            mesh_from_mask(&mask, None, (source.width(), source.height()), options).map_err(
                |error| match error {
                    // A mesh error of a mask names the mask, as a read error does.
                    crate::clone::CloneError::Mesh(source) => mask_error(source),
                    other => clone_error(other),
                },
            )
        }
        Shape::Polygons(polygons) => {
            let size = (source.width(), source.height());
            if polygons_outside(polygons, size).is_some_and(|far| far.is_infinite()) {
                let patch = patch.name.clone();
                return Err(RenderError::OutsideSource { patch, size });
            }
            mesh_from_polygons(polygons, options).map_err(clone_error)
        }
    }
}

/// How far (px) `polygons` reach past a `size` source's rectangle, when they do (see
/// [`reach_past`]). Only outer rings count: holes lie inside them.
pub(super) fn polygons_outside(polygons: &[Polygon], size: (u32, u32)) -> Option<f64> {
    let points = polygons.iter().flat_map(|p| &p.outer);
    let (min, max) = points.fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| {
        (lo.min(p), hi.max(p))
    });
    reach_past(min, max, size)
}
