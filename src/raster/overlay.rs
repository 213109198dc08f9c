//! Mesh overlay pictures: takes a background RGBA image, mesh positions (in background pixel
//! coordinates), triangles, boundary loops and optional handle markers, and gives an upscaled
//! RGBA picture with the wireframe, the boundary loops in their own colours (outer / hole)
//! and handles as circles with arrows to their targets. Used by `lapclone mesh -o` for rest
//! meshes and meant for `--show-mesh` with deformed positions over a clone result.

use glam::DVec2;
use tiny_skia::{Color, LineCap, LineJoin, Paint, PathBuilder, Pixmap, Stroke, Transform};

use crate::mesh::{BoundaryLoop, LoopKind};

/// A handle to draw: a circle at `at`, and an arrow to `target` when it has moved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandleMarker {
    pub at: DVec2,
    pub target: Option<DVec2>,
}

/// Colours (straight RGBA) and sizes (output pixels) of an overlay.
#[derive(Clone, Debug, PartialEq)]
pub struct OverlayStyle {
    /// Output pixels per background pixel.
    pub scale: f32,
    pub wire: [u8; 4],
    pub wire_width: f32,
    pub outer: [u8; 4],
    pub hole: [u8; 4],
    pub loop_width: f32,
    pub handle: [u8; 4],
    pub handle_radius: f32,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        Self {
            scale: 1.0,
            wire: [40, 110, 255, 200],
            wire_width: 1.0,
            outer: [255, 60, 40, 255],
            hole: [255, 190, 0, 255],
            loop_width: 2.0,
            handle: [0, 200, 90, 255],
            handle_radius: 6.0,
        }
    }
}

impl OverlayStyle {
    /// A scale that makes the picture at least ~1000 px on its longer side (at most 8×).
    pub fn auto_scale(width: u32, height: u32) -> f32 {
        let longer = width.max(height).max(1) as f32;
        (1000.0 / longer).clamp(1.0, 8.0).floor()
    }
}

#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    #[error("overlay of {width}×{height} pixels is empty or too large")]
    BadSize { width: u32, height: u32 },
    #[error("triangle or loop refers to vertex {0}, out of range")]
    VertexOutOfRange(u32),
}

/// The mesh (and handles) drawn over `background`, upscaled by `style.scale`.
pub fn draw_mesh_overlay(
    background: &image::RgbaImage,
    positions: &[DVec2],
    triangles: &[[u32; 3]],
    loops: &[BoundaryLoop],
    handles: &[HandleMarker],
    style: &OverlayStyle,
) -> Result<image::RgbaImage, OverlayError> {
    let n = positions.len() as u32;
    let bad = triangles
        .iter()
        .flatten()
        .chain(loops.iter().flat_map(|l| &l.vertices))
        .find(|&&v| v >= n);
    if let Some(&v) = bad {
        return Err(OverlayError::VertexOutOfRange(v));
    }
    let scale = style.scale.max(1.0 / 64.0);
    let width = (background.width() as f32 * scale).round() as u32;
    let height = (background.height() as f32 * scale).round() as u32;
    let mut pixmap = upscaled_background(background, width, height)
        .ok_or(OverlayError::BadSize { width, height })?;
    let to_px = |p: DVec2| ((p.x as f32) * scale, (p.y as f32) * scale);
    draw_wire(&mut pixmap, positions, triangles, style, &to_px);
    draw_loops(&mut pixmap, positions, loops, style, &to_px);
    draw_handles(&mut pixmap, handles, style, &to_px);
    Ok(to_rgba(&pixmap))
}

