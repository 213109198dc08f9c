//! Glue where a patch overlaps itself: front-layer boundary vertices over the patch continue
//! the patch's composite beneath them. Checks: a constant grey source shows no seam along the
//! front layer's edge (its largest step inside the patch is at most twice the unfolded one,
//! on a small mask and on the README's horse); the glued membrane is the fixed point of the
//! glue constraints, compared with a dense solve of the same system over random folds that
//! appear, move and vanish (fixed seed), with the glued set against a brute force; the
//! membrane does not depend on the history of folds; clones are byte-identical across runs
//! and thread counts.

use crate::fixtures;

use std::cell::{Cell, RefCell};
use std::path::Path;
use std::process::Command;

use fixtures::{cloner_for, smooth_target, RGB8};
use glam::DVec2;
use lapclone::clone::{Anchor, CloneOptions, CloneStats, PatchCloner, Placement, GLUE_TOLERANCE};
use lapclone::deform::{DeformRig, Deformed, Handle, Pin};
use lapclone::mesh::BitMask;
use lapclone::pixels::{Canvas, FloatImage};
use lapclone::raster::weights_if_strictly_inside;
use lapclone::solve::{laplacian, LaplacianKind};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};

fn asset(name: &str) -> String {
    format!("{}/assets/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The bundled horse silhouette scaled to 100×82 (a quarter of its size).
fn small_horse() -> BitMask {
    let full = image::open(asset("horse_mask.png")).unwrap().to_luma8();
    let small = image::imageops::resize(&full, 100, 82, image::imageops::FilterType::Triangle);
    BitMask::from_image(&image::DynamicImage::ImageLuma8(small), 0.5)
}

fn grey_source(width: u32, height: u32) -> FloatImage {
    FloatImage::from_fn(width, height, RGB8, |_, _| [0.5, 0.5, 0.5, 1.0]).unwrap()
}

/// A dark blue ramp with a bright disc (`centre`, `radius`, a 2 px soft edge): where the
/// disc lies under an overlap but away from the patch's outline, a front layer held to the
/// target pixel beneath it steps against the layer below, while the unfolded clone never
/// sees it.
fn disc_target(width: u32, height: u32, centre: DVec2, radius: f64) -> FloatImage {
    FloatImage::from_fn(width, height, RGB8, |i, j| {
        let p = DVec2::new(f64::from(i) + 0.5, f64::from(j) + 0.5);
        let t = ((radius - p.distance(centre)) / 2.0).clamp(0.0, 1.0) as f32;
        let (x, y) = (i as f32 / width as f32, j as f32 / height as f32);
        let (dark, bright) = ([0.1 + 0.2 * x, 0.15 + 0.15 * y, 0.35], [0.95, 0.95, 0.9]);
        let c: [f32; 3] = std::array::from_fn(|k| dark[k] + t * (bright[k] - dark[k]));
        [c[0], c[1], c[2], 1.0]
    })
    .unwrap()
}

/// Clones with `handles` and `pins` (a rigid clone when both are empty); gives the stats.
fn clone_with(
    cloner: &mut PatchCloner,
    canvas: &mut Canvas,
    placement: &Placement,
    (handles, pins): (&[Handle], &[Pin]),
    rig: &mut DeformRig,
) -> CloneStats {
    if handles.is_empty() && pins.is_empty() {
        return cloner.clone_onto(canvas, placement).unwrap();
    }
    let mut deformed = Deformed::default();
    rig.deform(handles, pins, &mut deformed).unwrap();
    cloner
        .clone_deformed(
            canvas,
            placement,
            &deformed.positions,
            Some(&deformed.depth),
        )
        .unwrap()
}

/// Per pixel: its centre lies in a placed triangle (closed, either orientation).
fn inside_patch(width: u32, height: u32, placed: &[DVec2], triangles: &[[u32; 3]]) -> Vec<bool> {
    let mut inside = vec![false; (width * height) as usize];
    for tri in triangles {
        let [a, b, c] = tri.map(|v| placed[v as usize]);
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        let area = (b - a).perp_dot(c - a);
        if area == 0.0 {
            continue;
        }
        let y0 = min.y.floor().max(0.0) as u32;
        let x0 = min.x.floor().max(0.0) as u32;
        for y in y0..(max.y.ceil().max(0.0) as u32).min(height) {
            for x in x0..(max.x.ceil().max(0.0) as u32).min(width) {
                let p = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let e = [
                    (c - b).perp_dot(p - b),
                    (a - c).perp_dot(p - c),
                    (b - a).perp_dot(p - a),
                ];
                if e.iter().all(|&e| e * area >= 0.0) {
                    inside[(y * width + x) as usize] = true;
                }
            }
        }
    }
    inside
}

/// The largest and the 99.9th-percentile one-pixel step (8-bit levels, any channel) between
/// 4-neighbours both inside the placed patch and at least 3 px from its outline.
fn inner_steps(image: &FloatImage, placed: &[DVec2], triangles: &[[u32; 3]]) -> (f64, f64) {
    let (w, h) = (image.width(), image.height());
    let inside = inside_patch(w, h, placed, triangles);
    let deep = |x: i64, y: i64| {
        (-3..=3i64).all(|dy| {
            (-3..=3i64).all(|dx| {
                let (u, v) = (x + dx, y + dy);
                dx * dx + dy * dy > 9
                    || (u >= 0
                        && v >= 0
                        && u < i64::from(w)
                        && v < i64::from(h)
                        && inside[(v * i64::from(w) + u) as usize])
            })
        })
    };
    let pixels = image.pixels();
    let mut steps = Vec::new();
    for y in 0..i64::from(h) {
        for x in 0..i64::from(w) {
            if !deep(x, y) {
                continue;
            }
            let p = pixels[(y * i64::from(w) + x) as usize];
            for (u, v) in [(x + 1, y), (x, y + 1)] {
                if u < i64::from(w) && v < i64::from(h) && deep(u, v) {
                    let q = pixels[(v * i64::from(w) + u) as usize];
                    let step = (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f32::max);
                    steps.push(f64::from(step) * 255.0);
                }
            }
        }
    }
    assert!(!steps.is_empty(), "no pixel deep inside the patch");
    steps.sort_by(f64::total_cmp);
    let percentile = steps[((steps.len() - 1) as f64 * 0.999).round() as usize];
    (steps[steps.len() - 1], percentile)
}

/// The grey-source step with and without the fold, and the glued count of the fold.
struct StepFigures {
    flat: (f64, f64),
    folded: (f64, f64),
    glued: usize,
}

fn grey_steps(
    mask: &BitMask,
    target: &FloatImage,
    placement_of: impl Fn(DVec2, DVec2) -> Placement,
    (handles, pins): (&[Handle], &[Pin]),
) -> StepFigures {
    let source = grey_source(mask.width as u32, mask.height as u32);
    let (mut cloner, min, max) = cloner_for(&source, mask, &CloneOptions::default());
    let placement = placement_of(min, max);
    let mut rig = DeformRig::new(cloner.mesh(), LaplacianKind::Combinatorial).unwrap();
    let mut figures = |deform: (&[Handle], &[Pin])| {
        let mut canvas = Canvas::from_image(target);
        let stats = clone_with(&mut cloner, &mut canvas, &placement, deform, &mut rig);
        let image = canvas.to_float_image(target.format());
        let triangles = &cloner.mesh().triangles;
        (inner_steps(&image, cloner.placed(), triangles), stats)
    };
    let (flat, _) = figures((&[], &[]));
    let (folded, stats) = figures((handles, pins));
    StepFigures {
        flat,
        folded,
        glued: stats.membrane.glued,
    }
}

/// The hind leg swung forward over the belly, as in the README (a quarter of its size).
fn small_hind_leg() -> (Vec<Handle>, Vec<Pin>) {
    let leg = Handle::drag(DVec2::new(29.5, 74.5), DVec2::new(53.75, 43.75), 17.5);
    (
        vec![leg],
        vec![Pin(DVec2::new(90.0, 17.5)), Pin(DVec2::new(7.5, 37.5))],
    )
}

#[test]
fn grey_source_has_no_seam_where_the_leg_lies_over_the_belly() {
    // The hind leg swung up over the body, whose middle lies over the disc.
    let leg = Handle::drag(DVec2::new(29.5, 74.5), DVec2::new(50.0, 32.0), 17.5);
    let (handles, pins) = (vec![leg], small_hind_leg().1);
    let target = disc_target(120, 100, DVec2::new(60.0, 41.0), 5.0);
    let at =
        |_: DVec2, _: DVec2| Placement::translate(DVec2::new(50.0, 41.0), DVec2::new(60.0, 50.0));
    let figures = grey_steps(&small_horse(), &target, at, (&handles, &pins));
    println!(
        "small horse, grey source: max step {:.1} / 99.9% {:.1} levels without the fold, {:.1} / {:.1} with it ({} glued)",
        figures.flat.0, figures.flat.1, figures.folded.0, figures.folded.1, figures.glued
    );
    assert!(
        figures.glued >= 3,
        "the leg lies over the belly: {} glued",
        figures.glued
    );
    // The unfolded figure is a level or two here; one level is the output's rounding.
    assert!(
        figures.folded.0 <= 2.0 * figures.flat.0.max(1.0),
        "step {:.1} levels with the fold, {:.1} without",
        figures.folded.0,
        figures.flat.0
    );
}

/// The README's command with a constant grey source: the measurement.
#[test]
fn readme_horse_grey_source_has_no_seam_over_the_belly() {
    let mask = BitMask::load(Path::new(&asset("horse_mask.png")), 0.5).unwrap();
    let target = FloatImage::load(Path::new(&asset("rocket.jpg"))).unwrap();
    let at = |min: DVec2, max: DVec2| Placement {
        pivot: Anchor::Centre.point(min, max),
        at: DVec2::new(320.0, 250.0),
        scale: 0.9,
        rotation_deg: 0.0,
    };
    let leg = Handle::drag(DVec2::new(118.0, 298.0), DVec2::new(215.0, 175.0), 70.0);
    let pins = [Pin(DVec2::new(360.0, 70.0)), Pin(DVec2::new(30.0, 150.0))];
    let figures = grey_steps(&mask, &target, at, (&[leg], &pins));
    println!(
        "README horse, grey source: max step {:.1} / 99.9% {:.1} levels without the drag, {:.1} / {:.1} with it ({} glued)",
        figures.flat.0, figures.flat.1, figures.folded.0, figures.folded.1, figures.glued
    );
    assert!(figures.glued >= 5, "{} glued", figures.glued);
    assert!(
        figures.folded.0 <= 2.0 * figures.flat.0,
        "step {:.1} levels with the drag, {:.1} without",
        figures.folded.0,
        figures.flat.0
    );
}

/// Gaussian elimination with partial pivoting, `k` right-hand sides (columns of `b`).
fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<[f64; 3]>) -> Vec<[f64; 3]> {
    let n = a.len();
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap();
        a.swap(col, pivot);
        b.swap(col, pivot);
        let (top, below) = a.split_at_mut(col + 1);
        let (top_b, below_b) = b.split_at_mut(col + 1);
        let (pivot_row, pivot_b) = (&top[col], top_b[col]);
        for (row, rhs) in below.iter_mut().zip(below_b.iter_mut()) {
            let factor = row[col] / pivot_row[col];
            if factor == 0.0 {
                continue;
            }
            for (x, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= factor * p;
            }
            for (x, p) in rhs.iter_mut().zip(pivot_b) {
                *x -= factor * p;
            }
        }
    }
    let mut x = vec![[0.0; 3]; n];
    for row in (0..n).rev() {
        for c in 0..3 {
            let sum: f64 = (row + 1..n).map(|k| a[row][k] * x[k][c]).sum();
            x[row][c] = (b[row][c] - sum) / a[row][row];
        }
    }
    x
}

