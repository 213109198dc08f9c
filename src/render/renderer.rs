//! The scene renderer: takes a [`Scene`] once and frame indices or times after, and gives
//! each frame in a [`Canvas`] it keeps (no allocation per frame once warm).

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

use glam::DVec2;

use super::layer::{Layer, LayerSettings};
use super::RenderError;
use crate::mesh::Mesh;
use crate::pixels::{Canvas, Depth, FloatImage, PixelFormat};
use crate::raster::PixelRect;
use crate::scene::{frame_time, Background, FrameState, Patch, Scene};
use crate::util::lock;

/// What [`Renderer::set_scene`] kept and built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneUpdate {
    /// Layers kept with their mesh, cloning factor and rig.
    pub reused: usize,
    /// Layers meshed and factored anew (new patches, or changed mesh-defining settings).
    pub rebuilt: usize,
    /// Old layers not kept: their patch was removed, renamed or changed its mesh settings.
    pub dropped: usize,
    /// Deformation rigs built for kept layers whose patch gained its first handle or pin.
    pub rigs_built: usize,
    /// Whether the background was reloaded (changed background or canvas size).
    pub background_changed: bool,
}

/// One patch's mesh where the last frame put it: for mesh overlays.
#[derive(Clone, Copy, Debug)]
pub struct PlacedMesh<'a> {
    pub name: &'a str,
    pub mesh: &'a Mesh,
    /// Canvas positions of `mesh`'s vertices in the last rendered frame (empty before one).
    pub placed: &'a [DVec2],
}

/// Timings and counts of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Scene time of the frame, seconds.
    pub time: f64,
    /// Deformation constraint switches (all patches).
    pub deform_switches: usize,
    /// Cloning constraint switches (all patches).
    pub clone_switches: usize,
    /// Boundary vertices hidden under their own patch's front layer.
    pub hidden: usize,
    /// Boundary vertices outside the canvas.
    pub outside: usize,
    /// Deformation (rigs) over all patches, ms.
    pub deform_ms: f64,
    /// Membrane solves over all patches, ms.
    pub solve_ms: f64,
    /// Rasterisation and compositing, ms.
    pub raster_ms: f64,
    /// The whole frame, ms.
    pub total_ms: f64,
}

/// A scene with everything built once per patch. See the module doc.
pub struct Renderer {
    scene: Scene,
    background: Canvas,
    frame: Canvas,
    layers: Vec<Layer>,
    state: FrameState,
    stats: FrameStats,
    /// Rectangles the last frame drew into (valid when `dirty_valid`): the frame equals the
    /// background outside them.
    dirty: Vec<PixelRect>,
    dirty_valid: bool,
}

impl Renderer {
    /// Loads images and meshes every patch; the cloning factors are built by the first frame
    /// (see `PatchCloner::new`).
    pub fn new(scene: Scene) -> Result<Self, RenderError> {
        scene.sanity_check()?;
        let background = background_canvas(&scene)?;
        let mut sources: HashMap<PathBuf, FloatImage> = HashMap::new();
        let mut layers = Vec::with_capacity(scene.patches.len());
        for patch in &scene.patches {
            layers.push(Layer::new(patch, source_image(&mut sources, patch)?)?);
        }
        let frame = background.clone();
        Ok(Self {
            scene,
            background,
            frame,
            layers,
            state: FrameState::default(),
            stats: FrameStats::default(),
            dirty: Vec::new(),
            dirty_valid: true,
        })
    }

    /// The scene being rendered.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Switches to a new version of the scene, keeping every layer (mesh, cloning factor,
    /// deformation rig) whose patch — matched by name — has the same mesh-defining settings
    /// (source, shape, density, Laplacian kind, mode, feather, boundary data). Only new or changed patches
    /// are meshed and factored; a kept patch that gained its first handle or pin gets a rig.
    /// On error the renderer is unchanged.
    pub fn set_scene(&mut self, scene: Scene) -> Result<SceneUpdate, RenderError> {
        scene.sanity_check()?;
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
                    let mut layer = old[index].take().expect("layer kept once"); // invariant: plan_layers hands out each old index at most once.
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
        if let Some(background) = background {
            self.frame = background.clone();
            self.background = background;
            self.dirty.clear();
            self.dirty_valid = true;
        }
        self.scene = scene;
        Ok(update)
    }

