//! The meshing pipeline: [`mesh_mask`] takes a [`BitMask`], [`mesh_polygons`] takes
//! [`Polygon`]s; both give a [`MeshResult`]. Mask path: drop small pieces → crack loops →
//! loops through the outside pixel centres, thinned to `density` (the default,
//! [`BoundaryPlacement::OutsideCentres`]; boundary edges never split) → CDT + refinement; if
//! those loops cannot be meshed, the crack path is taken: Douglas–Peucker (anchored at saddle
//! corners) → subdivide to `density` → CDT + refinement, and if simplification makes two loops
//! touch or cross (a thin gap closed by the tolerance), the raw crack loops, which never
//! cross. Every mask is meshed whole, so the refinement's angle bound holds everywhere.

use glam::DVec2;

use super::bitmask::crack_edge_count;
use super::centre_loops::outside_centre_loops;
use super::contour::{label_pieces, piece_sizes, trace_crack_loops, CrackLoop};
use super::options::{min_angle_deg, BoundaryPlacement};
use super::simplify::{doubled_signed_area, simplify_loop, subdivide_loop, subdivided_len};
use super::triangulate::{triangulate_loops, Refinement};
use super::{BitMask, Mesh, MeshError, MeshOptions, MeshResult, MeshStats};

/// A polygon with holes in pixel coordinates; orientation does not matter (it is fixed up).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Polygon {
    /// The outer boundary, any orientation, source-pixel coordinates.
    pub outer: Vec<DVec2>,
    /// Holes inside `outer`, each a closed ring.
    pub holes: Vec<Vec<DVec2>>,
}

impl Polygon {
    /// The enclosed area in px²: the outer ring's less its holes', never below zero.
    pub fn area(&self) -> f64 {
        let ring = |r: &[DVec2]| doubled_signed_area(r).abs() / 2.0;
        let holes: f64 = self.holes.iter().map(|h| ring(h)).sum();
        (ring(&self.outer) - holes).max(0.0)
    }
}

/// Meshes the inside of a mask.
pub fn mesh_mask(mask: &BitMask, options: &MeshOptions) -> Result<MeshResult, MeshError> {
    options.validate()?;
    if mask.count_inside() == 0 {
        return Err(MeshError::EmptyMask);
    }
    let mut warnings = Vec::new();
    let (kept, dropped_pieces, dropped_pixels, pieces) =
        drop_small_pieces(mask, options.min_piece_area, &mut warnings);
    if pieces == 0 {
        return Err(MeshError::AllPiecesTooSmall {
            min_piece_area: options.min_piece_area,
        });
    }
    let kept_mask = kept.as_ref().unwrap_or(mask);
    let edges = crack_edge_count(kept_mask);
    let max_edges = MAX_CRACK_EDGES_PER_VERTEX
        .saturating_mul(options.max_vertices)
        .max(MIN_CRACK_EDGE_LIMIT);
    if edges > max_edges {
        return Err(MeshError::BoundaryTooLong { edges, max_edges });
    }
    let meshed = mesh_whole(kept_mask, pieces, options, &mut warnings)?;
    if meshed.fell_back {
        warnings.push(
            "simplification made boundary loops touch; meshed the unsimplified crack boundary"
                .into(),
        );
    }
    if !meshed.complete {
        warnings.push(budget_warning(options));
    }
    let mut stats = stats_of(
        &meshed.mesh,
        meshed.deviation,
        meshed.simplified,
        meshed.complete,
        dropped_pieces,
        dropped_pixels,
    );
    stats.boundary = meshed.placement;
    stats.off_centre_boundary_vertices = meshed.off_centre;
    Ok(MeshResult {
        mesh: meshed.mesh,
        warnings,
        stats,
    })
}

/// A mask's mesh and how it was made.
struct Meshed {
    mesh: Mesh,
    /// spade's `refinement_complete` (false: the vertex budget ran out).
    complete: bool,
    /// Largest distance of a dropped crack corner from the simplified boundary, px.
    deviation: f64,
    simplified: bool,
    /// Simplification made loops touch, so the raw crack loops were meshed.
    fell_back: bool,
    placement: BoundaryPlacement,
    off_centre: usize,
}

