//! Whole-scene validation for `lapclone check`: takes a [`LoadedScene`] and checks what the
//! script could not — images decode, masks match their source's size and are non-empty,
//! polygons enclose area, and every frame evaluates to finite values — giving a summary or a
//! [`SceneError`] positioned at the call that named the offending file.

use crate::util::ShowPath;
use std::path::Path;

use super::engine::LoadedScene;
use super::error::SceneError;
use crate::mesh::{BitMask, MASK_THRESHOLD};
use crate::scene::{Background, FrameState, Patch, Shape};

/// What a valid scene contains.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckSummary {
    pub frames: u64,
    pub patches: usize,
    pub handles: usize,
    pub pins: usize,
    /// Inside pixels of each patch's mask (polygon patches: rounded polygon area).
    pub inside_pixels: Vec<u64>,
}

pub fn validate_scene(loaded: &LoadedScene) -> Result<CheckSummary, SceneError> {
    let scene = &loaded.scene;
    if let Background::Image(path) = &scene.canvas.background {
        decode(path).map_err(|m| loaded.error_at(loaded.origins.canvas.as_ref(), m))?;
    }
    let mut inside_pixels = Vec::with_capacity(scene.patches.len());
    // Each source file is decoded once, however many patches share it.
    let mut sizes = (std::collections::HashMap::new(), 0);
    for (i, patch) in scene.patches.iter().enumerate() {
        let origin = loaded.origins.patches.get(i);
        let inside = inside_pixels_of(patch, &mut sizes)
            .map_err(|m| loaded.error_at(origin, format!("patch `{}`: {m}", patch.name)))?;
        inside_pixels.push(inside);
    }
    let mut state = FrameState::default();
    for index in 0..scene.canvas.frame_count() {
        scene.evaluate_into(
            crate::scene::frame_time(index, scene.canvas.fps),
            &mut state,
        );
        if let Some(i) = state.patches.iter().position(|p| !state_is_finite(p)) {
            return Err(loaded.error_at(
                loaded.origins.patches.get(i),
                format!(
                    "patch `{}` has non-finite values at frame {index}",
                    scene.patches[i].name
                ),
            ));
        }
    }
    Ok(CheckSummary {
        frames: scene.canvas.frame_count(),
        patches: scene.patches.len(),
        handles: scene.patches.iter().map(|p| p.handles.len()).sum(),
        pins: scene.patches.iter().map(|p| p.pins.len()).sum(),
        inside_pixels,
    })
}

/// Each still source file's size, and the pixels of them all.
type SourceSizes = (std::collections::HashMap<std::path::PathBuf, (u32, u32)>, u64);

/// The patch's inside pixels (polygons: their rounded area); an empty patch, or a mask whose
/// size is not its source's, is refused.
fn inside_pixels_of(patch: &Patch, sizes: &mut SourceSizes) -> Result<u64, String> {
    // Footage was sized when the scene named it; a video is not an image file.
    let source = match &patch.footage {
        Some(f) => (f.width, f.height),
        None => match sizes.0.get(&patch.source) {
            Some(&size) => size,
            None => {
                let image = decode(&patch.source)?;
                let size = (image.width(), image.height());
                crate::limits::add_scene_source(&mut sizes.1, size.0, size.1)
                    .map_err(|e| e.to_string())?;
                sizes.0.insert(patch.source.clone(), size);
                size
            }
        },
    };
    let inside = match &patch.shape {
        Shape::Mask(path) => {
            let mask = decode(path)?;
            if (mask.width(), mask.height()) != source {
                let (w, h) = (mask.width(), mask.height());
                return Err(format!(
                    "mask is {w}×{h} but the source is {}×{}",
                    source.0, source.1
                ));
            }
            BitMask::from_image(&mask, MASK_THRESHOLD).count_inside() as u64
        }
        Shape::Polygons(polygons) => polygons.iter().map(|p| p.area()).sum::<f64>().round() as u64,
    };
    if inside > 0 {
        return Ok(inside);
    }
    Err(match &patch.shape {
        Shape::Polygons(_) => "the polygons are empty: they enclose no area (less than half a pixel)",
        Shape::Mask(_) => "the mask is empty (no inside pixels)",
    }
    .into())
}

fn decode(path: &Path) -> Result<image::DynamicImage, String> {
    crate::limits::open_image(path).map_err(|e| format!("cannot decode {}: {e}", path.shown()))
}

fn state_is_finite(p: &crate::scene::PatchState) -> bool {
    p.position.is_none_or(|v| v.is_finite())
        && p.scale.is_finite()
        && p.rotation.is_finite()
        && p.depth.is_finite()
        && p.opacity.is_finite()
        && p.handles.iter().all(|h| h.to.is_finite())
}
