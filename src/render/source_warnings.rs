//! Sizes a scene names that do not fit what it reads: takes the renderer's scene and
//! loaded sources, and gives a warning when the background image does not cover the canvas
//! (it is drawn from the top-left corner, black where it does not reach) and when a
//! polygon patch reaches past its source's edge (the pixels there repeat the edge).

use crate::util::ShowPath;
use super::layer::polygons_outside;
use super::Renderer;
use crate::clone::PAST_EDGE_TOLERANCE;
use crate::scene::{Background, Shape};

impl Renderer {
    /// One sentence per background or polygon patch whose size does not fit (see the module
    /// doc); the pin and drag warnings are [`Renderer::point_warnings`].
    pub fn source_warnings(&self) -> Vec<String> {
        let scene = self.scene();
        let mut out = Vec::new();
        let canvas = (scene.canvas.width, scene.canvas.height);
        // A larger background is cropped, as a demo scene's is on purpose; a smaller one
        // leaves black the user never asked for.
        if let Background::Image(path) = &scene.canvas.background {
            if let Ok(size) = image::image_dimensions(path) {
                if size.0 < canvas.0 || size.1 < canvas.1 {
                    out.push(format!(
                        "the background {} is {}×{} and the canvas {}×{}: it is drawn from the top-left corner, with opaque black where it does not reach",
                        path.shown(),
                        size.0,
                        size.1,
                        canvas.0,
                        canvas.1,
                    ));
                }
            }
        }
        for (patch, size) in scene.patches.iter().zip(self.source_sizes()) {
            let Shape::Polygons(polygons) = &patch.shape else {
                continue;
            };
            match polygons_outside(polygons, size) {
                Some(past) if past > PAST_EDGE_TOLERANCE => out.push(format!(
                    "patch `{}`: its polygons reach {} px past the edge of its {}×{} source; the pixels there repeat the edge",
                    patch.name,
                    crate::util::number_text((past * 10.0).round() / 10.0),
                    size.0,
                    size.1
                )),
                _ => {}
            }
        }
        out
    }

    /// Every warning about the scene as loaded: [`Renderer::point_warnings`] and
    /// [`Renderer::source_warnings`].
    pub fn warnings(&self) -> Vec<String> {
        let mut out = self.source_warnings();
        out.extend(self.point_warnings());
        out
    }
}
