//! The scene data model: plain Rust values (no Rhai) describing a canvas and layered,
//! keyframed patches. Built by `script` from a scene file, consumed by the renderer through
//! [`Scene::evaluate`](super::Scene::evaluate). Paths are already resolved (relative to the
//! scene file's folder); coordinates are pixels, x right, y down.

use std::path::PathBuf;

use glam::DVec2;

use super::track::{KeyError, Track};

/// Largest accepted canvas side, in pixels.
pub const MAX_CANVAS_SIDE: u32 = 16384;

/// A whole scene: one canvas and patches layered in order (each clones onto the composite of
/// the patches before it; see `FrameState::draw_order`).
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Size, timing and background.
    pub canvas: Canvas,
    /// Patches, back to front unless their depth says otherwise.
    pub patches: Vec<Patch>,
    /// What `lapclone test` checks and how strictly (`golden(#{ … })`); rendering ignores it.
    pub golden: Option<crate::golden::GoldenSettings>,
}

/// Output size, timing and what lies under every patch.
#[derive(Clone, Debug, PartialEq)]
pub struct Canvas {
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// Frames per second; frame i is shown at t = i / fps.
    pub fps: f64,
    /// Seconds; the scene has [`Canvas::frame_count`] frames.
    pub duration: f64,
    /// What the first patch is cloned onto.
    pub background: Background,
}

/// What lies under every patch.
#[derive(Clone, Debug, PartialEq)]
pub enum Background {
    /// An image, drawn at the canvas origin at its own size.
    Image(PathBuf),
    /// Straight (not premultiplied) RGBA, each channel in [0, 1].
    Colour([f32; 4]),
    /// Numbered plates or a video: frame i of the scene is drawn over the footage's frame i,
    /// at the canvas origin like an image.
    Footage(Footage),
}

pub use crate::pixels::{Footage, FootageSource};

/// A polygon with holes in source-pixel coordinates: the mesher's own type.
pub use crate::mesh::Polygon;

/// Which pixels of the source make up the patch.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A mask image of the source's size: alpha (or luma without alpha) at least
    /// [`MASK_THRESHOLD`](crate::MASK_THRESHOLD) is inside.
    Mask(PathBuf),
    /// Polygons with holes, source-pixel coordinates.
    Polygons(Vec<Polygon>),
}

pub use crate::clone::{BoundaryData, CloneMode};
pub use crate::mesh::BoundaryPlacement;
pub use crate::solve::LaplacianKind;

/// Where a patch sits in the canvas over time. Empty tracks take their defaults:
/// `position` = the patch stays where it is in the source (its bounding-box centre keeps its
/// source coordinates), `scale` 1, `rotation` 0°, `depth` 0, `opacity` 1.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Placement {
    /// Canvas position of the centre of the patch's bounding box.
    pub position: Track<DVec2>,
    /// Uniform scale about the bounding-box centre.
    pub scale: Track<f64>,
    /// Degrees, clockwise on screen (y down), about the bounding-box centre.
    pub rotation: Track<f64>,
    /// Layering: higher depth is drawn later (in front); ties keep scene order.
    pub depth: Track<f64>,
    /// In [0, 1]: how much of the cloned patch shows over the layers below (1 = all of it).
    pub opacity: Track<f64>,
}

/// A drag of the patch's rest point `from` (source coordinates) to `to(t)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Handle {
    /// Rest point (source coordinates) that is dragged.
    pub from: DVec2,
    /// Target over time in source coordinates; an empty track means `to = from`.
    pub to: Track<DVec2>,
    /// Radius of influence in source pixels (> 0).
    pub radius: f64,
    /// Explicit depth of the dragged region (front/back under self-overlap).
    pub depth: Option<f64>,
    /// Centre of the rotation the drag induces; default the patch's rest centroid.
    pub pivot: Option<DVec2>,
    /// Rotation override in degrees, replacing the angle derived from the drag; an empty
    /// track means no override.
    pub rotation: Track<f64>,
}

