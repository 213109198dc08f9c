//! Shared fixtures of the clone tests: takes sizes (and a mask or placement) and gives small
//! synthetic sources and targets with clearly different colours and texture, and one-call
//! clones through the library. Included by the `clone_*` test files with
//! `#[path = "common/clone_fixtures.rs"] mod fixtures;`.
#![allow(dead_code)]

use glam::DVec2;
use lapclone::clone::{mesh_from_mask, CloneOptions, PatchCloner, Placement};
use lapclone::mesh::{BitMask, MeshOptions};
use lapclone::pixels::{Canvas, ColorKind, Depth, FloatImage, PixelFormat};

pub const RGB8: PixelFormat = PixelFormat {
    color: ColorKind::Rgb,
    alpha: false,
    depth: Depth::Eight,
};

pub const GREY16: PixelFormat = PixelFormat {
    color: ColorKind::Grey,
    alpha: false,
    depth: Depth::Sixteen,
};

/// A warm, strongly textured source: diagonal stripes and a dotted grid over a red ramp.
pub fn textured_source(width: u32, height: u32) -> FloatImage {
    FloatImage::from_fn(width, height, RGB8, |i, j| {
        let (x, y) = (i as f32 + 0.5, j as f32 + 0.5);
        let stripe = 0.5 + 0.5 * ((x + y) * 0.45).sin();
        let dots = if i % 7 == 3 && j % 7 == 3 { 0.25 } else { 0.0 };
        [
            (0.55 + 0.35 * stripe + dots).min(1.0),
            0.25 + 0.3 * y / height as f32,
            0.15 + 0.2 * (1.0 - stripe),
            1.0,
        ]
    })
    .expect("non-empty source") // invariant: callers pass non-zero sizes
}

/// A cool, smooth target: a blue-green gradient with a slow wave, so seams would show.
pub fn smooth_target(width: u32, height: u32) -> FloatImage {
    FloatImage::from_fn(width, height, RGB8, |i, j| {
        let (x, y) = (i as f32 / width as f32, j as f32 / height as f32);
        [
            0.1 + 0.2 * x,
            0.35 + 0.3 * y + 0.05 * (x * 9.0).sin(),
            0.55 + 0.3 * (1.0 - x),
            1.0,
        ]
    })
    .expect("non-empty target")
}

/// A smooth 16-bit grey image with fine structure in the low bits.
pub fn grey16(width: u32, height: u32, phase: f32) -> FloatImage {
    FloatImage::from_fn(width, height, GREY16, |i, j| {
        let (x, y) = (i as f32 + 0.5, j as f32 + 0.5);
        let v = 0.5 + 0.3 * ((x * 0.31 + phase).sin() * (y * 0.23).cos()) + 0.001 * (x - y);
        [v, v, v, 1.0]
    })
    .expect("non-empty grey image")
}

/// Meshes `mask` (the source's size) at the default options and builds a cloner.
pub fn cloner_for(
    source: &FloatImage,
    mask: &BitMask,
    options: &CloneOptions,
) -> (PatchCloner, DVec2, DVec2) {
    let patch = mesh_from_mask(
        mask,
        None,
        (source.width(), source.height()),
        &MeshOptions::default(),
    )
    .expect("mask meshes");
    let cloner =
        PatchCloner::new(source.clone(), patch.result.mesh, options).expect("cloner builds");
    (cloner, patch.bbox_min, patch.bbox_max)
}

/// Clones `mask` of `source` onto `target` with the bounding-box centre placed at `at`.
pub fn clone_image(
    source: &FloatImage,
    mask: &BitMask,
    target: &FloatImage,
    at: DVec2,
    scale: f64,
    rotation_deg: f64,
) -> FloatImage {
    let (mut cloner, min, max) = cloner_for(source, mask, &CloneOptions::default());
    let placement = Placement {
        pivot: (min + max) * 0.5,
        at,
        scale,
        rotation_deg,
    };
    let mut canvas = Canvas::from_image(target);
    cloner
        .clone_onto(&mut canvas, &placement)
        .expect("clone succeeds");
    canvas.to_float_image(target.format())
}

/// Writes `image` as a PNG in its own format.
pub fn save(image: &FloatImage, path: &std::path::Path) {
    Canvas::from_image(image)
        .save_png(path, image.format())
        .expect("fixture PNG written");
}
