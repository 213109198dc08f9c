//! Drawing patches: identity and integer translation reproduce the source, a constant
//! membrane adds exactly, depth picks the front layer, anti-aliased coverage integrates to
//! the polygon area, the feather ramp is monotone, folds keep their coverage.

use crate::raster_meshes;

use glam::DVec2;
use lapclone::mesh::BoundaryLoop;
use lapclone::pixels::{Canvas, Depth, FloatImage, PixelFormat, Texel};
use lapclone::raster::{
    draw_patch, draw_patch_solving, Patch, RasterError, RasterOptions, RasterScratch,
};

fn opaque_canvas(width: u32, height: u32, grey: f32) -> Canvas {
    let image = FloatImage::from_fn(width, height, PixelFormat::RGBA8, |_, _| {
        [grey, grey, grey, 1.0]
    })
    .unwrap();
    Canvas::from_image(&image)
}

fn white_source(width: u32, height: u32) -> FloatImage {
    FloatImage::from_fn(width, height, PixelFormat::RGBA8, |_, _| [1.0; 4]).unwrap()
}

// A flat helper keeps each test to one line per draw.
#[allow(clippy::too_many_arguments)]
fn draw(
    canvas: &mut Canvas,
    rest: &[DVec2],
    placed: &[DVec2],
    triangles: &[[u32; 3]],
    membrane: &[[f32; 3]],
    depth: Option<&[f32]>,
    loops: &[BoundaryLoop],
    source: &FloatImage,
    options: RasterOptions,
) {
    let patch = Patch {
        rest,
        placed,
        triangles,
        membrane,
        depth,
        loops,
        source,
    };
    draw_patch(canvas, &patch, &options, &mut RasterScratch::new()).unwrap();
}

#[test]
fn identity_reproduces_the_source_inside() {
    let source = raster_meshes::pattern_image(40, 40);
    let mesh = raster_meshes::grid(DVec2::new(4.0, 5.0), 3.0, 10, 9);
    let zero = vec![[0.0; 3]; mesh.positions.len()];
    let mut canvas = opaque_canvas(40, 40, 0.0);
    let options = RasterOptions {
        anti_alias: false,
        feather: 0.0,
        ..RasterOptions::default()
    };
    draw(
        &mut canvas,
        &mesh.positions,
        &mesh.positions,
        &mesh.triangles,
        &zero,
        None,
        &mesh.loops,
        &source,
        options,
    );
    let background = opaque_canvas(40, 40, 0.0);
    for j in 0..40 {
        for i in 0..40 {
            let inside = (4..34).contains(&i) && (5..32).contains(&j);
            let expected = if inside {
                source.pixel(i, j)
            } else {
                background.pixel_f32(i, j)
            };
            let to_u8 = |p: Option<[f32; 4]>| p.map(|p| p.map(u8::from_unit));
            assert_eq!(
                to_u8(canvas.pixel_f32(i, j)),
                to_u8(expected),
                "pixel ({i}, {j})"
            );
        }
    }
}

#[test]
fn integer_translation_shifts_the_source_and_membrane_adds_exactly() {
    let source = raster_meshes::pattern_image(30, 30);
    let mesh = raster_meshes::grid(DVec2::new(2.0, 3.0), 2.5, 8, 8);
    let shift = DVec2::new(7.0, -2.0);
    let placed: Vec<DVec2> = mesh.positions.iter().map(|&p| p + shift).collect();
    let offset = [0.2f32, -0.1, 0.05];
    let membrane = vec![offset; placed.len()];
    let mut canvas = opaque_canvas(40, 40, 0.5);
    let options = RasterOptions {
        anti_alias: false,
        feather: 0.0,
        ..RasterOptions::default()
    };
    draw(
        &mut canvas,
        &mesh.positions,
        &placed,
        &mesh.triangles,
        &membrane,
        None,
        &mesh.loops,
        &source,
        options,
    );
    for j in 3..23u32 {
        for i in 2..22u32 {
            let s = source.pixel(i, j).unwrap();
            let got = canvas.pixel_f32(i + 7, j - 2).unwrap();
            for c in 0..3 {
                let expected = (s[c] + offset[c]).clamp(0.0, 1.0);
                assert!(
                    (got[c] - expected).abs() <= 0.5 / 255.0 + 1e-6,
                    "({i},{j}) c{c}: {got:?} vs {expected}"
                );
            }
        }
    }
}

