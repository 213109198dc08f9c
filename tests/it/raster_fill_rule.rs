//! The top-left fill rule: triangles sharing edges and vertices own every pixel centre of
//! their union exactly once — fans meeting at pixel centres, diagonals through pixel centres,
//! edges along pixel-centre rows, and randomly jittered grids (fixed seed).

use crate::raster_meshes;

use glam::DVec2;
use lapclone::raster::{triangle_pixels, PixelRect};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

const CLIP: PixelRect = PixelRect {
    x0: -4,
    y0: -4,
    x1: 40,
    y1: 40,
};

fn hit_counts(positions: &[DVec2], triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut counts = vec![0u32; CLIP.area()];
    for tri in triangles {
        let corners = tri.map(|v| positions[v as usize]);
        triangle_pixels(corners, CLIP, |x, y| {
            counts[((y - CLIP.y0) * CLIP.width() as i32 + (x - CLIP.x0)) as usize] += 1;
        });
    }
    counts
}

/// Every centre strictly inside the axis-aligned square [lo, hi]² is hit exactly once and
/// no centre outside the closed square is hit.
fn assert_square_partition(counts: &[u32], lo: f64, hi: f64) {
    for y in CLIP.y0..CLIP.y1 {
        for x in CLIP.x0..CLIP.x1 {
            let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let count = counts[((y - CLIP.y0) * CLIP.width() as i32 + (x - CLIP.x0)) as usize];
            let strictly_inside = cx > lo && cx < hi && cy > lo && cy < hi;
            let outside = cx < lo || cx > hi || cy < lo || cy > hi;
            if strictly_inside {
                assert_eq!(count, 1, "centre ({cx}, {cy}) hit {count} times");
            } else if outside {
                assert_eq!(count, 0, "centre ({cx}, {cy}) outside hit {count} times");
            } else {
                assert!(
                    count <= 1,
                    "centre ({cx}, {cy}) on the rim hit {count} times"
                );
            }
        }
    }
}

#[test]
fn fan_meeting_at_a_pixel_centre() {
    // Hub at a pixel centre; rim vertices every pixel along a square through pixel centres.
    let hub = DVec2::new(16.5, 16.5);
    let (lo, hi) = (4.5, 28.5);
    let mut rim = Vec::new();
    let steps = 24;
    for k in 0..steps {
        rim.push(DVec2::new(lo + f64::from(k), lo));
    }
    for k in 0..steps {
        rim.push(DVec2::new(hi, lo + f64::from(k)));
    }
    for k in 0..steps {
        rim.push(DVec2::new(hi - f64::from(k), hi));
    }
    for k in 0..steps {
        rim.push(DVec2::new(lo, hi - f64::from(k)));
    }
    let mut positions = vec![hub];
    positions.extend(&rim);
    let n = rim.len() as u32;
    let triangles: Vec<[u32; 3]> = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    for tri in &triangles {
        assert!(raster_meshes::signed_area2(tri.map(|v| positions[v as usize])) > 0.0);
    }
    let counts = hit_counts(&positions, &triangles);
    assert_square_partition(&counts, lo, hi);
    // The hub's own centre is owned by exactly one triangle.
    assert_eq!(
        counts[((16 - CLIP.y0) * CLIP.width() as i32 + 16 - CLIP.x0) as usize],
        1
    );
}

#[test]
fn diagonals_and_edges_through_pixel_centres() {
    // Unit cells on half-integer coordinates: every vertex is a pixel centre, every edge runs
    // along a row or column of centres, every diagonal passes through centres.
    let mesh = raster_meshes::grid(DVec2::new(2.5, 2.5), 1.0, 20, 20);
    let counts = hit_counts(&mesh.positions, &mesh.triangles);
    assert_square_partition(&counts, 2.5, 22.5);
    // Integer cells: diagonals through centres, edges on pixel borders.
    let mesh = raster_meshes::grid(DVec2::new(3.0, 3.0), 2.0, 10, 10);
    let counts = hit_counts(&mesh.positions, &mesh.triangles);
    assert_square_partition(&counts, 3.0, 23.0);
}

#[test]
fn inverted_triangles_are_drawn() {
    let corners = [
        DVec2::new(1.0, 1.0),
        DVec2::new(1.0, 9.0),
        DVec2::new(9.0, 1.0),
    ];
    assert!(raster_meshes::signed_area2(corners) < 0.0);
    let mut hits = 0;
    triangle_pixels(corners, CLIP, |_, _| hits += 1);
    // The inverted triangle owns the same centres as its positively oriented twin.
    let mut positive = 0;
    triangle_pixels([corners[0], corners[2], corners[1]], CLIP, |_, _| {
        positive += 1
    });
    assert_eq!(hits, positive);
    assert!(hits > 20);
}

proptest! {
    #![proptest_config(Config { rng_seed: RngSeed::Fixed(4), cases: 48, ..Config::default() })]

    /// Interior vertices of a 4-px grid jittered by multiples of ½ px (often landing on pixel
    /// centres and borders) still partition the square's centres.
    #[test]
    fn jittered_grid_partitions_the_square(jitter in proptest::collection::vec((-2i32..=2, -2i32..=2), 81)) {
        let mut mesh = raster_meshes::grid(DVec2::new(2.5, 2.5), 4.0, 8, 8);
        for (v, p) in mesh.positions.iter_mut().enumerate() {
            let (i, j) = (v % 9, v / 9);
            if (1..8).contains(&i) && (1..8).contains(&j) {
                let (dx, dy) = jitter[v];
                *p += DVec2::new(f64::from(dx), f64::from(dy)) * 0.5;
            }
        }
        for tri in &mesh.triangles {
            prop_assert!(raster_meshes::signed_area2(tri.map(|v| mesh.positions[v as usize])) > 0.0);
        }
        let counts = hit_counts(&mesh.positions, &mesh.triangles);
        assert_square_partition(&counts, 2.5, 34.5);
    }
}