/// The glued system's solution by a dense solve: `(L + εI + αP) f = α P c` with, at each
/// glued vertex `v`, `c_v = s(q) + Σ wₖ f(k) − s(v)` moved to the left. Constrained rows are
/// divided by α, so the dense matrix is well scaled.
fn dense_glued_membrane(cloner: &PatchCloner) -> Vec<[f64; 3]> {
    let membrane = cloner.membrane();
    let factor = membrane.factor();
    let (alpha, epsilon) = (factor.alpha(), factor.epsilon());
    let l = laplacian(cloner.mesh(), LaplacianKind::Combinatorial);
    let n = l.n;
    let mut a = vec![vec![0.0; n]; n];
    for (j, column) in l.col_ptr.windows(2).enumerate() {
        for k in column[0]..column[1] {
            let i = l.row_idx[k];
            (a[i][j], a[j][i]) = (l.values[k], l.values[k]);
        }
    }
    for (j, row) in a.iter_mut().enumerate() {
        row[j] += epsilon;
    }
    let mut b = vec![[0.0; 3]; n];
    let (target, own) = (membrane.target_at_boundary(), membrane.source_at_boundary());
    for (slot, &v) in membrane.boundary_vertices().iter().enumerate() {
        let v = v as usize;
        if factor.is_constrained(v) {
            a[v][v] += alpha;
            b[v] = [0, 1, 2].map(|c| alpha * f64::from(target[slot][c] - own[slot][c]));
        }
    }
    for g in cloner.glue().glued() {
        let (v, slot) = (g.beneath.vertex as usize, g.beneath.slot as usize);
        for (k, w) in g.beneath.triangle.iter().zip(g.beneath.weights) {
            a[v][*k as usize] -= alpha * w;
        }
        b[v] =
            [0, 1, 2].map(|c| alpha * (f64::from(g.source_beneath[c]) - f64::from(own[slot][c])));
    }
    for v in 0..n {
        if factor.is_constrained(v) {
            a[v].iter_mut().for_each(|x| *x /= alpha);
            b[v] = b[v].map(|x| x / alpha);
        }
    }
    dense_solve(a, b)
}