/// Holds a rest point of the patch still while it is active: `start ≤ t < end`.
#[derive(Clone, Debug, PartialEq)]
pub struct Pin {
    /// Rest point held still.
    pub at: DVec2,
    /// Seconds from which the pin holds.
    pub start: f64,
    /// Seconds at which it lets go; `None`: never.
    pub end: Option<f64>,
}

impl Pin {
    /// Whether the pin holds at time `t`.
    pub fn is_active(&self, t: f64) -> bool {
        t >= self.start && self.end.is_none_or(|end| t < end)
    }
}

/// One patch: where it comes from, how it is meshed and cloned, and how it moves.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    /// Name, unique in the scene (errors and the REPL use it).
    pub name: String,
    /// The source image; for an animated source, its first frame (what the mask fits).
    pub source: PathBuf,
    /// An animated source: frame i clones the footage's frame i (mask and mesh stay fixed).
    pub footage: Option<Footage>,
    /// Which pixels of the source make up the patch.
    pub shape: Shape,
    /// Mesh density (mesher's default when `None`).
    pub density: Option<f64>,
    /// Which Laplacian the membrane solves with.
    pub laplacian: LaplacianKind,
    /// Normal or monochrome cloning.
    pub mode: CloneMode,
    /// Width in pixels of the softened outer edge (0: hard edge, anti-aliased).
    pub feather: f64,
    /// How the membrane's boundary values are sampled.
    pub boundary_data: BoundaryData,
    /// Where a mask patch's mesh boundary runs (polygon patches ignore it).
    pub boundary: BoundaryPlacement,
    /// Animated position, scale, rotation and depth.
    pub placement: Placement,
    /// Drags, applied every frame.
    pub handles: Vec<Handle>,
    /// Points held still while active.
    pub pins: Vec<Pin>,
    /// Tracks this patch's keys came from (`follow` calls), latest last.
    pub follows: Vec<Follow>,
}

impl Patch {
    /// A patch with default settings and no keys.
    pub fn new(name: impl Into<String>, source: PathBuf, shape: Shape) -> Self {
        Patch {
            name: name.into(),
            source,
            footage: None,
            shape,
            density: None,
            laplacian: LaplacianKind::default(),
            mode: CloneMode::default(),
            feather: 0.0,
            boundary_data: BoundaryData::default(),
            boundary: BoundaryPlacement::default(),
            placement: Placement::default(),
            handles: Vec::new(),
            pins: Vec::new(),
            follows: Vec::new(),
        }
    }
}

/// A structural problem found by [`Scene::sanity_check`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// The canvas size is zero.
    #[error("canvas size {0}×{1} must be between 1 and {MAX_CANVAS_SIDE} on each side")]
    CanvasSize(u32, u32),
    /// The canvas exceeds a resource limit.
    #[error("canvas {0}×{1}: {2}")]
    CanvasLimit(u32, u32, crate::limits::LimitError),
    /// The frame rate is not within `limits::MIN_FPS` and `limits::MAX_FPS`.
    #[error("fps {0} must lie between {min} and {max}", min = crate::limits::MIN_FPS, max = crate::limits::MAX_FPS)]
    Fps(f64),
    /// The duration is not a positive finite number.
    #[error("duration {0} must be a finite number > 0")]
    Duration(f64),
    /// The duration at the frame rate gives more frames than `limits::MAX_FRAMES`.
    #[error(
        "duration {duration} s at {fps} fps is {frames} frames, over the limit of {max} \
         frames per scene",
        duration = crate::util::number_text(*.0),
        fps = crate::util::number_text(*.1),
        frames = crate::util::number_text((.0 * .1).ceil()),
        max = crate::limits::MAX_FRAMES
    )]
    TooLong(f64, f64),
    /// The background colour has a channel outside [0, 1].
    #[error("background colour channels must be finite and in [0, 1]")]
    Colour,
    /// A patch's setting is invalid.
    #[error("patch `{patch}`: {what}")]
    Patch {
        /// The patch's name.
        patch: String,
        /// What is wrong.
        what: String,
    },
    /// A key of a patch's track is invalid.
    #[error("patch `{patch}`: {track}: {error}")]
    Key {
        /// The patch's name.
        patch: String,
        /// Which track (`position`, `scale`, …).
        track: String,
        /// Why the key was refused.
        error: KeyError,
    },
}

