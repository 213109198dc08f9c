//! Drawing one patch: takes a [`Patch`], options and a [`RasterScratch`] and composites the
//! patch over a [`Canvas`]. Per frame: per-triangle setup, exact coverage with depth test,
//! silhouette coverage, feather, shading — all inside the patch's bounding box.

use super::coverage::fill_silhouette;
use super::feather::apply_feather;
use super::setup::{TriangleSetup, MAX_COORDINATE};
use super::shade::{shade_and_composite, ShadeInput};
use super::triangles::{rasterise_triangles, NO_TRIANGLE};
use super::{Patch, PixelRect, RasterError, RasterScratch};
use crate::pixels::{Canvas, CanvasPixels};

/// How to draw a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterOptions {
    /// Width in px of the coverage ramp inside the silhouette (0: none).
    pub feather: f32,
    /// Anti-alias the silhouette (tiny-skia coverage); off: pixel-centre coverage only.
    pub anti_alias: bool,
}

impl Default for RasterOptions {
    fn default() -> Self {
        RasterOptions {
            feather: 0.0,
            anti_alias: true,
        }
    }
}

/// What a draw touched.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Pixels examined (the patch's bounding box with margins, clipped near the canvas).
    pub work: PixelRect,
    /// Work pixels whose centre lies in a placed triangle.
    pub centre_hits: usize,
    /// Canvas pixels written.
    pub written: usize,
}

/// Composites `patch` over `canvas`. Allocates nothing once `scratch` has grown.
pub fn draw_patch(
    canvas: &mut Canvas,
    patch: &Patch,
    options: &RasterOptions,
    scratch: &mut RasterScratch,
) -> Result<RasterStats, RasterError> {
    patch.validate()?;
    if !options.feather.is_finite() || options.feather < 0.0 {
        return Err(RasterError::Feather(options.feather));
    }
    let Some(work) = work_rect(patch, canvas, options.feather) else {
        return Ok(RasterStats::default());
    };
    build_setups(patch, &mut scratch.setups);
    scratch.prepare_pixels(work.area());
    let use_depth = patch.depth.is_some();
    rasterise_triangles(
        &scratch.setups,
        work,
        use_depth,
        &mut scratch.ids,
        &mut scratch.depths,
    );
    let centre_hits = scratch.ids.iter().filter(|&&id| id != NO_TRIANGLE).count();
    compute_coverage(patch, work, options, scratch);
    let canvas_rect = canvas_rect(canvas);
    let target = work.intersect(&canvas_rect);
    let input = ShadeInput {
        setups: &scratch.setups,
        ids: &scratch.ids,
        coverage: &scratch.coverage,
        work,
        source: patch.source,
    };
    let canvas_width = canvas.width() as usize;
    let written = match canvas.pixels_mut() {
        CanvasPixels::Eight(p) => shade_and_composite(&input, target, p, canvas_width),
        CanvasPixels::Sixteen(p) => shade_and_composite(&input, target, p, canvas_width),
    };
    Ok(RasterStats {
        work,
        centre_hits,
        written,
    })
}

fn canvas_rect(canvas: &Canvas) -> PixelRect {
    PixelRect {
        x0: 0,
        y0: 0,
        x1: canvas.width().min(i32::MAX as u32) as i32,
        y1: canvas.height().min(i32::MAX as u32) as i32,
    }
}

/// The placed bounding box grown by the AA band and the feather width, intersected with the
/// canvas grown by the feather width (so distances near the canvas edge see the silhouette
/// just outside it). `None` when nothing can reach the canvas.
fn work_rect(patch: &Patch, canvas: &Canvas, feather: f32) -> Option<PixelRect> {
    let mut min = glam::DVec2::splat(f64::INFINITY);
    let mut max = glam::DVec2::splat(f64::NEG_INFINITY);
    for tri in patch.triangles {
        for &v in tri {
            let p = patch.placed[v as usize];
            min = min.min(p);
            max = max.max(p);
        }
    }
    if !(min.x <= max.x && min.y <= max.y) {
        return None;
    }
    let clamp = |v: f64| v.clamp(-MAX_COORDINATE, MAX_COORDINATE) as i32;
    let margin = feather.ceil() as i32 + 2;
    let placed = PixelRect {
        x0: clamp(min.x.floor()) - 1,
        y0: clamp(min.y.floor()) - 1,
        x1: clamp(max.x.ceil()) + 1,
        y1: clamp(max.y.ceil()) + 1,
    };
    let work = placed.intersect(&canvas_rect(canvas).grow(margin));
    (!work.is_empty() && !placed.intersect(&canvas_rect(canvas)).is_empty()).then_some(work)
}

fn build_setups(patch: &Patch, setups: &mut Vec<TriangleSetup>) {
    setups.clear();
    setups.extend(patch.triangles.iter().map(|tri| {
        let [a, b, c] = tri.map(|v| v as usize);
        let depth = patch.depth.map_or([0.0; 3], |d| [d[a], d[b], d[c]]);
        TriangleSetup::new(
            [patch.placed[a], patch.placed[b], patch.placed[c]],
            [patch.rest[a], patch.rest[b], patch.rest[c]],
            [patch.membrane[a], patch.membrane[b], patch.membrane[c]],
            depth,
        )
    }));
}

fn compute_coverage(
    patch: &Patch,
    work: PixelRect,
    options: &RasterOptions,
    s: &mut RasterScratch,
) {
    let width = work.width();
    if options.anti_alias {
        let stride = fill_silhouette(patch, &s.setups, work, &mut s.path_builder, &mut s.mask);
        let mask = s.mask.as_ref().expect("mask filled").data(); // invariant: fill_silhouette always leaves a mask in the slot.
        for (row, out) in s.coverage.chunks_mut(width).enumerate() {
            let src = &mask[row * stride..row * stride + width];
            for (c, &m) in out.iter_mut().zip(src) {
                *c = f32::from(m) * (1.0 / 255.0);
            }
        }
    } else {
        for (c, &id) in s.coverage.iter_mut().zip(&s.ids) {
            *c = if id == NO_TRIANGLE { 0.0 } else { 1.0 };
        }
    }
    apply_feather(
        &s.ids,
        width,
        options.feather,
        &mut s.distance,
        &mut s.distance_row,
        &mut s.coverage,
    );
}