#[test]
fn depth_picks_the_front_layer_and_ties_go_to_the_later_triangle() {
    // Two overlapping squares of 2 triangles each; membrane colours them red and blue.
    let square = |x: f64| {
        [
            DVec2::new(x, 4.0),
            DVec2::new(x + 12.0, 4.0),
            DVec2::new(x + 12.0, 16.0),
            DVec2::new(x, 16.0),
        ]
    };
    let mut placed = square(2.0).to_vec();
    placed.extend(square(8.0));
    let triangles = [[0, 1, 3], [1, 2, 3], [4, 5, 7], [5, 6, 7]];
    let membrane = [[[0.0, -1.0, -1.0]; 4], [[-1.0, -1.0, 0.0]; 4]].concat();
    let source = white_source(24, 24);
    let options = RasterOptions {
        anti_alias: false,
        feather: 0.0,
        ..RasterOptions::default()
    };
    let red = Some([1.0, 0.0, 0.0, 1.0]);
    let blue = Some([0.0, 0.0, 1.0, 1.0]);
    for (depth, winner) in [([2.0f32, 1.0], red), ([1.0, 2.0], blue), ([1.0, 1.0], blue)] {
        let depths = [[depth[0]; 4], [depth[1]; 4]].concat();
        let mut canvas = opaque_canvas(24, 24, 0.5);
        draw(
            &mut canvas,
            &placed,
            &placed,
            &triangles,
            &membrane,
            Some(&depths),
            &[],
            &source,
            options,
        );
        assert_eq!(
            canvas.pixel_f32(11, 10),
            winner,
            "overlap with depths {depth:?}"
        );
        assert_eq!(canvas.pixel_f32(4, 10), red);
        assert_eq!(canvas.pixel_f32(18, 10), blue);
    }
}

/// Sum over the canvas of how far each pixel moved from black towards white.
fn coverage_sum(canvas: &Canvas) -> f64 {
    let mut sum = 0.0;
    for j in 0..canvas.height() {
        for i in 0..canvas.width() {
            sum += f64::from(canvas.pixel_f32(i, j).unwrap()[0]);
        }
    }
    sum
}

/// A regular polygon patch (fan around the centre) with its outer loop.
fn polygon(
    centre: DVec2,
    radius: f64,
    sides: u32,
) -> (Vec<DVec2>, Vec<[u32; 3]>, Vec<BoundaryLoop>) {
    let mut positions = vec![centre];
    for k in 0..sides {
        let angle = std::f64::consts::TAU * f64::from(k) / f64::from(sides);
        positions.push(centre + radius * DVec2::new(angle.cos(), angle.sin()));
    }
    let triangles = (0..sides)
        .map(|k| [0, 1 + k, 1 + (k + 1) % sides])
        .collect();
    let loops = vec![BoundaryLoop {
        kind: lapclone::mesh::LoopKind::Outer,
        piece: 0,
        vertices: (1..=sides).collect(),
    }];
    (positions, triangles, loops)
}

#[test]
fn anti_aliased_coverage_integrates_to_the_area() {
    let source = white_source(64, 64);
    let (positions, triangles, loops) = polygon(DVec2::new(31.3, 30.7), 20.2, 40);
    let zero = vec![[0.0; 3]; positions.len()];
    let mut canvas = Canvas::from_image(
        &FloatImage::from_fn(64, 64, PixelFormat::RGBA16, |_, _| [0.0, 0.0, 0.0, 1.0]).unwrap(),
    );
    assert_eq!(canvas.depth(), Depth::Sixteen);
    draw(
        &mut canvas,
        &positions,
        &positions,
        &triangles,
        &zero,
        None,
        &loops,
        &source,
        RasterOptions::default(),
    );
    let area: f64 = triangles
        .iter()
        .map(|t| 0.5 * raster_meshes::signed_area2(t.map(|v| positions[v as usize])))
        .sum();
    let sum = coverage_sum(&canvas);
    assert!(
        (sum - area).abs() < 0.01 * area,
        "coverage {sum} vs area {area}"
    );
    // Anti-aliased: some edge pixels are partial.
    let partial = (0..64 * 64).filter(|k| {
        let v = canvas.pixel_f32(k % 64, k / 64).unwrap()[0];
        v > 0.05 && v < 0.95
    });
    assert!(partial.count() > 40);
}

#[test]
fn a_large_silhouette_has_no_seam_between_its_strips() {
    // Large enough (≥ 256K px of work) for the four-strip silhouette; every pixel farther
    // than 1.5 px from the outline must be exactly in or out, the strips' border row
    // included, and the coverage must integrate to the area.
    let source = white_source(640, 640);
    let centre = DVec2::new(320.3, 321.7);
    let (positions, triangles, loops) = polygon(centre, 300.4, 96);
    let zero = vec![[0.0; 3]; positions.len()];
    for threads in [1, 2] {
        let mut canvas = opaque_canvas(640, 640, 0.0);
        let options = RasterOptions {
            threads,
            ..RasterOptions::default()
        };
        draw(
            &mut canvas,
            &positions,
            &positions,
            &triangles,
            &zero,
            None,
            &loops,
            &source,
            options,
        );
        let area: f64 = triangles
            .iter()
            .map(|t| 0.5 * raster_meshes::signed_area2(t.map(|v| positions[v as usize])))
            .sum();
        let sum = coverage_sum(&canvas);
        assert!((sum - area).abs() < 1e-3 * area, "{sum} vs {area}");
        // The polygon's inscribed radius bounds "inside"; its circumradius bounds "outside".
        let inscribed = 300.4 * (std::f64::consts::PI / 96.0).cos();
        for j in 0..640 {
            for i in 0..640 {
                let distance =
                    (DVec2::new(f64::from(i) + 0.5, f64::from(j) + 0.5) - centre).length();
                let value = canvas.pixel_f32(i, j).unwrap()[0];
                if distance < inscribed - 1.5 {
                    assert_eq!(value, 1.0, "pixel ({i}, {j}) inside");
                } else if distance > 300.4 + 1.5 {
                    assert_eq!(value, 0.0, "pixel ({i}, {j}) outside");
                }
            }
        }
    }
}