/// The inside-pixel topology a mesh of some crack loops must have.
#[derive(Clone, Copy)]
struct Topology {
    holes: usize,
    pieces: usize,
}

/// Meshes `mask` in one piece, through the outside pixel centres if asked and possible,
/// else on the (simplified) crack loops.
fn mesh_whole(
    mask: &BitMask,
    pieces: usize,
    options: &MeshOptions,
    warnings: &mut Vec<String>,
) -> Result<Meshed, MeshError> {
    let crack = trace_crack_loops(mask);
    let expected = Topology {
        holes: crack.iter().filter(|l| l.is_hole()).count(),
        pieces,
    };
    if options.boundary == BoundaryPlacement::OutsideCentres {
        let (loops, fallbacks) = outside_centre_loops(&crack, options.density);
        check_budget(loops.iter().map(Vec::len).sum::<usize>() as f64, options)?;
        // Splitting a boundary edge would put a vertex between two centres, sampling mixed
        // pixels: keep the edges as given.
        match triangulate_checked(&loops, true, expected, options) {
            Ok((mesh, complete)) => {
                return Ok(Meshed {
                    mesh,
                    complete,
                    deviation: 0.0,
                    simplified: false,
                    fell_back: false,
                    placement: BoundaryPlacement::OutsideCentres,
                    off_centre: fallbacks,
                })
            }
            Err(MeshError::IntersectingBoundary { .. } | MeshError::Sanity(_)) => {
                warnings.push(
                    "the loops through the outside pixel centres touch or cross; meshed the \
                     crack boundary instead"
                        .into(),
                );
            }
            Err(e) => return Err(e),
        }
    }
    mesh_crack_loops(&crack, expected, options)
}

/// Meshes crack loops simplified with the options' tolerance or, if simplification makes two
/// loops touch or cross (a thin gap closed by the tolerance), unsimplified.
fn mesh_crack_loops(
    crack: &[CrackLoop],
    expected: Topology,
    options: &MeshOptions,
) -> Result<Meshed, MeshError> {
    let attempt = |tolerance: f64| -> Result<(Mesh, bool, f64), MeshError> {
        let (loops, deviation) = sample_crack_loops(crack, tolerance, options)?;
        let (mesh, complete) = triangulate_checked(&loops, false, expected, options)?;
        Ok((mesh, complete, deviation))
    };
    let simplify = options.simplify_tolerance > 0.0;
    let (result, fell_back) = match attempt(options.simplify_tolerance) {
        Err(MeshError::IntersectingBoundary { .. } | MeshError::Sanity(_)) if simplify => {
            (attempt(0.0)?, true)
        }
        result => (result?, false),
    };
    let (mesh, complete, deviation) = result;
    Ok(Meshed {
        mesh,
        complete,
        deviation,
        simplified: simplify && !fell_back,
        fell_back,
        placement: BoundaryPlacement::Cracks,
        off_centre: 0,
    })
}

/// Triangulates and refines `loops`, and checks the result's holes and pieces.
fn triangulate_checked(
    loops: &[Vec<DVec2>],
    keep_boundary: bool,
    expected: Topology,
    options: &MeshOptions,
) -> Result<(Mesh, bool), MeshError> {
    let refinement = Refinement {
        max_area: options.max_area,
        keep_boundary,
        ..Refinement::new(options.min_angle_deg, options.max_vertices)
    };
    let t = triangulate_loops(loops, &refinement)?;
    // The full check costs about as much as the refinement; the tests run it on every
    // shape family, so release builds rely on the topology counts below.
    if cfg!(debug_assertions) {
        t.mesh.sanity_check()?;
    }
    if t.mesh.hole_count() != expected.holes || t.mesh.piece_count as usize != expected.pieces {
        return Err(MeshError::IntersectingBoundary { conflicts: 0 });
    }
    Ok((t.mesh, t.refinement_complete))
}

