//! Numerical checks of the clone against exact expectations: the membrane matches
//! target − source at constrained boundary vertices; a clone onto itself reproduces the
//! source; re-cloning after a move (rank-1 constraint switches in the kept factor) equals a
//! fresh cloner at the new placement; boundary vertices outside the target switch off and
//! come back; monochrome mode; the source's alpha.

use crate::fixtures;

use crate::synth;
use glam::DVec2;
use lapclone::clone::{
    BoundaryData, BoundarySampler, CloneMode, CloneOptions, MembraneSolver, PatchCloner, Placement,
};
use lapclone::pixels::{Canvas, ColorKind, Depth, FloatImage, PixelFormat};
use lapclone::raster::{draw_patch, Patch, RasterOptions, RasterScratch};
use lapclone::solve::LaplacianKind;

use fixtures::*;

fn centred(at: DVec2) -> Placement {
    Placement {
        pivot: DVec2::new(32.0, 32.0),
        at,
        scale: 1.0,
        rotation_deg: 0.0,
    }
}

fn two_holes_cloner(options: &CloneOptions) -> PatchCloner {
    cloner_for(&textured_source(64, 64), &synth::two_holes(64, 64), options).0
}

/// Largest |membrane − (target − source)| over constrained boundary vertices: for
/// `BoundaryData::Vertex` sampled at the vertex (written out here), for a hat average as
/// `BoundarySampler` gives it (its own tests check it against the integral it stands for).
fn boundary_mismatch(cloner: &PatchCloner, target: &Canvas) -> f64 {
    let factor = cloner.membrane().factor();
    let boundary = cloner.membrane().boundary_vertices();
    let rgb = |c: [f32; 4]| [c[0], c[1], c[2]];
    let (mut at_target, mut at_source) = (
        vec![[0.0; 3]; boundary.len()],
        vec![[0.0; 3]; boundary.len()],
    );
    match cloner.membrane().boundary_data() {
        BoundaryData::Vertex => {
            for (slot, &v) in boundary.iter().enumerate() {
                let (p, rest) = (
                    cloner.placed()[v as usize],
                    cloner.mesh().positions[v as usize],
                );
                at_target[slot] = rgb(target.sample_bilinear(p.x, p.y));
                at_source[slot] = rgb(cloner.source().sample_bilinear(rest.x, rest.y));
            }
        }
        data => {
            let sampler = BoundarySampler::new(cloner.mesh(), data);
            let placed = cloner.placed();
            sampler.sample(
                placed,
                |p| rgb(target.sample_bilinear(p.x, p.y)),
                &mut at_target,
            );
            let rest = &cloner.mesh().positions;
            let source = cloner.source();
            sampler.sample(
                rest,
                |p| rgb(source.sample_bilinear(p.x, p.y)),
                &mut at_source,
            );
        }
    }
    let mut worst = 0.0f64;
    for (slot, &v) in boundary.iter().enumerate() {
        if !factor.is_constrained(v as usize) {
            continue;
        }
        for c in 0..3 {
            let want = f64::from(at_target[slot][c]) - f64::from(at_source[slot][c]);
            let got = f64::from(cloner.membrane().membrane()[v as usize][c]);
            worst = worst.max((got - want).abs());
        }
    }
    worst
}

#[test]
fn membrane_matches_target_minus_source_on_the_boundary() {
    for boundary_data in [BoundaryData::Vertex, BoundaryData::HatAverage] {
        let mut cloner = two_holes_cloner(&CloneOptions {
            boundary_data,
            ..CloneOptions::default()
        });
        let target = Canvas::from_image(&smooth_target(96, 80));
        let mut canvas = target.clone();
        let placement = Placement {
            rotation_deg: 17.0,
            scale: 1.1,
            ..centred(DVec2::new(47.3, 40.6))
        };
        let stats = cloner.clone_onto(&mut canvas, &placement).unwrap();
        assert_eq!(
            stats.membrane.constrained,
            cloner.membrane().boundary_vertices().len()
        );
        let worst = boundary_mismatch(&cloner, &target);
        assert!(
            worst <= 1e-5,
            "{boundary_data:?}: membrane off target − source by {worst}"
        );
    }
}