    /// For each new patch, the old layer it keeps (and a rig it still needs) or a new layer.
    /// Does all fallible work without touching `self`.
    fn plan_layers(&self, patches: &[Patch]) -> Result<Vec<Planned>, RenderError> {
        let mut taken = vec![false; self.layers.len()];
        let mut sources: HashMap<PathBuf, FloatImage> = self
            .layers
            .iter()
            .map(|l| (l.settings_source().to_path_buf(), l.source().clone()))
            .collect();
        let mut plan = Vec::with_capacity(patches.len());
        for patch in patches {
            let settings = LayerSettings::of(patch);
            let kept = self
                .layers
                .iter()
                .enumerate()
                .position(|(i, l)| !taken[i] && l.name == patch.name && l.settings == settings);
            plan.push(match kept {
                Some(index) => {
                    taken[index] = true;
                    let rig = self.layers[index].missing_rig(patch)?.map(Box::new);
                    Planned::Keep { index, rig }
                }
                None => {
                    let source = source_image(&mut sources, patch)?;
                    Planned::Build(Box::new(Layer::new(patch, source)?))
                }
            });
        }
        Ok(plan)
    }

    /// Each patch's mesh and where the last frame placed it, in scene order.
    pub fn placed_meshes(&self) -> Vec<PlacedMesh<'_>> {
        self.layers
            .iter()
            .map(|l| PlacedMesh {
                name: &l.name,
                mesh: l.mesh(),
                placed: l.placed(),
            })
            .collect()
    }

    /// Whether each patch (scene order) has a deformation rig built.
    pub fn rigs_built(&self) -> Vec<bool> {
        self.layers.iter().map(Layer::has_rig).collect()
    }

    /// Number of frames: ⌈duration · fps⌉.
    pub fn frame_count(&self) -> u64 {
        self.scene.canvas.frame_count()
    }

    /// Frame `index` (from 0) at t = index / fps.
    pub fn render_frame(&mut self, index: u64) -> Result<&Canvas, RenderError> {
        self.render_time(frame_time(index, self.scene.canvas.fps))
    }

    /// The frame at time `t` seconds.
    pub fn render_time(&mut self, t: f64) -> Result<&Canvas, RenderError> {
        let started = Instant::now();
        self.scene.evaluate_into(t, &mut self.state);
        self.restore_background()?;
        let mut stats = FrameStats {
            time: t,
            ..FrameStats::default()
        };
        let prepare_started = Instant::now();
        stats.deform_switches = self.prepare_layers()?;
        stats.deform_ms = millis(prepare_started.elapsed());
        for &index in &self.state.draw_order {
            let composite_started = Instant::now();
            let clone = self.layers[index].composite(&mut self.frame)?;
            stats.deform_ms +=
                millis(composite_started.elapsed()) - clone.solve_ms - clone.raster_ms;
            stats.solve_ms += clone.solve_ms;
            stats.raster_ms += clone.raster_ms;
            let switches = clone.membrane.switches;
            stats.clone_switches += switches.updates + switches.downdates;
            stats.hidden += clone.membrane.hidden;
            stats.outside += clone.membrane.outside;
            self.dirty.push(clone.raster.work);
        }
        self.dirty_valid = true;
        stats.total_ms = millis(started.elapsed());
        self.stats = stats;
        Ok(&self.frame)
    }

    /// Deforms and places every drawn layer (they do not read the canvas): in parallel when
    /// several deform and there are cores for them, else in order. Gives the deformation
    /// constraint switches; on failure, the error of the first failing layer in draw order.
    fn prepare_layers(&mut self) -> Result<usize, RenderError> {
        let order = &self.state.draw_order;
        let patches = &self.state.patches;
        let deforming = order.iter().filter(|&&i| self.layers[i].deforms()).count();
        if deforming < 2 || available_cores() < 2 {
            let mut switches = 0;
            for &index in order {
                switches += self.layers[index].prepare(&patches[index])?.switches();
            }
            return Ok(switches);
        }
        let mut drawn = vec![false; self.layers.len()];
        order.iter().for_each(|&i| drawn[i] = true);
        type Job<'a> = (usize, &'a mut Layer, Option<Result<usize, RenderError>>);
        let mut jobs: Vec<Job> = self
            .layers
            .iter_mut()
            .enumerate()
            .filter(|(index, _)| drawn[*index])
            .map(|(index, layer)| (index, layer, None))
            .collect();
        let queue = std::sync::Mutex::new(jobs.iter_mut());
        std::thread::scope(|scope| {
            for _ in 0..available_cores().min(deforming) {
                scope.spawn(|| loop {
                    let job = lock(&queue).next();
                    let Some((index, layer, result)) = job else {
                        break;
                    };
                    *result = Some(layer.prepare(&patches[*index]).map(|d| d.switches()));
                });
            }
        });
        let mut switches = 0;
        for &index in order {
            if let Some((_, _, Some(result))) = jobs.iter_mut().find(|job| job.0 == index) {
                switches += std::mem::replace(result, Ok(0))?;
            }
        }
        Ok(switches)
    }

    /// Resets the frame to the background: only the rectangles the last frame drew into when
    /// they are known (a frame is mostly background), else the whole canvas.
    fn restore_background(&mut self) -> Result<(), RenderError> {
        if self.dirty_valid {
            for rect in &self.dirty {
                self.frame.copy_rect_from(&self.background, *rect)?;
            }
        } else {
            self.frame.copy_from(&self.background);
        }
        // Until this frame completes, a failure may leave other pixels drawn.
        self.dirty_valid = false;
        self.dirty.clear();
        Ok(())
    }

    /// The last rendered frame.
    pub fn frame(&self) -> &Canvas {
        &self.frame
    }

    /// Timings of the last frame rendered.
    pub fn last_stats(&self) -> FrameStats {
        self.stats
    }

    /// Vertex counts of the patch meshes, in scene order.
    pub fn vertex_counts(&self) -> Vec<usize> {
        self.layers.iter().map(Layer::vertex_count).collect()
    }

    /// The PNG format frames are written in: RGBA in the canvas's depth.
    pub fn output_format(&self) -> PixelFormat {
        match self.frame.depth() {
            Depth::Eight => PixelFormat::RGBA8,
            Depth::Sixteen => PixelFormat::RGBA16,
        }
    }
}

