//! Golden frames of the whole clone (mesh → membrane → raster) on small synthetic images:
//! a disc, a patch with two holes, a spiral, a patch half outside the target, a rotated and
//! scaled patch, a 16-bit grey case (library API); the disc again and a dragged patch through
//! the CLI binary; and the horse silhouette with a leg dragged across its body (self-overlap,
//! depth order), checked for determinism and for exactly which boundary constraints it
//! switches off.

use crate::fixtures;
use crate::golden;

use std::process::Command;

use crate::synth;
use glam::DVec2;
use lapclone::clone::{CloneOptions, Placement};
use lapclone::deform::{DeformRig, Deformed, Handle};
use lapclone::mesh::BitMask;
use lapclone::pixels::{Canvas, FloatImage};
use lapclone::solve::LaplacianKind;

use fixtures::*;

/// One and a half 8-bit levels: room for float rounding across platforms, far below a seam.
const TOLERANCE: f32 = 1.5 / 255.0;

#[test]
fn disc() {
    let source = textured_source(64, 64);
    let mask = synth::disc(64, 64, 22.0);
    let out = clone_image(
        &source,
        &mask,
        &smooth_target(96, 80),
        DVec2::new(48.0, 40.0),
        1.0,
        0.0,
    );
    golden::assert_golden("clone_disc", &out, TOLERANCE);
}

#[test]
fn two_holes() {
    let source = textured_source(64, 64);
    let mask = synth::two_holes(64, 64);
    let out = clone_image(
        &source,
        &mask,
        &smooth_target(96, 80),
        DVec2::new(48.0, 40.0),
        1.0,
        0.0,
    );
    golden::assert_golden("clone_two_holes", &out, TOLERANCE);
}

#[test]
fn spiral() {
    let source = textured_source(96, 96);
    let mask = synth::spiral(96, 96);
    let out = clone_image(
        &source,
        &mask,
        &smooth_target(120, 108),
        DVec2::new(60.0, 54.0),
        1.0,
        0.0,
    );
    golden::assert_golden("clone_spiral", &out, TOLERANCE);
}

#[test]
fn half_outside() {
    let source = textured_source(64, 64);
    let mask = synth::disc(64, 64, 22.0);
    let out = clone_image(
        &source,
        &mask,
        &smooth_target(96, 80),
        DVec2::new(4.0, 30.0),
        1.0,
        0.0,
    );
    golden::assert_golden("clone_half_outside", &out, TOLERANCE);
}

#[test]
fn rotated_and_scaled() {
    let source = textured_source(64, 64);
    let mask = synth::two_holes(64, 64);
    let out = clone_image(
        &source,
        &mask,
        &smooth_target(96, 80),
        DVec2::new(50.0, 40.0),
        0.8,
        30.0,
    );
    golden::assert_golden("clone_rotated_scaled", &out, TOLERANCE);
}

#[test]
fn grey_16_bit() {
    let source = grey16(64, 64, 0.0);
    let target = FloatImage::from_fn(96, 80, GREY16, |i, j| {
        let v = 0.2 + 0.5 * i as f32 / 96.0 + 0.1 * j as f32 / 80.0;
        [v, v, v, 1.0]
    })
    .unwrap();
    let mask = synth::disc(64, 64, 24.0);
    let out = clone_image(&source, &mask, &target, DVec2::new(50.0, 38.0), 1.0, 0.0);
    assert_eq!(out.format(), GREY16);
    // 16-bit reference: a tighter tolerance than 8-bit cases (40 16-bit levels).
    golden::assert_golden("clone_grey16", &out, 40.0 / 65535.0);
}

fn lapclone() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lapclone"))
}

/// Writes the disc case's inputs as PNGs into `dir`.
fn write_disc_inputs(dir: &std::path::Path) {
    save(&textured_source(64, 64), &dir.join("source.png"));
    save(&smooth_target(96, 80), &dir.join("target.png"));
    synth::disc(64, 64, 22.0)
        .to_image()
        .save(dir.join("mask.png"))
        .unwrap();
}

fn run_clone(dir: &std::path::Path, extra: &[&str]) -> Vec<u8> {
    let out = dir.join("out.png");
    let status = lapclone()
        .arg("clone")
        .args([
            "--source",
            "source.png",
            "--mask",
            "mask.png",
            "--target",
            "target.png",
        ])
        .args(extra)
        .arg("-o")
        .arg(&out)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "clone failed: {}",
        String::from_utf8_lossy(&status.stderr)
    );
    std::fs::read(out).unwrap()
}

