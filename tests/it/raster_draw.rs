//! Drawing patches: identity and integer translation reproduce the source, a constant
//! membrane adds exactly, depth picks the front layer, anti-aliased coverage integrates to
//! the polygon area, the feather ramp is monotone, folds keep their coverage.

use crate::raster_meshes;

use glam::DVec2;
use lapclone::mesh::BoundaryLoop;
use lapclone::pixels::{Canvas, Depth, FloatImage, PixelFormat, Texel};
use lapclone::raster::{draw_patch, Patch, RasterOptions, RasterScratch};

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
    {
        let mut canvas = opaque_canvas(640, 640, 0.0);
        let options = RasterOptions::default();
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

/// A 32×32-cell grid placed with a wave, a rotation and a depth ramp: large enough for
/// several silhouette strips.
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
    /// size.
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
fn a_wrong_membrane_is_an_error_and_leaves_the_canvas_as_it_was() {
    let grid = WavyGrid::new();
    let vertices = grid.mesh.positions.len();
    let (inside, (width, height)) = grid.inside_a_canvas();
    let before = opaque_canvas(width, height, 0.3);
    let short = vec![[0.0f32; 3]; vertices - 1];
    let mut nan = vec![[0.0f32; 3]; vertices];
    nan[7][1] = f32::NAN;
    for with_depth in [false, true] {
        let mut canvas = before.clone();
        for wrong in [&short, &nan] {
            let patch = Patch {
                membrane: wrong,
                placed: &inside,
                ..grid.patch(with_depth)
            };
            let options = RasterOptions::default();
            let result = draw_patch(&mut canvas, &patch, &options, &mut RasterScratch::new());
            assert!(result.is_err(), "depth {with_depth}: {result:?}");
        }
        assert!(canvas == before, "depth {with_depth}: the canvas changed");
    }
}

/// Shading on several threads (row ranges) gives exactly the one-thread pixels, with
/// anti-aliasing, pixel-centre coverage and a feather, over a canvas edge, and on a patch
/// large enough for several silhouette strips (threads split rows across strips), with and
/// without depth.
#[test]
fn threads_shade_the_same_pixels() {
    let source = raster_meshes::pattern_image(300, 300);
    let mesh = raster_meshes::grid(DVec2::new(2.0, 3.5), 2.9, 100, 99);
    let membrane: Vec<[f32; 3]> = (0..mesh.positions.len())
        .map(|i| [(i % 7) as f32 * 0.01, -0.02, 0.03])
        .collect();
    let depth: Vec<f32> = mesh
        .positions
        .iter()
        .map(|p| (p.x * 0.05).sin() as f32)
        .collect();
    let cases = [(true, 0.0), (false, 0.0), (true, 3.5), (false, 2.0)];
    for (scale, (anti_alias, feather), with_depth) in [1.0, 1.7]
        .into_iter()
        .flat_map(|s| cases.into_iter().map(move |c| (s, c)))
        .flat_map(|(s, c)| [false, true].into_iter().map(move |d| (s, c, d)))
    {
        let placed: Vec<DVec2> = mesh
            .positions
            .iter()
            .map(|p| DVec2::new(p.x * 0.97 + 0.3 * p.y.sin(), p.y + 0.2) * scale)
            .collect();
        let (width, height) = if scale > 1.0 { (520, 460) } else { (280, 300) };
        // Any count asked for is taken: far more than the rows can use are capped.
        let canvases: Vec<Canvas> = [1, 2, 3, usize::MAX]
            .into_iter()
            .map(|threads| {
                let mut canvas = opaque_canvas(width, height, 0.4);
                let options = RasterOptions {
                    anti_alias,
                    feather,
                    threads,
                };
                draw(
                    &mut canvas,
                    &mesh.positions,
                    &placed,
                    &mesh.triangles,
                    &membrane,
                    with_depth.then_some(&depth[..]),
                    &mesh.loops,
                    &source,
                    options,
                );
                canvas
            })
            .collect();
        let background = opaque_canvas(width, height, 0.4);
        assert!(
            canvases[0].pixels() != background.pixels(),
            "the patch drew"
        );
        for canvas in &canvases[1..] {
            assert!(
                canvas.pixels() == canvases[0].pixels(),
                "scale {scale}, AA {anti_alias}, feather {feather}, depth {with_depth}"
            );
        }
    }
}

/// A wide feather around a patch scaled far past the canvas would need its silhouette over
/// the canvas grown by the feather: past `limits::MAX_RASTER_PIXELS` the draw is refused
/// before anything is allocated, the canvas untouched; just under it, it draws.
#[test]
fn a_feather_past_the_pixel_budget_is_refused_not_allocated() {
    let source = white_source(80, 80);
    let mesh = raster_meshes::grid(DVec2::new(10.0, 10.0), 6.0, 10, 10);
    let zero = vec![[0.0; 3]; mesh.positions.len()];
    let huge: Vec<DVec2> = mesh
        .positions
        .iter()
        .map(|&p| (p - DVec2::splat(40.0)) * 1e4)
        .collect();
    let patch = Patch {
        rest: &mesh.positions,
        placed: &huge,
        triangles: &mesh.triangles,
        membrane: &zero,
        depth: None,
        loops: &mesh.loops,
        source: &source,
    };
    let mut canvas = opaque_canvas(64, 48, 0.25);
    let before = canvas.clone();
    let options = RasterOptions {
        feather: 65_536.0,
        ..RasterOptions::default()
    };
    let error = draw_patch(&mut canvas, &patch, &options, &mut RasterScratch::new()).unwrap_err();
    assert!(
        matches!(error, lapclone::raster::RasterError::WorkTooLarge { .. }),
        "{error}"
    );
    assert!(error.to_string().contains("lower the feather"), "{error}");
    assert!(canvas == before, "the canvas was touched");
    let options = RasterOptions {
        feather: 100.0,
        ..options
    };
    draw_patch(&mut canvas, &patch, &options, &mut RasterScratch::new()).unwrap();
    assert_eq!(
        canvas.pixel_f32(30, 20).unwrap()[0],
        1.0,
        "covered far from any edge"
    );
}
