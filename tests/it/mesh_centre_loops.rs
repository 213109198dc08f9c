//! `outside_centre_loops`: the loops through the outside pixel centres enclose the inside
//! pixels.

use glam::DVec2;
use lapclone::mesh::{outside_centre_loops, trace_crack_loops, BitMask};
use proptest::prelude::*;

/// Even-odd test against all loops.
fn inside_loops(loops: &[Vec<DVec2>], p: DVec2) -> bool {
    let mut inside = false;
    for lp in loops {
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
                inside = !inside;
            }
        }
    }
    inside
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x7417_c0de),
        ..ProptestConfig::default()
    })]
    /// Thinned at 3 px, the loops leave every mask pixel at least half its square inside
    /// (8 × 8 samples per pixel), and every pixel centre: unions of discs, and pixel noise.
    #[test]
    fn thinned_loops_keep_at_least_half_of_every_mask_pixel(
        discs in proptest::collection::vec((4.0f64..36.0, 4.0f64..28.0, 2.0f64..12.0), 1..5),
        noise in proptest::collection::vec(any::<u8>(), 40 * 32),
        density in 0u8..120,
    ) {
        let blobs = BitMask::from_fn(40, 32, |x, y| {
            discs.iter().any(|&(cx, cy, r)| (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy) < r)
        });
        let speckle = BitMask::from_fn(40, 32, |x, y| noise[y * 40 + x] < density);
        for mask in [blobs, speckle] {
            check_half_coverage(&mask)?;
        }
    }
}

fn check_half_coverage(mask: &BitMask) -> Result<(), TestCaseError> {
    let (loops, _) = outside_centre_loops(&trace_crack_loops(mask), 3.0);
    for (x, y) in (0..mask.height).flat_map(|y| (0..mask.width).map(move |x| (x, y))) {
        if !mask.get(x as i64, y as i64) {
            continue;
        }
        let at = |u: f64, v: f64| DVec2::new(x as f64 + u, y as f64 + v);
        prop_assert!(inside_loops(&loops, at(0.5, 0.5)), "centre of ({x}, {y})");
        let covered = (0..64)
            .filter(|k| {
                let (u, v) = ((k % 8) as f64 + 0.5, (k / 8) as f64 + 0.5);
                inside_loops(&loops, at(u / 8.0, v / 8.0))
            })
            .count();
        prop_assert!(
            covered >= 32,
            "pixel ({x}, {y}): {covered} of 64 samples inside"
        );
    }
    Ok(())
}

fn centres(mask: &BitMask) -> (Vec<Vec<DVec2>>, usize) {
    outside_centre_loops(&trace_crack_loops(mask), 1.0)
}

#[test]
fn a_rectangle_gives_its_outside_ring_without_corners() {
    let mask = BitMask::from_fn(8, 7, |x, y| (2..5).contains(&x) && (2..4).contains(&y));
    let (loops, fallbacks) = centres(&mask);
    assert_eq!((loops.len(), fallbacks), (1, 0));
    // 3 above, 3 below, 2 left, 2 right: the 4-neighbours, not the diagonal corners.
    assert_eq!(loops[0].len(), 10);
    for p in &loops[0] {
        let pixel = (p.x.floor() as i64, p.y.floor() as i64);
        assert_eq!(p.fract(), DVec2::splat(0.5));
        assert!(!mask.get(pixel.0, pixel.1));
        let touches = [(-1, 0), (1, 0), (0, -1), (0, 1)]
            .iter()
            .any(|(dx, dy)| mask.get(pixel.0 + dx, pixel.1 + dy));
        assert!(touches, "{p} is not a 4-neighbour of the mask");
    }
    assert!(lapclone::mesh::doubled_signed_area(&loops[0]) > 0.0);
}

#[test]
fn a_one_pixel_notch_and_hole_fall_back_to_quarter_pixel_points() {
    let notch = BitMask::from_fn(9, 9, |x, y| {
        (1..8).contains(&x) && (1..8).contains(&y) && !(x == 4 && y < 5)
    });
    let (loops, fallbacks) = centres(&notch);
    assert!(fallbacks > 0);
    let mut all: Vec<(i64, i64)> = loops[0]
        .iter()
        .map(|p| ((p.x * 4.0) as i64, (p.y * 4.0) as i64))
        .collect();
    let n = all.len();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), n, "a vertex repeats");
    let hole = BitMask::from_fn(5, 5, |x, y| {
        (1..4).contains(&x) && (1..4).contains(&y) && (x, y) != (2, 2)
    });
    let (loops, fallbacks) = centres(&hole);
    assert_eq!((loops.len(), fallbacks), (2, 4));
    assert!(loops.iter().all(|l| l.len() >= 3));
}