/// The CLI gives the same picture as the library for the same inputs.
#[test]
fn disc_through_cli_matches_library_reference() {
    let dir = tempfile::tempdir().unwrap();
    write_disc_inputs(dir.path());
    let png = run_clone(dir.path(), &["--at", "48,40"]);
    golden::assert_golden_png("clone_disc", &png, TOLERANCE);
}

#[test]
fn dragged_disc_through_cli() {
    let dir = tempfile::tempdir().unwrap();
    write_disc_inputs(dir.path());
    let args = [
        "--at",
        "48,40",
        "--drag",
        "46,32:56,24:12",
        "--pin",
        "18,32",
    ];
    let png = run_clone(dir.path(), &args);
    assert_eq!(png, run_clone(dir.path(), &args), "two runs differ");
    golden::assert_golden_png("clone_drag", &png, TOLERANCE);
}

/// The bundled horse silhouette scaled to 100×82.
fn small_horse() -> BitMask {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/horse_mask.png");
    let full = image::open(path).unwrap().to_luma8();
    let small = image::imageops::resize(&full, 100, 82, image::imageops::FilterType::Triangle);
    BitMask::from_image(&image::DynamicImage::ImageLuma8(small), 0.5)
}

struct OverlapFrame {
    image: FloatImage,
    placed: Vec<DVec2>,
    depth: Vec<f32>,
    triangles: Vec<[u32; 3]>,
    boundary: Vec<u32>,
    constrained: Vec<bool>,
    hidden_count: usize,
    outside_count: usize,
}

/// The front leg (near (64, 72) at rest) dragged up across the body.
fn horse_overlap_frame() -> OverlapFrame {
    let source = textured_source(100, 82);
    let mask = small_horse();
    let (mut cloner, _, _) = cloner_for(&source, &mask, &CloneOptions::default());
    let mut rig = DeformRig::new(cloner.mesh(), LaplacianKind::Combinatorial).unwrap();
    let mut deformed = Deformed::default();
    let leg = Handle::drag(DVec2::new(64.0, 72.0), DVec2::new(44.0, 34.0), 12.0);
    rig.deform(&[leg], &[], &mut deformed).unwrap();
    let target = smooth_target(120, 100);
    let mut canvas = Canvas::from_image(&target);
    let placement = Placement::translate(DVec2::new(50.0, 41.0), DVec2::new(60.0, 50.0));
    let stats = cloner
        .clone_deformed(
            &mut canvas,
            &placement,
            &deformed.positions,
            Some(&deformed.depth),
        )
        .unwrap();
    OverlapFrame {
        image: canvas.to_float_image(target.format()),
        placed: cloner.placed().to_vec(),
        depth: deformed.depth.clone(),
        triangles: cloner.mesh().triangles.clone(),
        boundary: cloner.membrane().boundary_vertices().to_vec(),
        constrained: cloner.membrane().factor().constrained().to_vec(),
        hidden_count: stats.membrane.hidden,
        outside_count: stats.membrane.outside,
    }
}

/// Brute force over every triangle: is `v` strictly inside a triangle it is not a corner of,
/// with a larger interpolated depth there than its own?
fn covered_by_front_layer(frame: &OverlapFrame, v: u32) -> bool {
    let p = frame.placed[v as usize];
    let own = f64::from(frame.depth[v as usize]);
    frame.triangles.iter().any(|tri| {
        if tri.contains(&v) {
            return false;
        }
        let [a, b, c] = tri.map(|i| frame.placed[i as usize]);
        let area = (b - a).perp_dot(c - a);
        let w = [
            (b - p).perp_dot(c - p),
            (c - p).perp_dot(a - p),
            (a - p).perp_dot(b - p),
        ]
        .map(|x| x / area);
        let depth: f64 = (0..3)
            .map(|k| w[k] * f64::from(frame.depth[tri[k] as usize]))
            .sum();
        w.iter().all(|&x| x > 0.0) && depth > own
    })
}

#[test]
fn horse_self_overlap() {
    let frame = horse_overlap_frame();
    let again = horse_overlap_frame();
    assert_eq!(frame.image, again.image, "two runs differ");
    assert_eq!(frame.outside_count, 0, "the horse sits inside the target");

    let covered: Vec<u32> = frame
        .boundary
        .iter()
        .copied()
        .filter(|&v| covered_by_front_layer(&frame, v))
        .collect();
    assert!(
        covered.len() >= 5,
        "the leg should cover part of the body's outline, covers {}",
        covered.len()
    );
    assert_eq!(frame.hidden_count, covered.len());
    for &v in &frame.boundary {
        let expect_on = !covered.contains(&v);
        assert_eq!(
            frame.constrained[v as usize], expect_on,
            "boundary vertex {v}"
        );
    }
    golden::assert_golden("clone_horse_overlap", &frame.image, TOLERANCE);
}
