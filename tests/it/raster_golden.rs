//! Golden frames of the raster alone: a rotated, scaled polygon patch with a membrane
//! gradient, anti-aliased and feathered, and a folded strip with depth, over a pattern.

use crate::golden;
use crate::raster_meshes;

use glam::{DAffine2, DVec2};
use lapclone::mesh::{BoundaryLoop, LoopKind};
use lapclone::pixels::{Canvas, FloatImage, PixelFormat};
use lapclone::raster::{draw_patch, Patch, RasterOptions, RasterScratch};

/// A smooth source with soft stripes, so layers and seams are easy to see.
fn stripes_source() -> FloatImage {
    FloatImage::from_fn(40, 40, PixelFormat::RGBA8, |i, j| {
        let stripe = 0.5 + 0.5 * ((i as f32 + 0.5) * 0.6).sin();
        [
            0.9 * stripe,
            0.3 + 0.5 * j as f32 / 40.0,
            0.2 + 0.6 * (1.0 - stripe),
            1.0,
        ]
    })
    .unwrap()
}

fn background() -> Canvas {
    let image = FloatImage::from_fn(64, 48, PixelFormat::RGBA8, |i, j| {
        let checker = ((i / 6 + j / 6) % 2) as f32;
        [0.25 + 0.2 * checker, 0.3, 0.45 - 0.1 * checker, 1.0]
    })
    .unwrap();
    Canvas::from_image(&image)
}

#[test]
fn rotated_feathered_polygon() {
    let source = stripes_source();
    let centre = DVec2::new(20.0, 20.0);
    let sides = 24u32;
    let mut rest = vec![centre];
    for k in 0..sides {
        let angle = std::f64::consts::TAU * f64::from(k) / f64::from(sides);
        let radius = if k % 2 == 0 { 17.0 } else { 12.0 };
        rest.push(centre + radius * DVec2::new(angle.cos(), angle.sin()));
    }
    let triangles: Vec<[u32; 3]> = (0..sides)
        .map(|k| [0, 1 + k, 1 + (k + 1) % sides])
        .collect();
    let loops = vec![BoundaryLoop {
        kind: LoopKind::Outer,
        piece: 0,
        vertices: (1..=sides).collect(),
    }];
    let placement = DAffine2::from_translation(DVec2::new(31.7, 23.2))
        * DAffine2::from_scale_angle_translation(DVec2::splat(1.2), 0.6, DVec2::ZERO)
        * DAffine2::from_translation(-centre);
    let placed: Vec<DVec2> = rest
        .iter()
        .map(|&p| placement.transform_point2(p))
        .collect();
    let membrane: Vec<[f32; 3]> = rest
        .iter()
        .map(|p| {
            [
                ((p.x - 20.0) / 60.0) as f32,
                0.0,
                ((p.y - 20.0) / -60.0) as f32,
            ]
        })
        .collect();
    let mut canvas = background();
    let patch = Patch {
        rest: &rest,
        placed: &placed,
        triangles: &triangles,
        membrane: &membrane,
        depth: None,
        loops: &loops,
        source: &source,
    };
    let options = RasterOptions {
        feather: 2.5,
        anti_alias: true,
        ..RasterOptions::default()
    };
    draw_patch(&mut canvas, &patch, &options, &mut RasterScratch::new()).unwrap();
    golden::assert_golden(
        "raster_rotated_feathered_polygon",
        &canvas.to_float_image(PixelFormat::RGBA8),
        1.5 / 255.0,
    );
}

#[test]
fn folded_strip_with_depth() {
    let source = stripes_source();
    let mesh = raster_meshes::grid(DVec2::new(2.0, 14.0), 3.0, 12, 3);
    // Fold the strip: past x = 20 it turns by up to 150° about (20, 26) and comes back over
    // its left half, in front (depth grows along the strip). The bend inverts a few triangles.
    let hinge = DVec2::new(20.0, 26.0);
    let mut depth = vec![0.0f32; mesh.positions.len()];
    let placed: Vec<DVec2> = mesh
        .positions
        .iter()
        .enumerate()
        .map(|(v, &p)| {
            let t = ((p.x - 20.0) / 6.0).clamp(0.0, 1.0);
            let angle = -150f64.to_radians() * t;
            depth[v] = (p.x / 38.0) as f32;
            let turned = hinge + DVec2::from_angle(angle).rotate(p - hinge);
            turned + DVec2::new(8.0, 8.0)
        })
        .collect();
    let zero = vec![[0.0; 3]; placed.len()];
    let mut canvas = background();
    let patch = Patch {
        rest: &mesh.positions,
        placed: &placed,
        triangles: &mesh.triangles,
        membrane: &zero,
        depth: Some(&depth),
        loops: &mesh.loops,
        source: &source,
    };
    draw_patch(
        &mut canvas,
        &patch,
        &RasterOptions::default(),
        &mut RasterScratch::new(),
    )
    .unwrap();
    golden::assert_golden(
        "raster_folded_strip",
        &canvas.to_float_image(PixelFormat::RGBA8),
        1.5 / 255.0,
    );
    // Drawing twice into a fresh canvas with a reused scratch gives the same bytes.
    let mut scratch = RasterScratch::new();
    let mut first = background();
    draw_patch(&mut first, &patch, &RasterOptions::default(), &mut scratch).unwrap();
    let mut second = background();
    draw_patch(&mut second, &patch, &RasterOptions::default(), &mut scratch).unwrap();
    assert_eq!(first, second);
    assert_eq!(first, canvas);
}
