//! Numerical faults (docs/robustness.md), beyond tests/solve_update.rs (10 000 random
//! switches of a bare factor) and tests/deform_switching.rs (a scripted editing session):
//! - the clone membrane over a long random walk of placements that push boundary vertices
//!   off the canvas and back (switches by update/downdate) against a fresh solver each step;
//! - a long random sequence of deformations against fresh rigs;
//! - releasing the last constraint of one piece of a multi-piece mesh (a downdate that would
//!   break positive definiteness) refactors and gives that piece an exactly zero membrane;
//! - sliver (near-zero-area) triangles and collapsed placements never give a non-finite
//!   membrane or deformation, and never a NaN pixel in a rendered frame.

use glam::DVec2;
use lapclone::clone::{BoundaryData, CloneOptions, MembraneSolver, PatchCloner, Placement};
use lapclone::deform::{DeformOptions, DeformRig, Deformed, Handle, Pin};
use lapclone::mesh::{assemble_mesh, mesh_mask, BitMask, Mesh, MeshOptions};
use lapclone::pixels::{Canvas, CanvasPixels, FloatImage, PixelFormat};
use lapclone::render::Renderer;
use lapclone::script::{parse_scene, ScriptOptions};
use lapclone::solve::{FactorMethod, LaplacianKind, PenaltyOptions};

use crate::checks;
use checks::Rng;

/// Two discs and a bar: three pieces, one with a hole.
fn three_piece_mesh() -> Mesh {
    let mask = BitMask::from_fn(60, 40, |x, y| {
        let d = |cx: f64, cy: f64| {
            ((x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2)).sqrt()
        };
        let ring = (4.0..11.0).contains(&d(14.0, 14.0));
        let disc = d(42.0, 14.0) < 9.0;
        let bar = (5..55).contains(&x) && (30..35).contains(&y);
        ring || disc || bar
    });
    let options = MeshOptions {
        density: 2.0,
        ..MeshOptions::default()
    };
    let mesh = mesh_mask(&mask, &options).unwrap().mesh;
    assert_eq!(mesh.piece_count, 3);
    mesh
}

fn textured(width: u32, height: u32, seed: u32) -> FloatImage {
    FloatImage::from_fn(width, height, PixelFormat::RGBA8, |i, j| {
        let v = ((i * 13 + j * 7 + seed) % 17) as f32 / 17.0;
        [0.3 + 0.4 * v, 0.6 - 0.2 * v, 0.5, 1.0]
    })
    .unwrap()
}

fn max_abs_difference(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

#[test]
fn membrane_over_a_random_walk_matches_fresh_solvers() {
    let mesh = three_piece_mesh();
    let source = textured(60, 40, 3);
    let canvas = Canvas::from_image(&textured(50, 36, 11));
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let mut kept = MembraneSolver::new(&mesh, &source, kind, BoundaryData::default()).unwrap();
        let mut rng = Rng(0xc0ffee);
        let (mut switches, mut refactors) = (0, 0);
        let mut placed = Vec::new();
        for step in 0..300 {
            // Wander so that pieces leave the canvas on every side and come back.
            let placement = Placement {
                pivot: DVec2::new(30.0, 20.0),
                at: DVec2::new(rng.range(-30.0, 80.0), rng.range(-20.0, 56.0)),
                scale: rng.range(0.5, 1.5),
                rotation_deg: rng.range(-180.0, 180.0),
            };
            placement.apply(&mesh.positions, &mut placed);
            let stats = kept.solve(&placed, &canvas, None).unwrap();
            switches += stats.switches.updates + stats.switches.downdates;
            refactors += usize::from(stats.switches.refactored);
            let mut fresh =
                MembraneSolver::new(&mesh, &source, kind, BoundaryData::default()).unwrap();
            fresh.solve(&placed, &canvas, None).unwrap();
            let difference = max_abs_difference(kept.membrane(), fresh.membrane());
            assert!(
                kept.membrane().iter().flatten().all(|v| v.is_finite()),
                "{kind:?} step {step}: non-finite membrane"
            );
            assert!(
                difference <= 1e-5,
                "{kind:?} step {step}: differs by {difference}"
            );
        }
        assert!(switches > 1000, "{kind:?}: only {switches} switches");
        eprintln!("{kind:?}: {switches} switches, {refactors} guarded refactorisations");
    }
}