/// Polygon coordinates are bounded so that spade's predicates and the raster's fixed point
/// stay exact (2^24 px, far beyond any image: see `crate::limits`).
pub const MAX_POLYGON_COORDINATE: f64 = 16_777_216.0;

/// Meshes polygons with holes (not simplified; edges subdivided to `density`).
pub fn mesh_polygons(polygons: &[Polygon], options: &MeshOptions) -> Result<MeshResult, MeshError> {
    options.validate()?;
    if polygons.is_empty() {
        return Err(MeshError::NoPolygons);
    }
    let mut loops = Vec::new();
    let mut scratch = Vec::new();
    let mut boundary_len = 0.0;
    for (index, polygon) in polygons.iter().enumerate() {
        let rings =
            std::iter::once((&polygon.outer, true)).chain(polygon.holes.iter().map(|h| (h, false)));
        for (ring, outer) in rings {
            let mut ring = clean_ring(ring).map_err(|reason| MeshError::InvalidPolygon {
                polygon: index,
                reason,
            })?;
            if (doubled_signed_area(&ring) > 0.0) != outer {
                ring.reverse();
            }
            // Refuse before allocating: a vertex at 1e9 px would need 3e8 boundary points.
            boundary_len += subdivided_len(&ring, options.density);
            check_budget(boundary_len, options)?;
            subdivide_loop(&ring, options.density, &mut scratch);
            loops.push(scratch.clone());
        }
    }
    let refinement = Refinement {
        max_area: options.max_area,
        ..Refinement::new(options.min_angle_deg, options.max_vertices)
    };
    let t = triangulate_loops(&loops, &refinement)?;
    t.mesh.sanity_check()?;
    let mut warnings = Vec::new();
    if !t.refinement_complete {
        warnings.push(budget_warning(options));
    }
    let stats = stats_of(&t.mesh, 0.0, false, t.refinement_complete, 0, 0);
    Ok(MeshResult {
        mesh: t.mesh,
        warnings,
        stats,
    })
}

/// Removes repeated points; rejects non-finite, short or zero-area rings.
fn clean_ring(ring: &[DVec2]) -> Result<Vec<DVec2>, String> {
    if ring.iter().any(|p| !p.is_finite()) {
        return Err("has a non-finite point".into());
    }
    if let Some(p) = ring
        .iter()
        .find(|p| p.abs().max_element() > MAX_POLYGON_COORDINATE)
    {
        return Err(format!(
            "point ({}, {}) lies beyond ±{MAX_POLYGON_COORDINATE} px",
            p.x, p.y
        ));
    }
    let mut out = ring.to_vec();
    out.dedup();
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    if out.len() < 3 {
        return Err(format!(
            "a ring has {} distinct points (needs 3)",
            out.len()
        ));
    }
    if doubled_signed_area(&out).abs() < 1e-12 {
        return Err("a ring has zero area".into());
    }
    Ok(out)
}

/// Returns the mask without pieces below `min_area` (None if nothing was dropped), the number
/// of dropped pieces and pixels, and the number of kept pieces.
fn drop_small_pieces(
    mask: &BitMask,
    min_area: f64,
    warnings: &mut Vec<String>,
) -> (Option<BitMask>, usize, usize, usize) {
    let sizes = piece_sizes(mask);
    let small: Vec<bool> = sizes.iter().map(|&s| (s as f64) < min_area).collect();
    let dropped_pieces = small.iter().filter(|&&s| s).count();
    let kept_pieces = sizes.len() - dropped_pieces;
    if dropped_pieces == 0 {
        return (None, 0, 0, kept_pieces);
    }
    let dropped_pixels: usize = sizes
        .iter()
        .zip(&small)
        .filter(|(_, &s)| s)
        .map(|(&n, _)| n)
        .sum();
    warnings.push(format!(
        "dropped {dropped_pieces} piece(s) smaller than {min_area} px² ({dropped_pixels} pixels)"
    ));
    let (labels, _) = label_pieces(mask);
    let kept = BitMask::from_fn(mask.width, mask.height, |x, y| {
        let label = labels[y * mask.width + x];
        label != u32::MAX && !small[label as usize]
    });
    (Some(kept), dropped_pieces, dropped_pixels, kept_pieces)
}

