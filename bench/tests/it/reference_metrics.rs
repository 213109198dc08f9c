//! Metrics against hand-computed small cases, plus a PSNR threshold on a small fixed clone:
//! MVC on a pixel-aligned square patch against the pixel-grid reference.

use glam::DVec2;
use lapclone_bench::reference::{
    composite, poisson_membrane, psnr, psnr_by_ring, ring_of_pixels, seam_step, uncovered_pixels,
    ComparisonInput, GridMask, MembraneComparison, MetricError, MvcWeights,
};

/// 3×3 image, centre pixel inside.
fn centre_mask() -> Vec<bool> {
    let mut mask = vec![false; 9];
    mask[4] = true;
    mask
}

#[test]
fn psnr_matches_hand_computation() {
    // 2×1 image, 2 channels, both pixels inside: errors 0.1, 0, 0, 0.4 → MSE 0.17 / 4.
    let inside = [true, true];
    let mask = GridMask::new(2, 1, &inside).unwrap();
    let a = [0.5f32, 0.5, 0.5, 0.5];
    let b = [0.6f64, 0.5, 0.5, 0.9];
    let expected = 10.0 * (4.0 / 0.17f64).log10(); // ≈ 13.716 dB
    assert!((psnr(&a, &b, 2, mask).unwrap() - expected).abs() < 1e-5);
    // Outside-mask pixels do not count: errors 0.1, 0 → MSE 0.005.
    let first_only = [true, false];
    let mask = GridMask::new(2, 1, &first_only).unwrap();
    let expected = 10.0 * (1.0 / 0.005f64).log10(); // ≈ 23.010 dB
    assert!((psnr(&a, &b, 2, mask).unwrap() - expected).abs() < 1e-5);
    assert_eq!(psnr(&a, &a, 2, mask).unwrap(), f64::INFINITY);
}

#[test]
fn seam_step_matches_hand_computation() {
    let inside = centre_mask();
    let mask = GridMask::new(3, 3, &inside).unwrap();
    // Result 0.8 in the centre; target: left 0.5, right 0.7, up 0.8, down 1.0.
    let mut result = vec![0.0f32; 9];
    result[4] = 0.8;
    let mut target = vec![9.0f32; 9]; // corners and centre are never read
    target[3] = 0.5;
    target[5] = 0.7;
    target[1] = 0.8;
    target[7] = 1.0;
    let step = seam_step(&result, &target, 1, mask).unwrap();
    assert_eq!(step.pairs, 4);
    // (0.3 + 0.1 + 0.0 + 0.2) / 4 = 0.15
    assert!((step.mean_abs - 0.15).abs() < 1e-6, "{step:?}");
}

#[test]
fn uncovered_and_composite_and_errors() {
    let inside = centre_mask();
    let mask = GridMask::new(3, 3, &inside).unwrap();
    let mut covered = vec![false; 9];
    assert_eq!(uncovered_pixels(mask, &covered).unwrap(), 1);
    covered[4] = true;
    assert_eq!(uncovered_pixels(mask, &covered).unwrap(), 0);

    let source = [0.25f32; 9];
    let target = [0.75f32; 9];
    let membrane = [0.5f64; 9];
    let out = composite(&source, &target, &membrane, 1, mask).unwrap();
    assert_eq!(out[4], 0.75);
    assert_eq!(out[0], 0.75f32 as f64);

    assert_eq!(
        psnr(&source[..8], &target, 1, mask).unwrap_err(),
        MetricError::BufferLength {
            what: "first image",
            expected: 9,
            got: 8
        }
    );
    let nothing = [false; 9];
    let empty = GridMask::new(3, 3, &nothing).unwrap();
    assert_eq!(
        psnr(&source, &target, 1, empty).unwrap_err(),
        MetricError::EmptyMask
    );
    assert_eq!(
        seam_step(&source, &target, 1, empty).unwrap_err(),
        MetricError::NoSeam
    );
}

