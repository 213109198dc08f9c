//! `Placement`: OpenCV's centring, the placed grid, the affine map.

use glam::DVec2;
use lapclone::clone::{Placement, PLACED_GRID};

/// OpenCV's placement: the box's top-left pixel lands on p − (⌊w/2⌋, ⌊h/2⌋), for even and
/// odd sides and negative targets, by a whole-pixel shift.
#[test]
fn centred_on_pixel_puts_the_top_left_pixel_where_opencv_does() {
    for (min, max, p, top_left) in [
        ((95.0, 40.0), (331.0, 261.0), [288, 143], (170.0, 33.0)),
        ((10.0, 21.0), (101.0, 80.0), [150, 100], (105.0, 71.0)),
        ((0.0, 0.0), (1.0, 1.0), [-7, 3], (-7.0, 3.0)),
    ] {
        let (min, max) = (DVec2::from(min), DVec2::from(max));
        let placement = Placement::centred_on_pixel(min, max, p);
        let mut placed = Vec::new();
        placement.apply(&[min, max], &mut placed);
        assert_eq!(placed[0], DVec2::from(top_left));
        assert_eq!(placed[1] - placed[0], max - min);
    }
}

#[test]
fn pivot_lands_on_target_position() {
    let placement = Placement {
        pivot: DVec2::new(10.0, 20.0),
        at: DVec2::new(100.0, 50.0),
        scale: 2.5,
        rotation_deg: 33.0,
    };
    let moved = placement.to_affine().transform_point2(placement.pivot);
    assert!((moved - placement.at).length() < 1e-12);
}

#[test]
fn scale_and_rotation_act_around_the_pivot() {
    let placement = Placement {
        pivot: DVec2::new(10.0, 10.0),
        at: DVec2::new(0.0, 0.0),
        scale: 2.0,
        rotation_deg: 90.0,
    };
    let moved = placement
        .to_affine()
        .transform_point2(DVec2::new(11.0, 10.0));
    // (1, 0) from the pivot, scaled by 2 and turned by 90° towards +y.
    assert!((moved - DVec2::new(0.0, 2.0)).length() < 1e-12);
}

#[test]
fn applied_points_are_the_affine_map_on_the_grid() {
    let placement = Placement {
        pivot: DVec2::new(10.3, 7.77),
        at: DVec2::new(401.123_456_7, -52.987_654_3),
        scale: 1.37,
        rotation_deg: 21.5,
    };
    let rest: Vec<DVec2> = (0..500)
        .map(|k| DVec2::new(k as f64 * 0.713_13, (k * k % 97) as f64 * 0.331_7))
        .collect();
    let mut placed = Vec::new();
    placement.apply(&rest, &mut placed);
    let map = placement.to_affine();
    for (p, q) in rest.iter().zip(&placed) {
        assert!((map.transform_point2(*p) - *q).abs().max_element() <= 0.5 * PLACED_GRID + 1e-9);
        assert_eq!(
            *q,
            (*q / PLACED_GRID).round() * PLACED_GRID,
            "{q} off the grid"
        );
    }
}

#[test]
fn whole_pixel_moves_shift_every_placed_point_exactly() {
    // Arbitrary fractional positions and a rotation: the plain affine map rounds its sums
    // differently after a move, the grid does not.
    let base = Placement {
        pivot: DVec2::new(123.456_789, 98.765_432_1),
        at: DVec2::new(500.318_7, 436.902_1),
        scale: 0.913,
        rotation_deg: -12.25,
    };
    let rest: Vec<DVec2> = (0..2000)
        .map(|k| {
            DVec2::new(
                (k as f64).sqrt() * 13.131_7,
                (k as f64 * 0.618_034).fract() * 301.7,
            )
        })
        .collect();
    let (mut before, mut after) = (Vec::new(), Vec::new());
    base.apply(&rest, &mut before);
    for shift in [
        DVec2::new(3.0, 2.0),
        DVec2::new(-117.0, 45.0),
        DVec2::new(0.0, -1.0),
    ] {
        let moved = Placement {
            at: base.at + shift,
            ..base
        };
        moved.apply(&rest, &mut after);
        let exact = before
            .iter()
            .zip(&after)
            .filter(|(b, a)| **b + shift == **a)
            .count();
        assert_eq!(exact, rest.len(), "shift {shift}");
    }
}

/// A patch pasted by whole pixels onto a target holding its own source moved by the same
/// pixels: the membrane is zero and every pixel the clone writes is the source's texel,
/// copied, not resampled, so the canvas comes back as it went in (interior and fringe
/// alike, for moves in every direction).
#[test]
fn a_whole_pixel_paste_copies_the_source_texels() {
    use lapclone::{mesh_from_mask, BitMask, Canvas, CanvasPixels, MeshOptions};
    use lapclone::{FloatImage, PatchCloner};
    let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let source = FloatImage::load(&assets.join("chelsea.png")).unwrap();
    let mask = BitMask::load(&assets.join("masks/chelsea_face.png"), 0.5).unwrap();
    let (w, h) = (source.width(), source.height());
    let patch = mesh_from_mask(&mask, None, (w, h), &MeshOptions::default()).unwrap();
    let centre = (patch.bbox_min + patch.bbox_max) / 2.0;
    let mut cloner =
        PatchCloner::new(source.clone(), patch.result.mesh, &Default::default()).unwrap();
    let levels = match Canvas::from_image(&source).pixels() {
        CanvasPixels::Eight(levels) => levels.clone(),
        CanvasPixels::Sixteen(_) => panic!("chelsea.png is 8-bit"),
    };
    let mut written = 0;
    for shift in [[17, 11], [-23, 4], [0, -9], [31, 0]] {
        // The target: the source moved by `shift`, on a grey margin.
        let (tw, th) = (w + 64, h + 64);
        let target: Vec<[u8; 4]> = (0..tw * th)
            .map(|k| {
                let (x, y) = (
                    (k % tw) as i64 - 32 - shift[0],
                    (k / tw) as i64 - 32 - shift[1],
                );
                let inside = (0..w as i64).contains(&x) && (0..h as i64).contains(&y);
                match inside {
                    true => levels[(y * w as i64 + x) as usize],
                    false => [128, 128, 128, 255],
                }
            })
            .collect();
        let mut canvas = Canvas::from_rgba8(tw, th, target.clone()).unwrap();
        let moved = DVec2::new(32.0 + shift[0] as f64, 32.0 + shift[1] as f64);
        let stats = cloner
            .clone_onto(&mut canvas, &Placement::translate(centre, centre + moved))
            .unwrap();
        written += stats.raster.written;
        let CanvasPixels::Eight(out) = canvas.pixels() else {
            panic!("an 8-bit canvas stays 8-bit")
        };
        let differ = out.iter().zip(&target).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{shift:?}: {differ} pixels differ");
    }
    assert!(written > 4 * 40_000, "{written} pixels written");
}