#[test]
fn a_draw_does_not_depend_on_earlier_draws() {
    // The silhouette masks grow and are kept; a patch hanging over the canvas edge must come
    // out the same from a fresh scratch as from one that drew something larger first.
    let source = raster_meshes::pattern_image(300, 300);
    let (positions, triangles, loops) = polygon(DVec2::new(150.2, 149.6), 140.3, 57);
    let zero = vec![[0.02, -0.03, 0.01]; positions.len()];
    let shifted: Vec<DVec2> = positions
        .iter()
        .map(|p| *p + DVec2::new(-61.7, 83.2))
        .collect();
    let big: Vec<DVec2> = positions.iter().map(|p| *p * 2.1).collect();
    let patch = |placed| Patch {
        rest: &positions,
        placed,
        triangles: &triangles,
        membrane: &zero,
        depth: None,
        loops: &loops,
        source: &source,
    };
    let draw_shifted = |scratch: &mut RasterScratch| {
        let mut canvas = opaque_canvas(260, 270, 0.4);
        draw_patch(
            &mut canvas,
            &patch(&shifted),
            &RasterOptions::default(),
            scratch,
        )
        .unwrap();
        canvas.to_float_image(PixelFormat::RGBA8)
    };
    let fresh = draw_shifted(&mut RasterScratch::new());
    let mut used = RasterScratch::new();
    let mut large = opaque_canvas(700, 700, 0.1);
    draw_patch(
        &mut large,
        &patch(&big),
        &RasterOptions::default(),
        &mut used,
    )
    .unwrap();
    assert!(draw_shifted(&mut used).pixels() == fresh.pixels());
}

#[test]
fn fold_over_keeps_union_coverage() {
    // A strip of 2 cells; the right cell's far edge is folded back over the left cell, so the
    // right cell's triangles invert and the loop's winding cancels over the overlap.
    let rest = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(10.0, 0.0),
        DVec2::new(20.0, 0.0),
        DVec2::new(0.0, 10.0),
        DVec2::new(10.0, 10.0),
        DVec2::new(20.0, 10.0),
    ];
    let offset = DVec2::new(10.0, 10.0);
    let mut placed: Vec<DVec2> = rest.iter().map(|&p| p + offset).collect();
    placed[2] = DVec2::new(3.0, 0.0) + offset;
    placed[5] = DVec2::new(3.0, 10.0) + offset;
    let triangles = vec![[0, 1, 3], [1, 4, 3], [1, 2, 4], [2, 5, 4]];
    let loop_ = BoundaryLoop {
        kind: lapclone::mesh::LoopKind::Outer,
        piece: 0,
        vertices: vec![0, 1, 2, 5, 4, 3],
    };
    let source = white_source(24, 24);
    let zero = vec![[0.0; 3]; 6];
    let mut with_loops = opaque_canvas(40, 40, 0.0);
    draw(
        &mut with_loops,
        &rest,
        &placed,
        &triangles,
        &zero,
        None,
        &[loop_],
        &source,
        RasterOptions::default(),
    );
    let mut from_triangles = opaque_canvas(40, 40, 0.0);
    draw(
        &mut from_triangles,
        &rest,
        &placed,
        &triangles,
        &zero,
        None,
        &[],
        &source,
        RasterOptions::default(),
    );
    // The union is the left cell, 10×10, pixel-aligned: exactly covered.
    for canvas in [&with_loops, &from_triangles] {
        for j in 0..40 {
            for i in 0..40 {
                let inside = (10..20).contains(&i) && (10..20).contains(&j);
                let value = canvas.pixel_f32(i, j).unwrap()[0];
                assert_eq!(value, if inside { 1.0 } else { 0.0 }, "({i}, {j})");
            }
        }
    }
}

