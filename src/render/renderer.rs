//! The scene renderer: takes a [`Scene`] once and frame indices or times after, and gives
//! each frame in a [`Canvas`] it keeps (no allocation per frame once warm). This file is the
//! frame loop; loading the layers and the background is in `setup`, switching to an edited
//! scene in `diff`.

use std::time::Instant;

use glam::DVec2;

use super::layer::Layer;
use super::opacity::blend_over_below;
use super::RenderError;
use crate::mesh::Mesh;
use crate::pixels::{Canvas, Depth, FootageReader, PixelFormat, PixelRect};
use crate::scene::{frame_time, FrameState, Scene};
use crate::util::lock;

mod diff;
mod setup;

pub use diff::SceneUpdate;
use setup::{background_canvas, build_layers, canvas_over, check_footage};

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
    /// Front-layer boundary vertices glued to their own patch beneath them.
    pub glued: usize,
    /// Deformation (rigs) over all patches, ms.
    pub deform_ms: f64,
    /// Membrane solves over all patches, ms.
    pub solve_ms: f64,
    /// Rasterisation and compositing, ms.
    pub raster_ms: f64,
    /// The whole frame, ms.
    pub total_ms: f64,
}

/// Where the last frame may differ from its background: outside `rect` it equals the
/// background `background` names. Two frames with the same `background` differ at most inside
/// the union of their rectangles, so a viewer compares only there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawnRegion {
    /// Names the background canvas: a new number whenever any renderer builds or replaces
    /// one (a new scene's background, a footage plate), never reused within a process.
    pub background: u64,
    /// The bounding rectangle of what the frame's layers drew into (empty: none drew).
    pub rect: PixelRect,
}

/// The number naming the next background canvas (see [`DrawnRegion::background`]).
fn next_background_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// A scene with everything built once per patch. See the module doc.
pub struct Renderer {
    scene: Scene,
    background: Canvas,
    /// Names `background` (see [`DrawnRegion`]).
    background_id: u64,
    frame: Canvas,
    layers: Vec<Layer>,
    state: FrameState,
    stats: FrameStats,
    /// Rectangles the last frame drew into (valid when `dirty_valid`): the frame equals the
    /// background outside them.
    dirty: Vec<PixelRect>,
    dirty_valid: bool,
    /// The frame before a translucent layer was drawn (allocated by the first one).
    below: Option<Canvas>,
    /// Background footage, and the scene frame whose plate `background` holds.
    plates: Option<(FootageReader, u64)>,
    /// Threads each patch's raster shades on (see [`Renderer::set_raster_threads`]).
    raster_threads: usize,
}

impl Renderer {
    /// Loads images, meshes every patch and factors its Laplacian (see `PatchCloner::new`).
    pub fn new(scene: Scene) -> Result<Self, RenderError> {
        scene.sanity_check()?;
        check_footage(&scene)?;
        // The background decodes on a thread of its own while the layers load and mesh.
        let (background, layers) = std::thread::scope(|scope| {
            let background = scope.spawn(|| background_canvas(&scene));
            let layers = build_layers(&scene);
            let background = background
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (background, layers)
        });
        let (background, plates) = background?;
        let layers = layers?;
        let frame = background.clone();
        Ok(Self {
            scene,
            background,
            background_id: next_background_id(),
            frame,
            layers,
            state: FrameState::default(),
            stats: FrameStats::default(),
            dirty: Vec::new(),
            dirty_valid: true,
            below: None,
            plates,
            raster_threads: 1,
        })
    }

    /// Shades each patch on `threads` threads (the caller's and the raster's worker pool's;
    /// 1 by default, at least 1; at most [`MAX_RASTER_THREADS`](crate::MAX_RASTER_THREADS)
    /// per draw): the pixels are the same for any count. One thread suits a scene render,
    /// whose other cores encode frames; an interactive session that waits on each frame
    /// gives it every core.
    pub fn set_raster_threads(&mut self, threads: usize) {
        self.raster_threads = threads.max(1);
    }