fn draw_wire(
    pixmap: &mut Pixmap,
    positions: &[DVec2],
    triangles: &[[u32; 3]],
    style: &OverlayStyle,
    to_px: &dyn Fn(DVec2) -> (f32, f32),
) {
    let mut wire = PathBuilder::new();
    for &(a, b) in &unique_edges(triangles) {
        let (pa, pb) = (to_px(positions[a as usize]), to_px(positions[b as usize]));
        wire.move_to(pa.0, pa.1);
        wire.line_to(pb.0, pb.1);
    }
    if let Some(path) = wire.finish() {
        let (paint, stroke) = (paint(style.wire), stroke(style.wire_width));
        pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
}

fn draw_loops(
    pixmap: &mut Pixmap,
    positions: &[DVec2],
    loops: &[BoundaryLoop],
    style: &OverlayStyle,
    to_px: &dyn Fn(DVec2) -> (f32, f32),
) {
    for lp in loops {
        let mut builder = PathBuilder::new();
        for (i, &v) in lp.vertices.iter().enumerate() {
            let p = to_px(positions[v as usize]);
            if i == 0 {
                builder.move_to(p.0, p.1);
            } else {
                builder.line_to(p.0, p.1);
            }
        }
        builder.close();
        let colour = if lp.kind == LoopKind::Outer {
            style.outer
        } else {
            style.hole
        };
        if let Some(path) = builder.finish() {
            let (paint, stroke) = (paint(colour), stroke(style.loop_width));
            pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
}

fn draw_handles(
    pixmap: &mut Pixmap,
    handles: &[HandleMarker],
    style: &OverlayStyle,
    to_px: &dyn Fn(DVec2) -> (f32, f32),
) {
    let handle_paint = paint(style.handle);
    let line = stroke(style.loop_width);
    for handle in handles {
        let at = to_px(handle.at);
        if let Some(path) = PathBuilder::from_circle(at.0, at.1, style.handle_radius) {
            pixmap.stroke_path(&path, &handle_paint, &line, Transform::identity(), None);
        }
        let Some(target) = handle.target else {
            continue;
        };
        let to = to_px(target);
        let (dx, dy) = (to.0 - at.0, to.1 - at.1);
        let length = dx.hypot(dy);
        if length < 1.0 {
            continue;
        }
        let (ux, uy) = (dx / length, dy / length);
        let head = (3.0 * style.handle_radius).min(0.5 * length);
        let mut arrow = PathBuilder::new();
        arrow.move_to(at.0, at.1);
        arrow.line_to(to.0, to.1);
        for side in [-1.0f32, 1.0] {
            arrow.move_to(to.0, to.1);
            arrow.line_to(
                to.0 - head * (ux - 0.5 * side * uy),
                to.1 - head * (uy + 0.5 * side * ux),
            );
        }
        if let Some(path) = arrow.finish() {
            pixmap.stroke_path(&path, &handle_paint, &line, Transform::identity(), None);
        }
    }
}

fn unique_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

fn paint(rgba: [u8; 4]) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color(Color::from_rgba8(rgba[0], rgba[1], rgba[2], rgba[3]));
    paint.anti_alias = true;
    paint
}

fn stroke(width: f32) -> Stroke {
    Stroke {
        width,
        line_cap: LineCap::Round,
        line_join: LineJoin::Round,
        ..Stroke::default()
    }
}

/// Nearest-neighbour upscale of the background, composited over black (opaque result).
fn upscaled_background(background: &image::RgbaImage, width: u32, height: u32) -> Option<Pixmap> {
    if width == 0 || height == 0 || (width as u64) * (height as u64) > 400_000_000 {
        return None;
    }
    let mut pixmap = Pixmap::new(width, height)?;
    let (bw, bh) = (background.width(), background.height());
    let data = pixmap.data_mut();
    for y in 0..height {
        let sy = ((y as u64 * bh as u64) / height as u64) as u32;
        for x in 0..width {
            let sx = ((x as u64 * bw as u64) / width as u64) as u32;
            let [r, g, b, a] = background.get_pixel(sx, sy).0;
            let over_black = |c: u8| ((c as u32 * a as u32 + 127) / 255) as u8;
            let offset = 4 * (y as usize * width as usize + x as usize);
            data[offset..offset + 4].copy_from_slice(&[
                over_black(r),
                over_black(g),
                over_black(b),
                255,
            ]);
        }
    }
    Some(pixmap)
}

/// Premultiplied pixmap → straight RGBA image.
fn to_rgba(pixmap: &Pixmap) -> image::RgbaImage {
    let mut out = image::RgbaImage::new(pixmap.width(), pixmap.height());
    for (dst, src) in out.pixels_mut().zip(pixmap.pixels()) {
        let c = src.demultiply();
        dst.0 = [c.red(), c.green(), c.blue(), c.alpha()];
    }
    out
}
