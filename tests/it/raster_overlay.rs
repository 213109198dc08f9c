//! The mesh overlay: loops and wire drawn in their colours, bad styles refused.

use glam::DVec2;
use lapclone::mesh::{BoundaryLoop, LoopKind};
use lapclone::raster::overlay::*;

#[test]
fn draws_loops_and_wire_in_their_colours() {
    let background = image::RgbaImage::from_pixel(20, 20, image::Rgba([0, 0, 0, 255]));
    let positions = vec![
        DVec2::new(2.0, 2.0),
        DVec2::new(18.0, 2.0),
        DVec2::new(18.0, 18.0),
        DVec2::new(2.0, 18.0),
    ];
    let triangles = vec![[0, 1, 2], [0, 2, 3]];
    let loops = vec![BoundaryLoop {
        kind: LoopKind::Outer,
        piece: 0,
        vertices: vec![0, 1, 2, 3],
    }];
    let style = OverlayStyle {
        scale: 4.0,
        ..OverlayStyle::default()
    };
    let image =
        draw_mesh_overlay(&background, &positions, &triangles, &loops, &[], &style).unwrap();
    assert_eq!(image.dimensions(), (80, 80));
    // On the top boundary edge (y = 8 in output pixels): the outer-loop colour.
    let on_loop = image.get_pixel(40, 8).0;
    assert!(on_loop[0] > 200 && on_loop[2] < 100, "{on_loop:?}");
    // On the diagonal (interior edge) away from the boundary: blue-ish wire.
    let on_wire = image.get_pixel(40, 40).0;
    assert!(on_wire[2] > 100 && on_wire[0] < 100, "{on_wire:?}");
    // Far from every line: the background.
    assert_eq!(image.get_pixel(60, 30).0, [0, 0, 0, 255]);
}

#[test]
fn bad_index_is_an_error() {
    let background = image::RgbaImage::new(4, 4);
    let err = draw_mesh_overlay(
        &background,
        &[DVec2::ZERO],
        &[[0, 1, 2]],
        &[],
        &[],
        &OverlayStyle::default(),
    );
    assert!(matches!(err, Err(OverlayError::VertexOutOfRange(1))));
}
