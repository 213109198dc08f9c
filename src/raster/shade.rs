//! Shading and compositing: takes the per-pixel triangle ids and coverage over the work
//! rectangle and gives the composited canvas pixels: source sampled bilinearly at the rest
//! position, plus the interpolated membrane, clamped to [0, 1], source alpha kept, composited
//! source-over with alpha = coverage · source alpha.
//!
//! Edge pixels with coverage but no triangle at their centre extrapolate the affine maps of
//! the triangle of the nearest hit pixel within two pixels (ties broken by a fixed scan
//! order), so the anti-aliased fringe continues the patch's colours instead of guessing.

use super::setup::TriangleSetup;
use super::triangles::NO_TRIANGLE;
use super::PixelRect;
use crate::pixels::{FloatImage, Texel};

/// Neighbour offsets within radius 2, nearest first (fixed order for determinism).
const NEIGHBOURS: [(i32, i32); 24] = [
    (0, -1),
    (-1, 0),
    (1, 0),
    (0, 1),
    (-1, -1),
    (1, -1),
    (-1, 1),
    (1, 1),
    (0, -2),
    (-2, 0),
    (2, 0),
    (0, 2),
    (-1, -2),
    (1, -2),
    (-2, -1),
    (2, -1),
    (-2, 1),
    (2, 1),
    (-1, 2),
    (1, 2),
    (-2, -2),
    (2, -2),
    (-2, 2),
    (2, 2),
];

/// Everything shading reads, bundled to keep signatures short.
pub(crate) struct ShadeInput<'a> {
    pub setups: &'a [TriangleSetup],
    pub ids: &'a [u32],
    pub coverage: &'a [f32],
    pub work: PixelRect,
    pub source: &'a FloatImage,
}

/// Composites the patch over `canvas` (row-major, `canvas_width` wide) inside `target`
/// (the work rectangle clipped to the canvas). Returns the number of pixels written.
pub(crate) fn shade_and_composite<T: Texel>(
    input: &ShadeInput,
    target: PixelRect,
    canvas: &mut [[T; 4]],
    canvas_width: usize,
) -> usize {
    let work = input.work;
    let work_width = work.width();
    let mut written = 0;
    for y in target.y0..target.y1 {
        let work_row = (y - work.y0) as usize * work_width;
        let canvas_row = y as usize * canvas_width;
        for x in target.x0..target.x1 {
            let cell = work_row + (x - work.x0) as usize;
            let coverage = input.coverage[cell];
            if coverage <= 0.0 {
                continue;
            }
            let Some(triangle) = owning_triangle(input, x, y) else {
                continue;
            };
            let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let colour = patch_colour(&input.setups[triangle as usize], input.source, cx, cy);
            let alpha = coverage.min(1.0) * colour[3];
            if alpha <= 0.0 {
                continue;
            }
            let pixel = &mut canvas[canvas_row + x as usize];
            if alpha >= 1.0 {
                *pixel = colour.map(T::from_unit);
                written += 1;
                continue;
            }
            let premultiplied = [colour[0] * alpha, colour[1] * alpha, colour[2] * alpha];
            let under = pixel.map(Texel::to_unit);
            let out = crate::pixels::canvas_composite_over(premultiplied, alpha, under);
            *pixel = out.map(T::from_unit);
            written += 1;
        }
    }
    written
}

#[inline(always)]
fn patch_colour(setup: &TriangleSetup, source: &FloatImage, x: f64, y: f64) -> [f32; 4] {
    let values = setup.interpolate(x, y);
    let sample = source.sample_bilinear(values.rest.x, values.rest.y);
    [
        (sample[0] + values.membrane[0]).clamp(0.0, 1.0),
        (sample[1] + values.membrane[1]).clamp(0.0, 1.0),
        (sample[2] + values.membrane[2]).clamp(0.0, 1.0),
        sample[3],
    ]
}

/// The triangle at the pixel's centre, or the nearest hit neighbour's.
#[inline]
fn owning_triangle(input: &ShadeInput, x: i32, y: i32) -> Option<u32> {
    let work = input.work;
    let width = work.width();
    let id = input.ids[(y - work.y0) as usize * width + (x - work.x0) as usize];
    if id != NO_TRIANGLE {
        return Some(id);
    }
    NEIGHBOURS.iter().find_map(|&(dx, dy)| {
        let (nx, ny) = (x + dx, y + dy);
        if nx < work.x0 || ny < work.y0 || nx >= work.x1 || ny >= work.y1 {
            return None;
        }
        let id = input.ids[(ny - work.y0) as usize * width + (nx - work.x0) as usize];
        (id != NO_TRIANGLE).then_some(id)
    })
}
