//! Small synthetic patches for the raster tests: grid-triangulated rectangles with their
//! boundary loop, and images with distinct pixel values.
#![allow(dead_code)]

use glam::DVec2;
use lapclone::mesh::{BoundaryLoop, LoopKind};
use lapclone::pixels::{FloatImage, PixelFormat};

pub struct GridMesh {
    pub positions: Vec<DVec2>,
    pub triangles: Vec<[u32; 3]>,
    pub loops: Vec<BoundaryLoop>,
}

/// `columns` × `rows` cells of size `cell` with top-left corner `origin`, two positively
/// oriented triangles per cell, one outer loop of positive signed area.
pub fn grid(origin: DVec2, cell: f64, columns: u32, rows: u32) -> GridMesh {
    let index = |i: u32, j: u32| j * (columns + 1) + i;
    let mut positions = Vec::new();
    for j in 0..=rows {
        for i in 0..=columns {
            positions.push(origin + DVec2::new(f64::from(i), f64::from(j)) * cell);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..rows {
        for i in 0..columns {
            let (p00, p10, p01, p11) = (
                index(i, j),
                index(i + 1, j),
                index(i, j + 1),
                index(i + 1, j + 1),
            );
            triangles.push([p00, p10, p01]);
            triangles.push([p10, p11, p01]);
        }
    }
    let mut vertices = Vec::new();
    vertices.extend((0..columns).map(|i| index(i, 0)));
    vertices.extend((0..rows).map(|j| index(columns, j)));
    vertices.extend((1..=columns).rev().map(|i| index(i, rows)));
    vertices.extend((1..=rows).rev().map(|j| index(0, j)));
    let loops = vec![BoundaryLoop {
        kind: LoopKind::Outer,
        piece: 0,
        vertices,
    }];
    GridMesh {
        positions,
        triangles,
        loops,
    }
}

/// An image whose channels all differ from pixel to pixel (exact in 8 bit).
pub fn pattern_image(width: u32, height: u32) -> FloatImage {
    FloatImage::from_fn(width, height, PixelFormat::RGBA8, |i, j| {
        [
            ((i * 37 + j * 11) % 256) as f32 / 255.0,
            ((i * 5 + j * 73) % 256) as f32 / 255.0,
            ((i * j + 19) % 256) as f32 / 255.0,
            1.0,
        ]
    })
    .unwrap()
}

pub fn signed_area2(points: [DVec2; 3]) -> f64 {
    (points[1] - points[0]).perp_dot(points[2] - points[0])
}