fn random_handles(rng: &mut Rng, mesh: &Mesh) -> (Vec<Handle>, Vec<Pin>) {
    let vertex = |rng: &mut Rng| mesh.positions[(rng.next() * mesh.vertex_count() as f64) as usize];
    let handles = (0..(rng.next() * 4.0) as usize)
        .map(|_| {
            let from = vertex(rng);
            let mut handle = Handle::drag(
                from,
                from + DVec2::new(rng.range(-8.0, 8.0), rng.range(-8.0, 8.0)),
                rng.range(2.0, 20.0),
            );
            if rng.next() < 0.2 {
                handle.rotation_deg = Some(rng.range(-90.0, 90.0));
            }
            if rng.next() < 0.2 {
                handle.pivot = Some(vertex(rng));
            }
            handle
        })
        .collect();
    let pins = (0..(rng.next() * 3.0) as usize)
        .map(|_| Pin(vertex(rng)))
        .collect();
    (handles, pins)
}

/// Incremental rigs against fresh ones. Random handles conflict (overlapping drags, pins
/// inside drags), which makes some frames ill-conditioned: two exact fresh factorisations
/// (simplicial and supernodal) then already disagree by up to ~1e-4 px. So each frame's
/// tolerance is 10× that spread between two fresh solves, and never below 1e-7 px: the
/// updated factor must be as good as a refactorisation, up to a small factor, on every
/// frame of the sequence (no accumulating drift).
#[test]
fn long_random_deformation_sequences_match_fresh_rigs() {
    let mesh = three_piece_mesh();
    let fresh_rig = |kind, method| {
        let options = DeformOptions {
            penalty: PenaltyOptions {
                method,
                ..PenaltyOptions::default()
            },
            ..DeformOptions::default()
        };
        DeformRig::with_options(&mesh, kind, options).unwrap()
    };
    let distance = |a: &Deformed, b: &Deformed| {
        a.positions
            .iter()
            .zip(&b.positions)
            .map(|(p, q)| p.distance(*q))
            .fold(0.0, f64::max)
    };
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let mut out = Deformed::default();
        let (mut simplicial, mut supernodal) = (Deformed::default(), Deformed::default());
        let mut rng = Rng(0xdef0 + kind as u64);
        let (mut switches, mut worst_ratio) = (0, 0.0f64);
        for frame in 0..120 {
            let (handles, pins) = random_handles(&mut rng, &mesh);
            switches += rig.deform(&handles, &pins, &mut out).unwrap().switches();
            fresh_rig(kind, FactorMethod::Simplicial)
                .deform(&handles, &pins, &mut simplicial)
                .unwrap();
            fresh_rig(kind, FactorMethod::Supernodal)
                .deform(&handles, &pins, &mut supernodal)
                .unwrap();
            assert!(
                out.positions.iter().all(|p| p.is_finite())
                    && out.depth.iter().all(|d| d.is_finite()),
                "{kind:?} frame {frame}: non-finite deformation"
            );
            let spread = distance(&simplicial, &supernodal);
            let tolerance = (10.0 * spread).max(1e-7);
            let error = distance(&out, &simplicial);
            assert!(
                error <= tolerance,
                "{kind:?} frame {frame}: {error} px from a fresh rig (fresh rigs differ by {spread})"
            );
            worst_ratio = worst_ratio.max(error / tolerance);
        }
        assert!(switches > 100, "{kind:?}: only {switches} switches");
        eprintln!("{kind:?}: {switches} switches, worst error / tolerance {worst_ratio:.3}");
    }
}

