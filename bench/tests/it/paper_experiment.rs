//! The paper experiment on small fixed cases: PSNR thresholds against the pixel-grid
//! reference (crack and Dirichlet-centre boundaries), exactness on linear data, MVC refusing holes, uncovered-pixel counts, the
//! figure's shape, and the `bench paper --quick` command's columns.

use lapclone::clone::BoundaryData;
use lapclone::mesh::{BoundaryPlacement, MeshOptions};
use lapclone::pixels::{FloatImage, PixelFormat};
use lapclone_bench::reference::experiment::{Experiment, MvcOutcome, RunOptions};
use lapclone_bench::reference::figure::comparison_figure;
use lapclone_bench::reference::GridMask;
use lapclone_bench::synth;

const SIZE: usize = 64;

fn disc_mask() -> Vec<bool> {
    let bits = synth::disc(SIZE, SIZE, 26.0);
    (0..SIZE * SIZE)
        .map(|p| bits.get((p % SIZE) as i64, (p / SIZE) as i64))
        .collect()
}

/// A 16-bit image whose pixel centre (x + ½, y + ½) gets `f(x, y)` per channel.
fn image(f: impl Fn(f64, f64, usize) -> f64) -> FloatImage {
    FloatImage::from_fn(SIZE as u32, SIZE as u32, PixelFormat::RGBA16, |i, j| {
        let (x, y) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
        let c = |k| f(x, y, k).clamp(0.0, 1.0) as f32;
        [c(0), c(1), c(2), 1.0]
    })
    .unwrap()
}

/// Smooth, non-harmonic source and target (periods of 20–40 px).
fn smooth_pair() -> (FloatImage, FloatImage) {
    let source = image(|x, y, c| 0.5 + 0.3 * ((x + 7.0 * c as f64) / 9.0).sin() * (y / 13.0).cos());
    let target =
        image(|x, y, c| 0.5 + 0.3 * ((y - 5.0 * c as f64) / 6.0).sin() + 0.1 * (x / 11.0).cos());
    (source, target)
}

fn exact_cover_options(density: f64) -> MeshOptions {
    MeshOptions {
        density,
        simplify_tolerance: 0.0,
        ..MeshOptions::default()
    }
}

fn run_options() -> RunOptions {
    RunOptions {
        repeats: 1,
        ..RunOptions::default()
    }
}

#[test]
fn smooth_disc_meets_measured_psnr_thresholds() {
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, target) = smooth_pair();
    let experiment = Experiment::new(mask, source, target).unwrap();
    let run = experiment
        .run(&exact_cover_options(1.0), &run_options())
        .unwrap();
    let combinatorial = run.combinatorial.comparison.psnr_db;
    let cotangent = run.cotangent.comparison.psnr_db;
    // Measured 41.4 / 46.8 / 41.6 dB (combinatorial / cotangent / MVC; density 1 px, no
    // simplification, hat-averaged boundary values, 2 relaxation sweeps; 37.1 / 38.0 / 37.6
    // before the boundary moved onto the outside pixel centres); 1.5 dB margin. See
    // docs/quality.md for why this is not higher.
    assert!(combinatorial >= 39.9, "combinatorial {combinatorial} dB");
    assert!(cotangent >= combinatorial - 0.5, "cotangent {cotangent} dB");
    let mvc = run.mvc.figures().expect("a disc has no holes");
    assert!(mvc.comparison.psnr_db.is_finite() && mvc.comparison.psnr_db > 30.0);
    assert_eq!(run.uncovered, 0);
    assert_eq!(run.combinatorial.comparison.uncovered, 0);
    let seam = run.combinatorial.comparison.seam_step.mean_abs;
    let reference_seam = run.combinatorial.comparison.reference_seam_step.mean_abs;
    assert!(seam.is_finite() && reference_seam.is_finite());
}

#[test]
fn refining_the_mesh_improves_the_combinatorial_membrane() {
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, target) = smooth_pair();
    let experiment = Experiment::new(mask, source, target).unwrap();
    let coarse = experiment
        .run(&exact_cover_options(6.0), &run_options())
        .unwrap();
    let fine = experiment
        .run(&exact_cover_options(1.0), &run_options())
        .unwrap();
    assert!(fine.mesh.vertex_count() > coarse.mesh.vertex_count());
    assert!(
        fine.combinatorial.comparison.psnr_db > coarse.combinatorial.comparison.psnr_db + 1.0,
        "coarse {} dB, fine {} dB",
        coarse.combinatorial.comparison.psnr_db,
        fine.combinatorial.comparison.psnr_db
    );
}

