//! The layer queries: boundary vertices under the patch's own front layer and the lower
//! layer beneath the others, compared with a brute-force check over all triangles on random
//! folded meshes (fixed seed).

use crate::raster_meshes;

use glam::DVec2;
use lapclone::raster::{boundary_layers, covered_boundary_vertices, Beneath, CoverageGrid};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// The interpolated depth at `v`'s placed point in `tri` when it lies strictly inside it and
/// is not one of its corners, with the weights there.
fn depth_inside(placed: &[DVec2], depth: &[f32], tri: [u32; 3], v: u32) -> Option<(f64, [f64; 3])> {
    if tri.contains(&v) {
        return None;
    }
    let p = placed[v as usize];
    let [a, b, c] = tri.map(|i| placed[i as usize]);
    // Strictly inside the triangle implies strictly inside its bounding box; the query
    // rejects by the box first, which also overrules edge functions that rounding pushed
    // inside near a degenerate triangle's corner.
    let (min, max) = (a.min(b).min(c), a.max(b).max(c));
    if !(p.x > min.x && p.y > min.y && p.x < max.x && p.y < max.y) {
        return None;
    }
    let area = (b - a).perp_dot(c - a);
    if area == 0.0 {
        return None;
    }
    let w = [
        (c - b).perp_dot(p - b) / area,
        (a - c).perp_dot(p - c) / area,
        (b - a).perp_dot(p - a) / area,
    ];
    let d: f64 = (0..3)
        .map(|k| w[k] * f64::from(depth[tri[k] as usize]))
        .sum();
    w.iter().all(|&x| x > 0.0).then_some((d, w))
}

fn brute_force(
    placed: &[DVec2],
    triangles: &[[u32; 3]],
    depth: &[f32],
    candidates: &[u32],
) -> Vec<u32> {
    candidates
        .iter()
        .copied()
        .filter(|&v| {
            let own = f64::from(depth[v as usize]);
            triangles
                .iter()
                .any(|&tri| depth_inside(placed, depth, tri, v).is_some_and(|(d, _)| d > own))
        })
        .collect()
}

/// The topmost lower triangle under each candidate not covered (the later one on equal
/// depth), in the candidates' order.
fn brute_force_beneath(
    placed: &[DVec2],
    triangles: &[[u32; 3]],
    depth: &[f32],
    candidates: &[u32],
) -> Vec<Beneath> {
    let covered = brute_force(placed, triangles, depth, candidates);
    let mut found = Vec::new();
    for (slot, &v) in candidates.iter().enumerate() {
        if covered.contains(&v) {
            continue;
        }
        let own = f64::from(depth[v as usize]);
        let mut best: Option<(f64, Beneath)> = None;
        for &tri in triangles {
            let Some((d, weights)) = depth_inside(placed, depth, tri, v) else {
                continue;
            };
            if d < own && best.is_none_or(|(top, _)| d >= top) {
                let slot = slot as u32;
                best = Some((
                    d,
                    Beneath {
                        vertex: v,
                        slot,
                        triangle: tri,
                        weights,
                    },
                ));
            }
        }
        found.extend(best.map(|(_, b)| b));
    }
    found
}

