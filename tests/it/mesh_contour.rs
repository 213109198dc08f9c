//! Crack loops and pieces of masks: orientation, holes, pieces, and the edge pixels.

use glam::DVec2;
use lapclone::mesh::*;

fn mask_from(rows: &[&str]) -> BitMask {
    BitMask::from_fn(rows[0].len(), rows.len(), |x, y| {
        rows[y].as_bytes()[x] == b'#'
    })
}

#[test]
fn single_pixel_is_a_unit_square() {
    let loops = trace_crack_loops(&mask_from(&["#"]));
    assert_eq!(loops.len(), 1);
    let pts: Vec<_> = loops[0].points.iter().map(|p| (p.x, p.y)).collect();
    assert_eq!(pts, vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
    assert_eq!(loops[0].doubled_area, 2);
}

#[test]
fn ring_has_outer_and_hole() {
    let loops = trace_crack_loops(&mask_from(&["###", "#.#", "###"]));
    assert_eq!(loops.len(), 2);
    assert_eq!(loops[0].doubled_area, 18);
    assert_eq!(loops[1].doubled_area, -2);
}

#[test]
fn diagonal_pixels_join_into_one_loop_through_the_saddle() {
    let loops = trace_crack_loops(&mask_from(&["#.", ".#"]));
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].doubled_area, 4);
    let saddle = DVec2::new(1.0, 1.0);
    let hits: Vec<bool> = loops[0]
        .points
        .iter()
        .zip(&loops[0].anchor)
        .filter(|(p, _)| **p == saddle)
        .map(|(_, &a)| a)
        .collect();
    assert_eq!(hits, vec![true, true]);
}

#[test]
fn diamond_of_diagonal_pixels_encloses_a_hole() {
    let loops = trace_crack_loops(&mask_from(&[".#.", "#.#", ".#."]));
    let holes = loops.iter().filter(|l| l.is_hole()).count();
    assert_eq!((loops.len(), holes), (2, 1));
    let (_, sizes) = label_pieces(&mask_from(&[".#.", "#.#", ".#."]));
    assert_eq!(sizes, vec![4]);
}

/// The straightforward flood fill the run-based labelling must agree with.
fn flood_fill_labels(mask: &BitMask) -> (Vec<u32>, Vec<usize>) {
    let (w, h) = (mask.width as i64, mask.height as i64);
    let mut labels = vec![u32::MAX; mask.width * mask.height];
    let mut sizes = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if !mask.get(x, y) || labels[(y * w + x) as usize] != u32::MAX {
                continue;
            }
            let label = sizes.len() as u32;
            let mut stack = vec![(x, y)];
            labels[(y * w + x) as usize] = label;
            let mut size = 0;
            while let Some((px, py)) = stack.pop() {
                size += 1;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (qx, qy) = (px + dx, py + dy);
                        if mask.get(qx, qy) && labels[(qy * w + qx) as usize] == u32::MAX {
                            labels[(qy * w + qx) as usize] = label;
                            stack.push((qx, qy));
                        }
                    }
                }
            }
            sizes.push(size);
        }
    }
    (labels, sizes)
}

use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x1abe_1500),
        ..ProptestConfig::default()
    })]
    #[test]
    fn run_labels_match_flood_fill(
        (width, height, bits) in (1usize..24, 1usize..24).prop_flat_map(|(w, h)| {
            (Just(w), Just(h), proptest::collection::vec(any::<u8>(), w * h))
        }),
        density in 1u8..255,
    ) {
        let mask = BitMask::from_fn(width, height, |x, y| bits[y * width + x] < density);
        prop_assert_eq!(label_pieces(&mask), flood_fill_labels(&mask));
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0xed9e),
        ..ProptestConfig::default()
    })]
    /// The word-at-a-time scan visits exactly the inside pixels with an outside
    /// 4-neighbour, in raster order (widths past 9 take the word path).
    #[test]
    fn edge_pixel_scan_matches_the_pixel_test(
        (width, height, bits) in (1usize..40, 1usize..12).prop_flat_map(|(w, h)| {
            (Just(w), Just(h), proptest::collection::vec(any::<u8>(), w * h))
        }),
        density in 1u8..255,
    ) {
        let mask = BitMask::from_fn(width, height, |x, y| bits[y * width + x] < density);
        let mut visited = Vec::new();
        for_each_edge_pixel(&mask, |x, y| visited.push((x, y)));
        let mut expected = Vec::new();
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let outside_neighbour = [(-1, 0), (1, 0), (0, -1), (0, 1)]
                    .iter()
                    .any(|(dx, dy)| !mask.get(x + dx, y + dy));
                if mask.get(x, y) && outside_neighbour {
                    expected.push((x as usize, y as usize));
                }
            }
        }
        prop_assert_eq!(visited, expected);
    }
}

#[test]
fn labels_count_separate_pieces() {
    let (labels, sizes) = label_pieces(&mask_from(&["#..#", "....", "##.."]));
    assert_eq!(sizes, vec![1, 1, 2]);
    assert_eq!(labels[0], 0);
    assert_eq!(labels[3], 1);
    assert_eq!(labels[8], 2);
}