impl Canvas {
    /// Whether time `t` (seconds) lies after the scene's end: `preview --t`, the REPL's `:t`
    /// and the live view's playhead refuse such a time, whose picture no render makes.
    pub fn is_past_end(&self, t: f64) -> bool {
        t > self.duration
    }

    /// Number of frames: every i with i / fps < duration.
    pub fn frame_count(&self) -> u64 {
        // The small slack keeps e.g. duration 3, fps 24 at exactly 72 frames despite rounding.
        let frames = (self.duration * self.fps - 1e-9).ceil();
        (frames.max(1.0)) as u64
    }

    /// Checks the whole scene: canvas, every patch and every key.
    pub fn sanity_check(&self) -> Result<(), ModelError> {
        let side_ok = |s: u32| (1..=MAX_CANVAS_SIDE).contains(&s);
        if !side_ok(self.width) || !side_ok(self.height) {
            return Err(ModelError::CanvasSize(self.width, self.height));
        }
        if crate::limits::fps_error(self.fps).is_some() {
            return Err(ModelError::Fps(self.fps));
        }
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(ModelError::Duration(self.duration));
        }
        let limit = |e| ModelError::CanvasLimit(self.width, self.height, e);
        crate::limits::check_image_size(u64::from(self.width), u64::from(self.height))
            .map_err(limit)?;
        // Decided on the product, not the saturated count, so the message names it.
        if crate::limits::check_frame_count(self.frame_count()).is_err() {
            return Err(ModelError::TooLong(self.duration, self.fps));
        }
        if let Background::Colour(c) = &self.background {
            if !c.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
                return Err(ModelError::Colour);
            }
        }
        Ok(())
    }
}

impl Scene {
    /// A scene of `patches` (back to front) on `canvas`, with no golden-frame settings.
    pub fn new(canvas: Canvas, patches: Vec<Patch>) -> Self {
        Self {
            canvas,
            patches,
            golden: None,
        }
    }

    /// Every value finite and in range, every track ordered.
    pub fn sanity_check(&self) -> Result<(), ModelError> {
        self.canvas.sanity_check()?;
        for patch in &self.patches {
            patch.sanity_check()?;
        }
        Ok(())
    }
}

impl Patch {
    /// Checks the placement's and the handles' tracks and rest values.
    fn check_tracks(&self) -> Result<(), ModelError> {
        let fail = |what: String| ModelError::Patch {
            patch: self.name.clone(),
            what,
        };
        let key = |track: &str, error: KeyError| ModelError::Key {
            patch: self.name.clone(),
            track: track.to_string(),
            error,
        };
        let p = &self.placement;
        p.position.sanity_check().map_err(|e| key("position", e))?;
        p.scale.sanity_check().map_err(|e| key("scale", e))?;
        p.rotation.sanity_check().map_err(|e| key("rotation", e))?;
        p.depth.sanity_check().map_err(|e| key("depth", e))?;
        p.opacity.sanity_check().map_err(|e| key("opacity", e))?;
        if p.scale.keys().iter().any(|k| k.value <= 0.0) {
            return Err(fail("scale must be > 0".into()));
        }
        if p.opacity
            .keys()
            .iter()
            .any(|k| !(0.0..=1.0).contains(&k.value))
        {
            return Err(fail("opacity must be in [0, 1]".into()));
        }
        for (i, h) in self.handles.iter().enumerate() {
            if !(h.from.is_finite() && h.radius.is_finite() && h.radius > 0.0) {
                return Err(fail(format!(
                    "handle {i}: rest point and radius must be finite, radius > 0"
                )));
            }
            if h.depth.is_some_and(|d| !d.is_finite()) || h.pivot.is_some_and(|p| !p.is_finite()) {
                return Err(fail(format!("handle {i}: depth and pivot must be finite")));
            }
            h.to.sanity_check()
                .map_err(|e| key(&format!("handle {i}"), e))?;
            h.rotation
                .sanity_check()
                .map_err(|e| key(&format!("handle {i} rotation"), e))?;
        }
        Ok(())
    }