#[test]
fn feather_is_monotone_inward_and_softer_than_none() {
    let source = white_source(80, 80);
    let mesh = raster_meshes::grid(DVec2::new(10.0, 10.0), 6.0, 10, 10);
    let zero = vec![[0.0; 3]; mesh.positions.len()];
    let mut previous_row: Option<Vec<f32>> = None;
    for feather in [0.0f32, 3.0, 8.0] {
        let mut canvas = opaque_canvas(80, 80, 0.0);
        let options = RasterOptions {
            anti_alias: true,
            feather,
            ..RasterOptions::default()
        };
        draw(
            &mut canvas,
            &mesh.positions,
            &mesh.positions,
            &mesh.triangles,
            &zero,
            None,
            &mesh.loops,
            &source,
            options,
        );
        let row: Vec<f32> = (0..80)
            .map(|i| canvas.pixel_f32(i, 40).unwrap()[0])
            .collect();
        for i in 1..=40 {
            assert!(
                row[i] >= row[i - 1],
                "feather {feather}: not monotone at {i}: {:?}",
                &row[..41]
            );
        }
        assert_eq!(row[40], 1.0);
        if let Some(previous) = &previous_row {
            assert!(row.iter().zip(previous).all(|(a, b)| a <= b));
            assert!(row[12] < previous[12]);
        }
        previous_row = Some(row);
    }
}

#[test]
fn patch_outside_the_canvas_draws_nothing_and_bad_input_is_an_error() {
    let source = white_source(8, 8);
    let mesh = raster_meshes::grid(DVec2::new(0.0, 0.0), 2.0, 2, 2);
    let placed: Vec<DVec2> = mesh
        .positions
        .iter()
        .map(|&p| p + DVec2::new(500.0, 0.0))
        .collect();
    let zero = vec![[0.0; 3]; placed.len()];
    let mut canvas = opaque_canvas(16, 16, 0.25);
    let before = canvas.clone();
    let patch = Patch {
        rest: &mesh.positions,
        placed: &placed,
        triangles: &mesh.triangles,
        membrane: &zero,
        depth: None,
        loops: &mesh.loops,
        source: &source,
    };
    let stats = draw_patch(
        &mut canvas,
        &patch,
        &RasterOptions::default(),
        &mut RasterScratch::new(),
    )
    .unwrap();
    assert_eq!(stats.written, 0);
    assert_eq!(canvas, before);
    let short = &zero[..2];
    let bad = Patch {
        membrane: short,
        ..patch
    };
    assert!(draw_patch(
        &mut canvas,
        &bad,
        &RasterOptions::default(),
        &mut RasterScratch::new()
    )
    .is_err());
    let mut nan = placed.clone();
    nan[3].x = f64::NAN;
    let bad = Patch {
        placed: &nan,
        ..patch
    };
    assert!(draw_patch(
        &mut canvas,
        &bad,
        &RasterOptions::default(),
        &mut RasterScratch::new()
    )
    .is_err());
    let bad_feather = RasterOptions {
        feather: -1.0,
        anti_alias: true,
        ..RasterOptions::default()
    };
    assert!(draw_patch(&mut canvas, &patch, &bad_feather, &mut RasterScratch::new()).is_err());
    assert_eq!(canvas, before);
}

#[test]
fn every_thread_count_draws_the_same_pixels() {
    let grid = WavyGrid::new();
    let render = |threads: usize, with_depth: bool| {
        let mut canvas = opaque_canvas(520, 470, 0.3);
        let options = RasterOptions {
            threads,
            ..RasterOptions::default()
        };
        let patch = grid.patch(with_depth);
        let stats = draw_patch(&mut canvas, &patch, &options, &mut RasterScratch::new()).unwrap();
        (canvas.to_float_image(PixelFormat::RGBA8), stats)
    };
    for with_depth in [false, true] {
        let (single, single_stats) = render(1, with_depth);
        assert!(single_stats.centre_hits > 64 * 1024, "{single_stats:?}");
        for threads in [2, 3, 5, 0] {
            let (image, stats) = render(threads, with_depth);
            assert_eq!(stats, single_stats, "{threads} threads");
            assert!(
                image.pixels() == single.pixels(),
                "{threads} threads differ from one"
            );
        }
    }
}

/// A 32×32-cell grid placed with a wave, a rotation and a depth ramp: large enough for the
/// threaded path (≥ 64K px), many row bands, two setup chunks and several silhouette
/// strips; bands cut through folds and spans.
struct WavyGrid {
    mesh: raster_meshes::GridMesh,
    placed: Vec<DVec2>,
    membrane: Vec<[f32; 3]>,
    depth: Vec<f32>,
    source: FloatImage,
}

impl WavyGrid {
    fn new() -> WavyGrid {
        let mesh = raster_meshes::grid(DVec2::new(2.0, 3.0), 6.0, 32, 32);
        let placed = mesh
            .positions
            .iter()
            .map(|p| {
                let wave = DVec2::new((p.y * 0.05).sin() * 40.0, (p.x * 0.04).cos() * 25.0);
                DVec2::new(1.6 * p.x - 0.5 * p.y + 60.0, 0.5 * p.x + 1.6 * p.y + 10.0) + wave
            })
            .collect();
        let membrane = mesh
            .positions
            .iter()
            .map(|p| [(p.x * 0.002) as f32, -0.1, (p.y * 0.001) as f32])
            .collect();
        let depth = mesh.positions.iter().map(|p| (p.x * 0.01) as f32).collect();
        let source = raster_meshes::pattern_image(200, 200);
        WavyGrid {
            mesh,
            placed,
            membrane,
            depth,
            source,
        }
    }