enum Planned {
    Keep {
        index: usize,
        rig: Option<Box<crate::deform::DeformRig>>,
    },
    Build(Box<Layer>),
}

/// The patch's source image, loaded once per path.
fn source_image(
    sources: &mut HashMap<PathBuf, FloatImage>,
    patch: &Patch,
) -> Result<FloatImage, RenderError> {
    if let Some(image) = sources.get(&patch.source) {
        return Ok(image.clone());
    }
    let image = FloatImage::load(&patch.source)?;
    sources.insert(patch.source.clone(), image.clone());
    Ok(image)
}

/// The canvas every frame starts from: the background image at the origin over opaque
/// black (16-bit when the image is), or a plain colour.
fn background_canvas(scene: &Scene) -> Result<Canvas, RenderError> {
    let (width, height) = (scene.canvas.width, scene.canvas.height);
    match &scene.canvas.background {
        Background::Colour(rgba) => {
            let image = FloatImage::from_fn(width, height, PixelFormat::RGBA8, |_, _| *rgba)?;
            Ok(Canvas::from_image(&image))
        }
        Background::Image(path) => {
            let picture = FloatImage::load(path)?;
            let format = PixelFormat {
                alpha: true,
                ..picture.format()
            };
            let image = FloatImage::from_fn(width, height, format, |x, y| {
                picture.pixel(x, y).unwrap_or([0.0, 0.0, 0.0, 1.0])
            })?;
            Ok(Canvas::from_image(&image))
        }
    }
}

fn millis(duration: std::time::Duration) -> f64 {
    duration.as_secs_f64() * 1e3
}

/// Cores available to this process (1 if unknown), looked up once.
fn available_cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}