/// A small fixed clone: a 12×12 square patch in a 20×20 image, boundary data
/// `(target − source)` smooth but not harmonic. MVC on the pixel-centre grid of the patch
/// (boundary polygon on the ring of outside pixel centres, where the grid reference pins its
/// values) is compared with the pixel-grid membrane. Both discretise the same Laplace problem,
/// so they agree to well over 30 dB, and a deliberately wrong membrane does not.
#[test]
fn mvc_membrane_is_close_to_the_grid_reference_on_a_small_square() {
    let (w, h) = (20usize, 20usize);
    let (lo, hi) = (4usize, 15usize); // inside: lo..=hi in x and y
    let inside: Vec<bool> = (0..w * h)
        .map(|p| (lo..=hi).contains(&(p % w)) && (lo..=hi).contains(&(p / w)))
        .collect();
    let mask = GridMask::new(w, h, &inside).unwrap();
    let centre = |p: usize| DVec2::new((p % w) as f64, (p / w) as f64);
    let difference = |x: DVec2| 0.2 + 0.1 * (0.3 * x.x).sin() * (0.2 * x.y).cos();
    let source: Vec<f32> = (0..w * h).map(|p| 0.3 + 0.01 * (p % 7) as f32).collect();
    let target: Vec<f32> = (0..w * h)
        .map(|p| source[p] + difference(centre(p)) as f32)
        .collect();
    let values: Vec<f64> = (0..w * h)
        .map(|p| target[p] as f64 - source[p] as f64)
        .collect();
    let reference = poisson_membrane(mask, &values, 1).unwrap();

    // Vertices: every pixel centre of the ring lo−1..=hi+1; boundary = the ring's outline.
    let ring = |x: usize, y: usize| x == lo - 1 || x == hi + 1 || y == lo - 1 || y == hi + 1;
    let mut boundary = Vec::new();
    let (a, b) = (lo - 1, hi + 1);
    boundary.extend((a..b).map(|x| a * w + x));
    boundary.extend((a..b).map(|y| y * w + b));
    boundary.extend((a + 1..=b).rev().map(|x| b * w + x));
    boundary.extend((a + 1..=b).rev().map(|y| y * w + a));
    let boundary: Vec<u32> = boundary.into_iter().map(|p| p as u32).collect();
    let positions: Vec<DVec2> = (0..w * h).map(centre).collect();
    // Only the patch and its ring are vertices of the MVC "mesh"; others get no weights.
    let relevant: Vec<u32> = (0..(w * h) as u32)
        .filter(|&p| {
            let (x, y) = (p as usize % w, p as usize / w);
            (a..=b).contains(&x) && (a..=b).contains(&y) && !ring(x, y)
        })
        .collect();
    let mut patch_positions: Vec<DVec2> = boundary.iter().map(|&p| positions[p as usize]).collect();
    patch_positions.extend(relevant.iter().map(|&p| positions[p as usize]));
    let local_boundary: Vec<u32> = (0..boundary.len() as u32).collect();
    let weights = MvcWeights::new(&patch_positions, &local_boundary).unwrap();
    let local_values: Vec<f64> = boundary
        .iter()
        .chain(&relevant)
        .map(|&p| values[p as usize])
        .collect();
    let mut local_out = vec![0.0; local_values.len()];
    weights.apply(&local_values, 1, &mut local_out).unwrap();
    let mut membrane = vec![0.0; w * h];
    for (i, &p) in relevant.iter().enumerate() {
        membrane[p as usize] = local_out[boundary.len() + i];
    }

    let comparison = MembraneComparison::new(ComparisonInput {
        mask,
        channels: 1,
        source: &source,
        target: &target,
        membrane: &membrane,
        covered: &inside,
        reference: &reference.values,
    })
    .unwrap();
    assert_eq!(comparison.uncovered, 0);
    assert!(comparison.psnr_db > 40.0, "{comparison:?}");
    // The reference is seamless up to the boundary data's own variation across one pixel.
    assert!(
        comparison.reference_seam_step.mean_abs < 0.05,
        "{comparison:?}"
    );
    assert!(comparison.seam_step.mean_abs < 0.05, "{comparison:?}");

    let wrong = vec![0.0; w * h];
    let bad = MembraneComparison::new(ComparisonInput {
        membrane: &wrong,
        ..ComparisonInput {
            mask,
            channels: 1,
            source: &source,
            target: &target,
            membrane: &membrane,
            covered: &inside,
            reference: &reference.values,
        }
    })
    .unwrap();
    assert!(
        bad.psnr_db < 20.0 && bad.seam_step.mean_abs > 0.1,
        "{bad:?}"
    );
}

#[test]
fn rings_count_four_steps_from_the_outside() {
    // 7×5 image, inside the 5×3 block at (1..6, 1..4): its rim is ring 1, the centre row's
    // middle three pixels ring 2; the image border row/column is outside.
    let inside: Vec<bool> = (0..35)
        .map(|p| (1..6).contains(&(p % 7)) && (1..4).contains(&(p / 7)))
        .collect();
    let mask = GridMask::new(7, 5, &inside).unwrap();
    let ring = ring_of_pixels(mask);
    #[rustfmt::skip]
    let expected = [
        0, 0, 0, 0, 0, 0, 0,
        0, 1, 1, 1, 1, 1, 0,
        0, 1, 2, 2, 2, 1, 0,
        0, 1, 1, 1, 1, 1, 0,
        0, 0, 0, 0, 0, 0, 0,
    ];
    assert_eq!(ring, expected);
    // One channel: error 0.1 on ring 1 pixel (1, 1), 0.2 on ring 2 pixel (3, 2).
    let a = vec![0.0f64; 35];
    let mut b = vec![0.0f64; 35];
    b[8] = 0.1;
    b[17] = 0.2;
    let by_ring = psnr_by_ring(&a, &b, 1, mask, &[(1, 1), (2, u32::MAX), (3, 3)]).unwrap();
    let ring1 = 10.0 * (12.0 / 0.01f64).log10();
    let ring2 = 10.0 * (3.0 / 0.04f64).log10();
    assert!((by_ring[0].unwrap() - ring1).abs() < 1e-9, "{by_ring:?}");
    assert!((by_ring[1].unwrap() - ring2).abs() < 1e-9, "{by_ring:?}");
    assert_eq!(by_ring[2], None);
}