#[test]
fn clone_onto_itself_reproduces_the_source() {
    let source = textured_source(64, 64);
    let (mut cloner, _, _) = cloner_for(
        &source,
        &synth::disc(64, 64, 24.0),
        &CloneOptions::default(),
    );
    let mut canvas = Canvas::from_image(&source);
    let stats = cloner
        .clone_onto(&mut canvas, &Placement::identity())
        .unwrap();
    assert!(stats.raster.written > 1000, "the patch was drawn");
    let out = canvas.to_float_image(source.format());
    let worst = out
        .pixels()
        .iter()
        .zip(source.pixels())
        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(
        worst <= 1.0 / 255.0 + 1e-6,
        "differs from the source by {worst}"
    );
}

/// The membranes of two cloners agree to within `tolerance`.
fn membrane_difference(a: &PatchCloner, b: &PatchCloner) -> f64 {
    a.membrane()
        .membrane()
        .iter()
        .zip(b.membrane().membrane())
        .flat_map(|(x, y)| (0..3).map(move |c| f64::from((x[c] - y[c]).abs())))
        .fold(0.0, f64::max)
}

#[test]
fn moving_the_patch_equals_a_fresh_cloner_at_the_new_place() {
    let target = Canvas::from_image(&smooth_target(96, 80));
    let mut moved = two_holes_cloner(&CloneOptions::default());
    // A path that leaves the target on the left and top, then comes back in.
    let path = [
        DVec2::new(48.0, 40.0),
        DVec2::new(51.0, 42.0),
        DVec2::new(10.0, 40.0),
        DVec2::new(-5.0, 8.0),
        DVec2::new(30.5, 33.25),
        DVec2::new(48.0, 40.0),
    ];
    for at in path {
        let mut canvas = target.clone();
        let stats = moved.clone_onto(&mut canvas, &centred(at)).unwrap();
        let mut fresh = two_holes_cloner(&CloneOptions::default());
        let mut fresh_canvas = target.clone();
        fresh.clone_onto(&mut fresh_canvas, &centred(at)).unwrap();
        assert_eq!(
            fresh.membrane().factor().constrained(),
            moved.membrane().factor().constrained()
        );
        let difference = membrane_difference(&moved, &fresh);
        assert!(
            difference <= 1e-6,
            "at {at}: membranes differ by {difference} ({stats:?})"
        );
        assert!(boundary_mismatch(&moved, &target) <= 1e-5);
    }
}

/// A first clone's membrane is a separately built solver's, bit for bit, and its pixels
/// those of a plain draw of that membrane.
#[test]
fn a_first_clone_solves_then_draws_the_plain_bytes() {
    let target = Canvas::from_image(&smooth_target(120, 100));
    for laplacian in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let options = CloneOptions {
            laplacian,
            ..CloneOptions::default()
        };
        let mut cloner = two_holes_cloner(&options);
        let placement = Placement {
            rotation_deg: -21.0,
            scale: 1.17,
            ..centred(DVec2::new(57.4, 49.85))
        };
        let mut canvas = target.clone();
        let first = cloner.clone_onto(&mut canvas, &placement).unwrap();
        assert!(first.raster.written > 1000, "{first:?}");

        let data = cloner.membrane().boundary_data();
        let mut eager =
            MembraneSolver::new(cloner.mesh(), cloner.source(), laplacian, data).unwrap();
        eager.solve(cloner.placed(), &target, None).unwrap();
        assert!(
            eager.membrane() == cloner.membrane().membrane(),
            "{laplacian:?}"
        );

        let mesh = cloner.mesh();
        let patch = Patch {
            rest: &mesh.positions,
            placed: cloner.placed(),
            triangles: &mesh.triangles,
            membrane: cloner.membrane().membrane(),
            depth: None,
            loops: &mesh.loops,
            source: cloner.source(),
        };
        let mut plain = target.clone();
        let options = RasterOptions::default();
        let stats = draw_patch(&mut plain, &patch, &options, &mut RasterScratch::new()).unwrap();
        assert_eq!(stats, first.raster, "{laplacian:?}");
        assert!(
            canvas.pixels() == plain.pixels(),
            "{laplacian:?}: the first clone differs from a plain draw"
        );
    }
}