#[test]
fn linear_boundary_data_is_reproduced_by_cotangent_and_mvc() {
    // target − source linear: the grid reference is exactly linear (the 5-point stencil is
    // exact on linear functions) and so is the bilinear sample at crack corners; cotangent
    // weights and MVC have linear precision, the combinatorial Laplacian does not. Linear
    // boundary data is what the vertex sample gives exactly: a hat average shifts it where
    // the boundary bends (checked at the end).
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let source = image(|_, _, c| 0.2 + 0.1 * c as f64);
    let target = image(|x, y, c| 0.1 + 0.006 * x + 0.004 * y + 0.05 * c as f64);
    let experiment = Experiment::new(mask, source, target).unwrap();
    let vertex_data = RunOptions {
        boundary_data: BoundaryData::Vertex,
        ..run_options()
    };
    let unrelaxed = MeshOptions {
        relax_sweeps: 0,
        ..exact_cover_options(2.0)
    };
    let run = experiment.run(&unrelaxed, &vertex_data).unwrap();
    let cotangent = run.cotangent.comparison.psnr_db;
    let mvc = run.mvc.figures().unwrap().comparison.psnr_db;
    let combinatorial = run.combinatorial.comparison.psnr_db;
    // 16-bit quantisation of the target bounds the agreement at roughly 100 dB.
    assert!(cotangent > 75.0, "cotangent {cotangent} dB");
    assert!(mvc > 75.0, "MVC {mvc} dB");
    assert!(
        combinatorial < cotangent,
        "combinatorial {combinatorial} dB"
    );
    // Relaxing the interior towards its neighbours' means restores part of the
    // combinatorial Laplacian's linear precision: not at the boundary's first ring, which
    // relaxation leaves where it is.
    let relaxed = experiment
        .run(
            &MeshOptions {
                relax_sweeps: 5,
                ..exact_cover_options(2.0)
            },
            &vertex_data,
        )
        .unwrap();
    let relaxed = relaxed.combinatorial.comparison.psnr_db;
    // Measured 43.7 → 50.0 dB (69.2 when the ring moved too).
    assert!(
        relaxed >= 48.0 && relaxed > combinatorial + 5.0,
        "{combinatorial} → {relaxed} dB"
    );
    // The hat average's weighted mean point lies up to about half a pixel off a vertex
    // where the boundary bends; with this gradient (0.007 per px) that bounds the cotangent
    // membrane's error to about 4e-3 (48 dB). Measured: 64.6 dB.
    let hat = experiment.run(&unrelaxed, &run_options()).unwrap();
    let hat_cotangent = hat.cotangent.comparison.psnr_db;
    assert!(
        (48.0..cotangent).contains(&hat_cotangent),
        "cotangent with hat-averaged data {hat_cotangent} dB"
    );
}

/// Pixel-scale texture (a hashed value per pixel) over a smooth target: the case point
/// samples alias.
fn textured_target() -> FloatImage {
    image(|x, y, c| {
        let cell = (x as u64).wrapping_mul(0x9e37_79b9) ^ (y as u64).wrapping_mul(0x85eb_ca6b);
        let noise = ((cell.wrapping_add(c as u64 * 0x27d4_eb2f) >> 7) % 1000) as f64 / 1000.0;
        0.4 + 0.2 * (x / 9.0).sin() + 0.25 * noise
    })
}

#[test]
fn hat_averaged_boundary_data_beats_the_vertex_sample_on_texture() {
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, _) = smooth_pair();
    let experiment = Experiment::new(mask, source, textured_target()).unwrap();
    let run = |boundary_data| {
        let options = RunOptions {
            boundary_data,
            ..run_options()
        };
        experiment.run(&MeshOptions::default(), &options).unwrap()
    };
    let (vertex, hat) = (run(BoundaryData::Vertex), run(BoundaryData::HatAverage));
    let gain = |pick: fn(&lapclone_bench::reference::experiment::MeshRun) -> f64| {
        pick(&hat) - pick(&vertex)
    };
    let combinatorial = gain(|r| r.combinatorial.comparison.psnr_db);
    let cotangent = gain(|r| r.cotangent.comparison.psnr_db);
    // Measured: 1.24 / 1.47 dB.
    assert!(
        combinatorial > 0.5,
        "combinatorial gains {combinatorial} dB"
    );
    assert!(cotangent > 0.5, "cotangent gains {cotangent} dB");
}

#[test]
fn mvc_is_not_run_on_a_patch_with_holes() {
    let bits = synth::annulus(SIZE, SIZE, 8.0, 26.0);
    let inside: Vec<bool> = (0..SIZE * SIZE)
        .map(|p| bits.get((p % SIZE) as i64, (p / SIZE) as i64))
        .collect();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, target) = smooth_pair();
    let experiment = Experiment::new(mask, source, target).unwrap();
    let run = experiment
        .run(&exact_cover_options(2.0), &run_options())
        .unwrap();
    assert!(matches!(run.mvc, MvcOutcome::Holes { holes: 1 }));
    assert_eq!(run.mvc.not_run_reason().as_deref(), Some("n/a (holes)"));
    // Measured 29.8 dB at density 2 px.
    assert!(run.combinatorial.comparison.psnr_db > 28.0);
}