/// Simplified and subdivided loops with the largest simplification deviation; refuses
/// (before subdividing) boundaries that would exceed the vertex budget.
fn sample_crack_loops(
    crack: &[CrackLoop],
    tolerance: f64,
    options: &MeshOptions,
) -> Result<(Vec<Vec<DVec2>>, f64), MeshError> {
    let mut deviation = 0.0f64;
    let mut points = 0.0;
    let mut loops = Vec::with_capacity(crack.len());
    for c in crack {
        let s = simplify_loop(&c.points, &c.anchor, tolerance);
        deviation = deviation.max(s.max_deviation);
        points += subdivided_len(&s.points, options.density);
        check_budget(points, options)?;
        let mut out = Vec::new();
        subdivide_loop(&s.points, options.density, &mut out);
        loops.push(out);
    }
    Ok((loops, deviation))
}

/// The warning of a refinement that ran out of vertices.
fn budget_warning(options: &MeshOptions) -> String {
    format!(
        "refinement stopped at its vertex budget (max_vertices {}, or the size-based bound) \
         before every angle reached {}°",
        options.max_vertices, options.min_angle_deg
    )
}

/// Refuses boundaries of more than `max_vertices` points (`as` saturates a huge count).
fn check_budget(points: f64, options: &MeshOptions) -> Result<(), MeshError> {
    if points > options.max_vertices as f64 {
        return Err(MeshError::VertexBudget {
            max_vertices: options.max_vertices,
            needed: points as usize,
        });
    }
    Ok(())
}

/// Crack tracing keeps every pixel edge of the boundary; this many per budgeted vertex is
/// the most a mask may have (a 64 Mi px checkerboard has 268 M).
const MAX_CRACK_EDGES_PER_VERTEX: usize = 16;
/// Below this many edges tracing is cheap (16 MiB of points): small budgets then fail with
/// the more useful `VertexBudget` error instead.
const MIN_CRACK_EDGE_LIMIT: usize = 1 << 20;