    /// The placed positions moved wholly inside a canvas (24 px margins), and that canvas's
    /// size: a clipped draw is not recorded for replays.
    fn inside_a_canvas(&self) -> (Vec<DVec2>, (u32, u32)) {
        let (min, max) = self.placed.iter().fold(
            (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let offset = DVec2::splat(24.0) - min.floor();
        let size = (max + offset + DVec2::splat(24.0)).ceil();
        let inside = self.placed.iter().map(|p| *p + offset).collect();
        (inside, (size.x as u32, size.y as u32))
    }

    /// The patch, with or without its depth ramp.
    fn patch(&self, with_depth: bool) -> Patch<'_> {
        Patch {
            rest: &self.mesh.positions,
            placed: &self.placed,
            triangles: &self.mesh.triangles,
            membrane: &self.membrane,
            depth: with_depth.then_some(&self.depth[..]),
            loops: &self.mesh.loops,
            source: &self.source,
        }
    }
}

#[test]
fn a_draw_that_solves_its_membrane_meanwhile_gives_the_same_bytes() {
    let grid = WavyGrid::new();
    for with_depth in [false, true] {
        for threads in [1, 2, 0] {
            for anti_alias in [true, false] {
                let options = RasterOptions {
                    threads,
                    anti_alias,
                    ..RasterOptions::default()
                };
                let mut solved = opaque_canvas(520, 470, 0.3);
                let first = draw_patch(
                    &mut solved,
                    &grid.patch(with_depth),
                    &options,
                    &mut RasterScratch::new(),
                );
                let mut solving = opaque_canvas(520, 470, 0.3);
                // The "solve" computes the membrane afresh (slowly, so the helper thread
                // gets ahead of it), reading the canvas it was given.
                let mut computed = Vec::new();
                let no_membrane = Patch {
                    membrane: &[],
                    ..grid.patch(with_depth)
                };
                let second = draw_patch_solving(
                    &mut solving,
                    &no_membrane,
                    &options,
                    &mut RasterScratch::new(),
                    |canvas: &Canvas| {
                        assert_eq!(canvas.width(), 520);
                        for p in &grid.mesh.positions {
                            let mut x = p.x;
                            for _ in 0..200 {
                                x = std::hint::black_box(x);
                            }
                            computed.push([(x * 0.002) as f32, -0.1, (p.y * 0.001) as f32]);
                        }
                        Ok::<_, RasterError>(&computed[..])
                    },
                );
                let context = format!("depth {with_depth}, {threads} threads, aa {anti_alias}");
                assert_eq!(first.unwrap(), second.unwrap(), "{context}");
                assert!(solving == solved, "{context}: the bytes differ");
            }
        }
    }
}

/// A recording draw (the first through a replaying scratch) records on the helper thread while
/// the solve runs, then composites the record: the bytes and counts of a plain draw, for any
/// thread count; the next whole-pixel move replays that record.
#[test]
fn a_recording_draw_that_solves_meanwhile_gives_the_bytes_of_a_plain_draw() {
    let grid = WavyGrid::new();
    let (inside, (width, height)) = grid.inside_a_canvas();
    let moved: Vec<DVec2> = inside.iter().map(|p| *p + DVec2::new(3.0, -2.0)).collect();
    let placed = Patch {
        placed: &inside,
        ..grid.patch(false)
    };
    for threads in [1, 2, 0] {
        for anti_alias in [true, false] {
            let plain_options = RasterOptions {
                threads,
                anti_alias,
                ..RasterOptions::default()
            };
            let recording = RasterOptions {
                replay: true,
                ..plain_options
            };
            let context = format!("{threads} threads, aa {anti_alias}");
            let mut plain = opaque_canvas(width, height, 0.3);
            let plain_stats = draw_patch(
                &mut plain,
                &placed,
                &plain_options,
                &mut RasterScratch::new(),
            )
            .unwrap();
            let mut scratch = RasterScratch::new();
            let mut recorded = opaque_canvas(width, height, 0.3);
            let no_membrane = Patch {
                membrane: &[],
                ..placed
            };
            let mut computed = Vec::new();
            let stats = draw_patch_solving(
                &mut recorded,
                &no_membrane,
                &recording,
                &mut scratch,
                |canvas: &Canvas| {
                    // Slowly, so the recording gets ahead of it; reads the untouched canvas.
                    assert!(canvas.pixels() == opaque_canvas(width, height, 0.3).pixels());
                    for p in &grid.mesh.positions {
                        let mut x = p.x;
                        for _ in 0..200 {
                            x = std::hint::black_box(x);
                        }
                        computed.push([(x * 0.002) as f32, -0.1, (p.y * 0.001) as f32]);
                    }
                    Ok::<_, RasterError>(&computed[..])
                },
            )
            .unwrap();
            assert_eq!(stats, plain_stats, "{context}");
            assert!(recorded == plain, "{context}: the bytes differ");

            let moved_patch = Patch {
                placed: &moved,
                ..placed
            };
            let mut replayed = opaque_canvas(width, height, 0.3);
            let stats = draw_patch(&mut replayed, &moved_patch, &recording, &mut scratch).unwrap();
            assert!(stats.replayed, "{context}");
            let mut fresh = opaque_canvas(width, height, 0.3);
            draw_patch(
                &mut fresh,
                &moved_patch,
                &plain_options,
                &mut RasterScratch::new(),
            )
            .unwrap();
            assert!(replayed == fresh, "{context}: the replay differs");
        }
    }
}

#[test]
fn a_failed_or_wrong_solve_leaves_the_canvas_as_it_was() {
    let grid = WavyGrid::new();
    let vertices = grid.mesh.positions.len();
    let (inside, (width, height)) = grid.inside_a_canvas();
    let before = opaque_canvas(width, height, 0.3);
    let short = vec![[0.0f32; 3]; vertices - 1];
    let mut nan = vec![[0.0f32; 3]; vertices];
    nan[7][1] = f32::NAN;
    // With depth: a plain draw; without, through a replaying scratch: a recording draw.
    for (threads, recording) in [(1, false), (2, false), (1, true), (2, true)] {
        let patch = Patch {
            membrane: &[],
            placed: &inside,
            ..grid.patch(!recording)
        };
        let options = RasterOptions {
            threads,
            replay: recording,
            ..RasterOptions::default()
        };
        let mut canvas = before.clone();
        let failed = draw_patch_solving(
            &mut canvas,
            &patch,
            &options,
            &mut RasterScratch::new(),
            |_| Err(RasterError::Feather(-1.0)),
        );
        assert!(matches!(failed, Err(RasterError::Feather(_))), "{failed:?}");
        for wrong in [&short, &nan] {
            let result = draw_patch_solving(
                &mut canvas,
                &patch,
                &options,
                &mut RasterScratch::new(),
                |_| Ok::<_, RasterError>(&wrong[..]),
            );
            assert!(result.is_err(), "{threads} threads: {result:?}");
        }
        // A panicking solve reaches the caller (the helper thread does not wait for it).
        let panicked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let _ = draw_patch_solving(
                &mut canvas,
                &patch,
                &options,
                &mut RasterScratch::new(),
                |_| {
                    panic!("solver bug");
                    #[allow(unreachable_code)]
                    Ok::<_, RasterError>(&short[..])
                },
            );
        }));
        assert!(panicked.is_err());
        assert!(canvas == before, "{threads} threads: the canvas changed");
    }
}