/// Brute force: the constrained boundary vertices that lie over a lower layer.
fn glued_by_brute_force(cloner: &PatchCloner, depth: &[f32]) -> Vec<u32> {
    let (placed, triangles) = (cloner.placed(), &cloner.mesh().triangles);
    let factor = cloner.membrane().factor();
    let boundary = cloner.membrane().boundary_vertices();
    boundary
        .iter()
        .copied()
        .filter(|&v| factor.is_constrained(v as usize))
        .filter(|&v| {
            let p = placed[v as usize];
            let own = f64::from(depth[v as usize]);
            triangles.iter().any(|tri| {
                let corners = tri.map(|k| placed[k as usize]);
                !tri.contains(&v)
                    && weights_if_strictly_inside(corners, p).is_some_and(|w| {
                        let d: f64 = (0..3)
                            .map(|k| w[k] * f64::from(depth[tri[k] as usize]))
                            .sum();
                        d < own
                    })
            })
        })
        .collect()
}

/// One step of a fold sequence: the front and hind legs' drags (absent: that fold vanishes).
type FoldStep = (Option<(f64, f64, f64)>, Option<(f64, f64, f64)>);

fn fold_steps() -> impl Strategy<Value = Vec<FoldStep>> {
    let front = (30.0..70.0f64, 20.0..50.0f64, 9.0..16.0f64);
    let hind = (35.0..65.0f64, 35.0..60.0f64, 12.0..20.0f64);
    prop::collection::vec((prop::option::of(front), prop::option::of(hind)), 4..7)
}