#[test]
fn a_piece_losing_its_last_constraint_gets_an_exactly_zero_membrane() {
    let mesh = three_piece_mesh();
    let source = textured(60, 40, 5);
    let mut cloner = PatchCloner::new(source, mesh.clone(), &CloneOptions::default()).unwrap();
    let mut canvas = Canvas::from_image(&textured(60, 40, 9));
    // All pieces on the canvas: every boundary vertex constrained.
    let home = Placement::translate(DVec2::new(30.0, 20.0), DVec2::new(30.0, 20.0));
    cloner.clone_onto(&mut canvas, &home).unwrap();
    let refactors_before = cloner.membrane().factor().refactor_count();
    // Shift right by 32 px: the right disc (piece of vertex nearest (42, 14)) leaves the
    // canvas entirely, so its last constraints are released by downdates.
    let shifted = Placement::translate(DVec2::new(30.0, 20.0), DVec2::new(62.0, 20.0));
    let mut canvas = Canvas::from_image(&textured(60, 40, 9));
    cloner.clone_onto(&mut canvas, &shifted).unwrap();
    let disc_piece = piece_nearest(&mesh, DVec2::new(42.0, 14.0));
    let membrane = cloner.membrane().membrane();
    for (v, m) in membrane.iter().enumerate() {
        if mesh.piece[v] == disc_piece {
            assert_eq!(*m, [0.0; 3], "vertex {v} of the unconstrained piece");
        }
    }
    assert!(
        cloner.membrane().factor().refactor_count() > refactors_before,
        "releasing a piece's last constraint must go through the refactor guard"
    );
    // The constrained pieces still match a fresh solve.
    let mut fresh = MembraneSolver::new(
        &mesh,
        cloner.source(),
        LaplacianKind::Combinatorial,
        BoundaryData::default(),
    )
    .unwrap();
    fresh
        .solve(
            cloner.placed(),
            &Canvas::from_image(&textured(60, 40, 9)),
            None,
        )
        .unwrap();
    assert!(max_abs_difference(membrane, fresh.membrane()) <= 1e-5);
}

fn piece_nearest(mesh: &Mesh, point: DVec2) -> u32 {
    let nearest = (0..mesh.vertex_count())
        .min_by(|&a, &b| {
            mesh.positions[a]
                .distance(point)
                .total_cmp(&mesh.positions[b].distance(point))
        })
        .unwrap();
    mesh.piece[nearest]
}

/// A fan around (10, 10) plus a boundary sliver: the rim vertex (6, 2 − 1e-8) sits
/// 1e-8 px outside the straight top edge, giving a triangle of area ~4e-8 px² beside
/// ordinary ones; it passes the sanity check.
fn sliver_mesh() -> Mesh {
    let rim = [
        (2.0, 2.0),
        (10.0, 2.0 - 1e-9),
        (18.0, 2.0),
        (18.0 + 1e-9, 10.0),
        (18.0, 18.0),
        (10.0, 18.0 + 1e-9),
        (2.0, 18.0),
        (2.0, 10.0),
        (2.0 - 1e-9, 6.0),
    ];
    let mut positions = vec![DVec2::new(10.0, 10.0)];
    positions.extend(rim.iter().map(|&(x, y)| DVec2::new(x, y)));
    let n = rim.len() as u32;
    let mut triangles: Vec<[u32; 3]> = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    let sliver = positions.len() as u32;
    positions.push(DVec2::new(6.0, 2.0 - 1e-8));
    triangles.push([1, sliver, 2]);
    assemble_mesh(positions, triangles)
}

#[test]
fn slivers_and_collapsed_placements_never_give_non_finite_values() {
    let mesh = sliver_mesh();
    mesh.sanity_check()
        .expect("the sliver mesh is a valid mesh");
    let smallest = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            (b - a).perp_dot(c - a)
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        smallest < 1e-7,
        "no sliver: smallest doubled area {smallest}"
    );
    for kind in [LaplacianKind::Combinatorial, LaplacianKind::Cotangent] {
        let options = CloneOptions {
            laplacian: kind,
            ..CloneOptions::default()
        };
        let mut cloner = PatchCloner::new(textured(20, 20, 1), mesh.clone(), &options).unwrap();
        let target = textured(30, 30, 4);
        let placements = [
            Placement::translate(DVec2::new(10.0, 10.0), DVec2::new(15.0, 15.0)),
            Placement {
                scale: 1e-12,
                ..Placement::translate(DVec2::new(10.0, 10.0), DVec2::new(15.0, 15.0))
            },
            Placement {
                scale: 1e6,
                ..Placement::translate(DVec2::new(10.0, 10.0), DVec2::new(15.0, 15.0))
            },
            Placement {
                rotation_deg: 1e15,
                ..Placement::translate(DVec2::new(10.0, 10.0), DVec2::new(15.0, 15.0))
            },
        ];
        for placement in &placements {
            let mut canvas = Canvas::from_image(&target);
            cloner.clone_onto(&mut canvas, placement).unwrap();
            assert_finite_membrane(&cloner, &format!("{kind:?} {placement:?}"));
        }
        // Deformed positions collapsed onto one point, or onto a line: zero-area triangles.
        let n = mesh.vertex_count();
        let point = vec![DVec2::new(10.0, 10.0); n];
        let line: Vec<DVec2> = (0..n).map(|v| DVec2::new(v as f64, 10.0)).collect();
        let depth = vec![0.0f32; n];
        let home = Placement::translate(DVec2::new(10.0, 10.0), DVec2::new(15.0, 15.0));
        for deformed in [&point, &line] {
            let mut canvas = Canvas::from_image(&target);
            cloner
                .clone_deformed(&mut canvas, &home, deformed, Some(&depth))
                .unwrap();
            assert_finite_membrane(&cloner, &format!("{kind:?} collapsed"));
        }
        // A drag on the sliver mesh deforms to finite positions.
        let mut rig = DeformRig::new(&mesh, kind).unwrap();
        let mut out = Deformed::default();
        let handle = Handle::drag(DVec2::new(6.0, 2.0), DVec2::new(6.0, -4.0), 5.0);
        rig.deform(&[handle], &[Pin(DVec2::new(10.0, 18.0))], &mut out)
            .unwrap();
        assert!(
            out.positions.iter().all(|p| p.is_finite()),
            "{kind:?} deformation"
        );
        assert!(out.depth.iter().all(|d| d.is_finite()), "{kind:?} depth");
    }
}