#[test]
fn a_replay_whose_solve_fails_leaves_the_canvas_and_the_record_usable() {
    let grid = WavyGrid::new();
    // Inside the canvas (a clipped draw is not recorded), then moved by whole pixels.
    let shifted =
        |from: &[DVec2], by: DVec2| -> Vec<DVec2> { from.iter().map(|p| *p + by).collect() };
    let first = shifted(&grid.placed, DVec2::new(120.0, 40.0));
    let moved = shifted(&first, DVec2::new(3.0, 2.0));
    let first_patch = Patch {
        placed: &first,
        ..grid.patch(false)
    };
    let moved_patch = Patch {
        placed: &moved,
        ..grid.patch(false)
    };
    for threads in [1, 2] {
        let options = RasterOptions {
            threads,
            replay: true,
            ..RasterOptions::default()
        };
        let mut scratch = RasterScratch::new();
        let mut canvas = opaque_canvas(640, 600, 0.3);
        let recorded = draw_patch(&mut canvas, &first_patch, &options, &mut scratch).unwrap();
        assert!(recorded.written > 8 * 1024, "{recorded:?}");
        let before = canvas.clone();
        let failed = draw_patch_solving(&mut canvas, &moved_patch, &options, &mut scratch, |_| {
            Err(RasterError::Feather(-1.0))
        });
        assert!(failed.is_err());
        let panicked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let _ = draw_patch_solving(&mut canvas, &moved_patch, &options, &mut scratch, |_| {
                panic!("solver bug");
                #[allow(unreachable_code)]
                Ok::<_, RasterError>(&grid.membrane[..])
            });
        }));
        assert!(panicked.is_err());
        assert!(canvas == before, "{threads} threads: the canvas changed");
        // The record survived: the move still replays, byte for byte a fresh draw.
        let mut replayed = opaque_canvas(640, 600, 0.3);
        let stats = draw_patch(&mut replayed, &moved_patch, &options, &mut scratch).unwrap();
        assert!(stats.replayed, "{threads} threads");
        let mut fresh = opaque_canvas(640, 600, 0.3);
        let fresh_options = RasterOptions {
            replay: false,
            ..options
        };
        draw_patch(
            &mut fresh,
            &moved_patch,
            &fresh_options,
            &mut RasterScratch::new(),
        )
        .unwrap();
        assert!(replayed == fresh, "{threads} threads: the replay differs");
    }
}

