//! Loading what a scene draws on: takes a [`Scene`] and gives its layers (sources decoded
//! once per file), its background canvas with the footage reader that refreshes it, and the
//! footage checks made before anything renders.

use std::collections::HashMap;
use std::path::PathBuf;

use crate::pixels::{Canvas, FloatImage, FootageReader, PixelFormat};
use crate::render::layer::Layer;
use crate::render::RenderError;
use crate::scene::{Background, Patch, Scene};

pub(super) fn build_layers(scene: &Scene) -> Result<Vec<Layer>, RenderError> {
    check_source_pixels(scene)?;
    let mut sources: HashMap<PathBuf, FloatImage> = HashMap::new();
    let mut layers = Vec::with_capacity(scene.patches.len());
    for patch in &scene.patches {
        let source = source_image(&mut sources, patch, scene.canvas.fps)?;
        layers.push(Layer::new(patch, source, scene.canvas.fps)?);
    }
    Ok(layers)
}

/// Refuses, from their headers and before any is decoded, still sources that hold more
/// pixels in all than a scene may (a scene built in code meets the rule `check` applies).
fn check_source_pixels(scene: &Scene) -> Result<(), RenderError> {
    let mut seen = std::collections::HashSet::new();
    let mut total = 0;
    for patch in scene.patches.iter().filter(|p| p.footage.is_none()) {
        if !seen.insert(&patch.source) {
            continue;
        }
        // A header that cannot be read is reported by the decode that follows.
        let Ok((width, height)) = crate::limits::image_dimensions(&patch.source) else {
            continue;
        };
        let named = |source| RenderError::Sources {
            patch: patch.name.clone(),
            source,
        };
        crate::limits::add_scene_source(&mut total, width, height).map_err(named)?;
    }
    Ok(())
}

/// The patch's source image, loaded once per path (an animated source's first frame, read
/// at the scene's `fps` as every later one is: at a slower rate a clip shorter than one of
/// its frames would give none).
pub(super) fn source_image(
    sources: &mut HashMap<PathBuf, FloatImage>,
    patch: &Patch,
    fps: f64,
) -> Result<FloatImage, RenderError> {
    if let Some(footage) = &patch.footage {
        let mut reader = FootageReader::new(footage.clone(), fps);
        return reader.take_frame(0).map_err(|e| RenderError::footage(Some(&patch.name), e));
    }
    if let Some(image) = sources.get(&patch.source) {
        return Ok(image.clone());
    }
    let image = FloatImage::load(&patch.source)?;
    sources.insert(patch.source.clone(), image.clone());
    Ok(image)
}

/// Refuses, before anything is drawn, footage that runs out before the scene does (unless
/// it holds its last frame).
pub(super) fn check_footage(scene: &Scene) -> Result<(), RenderError> {
    let (frames, fps) = (scene.canvas.frame_count(), scene.canvas.fps);
    let background = match &scene.canvas.background {
        Background::Footage(footage) => Some((None, footage)),
        _ => None,
    };
    let sources = scene
        .patches
        .iter()
        .filter_map(|patch| Some((Some(patch.name.as_str()), patch.footage.as_ref()?)));
    for (patch, footage) in background.into_iter().chain(sources) {
        footage
            .check_covers(frames, fps)
            .map_err(|e| RenderError::footage(patch, e))?;
    }
    Ok(())
}

/// The canvas every frame starts from: the background image (or footage's first plate, with
/// its reader) at the origin over opaque black (16-bit when the image is), or a plain colour.
pub(super) fn background_canvas(scene: &Scene) -> Result<(Canvas, Option<(FootageReader, u64)>), RenderError> {
    let (width, height) = (scene.canvas.width, scene.canvas.height);
    match &scene.canvas.background {
        Background::Colour(rgba) => {
            let image = FloatImage::from_fn(width, height, PixelFormat::RGBA8, |_, _| *rgba)?;
            Ok((Canvas::from_image(&image), None))
        }
        Background::Image(path) => {
            let decoded = FloatImage::decode(path)?;
            // An 8-bit image of the canvas's size straight from its bytes (no float copy; the
            // same bytes as the float path).
            if (decoded.width(), decoded.height()) == (width, height) {
                if let Some(canvas) = Canvas::from_eight_bit(&decoded) {
                    return Ok((canvas, None));
                }
            }
            let picture = FloatImage::from_dynamic(&decoded)?;
            Ok((canvas_over(&picture, width, height)?, None))
        }
        Background::Footage(footage) => {
            let mut reader = FootageReader::new(footage.clone(), scene.canvas.fps);
            let plate = reader.frame(0).map_err(|e| RenderError::footage(None, e))?;
            let canvas = canvas_over(plate, width, height)?;
            Ok((canvas, Some((reader, 0))))
        }
    }
}

/// `picture` at the origin of a `width`×`height` canvas, opaque black where it does not
/// reach, in the picture's bit depth.
pub(super) fn canvas_over(picture: &FloatImage, width: u32, height: u32) -> Result<Canvas, RenderError> {
    if (picture.width(), picture.height()) == (width, height) {
        return Ok(Canvas::from_image(picture));
    }
    let format = PixelFormat {
        alpha: true,
        ..picture.format()
    };
    let image = FloatImage::from_fn(width, height, format, |x, y| {
        picture.pixel(x, y).unwrap_or([0.0, 0.0, 0.0, 1.0])
    })?;
    Ok(Canvas::from_image(&image))
}