#[test]
fn whole_pixel_drags_equal_fresh_clones_byte_for_byte() {
    // Fractional position, scale and rotation, and a mesh with free interior vertices:
    // every whole-pixel move of a kept cloner gives the bytes of a fresh cloner at the new
    // place.
    let target = Canvas::from_image(&smooth_target(120, 100));
    let mut dragged = two_holes_cloner(&CloneOptions::default());
    let start = Placement {
        rotation_deg: 13.7,
        scale: 0.93,
        ..centred(DVec2::new(55.318, 47.902))
    };
    let mut canvas = target.clone();
    dragged.clone_onto(&mut canvas, &start).unwrap();
    for shift in [
        DVec2::new(3.0, 2.0),
        DVec2::new(-7.0, 1.0),
        DVec2::new(0.0, -4.0),
    ] {
        let placement = Placement {
            at: start.at + shift,
            ..start
        };
        let mut canvas = target.clone();
        dragged.clone_onto(&mut canvas, &placement).unwrap();
        let mut fresh = two_holes_cloner(&CloneOptions::default());
        let mut fresh_canvas = target.clone();
        fresh.clone_onto(&mut fresh_canvas, &placement).unwrap();
        assert!(
            canvas.pixels() == fresh_canvas.pixels(),
            "a move by {shift}: the kept cloner differs from a fresh one"
        );
    }
}

#[test]
fn outside_boundary_vertices_switch_off_and_come_back() {
    let target = Canvas::from_image(&smooth_target(96, 80));
    let mut cloner = two_holes_cloner(&CloneOptions::default());
    let boundary = cloner.membrane().boundary_vertices().to_vec();
    let inside = centred(DVec2::new(48.0, 40.0));
    let first = cloner.clone_onto(&mut target.clone(), &inside).unwrap();
    let membrane_inside = cloner.membrane().membrane().to_vec();
    assert_eq!(
        (first.membrane.constrained, first.membrane.outside),
        (boundary.len(), 0)
    );
    // The factor is built with the whole boundary constrained: a first clone inside the
    // target switches nothing (and so never refactors).
    let switches = first.membrane.switches;
    assert_eq!((switches.updates, switches.downdates), (0, 0));
    assert!(!switches.refactored);

    let out = cloner
        .clone_onto(&mut target.clone(), &centred(DVec2::new(8.0, 40.0)))
        .unwrap();
    let width = f64::from(target.width());
    for &v in &boundary {
        let p = cloner.placed()[v as usize];
        let outside = p.x < 0.0 || p.y < 0.0 || p.x > width || p.y > f64::from(target.height());
        assert_eq!(
            cloner.membrane().factor().is_constrained(v as usize),
            !outside,
            "vertex {v} at {p}"
        );
    }
    assert!(out.membrane.outside > 0);
    assert_eq!(
        out.membrane.constrained + out.membrane.outside,
        boundary.len()
    );
    assert!(out.membrane.switches.downdates >= out.membrane.outside);

    let back = cloner.clone_onto(&mut target.clone(), &inside).unwrap();
    assert_eq!(
        (back.membrane.constrained, back.membrane.outside),
        (boundary.len(), 0)
    );
    assert_eq!(back.membrane.switches.updates, out.membrane.outside);
    let drift = cloner
        .membrane()
        .membrane()
        .iter()
        .zip(&membrane_inside)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(drift <= 1e-6, "membrane after returning differs by {drift}");
}