#[test]
fn whole_pixel_moves_replay_the_same_bytes_as_fresh_draws() {
    let source = raster_meshes::pattern_image(120, 100);
    let mesh = raster_meshes::grid(DVec2::new(3.0, 4.0), 5.5, 18, 15);
    let base: Vec<DVec2> = mesh
        .positions
        .iter()
        .map(|p| DVec2::new(1.2 * p.x - 0.3 * p.y + 60.25, 0.3 * p.x + 1.2 * p.y + 11.5))
        .collect();
    // Moves and whether each replays: the first draw records; whole-pixel shifts from the
    // record replay; a fractional shift draws fresh without recording; a whole-pixel move
    // after it records again, so the next whole-pixel move replays; a move across the
    // canvas edge draws fresh.
    let shifts = [
        ((0.0, 0.0), false),
        ((3.0, 2.0), true),
        ((3.0, 2.0), true),
        ((-4.0, 7.0), true),
        ((0.5, 0.0), false),
        ((1.5, 0.0), false),
        ((2.5, 1.0), true),
        ((-45.0, 0.0), false),
    ];
    for (anti_alias, format, simd) in [
        (true, PixelFormat::RGBA8, true),
        (true, PixelFormat::RGBA8, false),
        (false, PixelFormat::RGBA8, true),
        (true, PixelFormat::RGBA16, true),
    ] {
        let mut replaying = RasterScratch::new();
        for (k, &((dx, dy), replays)) in shifts.iter().enumerate() {
            let placed: Vec<DVec2> = base.iter().map(|p| *p + DVec2::new(dx, dy)).collect();
            // The membrane changes every frame, as the target under a moving patch does.
            let membrane: Vec<[f32; 3]> = mesh
                .positions
                .iter()
                .map(|p| {
                    [
                        (p.x * 0.003) as f32 + k as f32 * 0.02,
                        -0.05,
                        (p.y * 0.002) as f32,
                    ]
                })
                .collect();
            let patch = Patch {
                rest: &mesh.positions,
                placed: &placed,
                triangles: &mesh.triangles,
                membrane: &membrane,
                depth: None,
                loops: &mesh.loops,
                source: &source,
            };
            let draw = |scratch: &mut RasterScratch, replay: bool| {
                let background = FloatImage::from_fn(190, 170, format, |i, j| {
                    [0.2, (i % 7) as f32 / 7.0, (j % 5) as f32 / 5.0, 1.0]
                })
                .unwrap();
                let mut canvas = Canvas::from_image(&background);
                let options = RasterOptions {
                    anti_alias,
                    replay,
                    simd,
                    ..RasterOptions::default()
                };
                let stats = draw_patch(&mut canvas, &patch, &options, scratch).unwrap();
                (canvas.to_float_image(format), stats)
            };
            let (image, stats) = draw(&mut replaying, true);
            let (fresh, fresh_stats) = draw(&mut RasterScratch::new(), false);
            assert!(
                image.pixels() == fresh.pixels(),
                "move {k} ({dx}, {dy}), anti-alias {anti_alias}: replay differs from a fresh draw"
            );
            assert_eq!(
                (stats.centre_hits, stats.written, stats.work),
                (
                    fresh_stats.centre_hits,
                    fresh_stats.written,
                    fresh_stats.work
                )
            );
            assert_eq!(stats.replayed, replays, "move {k}");
        }
    }
}

/// The SIMD shading kernel (AVX2 where the CPU has it) and the scalar path give the same
/// bytes: rotated and scaled placements (fractional source positions, taps clamped at the
/// source's edges), cells from 2 to 23 px (runs of every length), a translucent band in the
/// source, a membrane that pushes colours past 0 and 1, with and without depth and
/// anti-aliasing. On a CPU without SIMD both draws take the scalar path and agree trivially.
#[test]
fn simd_and_scalar_shading_give_the_same_bytes() {
    // 8-bit levels (the raster reads its 8-bit texels), and the same levels nudged off the
    // 8-bit grid (it reads the f32 pixels): both texel kinds of both kernels; and an opaque
    // 8-bit source, whose samples the kernel knows to be opaque without testing them.
    for (nudge, translucent_band) in [(0.0, true), (0.3 / 255.0, true), (0.0, false)] {
        let source = FloatImage::from_fn(97, 83, PixelFormat::RGBA8, |i, j| {
            let alpha = if translucent_band && (30..45).contains(&i) {
                0.6
            } else {
                1.0
            };
            [
                ((i * 37 + j * 11) % 256) as f32 / 255.0,
                ((i * 5 + j * 73) % 256) as f32 / 255.0,
                ((i * j + 19) % 256) as f32 / 255.0 * (1.0 - nudge) + nudge,
                alpha,
            ]
        })
        .unwrap();
        assert_eq!(source.eight_bit_texels().is_some(), nudge == 0.0);
        simd_matches_scalar(&source);
    }
}