fn stats_of(
    mesh: &Mesh,
    deviation: f64,
    simplified: bool,
    complete: bool,
    dropped_pieces: usize,
    dropped_pixels: usize,
) -> MeshStats {
    MeshStats {
        vertices: mesh.vertex_count(),
        triangles: mesh.triangles.len(),
        boundary_vertices: mesh.is_boundary.iter().filter(|&&b| b).count(),
        pieces: mesh.piece_count as usize,
        holes: mesh.hole_count(),
        min_angle_deg: min_angle_deg(mesh),
        max_boundary_deviation_px: deviation,
        simplified,
        refinement_complete: complete,
        dropped_pieces,
        dropped_pixels,
        boundary: BoundaryPlacement::Cracks,
        off_centre_boundary_vertices: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The word-wise crack count against its definition: outside 4-neighbours of inside
    /// pixels, beyond the image counting as outside.
    #[test]
    fn crack_edges_are_counted_like_outside_neighbours() {
        type Shape = (usize, usize, fn(usize, usize) -> bool);
        let shapes: [Shape; 5] = [
            (1, 1, |_, _| true),
            (9, 1, |x, _| x % 3 != 1),
            (17, 11, |x, y| (x * 7 + y * 3) % 5 < 2),
            (33, 20, |x, y| (x / 4 + y / 3) % 2 == 0 || x == 32),
            (24, 16, |x, y| {
                x > 2 && y > 1 && x < 21 && y < 14 && (x, y) != (9, 7)
            }),
        ];
        for (width, height, inside) in shapes {
            let mask = BitMask::from_fn(width, height, inside);
            let mut expected = 0;
            for y in 0..height as i64 {
                for x in 0..width as i64 {
                    if mask.get(x, y) {
                        let around = [(-1, 0), (1, 0), (0, -1), (0, 1)];
                        expected += around
                            .iter()
                            .filter(|(dx, dy)| !mask.get(x + dx, y + dy))
                            .count();
                    }
                }
            }
            assert_eq!(crack_edge_count(&mask), expected, "{width}×{height}");
        }
        assert_eq!(crack_edge_count(&BitMask::new(0, 0)), 0);
        assert_eq!(crack_edge_count(&BitMask::new(5, 0)), 0);
    }

    /// Spiral masks of the sizes the two-half mesher once failed on are meshed whole, with
    /// every angle at the refinement's bound (a 1e-9° tolerance for rounding in the angle
    /// computation), for either boundary placement.
    #[test]
    fn large_spirals_keep_the_angle_bound_everywhere() {
        for (width, height) in [(770, 743), (800, 800)] {
            let mask = crate::mesh::synth::spiral(width, height);
            for boundary in [BoundaryPlacement::OutsideCentres, BoundaryPlacement::Cracks] {
                let options = MeshOptions {
                    boundary,
                    ..MeshOptions::default()
                };
                let meshed = mesh_mask(&mask, &options).unwrap();
                assert!(meshed.stats.refinement_complete, "{width}×{height}");
                let angle = min_angle_deg(&meshed.mesh);
                assert!(
                    angle >= options.min_angle_deg - 1e-9,
                    "{width}×{height} {boundary:?}: {angle}°"
                );
            }
        }
    }

    fn triangle(far: f64) -> Vec<Polygon> {
        vec![Polygon {
            outer: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(far, 0.0),
                DVec2::new(0.0, 5.0),
            ],
            holes: Vec::new(),
        }]
    }

    /// Found by tests/fuzz_scene.rs: a polygon vertex at 1e308 px made the boundary
    /// subdivision allocate without bound (the process was killed for lack of memory).
    #[test]
    fn far_polygon_vertices_are_refused_before_allocating() {
        let options = MeshOptions::default();
        for far in [1e308, 1e9] {
            let error = mesh_polygons(&triangle(far), &options).unwrap_err();
            assert!(error.to_string().contains("beyond"), "{error}");
        }
        let fine = MeshOptions {
            density: 0.05,
            ..MeshOptions::default()
        };
        // 1.6e7 px at 0.05 px per edge needs 3.2e8 boundary points: over the budget.
        let error = mesh_polygons(&triangle(1.6e7), &fine).unwrap_err();
        assert!(
            matches!(error, MeshError::VertexBudget { needed, .. } if needed > 300_000_000),
            "{error}"
        );
    }

    #[test]
    fn masks_with_too_long_a_boundary_are_refused_before_tracing() {
        let checker = BitMask::from_fn(1024, 1024, |x, y| (x + y) % 2 == 0);
        let options = MeshOptions {
            max_vertices: 3,
            ..MeshOptions::default()
        };
        let error = mesh_mask(&checker, &options).unwrap_err();
        assert!(
            matches!(
                error,
                MeshError::BoundaryTooLong {
                    edges: 2_097_152,
                    max_edges: 1_048_576
                }
            ),
            "{error}"
        );
        // Within the edge bound but over the vertex budget once subdivided.
        let disc = BitMask::from_fn(64, 64, |x, y| {
            (x as i64 - 32).pow(2) + (y as i64 - 32).pow(2) < 600
        });
        // The crack boundary is subdivided to `density` (centre loops stop at every centre).
        let options = MeshOptions {
            max_vertices: 200,
            density: 0.05,
            boundary: BoundaryPlacement::Cracks,
            ..MeshOptions::default()
        };
        let error = mesh_mask(&disc, &options).unwrap_err();
        assert!(matches!(error, MeshError::VertexBudget { .. }), "{error}");
    }
}