fn assert_finite_membrane(cloner: &PatchCloner, what: &str) {
    assert!(
        cloner
            .membrane()
            .membrane()
            .iter()
            .flatten()
            .all(|v| v.is_finite()),
        "{what}: non-finite membrane"
    );
}

/// Scenes with sliver polygons, near-zero and huge scales, crushing drags: by the maximum
/// principle every cloned channel stays within the source's and target's range (both in
/// [0.4, 0.6] here), so a NaN or infinity — which a u8 frame would show as 0 or 255 —
/// cannot hide. Every channel of every frame is checked.
#[test]
fn rendered_frames_hold_no_nan_even_for_degenerate_patches() {
    let dir = tempfile::tempdir().unwrap();
    let grey = |w, h, seed: u32| {
        image::RgbImage::from_fn(w, h, |x, y| {
            let v = ((x * 7 + y * 3 + seed) % 11) as f32 / 11.0;
            let c = (255.0 * (0.4 + 0.2 * v)) as u8;
            image::Rgb([c, 255 - c, c])
        })
    };
    grey(40, 30, 0).save(dir.path().join("src.png")).unwrap();
    grey(48, 36, 5).save(dir.path().join("tgt.png")).unwrap();
    let scene = "canvas(48, 36, #{ fps: 8, duration: 1, background: \"tgt.png\" });\n\
        let a = patch(\"sliver\", #{ source: \"src.png\", polygons: [[[2, 2], [30, 2.000001], [38, 2], [20, 20]]] });\n\
        a.at(0, [24, 18]).scale(0, 1).scale(0.5, 0.000001).scale(1, 40);\n\
        let b = patch(\"thin\", #{ source: \"src.png\", polygons: [[[1, 10], [39, 10], [39, 10.01], [1, 10.02]]] });\n\
        b.at(0, [20, 12]).rotate(1, 3600);\n\
        let c = patch(\"crushed\", #{ source: \"src.png\", polygons: [[[5, 5], [35, 5], [35, 25], [5, 25]]] });\n\
        c.depth(0, 2).drag([20, 15], 30).key(0, [20, 15]).key(1, [400, -300]);\n\
        c.pin([6, 6]).pin([34, 24]);\n";
    let file = dir.path().join("degenerate.rhai");
    let loaded = parse_scene(scene, &file, &ScriptOptions::for_scene_file(&file)).unwrap();
    let mut renderer = Renderer::new(loaded.scene).unwrap();
    // Sources and target lie in [0.4, 0.6]: the membrane in [−0.2, 0.2], the clone in [0.2, 0.8].
    let (lo, hi) = ((0.2 * 255.0) as u8 - 1, (0.8 * 255.0) as u8 + 1);
    for frame in 0..renderer.frame_count() {
        let canvas = renderer.render_frame(frame).unwrap();
        let CanvasPixels::Eight(pixels) = canvas.pixels() else {
            panic!("8-bit scene gave a 16-bit canvas");
        };
        for (index, pixel) in pixels.iter().enumerate() {
            assert_eq!(pixel[3], 255, "frame {frame} pixel {index}: alpha");
            assert!(
                pixel[..3].iter().all(|c| (lo..=hi).contains(c)),
                "frame {frame} pixel {index}: {pixel:?} outside [{lo}, {hi}]"
            );
        }
    }
}