fn handles_of(step: &FoldStep) -> Vec<Handle> {
    let front = step
        .0
        .map(|(x, y, r)| Handle::drag(DVec2::new(64.0, 72.0), DVec2::new(x, y), r));
    let hind = step
        .1
        .map(|(x, y, r)| Handle::drag(DVec2::new(29.5, 74.5), DVec2::new(x, y), r));
    front.into_iter().chain(hind).collect()
}

#[test]
fn glued_membrane_is_the_dense_fixed_point_over_a_fold_sequence() {
    let source = fixtures::textured_source(100, 82);
    let target = smooth_target(120, 100);
    let placement = Placement::translate(DVec2::new(50.0, 41.0), DVec2::new(60.0, 50.0));
    let (cloner, _, _) = cloner_for(&source, &small_horse(), &CloneOptions::default());
    let rig = DeformRig::new(cloner.mesh(), LaplacianKind::Combinatorial).unwrap();
    // One cloner and rig for every case: their factors carry the switches of all earlier folds.
    let (cloner, rig) = (RefCell::new(cloner), RefCell::new(rig));
    let pins = [Pin(DVec2::new(90.0, 17.5))];
    let (glued_total, steps_glued) = (Cell::new(0), Cell::new(0));
    let config = Config {
        cases: 8,
        rng_seed: RngSeed::Fixed(0x0091_7e28),
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner = TestRunner::new(config);
    let result = runner.run(&fold_steps(), |steps| {
        let (mut cloner, mut rig) = (cloner.borrow_mut(), rig.borrow_mut());
        for step in &steps {
            let handles = handles_of(step);
            let mut deformed = Deformed::default();
            rig.deform(&handles, &pins, &mut deformed).unwrap();
            let mut canvas = Canvas::from_image(&target);
            let stats = cloner
                .clone_deformed(
                    &mut canvas,
                    &placement,
                    &deformed.positions,
                    Some(&deformed.depth),
                )
                .unwrap();
            let mut found: Vec<u32> = cloner
                .glue()
                .glued()
                .iter()
                .map(|g| g.beneath.vertex)
                .collect();
            found.sort_unstable();
            let mut expected = glued_by_brute_force(&cloner, &deformed.depth);
            expected.sort_unstable();
            prop_assert_eq!(&found, &expected, "glued set");
            prop_assert_eq!(stats.membrane.glued, found.len());
            glued_total.set(glued_total.get() + found.len());
            steps_glued.set(steps_glued.get() + usize::from(!found.is_empty()));
            let dense = dense_glued_membrane(&cloner);
            let mut worst = 0.0f64;
            for (m, d) in cloner.membrane().membrane().iter().zip(&dense) {
                for c in 0..3 {
                    worst = worst.max((f64::from(m[c]) - d[c]).abs());
                }
            }
            // Each step changes the glued values by at most the contraction times the last
            // change, so stopping at a change of GLUE_TOLERANCE leaves at most ρ/(1 − ρ) of it;
            // ten times covers ρ up to 0.9, and f32 storage adds 6e-8 at most.
            prop_assert!(
                worst <= 10.0 * GLUE_TOLERANCE,
                "glued membrane {worst:e} from the dense fixed point ({} glued, {} iterations)",
                found.len(),
                stats.membrane.glue_iterations
            );
        }
        Ok::<(), TestCaseError>(())
    });
    result.unwrap();
    let (steps_glued, glued_total) = (steps_glued.get(), glued_total.get());
    println!("{steps_glued} steps glued, {glued_total} glued vertices in all");
    assert!(
        steps_glued >= 8,
        "the sequences should fold often: {steps_glued} steps glued"
    );
}

/// The same fold cloned fresh and after other folds gives the same bytes: the glue starts
/// from the target values every time, never from an earlier frame.
#[test]
fn glue_does_not_depend_on_earlier_folds() {
    let source = fixtures::textured_source(100, 82);
    let target = smooth_target(120, 100);
    let placement = Placement::translate(DVec2::new(50.0, 41.0), DVec2::new(60.0, 50.0));
    let (handles, pins) = small_hind_leg();
    let run = |before: &[Vec<Handle>]| {
        let (mut cloner, _, _) = cloner_for(&source, &small_horse(), &CloneOptions::default());
        let mut rig = DeformRig::new(cloner.mesh(), LaplacianKind::Combinatorial).unwrap();
        let mut canvas = Canvas::from_image(&target);
        for earlier in before {
            clone_with(
                &mut cloner,
                &mut canvas,
                &placement,
                (earlier, &pins),
                &mut rig,
            );
        }
        let mut canvas = Canvas::from_image(&target);
        let stats = clone_with(
            &mut cloner,
            &mut canvas,
            &placement,
            (&handles, &pins),
            &mut rig,
        );
        (canvas, stats.membrane.glued)
    };
    let (fresh, glued) = run(&[]);
    assert!(glued > 0);
    let front = Handle::drag(DVec2::new(64.0, 72.0), DVec2::new(44.0, 34.0), 12.0);
    let hind = Handle::drag(DVec2::new(29.5, 74.5), DVec2::new(60.0, 40.0), 15.0);
    let (walked, _) = run(&[vec![front], vec![hind, front], vec![]]);
    assert!(
        fresh == walked,
        "the glued clone depends on the folds before it"
    );
}

/// The small horse's folded clone through the CLI: the same bytes on two runs, and on one
/// core (`taskset`, which sets what `available_parallelism` reports) as on all of them.
#[test]
fn glued_clone_is_deterministic_across_runs_and_threads() {
    let dir = tempfile::tempdir().unwrap();
    let mask = small_horse();
    let mask_path = dir.path().join("mask.png");
    mask.to_image().save(&mask_path).unwrap();
    let source = dir.path().join("source.png");
    Canvas::from_image(&fixtures::textured_source(100, 82))
        .save_png(&source, RGB8)
        .unwrap();
    let target = dir.path().join("target.png");
    Canvas::from_image(&disc_target(120, 100, DVec2::new(60.0, 54.0), 7.0))
        .save_png(&target, RGB8)
        .unwrap();
    let args = |out: &Path| {
        let mut args: Vec<String> = [
            "clone",
            "--source",
            "S",
            "--mask",
            "M",
            "--target",
            "T",
            "--at",
            "60,50",
            "--anchor",
            "topleft",
            "--drag",
            "29.5,74.5:53.75,43.75:17.5",
            "--pin",
            "90,17.5",
            "--pin",
            "7.5,37.5",
            "--stats",
            "-o",
            "O",
        ]
        .map(String::from)
        .to_vec();
        for (slot, path) in [(2, &source), (4, &mask_path), (6, &target)] {
            args[slot] = path.display().to_string();
        }
        let last = args.len() - 1;
        args[last] = out.display().to_string();
        args
    };
    let run = |name: &str, one_core: bool| {
        let out = dir.path().join(name);
        let mut command = if one_core {
            let mut c = Command::new("taskset");
            c.args(["-c", "0", env!("CARGO_BIN_EXE_lapclone")]);
            c
        } else {
            Command::new(env!("CARGO_BIN_EXE_lapclone"))
        };
        let output = command.args(args(&out)).output().unwrap();
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        let stats: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
        (
            std::fs::read(&out).unwrap(),
            stats["glued_vertices"].as_u64().unwrap(),
        )
    };
    let (first, glued) = run("a.png", false);
    assert!(glued > 0, "the leg lies over the belly");
    assert_eq!(first, run("b.png", false).0, "two runs differ");
    assert_eq!(first, run("c.png", true).0, "one core differs from all");
}