#[test]
fn arm_swung_over_the_body_covers_exactly_the_vertices_beneath() {
    // A 10×2 strip; the right half is turned by 180° (and shifted ½ px off the grid lines) onto
    // the left half and lifted in depth: the boundary vertices strictly beneath are covered.
    let mesh = raster_meshes::grid(DVec2::ZERO, 2.0, 10, 2);
    let mut placed = mesh.positions.clone();
    let mut depth = vec![0.0f32; placed.len()];
    for (v, p) in placed.iter_mut().enumerate() {
        if p.x > 10.0 {
            *p = DVec2::new(20.5 - p.x, 4.5 - p.y);
            depth[v] = 1.0;
        }
    }
    let boundary: Vec<u32> = mesh.loops[0].vertices.clone();
    let mut out = Vec::new();
    covered_boundary_vertices(
        &placed,
        &mesh.triangles,
        &depth,
        &boundary,
        &mut CoverageGrid::new(),
        &mut out,
    )
    .unwrap();
    assert_eq!(
        out,
        brute_force(&placed, &mesh.triangles, &depth, &boundary)
    );
    // Bottom-row vertices x = 2..8 (y = 4) lie under the lifted flap (which spans y ∈ [.5, 4.5]).
    for x in [2.0, 4.0, 6.0, 8.0] {
        let v = mesh
            .positions
            .iter()
            .position(|p| *p == DVec2::new(x, 4.0))
            .unwrap() as u32;
        assert!(
            out.contains(&v),
            "vertex at ({x}, 4) should be covered: {out:?}"
        );
    }
    // Lifted vertices are never covered by the lower layer.
    assert!(out.iter().all(|&v| depth[v as usize] == 0.0));
    // Without a depth difference nothing is covered.
    covered_boundary_vertices(
        &placed,
        &mesh.triangles,
        &vec![0.0; placed.len()],
        &boundary,
        &mut CoverageGrid::new(),
        &mut out,
    )
    .unwrap();
    assert!(out.is_empty());
}

proptest! {
    #![proptest_config(Config { rng_seed: RngSeed::Fixed(5), cases: 32, ..Config::default() })]

    #[test]
    fn grid_query_matches_brute_force(
        moves in proptest::collection::vec((-6.0f64..6.0, -6.0f64..6.0, 0.0f32..3.0), 49)
    ) {
        let mesh = raster_meshes::grid(DVec2::ZERO, 2.0, 6, 6);
        let placed: Vec<DVec2> = mesh.positions.iter().zip(&moves).map(|(&p, &(dx, dy, _))| p + DVec2::new(dx, dy)).collect();
        let depth: Vec<f32> = moves.iter().map(|m| m.2).collect();
        let boundary = mesh.loops[0].vertices.clone();
        let mut grid = CoverageGrid::new();
        let mut out = Vec::new();
        covered_boundary_vertices(&placed, &mesh.triangles, &depth, &boundary, &mut grid, &mut out).unwrap();
        prop_assert_eq!(&out, &brute_force(&placed, &mesh.triangles, &depth, &boundary));
        // Deterministic and reusable: a second call with the warmed grid agrees.
        let mut again = Vec::new();
        covered_boundary_vertices(&placed, &mesh.triangles, &depth, &boundary, &mut grid, &mut again).unwrap();
        prop_assert_eq!(out, again);
        // Every vertex a candidate (interior ones too), in a scrambled order.
        let everyone: Vec<u32> = (0..placed.len() as u32).map(|k| (k * 17) % placed.len() as u32).collect();
        let mut all = Vec::new();
        covered_boundary_vertices(&placed, &mesh.triangles, &depth, &everyone, &mut grid, &mut all).unwrap();
        prop_assert_eq!(all, brute_force(&placed, &mesh.triangles, &depth, &everyone));
    }

    #[test]
    fn one_sweep_gives_the_covered_and_the_layer_beneath_the_others(
        moves in proptest::collection::vec((-6.0f64..6.0, -6.0f64..6.0, 0.0f32..3.0), 49)
    ) {
        let mesh = raster_meshes::grid(DVec2::ZERO, 2.0, 6, 6);
        let placed: Vec<DVec2> = mesh.positions.iter().zip(&moves).map(|(&p, &(dx, dy, _))| p + DVec2::new(dx, dy)).collect();
        let depth: Vec<f32> = moves.iter().map(|m| m.2).collect();
        let everyone: Vec<u32> = (0..placed.len() as u32).map(|k| (k * 17) % placed.len() as u32).collect();
        for candidates in [&mesh.loops[0].vertices, &everyone] {
            let (mut covered, mut beneath) = (Vec::new(), Vec::new());
            let geometry = (&placed[..], &mesh.triangles[..], &depth[..]);
            boundary_layers(geometry, candidates, &mut CoverageGrid::new(), &mut covered, &mut beneath).unwrap();
            prop_assert_eq!(covered, brute_force(&placed, &mesh.triangles, &depth, candidates));
            prop_assert_eq!(beneath, brute_force_beneath(&placed, &mesh.triangles, &depth, candidates));
        }
    }
}