#[test]
fn mvc_over_the_weight_budget_is_reported_not_run() {
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, target) = smooth_pair();
    let experiment = Experiment::new(mask, source, target).unwrap();
    let options = RunOptions {
        mvc_max_weights: 10,
        ..run_options()
    };
    let run = experiment.run(&exact_cover_options(2.0), &options).unwrap();
    assert!(matches!(run.mvc, MvcOutcome::TooLarge { limit: 10, .. }));
}

#[test]
fn simplified_boundaries_leave_counted_uncovered_pixels() {
    // Default simplification (0.9 px) may cut pixel centres off the mesh; the count must
    // match the sampler's own point-in-triangle test and be reported by the comparison.
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, target) = smooth_pair();
    let experiment = Experiment::new(mask, source, target).unwrap();
    let options = MeshOptions {
        density: 4.0,
        ..MeshOptions::default()
    };
    let run = experiment.run(&options, &run_options()).unwrap();
    assert_eq!(run.combinatorial.comparison.uncovered, run.uncovered);
    let in_some_triangle = |x: f64, y: f64| {
        run.mesh.triangles.iter().any(|t| {
            let [a, b, c] = t.map(|v| run.mesh.positions[v as usize]);
            let p = glam::DVec2::new(x, y);
            let side = |u: glam::DVec2, v: glam::DVec2| (v - u).perp_dot(p - u);
            let s = [side(a, b), side(b, c), side(c, a)];
            s.iter().all(|&k| k >= 0.0) || s.iter().all(|&k| k <= 0.0)
        })
    };
    let brute = (0..SIZE * SIZE)
        .filter(|&p| inside[p])
        .filter(|&p| !in_some_triangle((p % SIZE) as f64 + 0.5, (p / SIZE) as f64 + 0.5))
        .count();
    assert_eq!(run.uncovered, brute);
}

#[test]
fn size_mismatch_is_an_error() {
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, _) = smooth_pair();
    let small = FloatImage::from_fn(8, 8, PixelFormat::RGBA8, |_, _| [0.0; 4]).unwrap();
    assert!(Experiment::new(mask, source, small).is_err());
}

#[test]
fn figure_has_one_column_per_run_and_is_not_blank() {
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, target) = smooth_pair();
    let experiment = Experiment::new(mask, source, target).unwrap();
    let options = RunOptions {
        keep_membranes: true,
        ..run_options()
    };
    let runs: Vec<_> = [4.0, 2.0]
        .iter()
        .map(|&d| experiment.run(&exact_cover_options(d), &options).unwrap())
        .collect();
    let one = comparison_figure(&experiment, &runs[..1], 1).unwrap();
    let two = comparison_figure(&experiment, &runs, 1).unwrap();
    assert_eq!(two.height(), one.height());
    assert!(two.width() > one.width() + 2 * 50);
    let distinct: std::collections::BTreeSet<[u8; 4]> = two
        .pixels()
        .iter()
        .map(|p| [p.red(), p.green(), p.blue(), p.alpha()])
        .collect();
    assert!(distinct.len() > 100, "{} colours", distinct.len());
    let without = RunOptions {
        keep_membranes: false,
        ..run_options()
    };
    let bare = experiment.run(&exact_cover_options(4.0), &without).unwrap();
    assert!(comparison_figure(&experiment, &[bare], 1).is_err());
}

#[test]
fn boundary_on_the_dirichlet_centres_beats_the_moved_crack_boundary() {
    let inside = disc_mask();
    let mask = GridMask::new(SIZE, SIZE, &inside).unwrap();
    let (source, target) = smooth_pair();
    let experiment = Experiment::new(mask, source, target).unwrap();
    let cracks = experiment
        .run(&exact_cover_options(1.0), &run_options())
        .unwrap();
    let centred_options = MeshOptions {
        boundary: BoundaryPlacement::OutsideCentres,
        density: 1.0,
        min_angle_deg: 30.0,
        ..MeshOptions::default()
    };
    let centred = experiment.run(&centred_options, &run_options()).unwrap();
    let psnr = |run: &lapclone_bench::reference::experiment::MeshRun| {
        (
            run.combinatorial.comparison.psnr_db,
            run.cotangent.comparison.psnr_db,
        )
    };
    let (cracks_cmb, cracks_cot) = psnr(&cracks);
    let (cmb, cot) = psnr(&centred);
    // Measured: cracks 40.0 / 46.2 dB, centred 44.5 / 57.4 dB (combinatorial / cotangent);
    // 1.5 dB margins.
    assert!(cmb >= 43.0 && cot >= 56.0, "centred {cmb} / {cot} dB");
    assert!(
        cmb >= cracks_cmb + 3.0,
        "centred {cmb} vs cracks {cracks_cmb} dB"
    );
    assert!(
        cot >= cracks_cot + 9.5,
        "centred {cot} vs cracks {cracks_cot} dB"
    );
    assert_eq!(centred.uncovered, 0);
}
