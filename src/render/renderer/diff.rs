//! Scene diffing for the REPL: takes a new version of the renderer's scene and gives the
//! renderer's layers for it, keeping each layer (mesh, cloning factor, rig) whose patch's
//! mesh-defining settings did not change, and a [`SceneUpdate`] saying what was kept.

use std::collections::HashMap;
use std::path::PathBuf;

use super::setup::{background_canvas, check_footage, source_image};
use super::Renderer;
use crate::pixels::FloatImage;
use crate::render::layer::{Layer, LayerSettings};
use crate::render::RenderError;
use crate::scene::{Patch, Scene};

/// What [`Renderer::set_scene`] kept and built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneUpdate {
    /// Layers kept with their mesh, cloning factor and rig.
    pub reused: usize,
    /// Layers meshed and factored anew (new patches, or changed mesh-defining settings).
    pub rebuilt: usize,
    /// Old layers not kept: their patch was removed or changed its mesh settings (a renamed
    /// patch keeps its layer).
    pub dropped: usize,
    /// Deformation rigs built for kept layers whose patch gained its first handle or pin.
    pub rigs_built: usize,
    /// Whether the background was reloaded (changed background or canvas size).
    pub background_changed: bool,
}

impl Renderer {
    /// Switches to a new version of the scene, keeping every layer (mesh, cloning factor,
    /// deformation rig) whose patch — matched by name, else (a rename) by settings alone — has the same mesh-defining settings
    /// (source, shape, density, Laplacian kind, mode, feather, boundary data). Only new or changed patches
    /// are meshed and factored; a kept patch that gained its first handle or pin gets a rig.
    /// On error the renderer is unchanged.
    pub fn set_scene(&mut self, scene: Scene) -> Result<SceneUpdate, RenderError> {
        scene.sanity_check()?;
        check_footage(&scene)?;
        let mut update = SceneUpdate::default();
        let canvas_changed = scene.canvas.background != self.scene.canvas.background
            || (scene.canvas.width, scene.canvas.height)
                != (self.scene.canvas.width, self.scene.canvas.height);
        let background = if canvas_changed {
            update.background_changed = true;
            Some(background_canvas(&scene)?)
        } else {
            None
        };
        let plan = self.plan_layers(&scene.patches)?;
        let mut old: Vec<Option<Layer>> = std::mem::take(&mut self.layers)
            .into_iter()
            .map(Some)
            .collect();
        for (patch, planned) in scene.patches.iter().zip(plan) {
            let layer = match planned {
                Planned::Keep { index, rig } => {
                    update.reused += 1;
                    update.rigs_built += usize::from(rig.is_some());
                    // invariant: plan_layers hands out each old index at most once.
                    let mut layer = old[index].take().expect("layer kept once");
                    layer.update(patch, rig.map(|rig| *rig));
                    layer
                }
                Planned::Build(layer) => {
                    update.rebuilt += 1;
                    *layer
                }
            };
            self.layers.push(layer);
        }
        update.dropped = old.iter().filter(|l| l.is_some()).count();
        if let Some((background, plates)) = background {
            self.frame = background.clone();
            self.background = background;
            self.background_id = super::next_background_id();
            self.plates = plates;
            self.dirty.clear();
            self.dirty_valid = true;
        }
        self.scene = scene;
        Ok(update)
    }

    /// For each new patch, the old layer it keeps (and a rig it still needs) or a new layer.
    /// Does all fallible work without touching `self`.
    fn plan_layers(&self, patches: &[Patch]) -> Result<Vec<Planned>, RenderError> {
        let kept = self.match_layers(patches);
        // Sources the kept layers already decoded, for new layers that share them (copied
        // only when a layer is to be built: an edit during a drag builds none).
        let mut sources: HashMap<PathBuf, FloatImage> = match kept.contains(&None) {
            true => self
                .layers
                .iter()
                .map(|l| (l.settings_source().to_path_buf(), l.source().clone()))
                .collect(),
            false => HashMap::new(),
        };
        let mut plan = Vec::with_capacity(patches.len());
        for (patch, kept) in patches.iter().zip(kept) {
            plan.push(match kept {
                Some(index) => {
                    let rig = self.layers[index].missing_rig(patch)?.map(Box::new);
                    Planned::Keep { index, rig }
                }
                None => {
                    let fps = self.scene.canvas.fps;
                    let source = source_image(&mut sources, patch, fps)?;
                    Planned::Build(Box::new(Layer::new(patch, source, fps)?))
                }
            });
        }
        Ok(plan)
    }

    /// The old layer each new patch keeps: first one of its own name with equal settings, then
    /// (a renamed patch) any unclaimed layer with equal settings — a layer's mesh, factor and
    /// rig depend on the settings alone.
    fn match_layers(&self, patches: &[Patch]) -> Vec<Option<usize>> {
        let settings: Vec<LayerSettings> = patches.iter().map(LayerSettings::of).collect();
        let mut taken = vec![false; self.layers.len()];
        let mut kept = vec![None; patches.len()];
        for by_name in [true, false] {
            for (i, patch) in patches.iter().enumerate() {
                if kept[i].is_some() {
                    continue;
                }
                kept[i] = self.layers.iter().enumerate().position(|(j, l)| {
                    !taken[j] && (!by_name || l.name == patch.name) && l.settings == settings[i]
                });
                if let Some(j) = kept[i] {
                    taken[j] = true;
                }
            }
        }
        kept
    }
}

enum Planned {
    Keep {
        index: usize,
        rig: Option<Box<crate::deform::DeformRig>>,
    },
    Build(Box<Layer>),
}