    /// The scene being rendered.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    internal_fn! {
        /// Each patch's mesh and where the last frame placed it, in scene order.
        fn placed_meshes(&self) -> Vec<PlacedMesh<'_>> {
            self.layers
                .iter()
                .map(|l| PlacedMesh {
                    name: &l.name,
                    mesh: l.mesh(),
                    placed: l.placed(),
                })
                .collect()
        }
    }

    /// Each patch's rest pivot, in scene order: the source point its `at` key places (the
    /// centre of its bounding box), about which `scale` and `rotate` act.
    pub fn pivots(&self) -> Vec<DVec2> {
        self.layers.iter().map(Layer::pivot).collect()
    }

    /// Each patch's source image size (width, height), in scene order.
    pub(crate) fn source_sizes(&self) -> Vec<(u32, u32)> {
        self.layers.iter().map(Layer::source_size).collect()
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
        self.render_at(frame_time(index, self.scene.canvas.fps), index)
    }

    /// The frame at time `t` seconds (footage shows its frame ⌊t · fps⌋).
    pub fn render_time(&mut self, t: f64) -> Result<&Canvas, RenderError> {
        let index = (t * self.scene.canvas.fps + 1e-9).floor().max(0.0) as u64;
        self.render_at(t, index)
    }

    /// Factorisations of the patches' cloning Laplacians so far (one per patch once each
    /// has drawn, whatever the frame count, unless a guard had to rebuild one).
    pub fn factorisations(&self) -> usize {
        self.layers.iter().map(Layer::factorisations).sum()
    }

    fn render_at(&mut self, t: f64, index: u64) -> Result<&Canvas, RenderError> {
        let started = Instant::now();
        self.scene.evaluate_into(t, &mut self.state);
        self.seek_footage(index)?;
        self.restore_background()?;
        let mut stats = FrameStats {
            time: t,
            ..FrameStats::default()
        };
        let prepare_started = Instant::now();
        stats.deform_switches = self.prepare_layers()?;
        stats.deform_ms = millis(prepare_started.elapsed());
        for &index in &self.state.draw_order {
            let opacity = self.state.patches[index].opacity;
            if opacity <= 0.0 {
                continue;
            }
            let composite_started = Instant::now();
            if opacity < 1.0 {
                let frame = &self.frame;
                self.below
                    .get_or_insert_with(|| frame.clone())
                    .copy_from(frame);
            }
            let clone = self.layers[index].composite(&mut self.frame, self.raster_threads)?;
            if let Some(below) = self.below.as_ref().filter(|_| opacity < 1.0) {
                blend_over_below(&mut self.frame, below, clone.raster.work, opacity);
            }
            stats.deform_ms +=
                millis(composite_started.elapsed()) - clone.solve_ms - clone.raster_ms;
            stats.solve_ms += clone.solve_ms;
            stats.raster_ms += clone.raster_ms;
            let switches = clone.membrane.switches;
            stats.clone_switches += switches.updates + switches.downdates;
            stats.hidden += clone.membrane.hidden;
            stats.outside += clone.membrane.outside;
            stats.glued += clone.membrane.glued;
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
        if deforming < 2 || crate::util::available_cores() < 2 {
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
            for _ in 0..crate::util::available_cores().min(deforming) {
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

    /// Puts footage at scene frame `index`: the background's plate and animated sources.
    fn seek_footage(&mut self, index: u64) -> Result<(), RenderError> {
        if let Some((reader, held)) = self.plates.as_mut().filter(|(_, held)| *held != index) {
            let plate = reader
                .frame(index)
                .map_err(|e| RenderError::footage(None, e))?;
            let (width, height) = (self.scene.canvas.width, self.scene.canvas.height);
            self.background = canvas_over(plate, width, height)?;
            self.background_id = next_background_id();
            *held = index;
            self.dirty_valid = false;
        }
        for &layer in &self.state.draw_order {
            self.layers[layer].seek_source(index)?;
        }
        Ok(())
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

    /// Where the last frame may differ from its background; `None` when that is not known
    /// (a frame failed midway).
    pub fn drawn_region(&self) -> Option<DrawnRegion> {
        if !self.dirty_valid {
            return None;
        }
        let rect = self
            .dirty
            .iter()
            .filter(|r| !r.is_empty())
            .copied()
            .reduce(|a, b| a.union(&b))
            .unwrap_or_default();
        Some(DrawnRegion {
            background: self.background_id,
            rect,
        })
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

fn millis(duration: std::time::Duration) -> f64 {
    duration.as_secs_f64() * 1e3
}