fn simd_matches_scalar(source: &FloatImage) {
    // The last grid reaches past the source's right and bottom edges, where the clamped
    // taps are not adjacent texels.
    for (origin, cell, columns, rows) in [
        (DVec2::new(-4.0, -3.0), 2.0, 40, 35),
        (DVec2::new(-4.0, -3.0), 7.5, 12, 10),
        (DVec2::new(-4.0, -3.0), 23.0, 4, 3),
        (DVec2::new(40.0, 30.0), 5.0, 14, 13),
    ] {
        let mesh = raster_meshes::grid(origin, cell, columns, rows);
        let membrane: Vec<[f32; 3]> = mesh
            .positions
            .iter()
            .map(|p| [(p.x * 0.02 - 0.6) as f32, (0.5 - p.y * 0.015) as f32, 0.1])
            .collect();
        let depth: Vec<f32> = mesh.positions.iter().map(|p| (p.x - p.y) as f32).collect();
        for (angle, scale) in [(0.0f64, 1.0f64), (0.37, 1.3), (-1.1, 0.8)] {
            let (sin, cos) = angle.sin_cos();
            let placed: Vec<DVec2> = mesh
                .positions
                .iter()
                .map(|p| {
                    // The first grids keep their old placement; the last is moved onto them.
                    let q = (*p - (origin - DVec2::new(-4.0, -3.0))) * scale;
                    DVec2::new(cos * q.x - sin * q.y + 70.3, sin * q.x + cos * q.y + 40.6)
                })
                .collect();
            for (anti_alias, with_depth) in [(true, false), (false, false), (true, true)] {
                let patch = Patch {
                    rest: &mesh.positions,
                    placed: &placed,
                    triangles: &mesh.triangles,
                    membrane: &membrane,
                    depth: with_depth.then_some(&depth[..]),
                    loops: &mesh.loops,
                    source,
                };
                let draw = |simd: bool| {
                    let mut canvas = opaque_canvas(170, 150, 0.3);
                    let options = RasterOptions {
                        anti_alias,
                        simd,
                        ..RasterOptions::default()
                    };
                    let stats =
                        draw_patch(&mut canvas, &patch, &options, &mut RasterScratch::new())
                            .unwrap();
                    (canvas.to_float_image(PixelFormat::RGBA8), stats)
                };
                let ((fast, fast_stats), (scalar, scalar_stats)) = (draw(true), draw(false));
                assert!(scalar_stats.written > 0);
                assert_eq!(fast_stats, scalar_stats, "cell {cell}, angle {angle}");
                assert!(
                    fast.pixels() == scalar.pixels(),
                    "cell {cell}, angle {angle}, anti-alias {anti_alias}, depth {with_depth}"
                );
            }
        }
    }
}

/// A replay large enough to be split across two threads (half the rows each) gives the same
/// bytes and counts as a one-thread replay and as a fresh draw.
#[test]
fn threaded_replays_match_one_thread_and_fresh_draws() {
    let source = raster_meshes::pattern_image(470, 420);
    let mesh = raster_meshes::grid(DVec2::new(2.0, 3.0), 9.0, 50, 45);
    let membrane: Vec<[f32; 3]> = mesh
        .positions
        .iter()
        .map(|p| [(p.x * 0.002) as f32, -0.04, (p.y * 0.001) as f32])
        .collect();
    let placed_at = |dx: f64, dy: f64| -> Vec<DVec2> {
        mesh.positions
            .iter()
            .map(|p| {
                DVec2::new(
                    0.9 * p.x + 0.2 * p.y + 20.3 + dx,
                    -0.2 * p.x + 0.9 * p.y + 110.6 + dy,
                )
            })
            .collect()
    };
    let draw = |scratch: &mut RasterScratch, placed: &[DVec2], threads: usize, replay: bool| {
        let patch = Patch {
            rest: &mesh.positions,
            placed,
            triangles: &mesh.triangles,
            membrane: &membrane,
            depth: None,
            loops: &mesh.loops,
            source: &source,
        };
        let mut canvas = opaque_canvas(560, 520, 0.25);
        let options = RasterOptions {
            threads,
            replay,
            ..RasterOptions::default()
        };
        let stats = draw_patch(&mut canvas, &patch, &options, scratch).unwrap();
        (canvas.to_float_image(PixelFormat::RGBA8), stats)
    };
    let (first, moved) = (placed_at(0.0, 0.0), placed_at(7.0, -5.0));
    let (fresh, fresh_stats) = draw(&mut RasterScratch::new(), &moved, 1, false);
    assert!(fresh_stats.written > 140_000, "large enough to split");
    for threads in [1, 2, 3] {
        let mut scratch = RasterScratch::new();
        draw(&mut scratch, &first, threads, true);
        let (replayed, stats) = draw(&mut scratch, &moved, threads, true);
        assert!(stats.replayed, "{threads} threads");
        assert_eq!(
            (stats.centre_hits, stats.written),
            (fresh_stats.centre_hits, fresh_stats.written)
        );
        assert!(replayed.pixels() == fresh.pixels(), "{threads} threads");
    }
}