fn is_grey_offset_of(pixel: [f32; 4], reference: [f32; 4], tolerance: f32) -> bool {
    let offset = |p: [f32; 4]| [p[0] - p[1], p[1] - p[2]];
    let (a, b) = (offset(pixel), offset(reference));
    (a[0] - b[0]).abs() <= tolerance && (a[1] - b[1]).abs() <= tolerance
}

/// Over a uniform target, monochrome mode adds the same offset to every channel (grey
/// texture, the target's colour); normal mode keeps the source's colour texture.
#[test]
fn monochrome_transfers_grey_texture_and_target_colour() {
    let teal = [0.2, 0.55, 0.5, 1.0];
    let target = FloatImage::from_fn(96, 80, RGB8, |_, _| teal).unwrap();
    let clone = |mode| {
        let options = CloneOptions {
            mode,
            ..CloneOptions::default()
        };
        let mut cloner = two_holes_cloner(&options);
        let mut canvas = Canvas::from_image(&target);
        cloner
            .clone_onto(&mut canvas, &centred(DVec2::new(48.0, 40.0)))
            .unwrap();
        canvas.to_float_image(RGB8)
    };
    let grey_ok = |image: &FloatImage| {
        let tolerance = 2.5 / 255.0;
        image
            .pixels()
            .iter()
            .all(|&p| is_grey_offset_of(p, teal, tolerance))
    };
    let mono = clone(CloneMode::Monochrome);
    assert!(grey_ok(&mono), "monochrome clone changed the target's hue");
    let textured = mono
        .pixels()
        .iter()
        .filter(|p| (p[1] - teal[1]).abs() > 0.01)
        .count();
    assert!(
        textured > 200,
        "monochrome clone lost the texture ({textured} pixels differ)"
    );
    assert!(
        !grey_ok(&clone(CloneMode::Normal)),
        "normal mode should carry colour texture"
    );
}

#[test]
fn alpha_of_an_rgba_source_is_kept() {
    let rgba8 = PixelFormat {
        color: ColorKind::Rgb,
        alpha: true,
        depth: Depth::Eight,
    };
    let opaque = textured_source(64, 64);
    let source = FloatImage::from_fn(64, 64, rgba8, |i, j| {
        let [r, g, b, _] = opaque.pixel(i, j).unwrap();
        [r, g, b, 0.3 + 0.6 * i as f32 / 64.0]
    })
    .unwrap();
    let transparent = FloatImage::from_fn(96, 80, rgba8, |_, _| [0.2, 0.4, 0.6, 0.0]).unwrap();
    let (mut cloner, _, _) = cloner_for(
        &source,
        &synth::disc(64, 64, 24.0),
        &CloneOptions::default(),
    );
    let mut canvas = Canvas::from_image(&transparent);
    cloner
        .clone_onto(&mut canvas, &centred(DVec2::new(48.0, 40.0)))
        .unwrap();
    let out = canvas.to_float_image(rgba8);
    assert_eq!(out.format(), rgba8);
    // Pixels well inside the disc (fully covered): alpha is the source's.
    let mut checked = 0;
    for j in 0..64u32 {
        for i in 0..64u32 {
            let d = DVec2::new(f64::from(i) + 0.5 - 32.0, f64::from(j) + 0.5 - 32.0).length();
            if d > 21.0 {
                continue;
            }
            let got = out.pixel(i + 16, j + 8).unwrap()[3];
            let want = source.pixel(i, j).unwrap()[3];
            assert!(
                (got - want).abs() <= 1.0 / 255.0 + 1e-6,
                "pixel ({i}, {j}): alpha {got}, source {want}"
            );
            checked += 1;
        }
    }
    assert!(checked > 1000);
    // Outside the patch the target stays transparent.
    assert_eq!(out.pixel(1, 1).unwrap()[3], 0.0);
}
