//! The scene renderer: takes a [`Scene`] once and frame indices or times after, and gives
//! each frame in a [`Canvas`] it keeps (no allocation per frame once warm).

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

use super::layer::Layer;
use super::RenderError;
use crate::pixels::{Canvas, Depth, FloatImage, PixelFormat};
use crate::scene::{frame_time, Background, FrameState, Scene};

/// Timings and counts of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    pub time: f64,
    /// Deformation constraint switches (all patches).
    pub deform_switches: usize,
    /// Cloning constraint switches (all patches).
    pub clone_switches: usize,
    /// Boundary vertices hidden under their own patch's front layer.
    pub hidden: usize,
    /// Boundary vertices outside the canvas.
    pub outside: usize,
    pub deform_ms: f64,
    pub solve_ms: f64,
    pub raster_ms: f64,
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
}

impl Renderer {
    /// Loads images, meshes and factors every patch.
    pub fn new(scene: Scene) -> Result<Self, RenderError> {
        scene.sanity_check()?;
        let background = background_canvas(&scene)?;
        let mut sources: HashMap<PathBuf, FloatImage> = HashMap::new();
        let mut layers = Vec::with_capacity(scene.patches.len());
        for patch in &scene.patches {
            let source = match sources.get(&patch.source) {
                Some(image) => image.clone(),
                None => {
                    let image = FloatImage::load(&patch.source)?;
                    sources.insert(patch.source.clone(), image.clone());
                    image
                }
            };
            layers.push(Layer::new(patch, source)?);
        }
        let frame = background.clone();
        Ok(Self {
            scene,
            background,
            frame,
            layers,
            state: FrameState::default(),
            stats: FrameStats::default(),
        })
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
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
        self.frame.copy_from(&self.background);
        let mut stats = FrameStats {
            time: t,
            ..FrameStats::default()
        };
        for &index in &self.state.draw_order {
            let deform_started = Instant::now();
            let (clone, deform) =
                self.layers[index].draw(&self.state.patches[index], &mut self.frame)?;
            stats.deform_ms +=
                millis(deform_started.elapsed()) - clone.solve_ms - clone.raster_ms;
            stats.solve_ms += clone.solve_ms;
            stats.raster_ms += clone.raster_ms;
            stats.deform_switches += deform.switches();
            let switches = clone.membrane.switches;
            stats.clone_switches += switches.updates + switches.downdates;
            stats.hidden += clone.membrane.hidden;
            stats.outside += clone.membrane.outside;
        }
        stats.total_ms = millis(started.elapsed());
        self.stats = stats;
        Ok(&self.frame)
    }

    /// The last rendered frame.
    pub fn frame(&self) -> &Canvas {
        &self.frame
    }

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