    /// Checks the patch's settings and keys.
    pub fn sanity_check(&self) -> Result<(), ModelError> {
        let fail = |what: String| ModelError::Patch {
            patch: self.name.clone(),
            what,
        };
        if self.name.is_empty() {
            return Err(fail("empty name".into()));
        }
        if let Some(d) = self.density {
            if !(d.is_finite() && d > 0.0) {
                let d = crate::util::number_text(d);
                return Err(fail(format!("density {d} must be finite and > 0")));
            }
        }
        if !crate::limits::feather_in_range(self.feather) {
            return Err(fail(format!(
                "feather {} must lie in [0, {}]",
                crate::util::number_text(self.feather),
                crate::limits::MAX_FEATHER
            )));
        }
        if let Shape::Polygons(polygons) = &self.shape {
            check_polygons(polygons).map_err(fail)?;
        }
        self.check_tracks()?;
        for (i, pin) in self.pins.iter().enumerate() {
            let window_ok = pin.start.is_finite()
                && pin.start >= 0.0
                && pin.end.is_none_or(|e| e.is_finite() && e > pin.start);
            if !pin.at.is_finite() || !window_ok {
                return Err(fail(format!(
                    "pin {i}: point must be finite, 0 ≤ from < until"
                )));
            }
        }
        Ok(())
    }
}

/// Polygons need ≥ 3 finite vertices per ring.
pub fn check_polygons(polygons: &[Polygon]) -> Result<(), String> {
    if polygons.is_empty() {
        return Err("no polygons".into());
    }
    for (i, polygon) in polygons.iter().enumerate() {
        for ring in std::iter::once(&polygon.outer).chain(&polygon.holes) {
            if ring.len() < 3 {
                return Err(format!(
                    "polygon {i}: a ring needs at least 3 points, got {}",
                    ring.len()
                ));
            }
            if ring.iter().any(|p| !p.is_finite()) {
                return Err(format!("polygon {i}: non-finite point"));
            }
        }
    }
    Ok(())
}

/// What a `follow` call drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FollowTarget {
    /// The patch's placement (`at`, and `rotate` / `scale` when followed).
    Patch,
    /// The target of the patch's handle with this index.
    Handle(usize),
}

/// One `follow` call: the file, its settings as written, and the tracks it set.
#[derive(Clone, Debug, PartialEq)]
pub struct Follow {
    /// The track file (resolved against the scene's folder).
    pub file: PathBuf,
    /// What it drives.
    pub target: FollowTarget,
    /// The point followed (from 1).
    pub point: usize,
    /// The offset added to the point.
    pub offset: DVec2,
    /// `rotate` as written (`None`: not written).
    pub rotate: Option<bool>,
    /// `scale` as written (`None`: not written).
    pub scale: Option<bool>,
    /// `from_frame` as written.
    pub from_frame: Option<u64>,
    /// The position keys it set.
    pub at: Track<DVec2>,
    /// The rotation keys it set, when it followed the rotation.
    pub rotation: Option<Track<f64>>,
    /// The scale keys it set, when it followed the scale.
    pub scale_keys: Option<Track<f64>>,
}
