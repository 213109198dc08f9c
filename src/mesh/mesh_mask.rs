//! The meshing pipeline: [`mesh_mask`] takes a [`BitMask`], [`mesh_polygons`] takes
//! [`Polygon`]s; both give a [`MeshResult`]. Mask path: drop small pieces → crack loops →
//! loops through the outside pixel centres, thinned to `density` (the default,
//! [`BoundaryPlacement::OutsideCentres`]; boundary edges never split) → CDT + refinement; if
//! those loops cannot be meshed, the crack path is taken: Douglas–Peucker (anchored at saddle
//! corners) → subdivide to `density` → CDT + refinement, and if simplification makes two loops
//! touch or cross (a thin gap closed by the tolerance), the raw crack loops, which never
//! cross. Masks with a long boundary go through either path as two halves at once, joined
//! afterwards (`split`, `centre_cut`), except centre loops that keep every centre.

use glam::DVec2;

use super::bitmask::crack_edges_by_row;
use super::centre_cut::cut_centre_loops;
use super::centre_loops::{
    keeps_every_centre, outside_centre_loops, outside_centre_points, thin_loop, KeptLoop,
};
use super::contour::{label_pieces, piece_sizes, trace_crack_loops, CrackLoop};
use super::options::{min_angle_deg, BoundaryPlacement};
use super::simplify::{
    doubled_signed_area, simplify_loop, subdivide_loop, subdivide_loop_sharing_row, subdivided_len,
};
use super::split::{merge, Cut, Interface};
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
    let edges_by_row = crack_edges_by_row(kept_mask);
    let edges: usize = edges_by_row.iter().sum();
    let max_edges = MAX_CRACK_EDGES_PER_VERTEX
        .saturating_mul(options.max_vertices)
        .max(MIN_CRACK_EDGE_LIMIT);
    if edges > max_edges {
        return Err(MeshError::BoundaryTooLong { edges, max_edges });
    }
    let split = Cut::choose(kept_mask, &edges_by_row, options.max_vertices)
        .map(|cut| match options.boundary {
            BoundaryPlacement::Cracks => mesh_in_halves(kept_mask, &cut, pieces, options),
            // Every centre kept is the accuracy preset's boundary: the cut's interface, a
            // line of vertices refinement may not split, cost it 1.3 dB (combinatorial, on
            // the spiral model), so such meshes are made whole (docs/quality.md).
            BoundaryPlacement::OutsideCentres if keeps_every_centre(options.density) => Ok(None),
            BoundaryPlacement::OutsideCentres => {
                mesh_centres_in_halves(kept_mask, &cut, pieces, options)
            }
        })
        .transpose()?
        .flatten();
    let meshed = match split {
        Some(meshed) => meshed,
        None => mesh_whole(kept_mask, pieces, options, &mut warnings)?,
    };
    if meshed.fell_back {
        warnings.push(
            "simplification made boundary loops touch; meshed the unsimplified crack boundary"
                .into(),
        );
    }
    if !meshed.complete {
        warnings.push(format!(
            "refinement stopped at its vertex budget (max_vertices {}, or the size-based bound) \
             before every angle reached {}°",
            options.max_vertices, options.min_angle_deg
        ));
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
    stats.cut_row = meshed.cut_row;
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
    /// The row the mask was cut at, when meshed as two halves.
    cut_row: Option<usize>,
}

/// The inside-pixel topology a mesh of some crack loops must have.
#[derive(Clone, Copy)]
struct Topology {
    holes: usize,
    pieces: usize,
}

impl Topology {
    /// The topology of the region `loops` bound (outer loops positive, holes negative): each
    /// piece has one outer loop.
    fn of_loops(loops: &[Vec<DVec2>]) -> Topology {
        let holes = loops
            .iter()
            .filter(|l| doubled_signed_area(l) < 0.0)
            .count();
        Topology {
            holes,
            pieces: loops.len() - holes,
        }
    }
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
                    cut_row: None,
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
    mesh_crack_loops(&crack, expected, options, None)
}

/// Meshes the two halves of `mask` on either side of `cut` at once and joins them; `None`
/// when the joined mesh exceeds the vertex budget (the caller then meshes the mask whole,
/// which refines within the budget).
fn mesh_in_halves(
    mask: &BitMask,
    cut: &Cut,
    pieces: usize,
    options: &MeshOptions,
) -> Result<Option<Meshed>, MeshError> {
    let [top, bottom] = cut.halves(mask);
    let mesh_half = |half: &BitMask, first_row: usize| {
        let mut crack = trace_crack_loops(half);
        cut.pin(&mut crack, first_row as f64);
        let expected = Topology {
            holes: crack.iter().filter(|l| l.is_hole()).count(),
            pieces: piece_sizes(half).len(),
        };
        mesh_crack_loops(&crack, expected, options, Some(cut.y()))
    };
    let (upper, lower) = rayon::join(|| mesh_half(&top, 0), || mesh_half(&bottom, cut.row));
    let (upper, lower) = (upper?, lower?);
    let mesh = merge(cut, &upper.mesh, &lower.mesh);
    if cfg!(debug_assertions) {
        mesh.sanity_check()?;
    }
    // Joined halves that miss the mask's pieces would be a fault of the join (the tests
    // check it on every shape family); the whole-mask path is the safe answer.
    debug_assert_eq!(mesh.piece_count as usize, pieces, "cut at row {}", cut.row);
    if mesh.piece_count as usize != pieces || mesh.vertex_count() > options.max_vertices {
        return Ok(None);
    }
    Ok(Some(Meshed {
        mesh,
        complete: upper.complete && lower.complete,
        deviation: upper.deviation.max(lower.deviation),
        simplified: upper.simplified && lower.simplified,
        fell_back: upper.fell_back || lower.fell_back,
        placement: BoundaryPlacement::Cracks,
        off_centre: 0,
        cut_row: Some(cut.row),
    }))
}

/// Meshes `mask` through its outside pixel centres as two halves at once, cut at `cut`'s row
/// (`centre_cut`), and joins them; `None` when the loops cannot be cut there, a half cannot
/// be meshed through its centres, or the joined mesh exceeds the vertex budget (the caller
/// then meshes the mask whole).
fn mesh_centres_in_halves(
    mask: &BitMask,
    cut: &Cut,
    pieces: usize,
    options: &MeshOptions,
) -> Result<Option<Meshed>, MeshError> {
    let crack = trace_crack_loops(mask);
    let whole = Topology {
        holes: crack.iter().filter(|l| l.is_hole()).count(),
        pieces,
    };
    let (loops, off_centre) = outside_centre_points(&crack);
    // A cut mask's budget is at least 8 × its crack edges (`Cut::choose`), and it has at most
    // one centre point per crack edge; the whole-mask path checks its own budget.
    let points: usize = loops.iter().map(|l| l.points.len()).sum();
    if points > options.max_vertices {
        return Ok(None);
    }
    let Some(parts) = cut_centre_loops(&loops, cut.y(), options.density) else {
        return Ok(None);
    };
    let mesh_half = |half: &[KeptLoop]| {
        let loops: Vec<Vec<DVec2>> = (half.iter())
            .map(|l| thin_loop(l, options.density))
            .collect();
        // As whole centre loops: boundary edges are not split (`mesh_whole`).
        triangulate_checked(&loops, true, Topology::of_loops(&loops), options)
    };
    let [upper, lower] = &parts.halves;
    let (upper, lower) = rayon::join(|| mesh_half(upper), || mesh_half(lower));
    let ((upper, upper_complete), (lower, lower_complete)) = match (upper, lower) {
        (Ok(upper), Ok(lower)) => (upper, lower),
        (Err(MeshError::IntersectingBoundary { .. } | MeshError::Sanity(_)), _)
        | (_, Err(MeshError::IntersectingBoundary { .. } | MeshError::Sanity(_))) => {
            return Ok(None)
        }
        (Err(e), _) | (_, Err(e)) => return Err(e),
    };
    let mesh = merge(&parts.interface, &upper, &lower);
    if cfg!(debug_assertions) {
        mesh.sanity_check()?;
    }
    if mesh.piece_count as usize != whole.pieces
        || mesh.hole_count() != whole.holes
        || mesh.vertex_count() > options.max_vertices
    {
        return Ok(None);
    }
    Ok(Some(Meshed {
        mesh,
        complete: upper_complete && lower_complete,
        deviation: 0.0,
        simplified: false,
        fell_back: false,
        placement: BoundaryPlacement::OutsideCentres,
        off_centre,
        cut_row: Some(cut.row),
    }))
}

/// Meshes crack loops simplified with the options' tolerance or, if simplification makes two
/// loops touch or cross (a thin gap closed by the tolerance), unsimplified. Edges on
/// `shared_row` are subdivided the same way in either direction.
fn mesh_crack_loops(
    crack: &[CrackLoop],
    expected: Topology,
    options: &MeshOptions,
    shared_row: Option<f64>,
) -> Result<Meshed, MeshError> {
    let attempt = |tolerance: f64| -> Result<(Mesh, bool, f64), MeshError> {
        let (loops, deviation) = sample_crack_loops(crack, tolerance, options, shared_row)?;
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
        cut_row: None,
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
            if boundary_len > options.max_vertices as f64 {
                return Err(MeshError::VertexBudget {
                    max_vertices: options.max_vertices,
                    needed: boundary_len.min(usize::MAX as f64) as usize,
                });
            }
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
        warnings.push(format!(
            "refinement stopped at its vertex budget (max_vertices {}, or the size-based bound) \
             before every angle reached {}°",
            options.max_vertices, options.min_angle_deg
        ));
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
    let mut out: Vec<DVec2> = Vec::with_capacity(ring.len());
    for &p in ring {
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
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
    shared_row: Option<f64>,
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
        subdivide_loop_sharing_row(&s.points, options.density, shared_row, &mut out);
        loops.push(out);
    }
    Ok((loops, deviation))
}

/// Refuses boundaries of more than `max_vertices` points.
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

/// Pixel edges between inside and outside (the image border counts as outside).
#[cfg(test)]
fn crack_edge_count(mask: &BitMask) -> usize {
    crack_edges_by_row(mask).iter().sum()
}

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
        cut_row: None,
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

    /// A mask of a few discs, some of them cut out again (holes, separate pieces).
    fn discs(width: usize, height: usize, discs: &[(f64, f64, f64, bool)]) -> BitMask {
        BitMask::from_fn(width, height, |x, y| {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let mut inside = false;
            for &(cx, cy, r, add) in discs {
                if (px - cx).powi(2) + (py - cy).powi(2) < r * r {
                    inside = add;
                }
            }
            inside
        })
    }

    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 64,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x5b11_7000),
            ..ProptestConfig::default()
        })]
        /// A mask meshed as two halves at any row is a sane mesh with the whole mask's pieces
        /// and holes, covering every mask pixel: the halves share every interface vertex (a
        /// vertex one half lacks would leave boundary along the cut, which the sanity check
        /// and the hole count catch).
        #[test]
        fn halves_join_into_the_masks_topology(
            (width, height) in (16usize..64, 16usize..64),
            shapes in proptest::collection::vec(
                (0.0f64..1.0, 0.0f64..1.0, 0.1f64..0.45, proptest::bool::weighted(0.7)),
                1..6,
            ),
            row_share in 0.0f64..1.0,
        ) {
            let size = width.min(height) as f64;
            let discs_px: Vec<_> = shapes
                .iter()
                .map(|&(x, y, r, add)| (x * width as f64, y * height as f64, r * size, add))
                .collect();
            let mask = discs(width, height, &discs_px);
            let options = cracks();
            let mut warnings = Vec::new();
            let (kept, _, _, pieces) = drop_small_pieces(&mask, options.min_piece_area, &mut warnings);
            prop_assume!(pieces > 0);
            let kept = kept.unwrap_or(mask);
            let whole = mesh_whole(&kept, pieces, &options, &mut warnings).unwrap();
            let row = 1 + ((height - 1) as f64 * row_share) as usize;
            let row = row.min(height - 1);
            let cut = Cut::at(&kept, row);
            let halves = mesh_in_halves(&kept, &cut, pieces, &options).unwrap().unwrap();
            prop_assert_eq!(halves.mesh.sanity_check(), Ok(()));
            prop_assert_eq!(halves.mesh.piece_count, whole.mesh.piece_count);
            prop_assert_eq!(halves.mesh.hole_count(), whole.mesh.hole_count());
            prop_assert_eq!(crate::mesh::uncovered_mask_pixels(&halves.mesh, &kept), 0);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 200,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x5b11_7001),
            ..ProptestConfig::default()
        })]
        /// Pixel noise cut at any row: pieces touching at a corner across the cut, one-pixel
        /// interface runs, steps on the cut line, holes cut in two.
        #[test]
        fn noisy_masks_cut_at_any_row_join_into_the_masks_topology(
            (width, height, bits) in (8usize..40, 4usize..40).prop_flat_map(|(w, h)| {
                (Just(w), Just(h), proptest::collection::vec(any::<u8>(), w * h))
            }),
            density in 64u8..230,
            row_share in 0.0f64..1.0,
        ) {
            let mask = BitMask::from_fn(width, height, |x, y| bits[y * width + x] < density);
            let options = cracks();
            let mut warnings = Vec::new();
            let (kept, _, _, pieces) = drop_small_pieces(&mask, options.min_piece_area, &mut warnings);
            prop_assume!(pieces > 0);
            let kept = kept.unwrap_or(mask);
            let whole = mesh_whole(&kept, pieces, &options, &mut warnings).unwrap();
            let row = (1 + ((height - 1) as f64 * row_share) as usize).min(height - 1);
            let halves = mesh_in_halves(&kept, &Cut::at(&kept, row), pieces, &options).unwrap();
            let halves = halves.expect("the joined mesh has the mask's pieces");
            prop_assert_eq!(halves.mesh.sanity_check(), Ok(()));
            prop_assert_eq!(halves.mesh.piece_count, whole.mesh.piece_count);
            prop_assert_eq!(halves.mesh.hole_count(), whole.mesh.hole_count());
            prop_assert_eq!(crate::mesh::uncovered_mask_pixels(&halves.mesh, &kept), 0);
        }
    }

    fn cracks() -> MeshOptions {
        MeshOptions {
            boundary: BoundaryPlacement::Cracks,
            ..MeshOptions::default()
        }
    }

    fn centres() -> MeshOptions {
        MeshOptions {
            boundary: BoundaryPlacement::OutsideCentres,
            ..MeshOptions::default()
        }
    }

    /// Checks a mask meshed through its outside centres as two halves at `row`: `None`
    /// when the halves fell back; otherwise a sane mesh with the whole centre mesh's pieces
    /// and holes, every mask pixel covered, and every boundary vertex a centre of the whole
    /// mask's centre loops (no vertex of the cut left on the boundary).
    fn check_centre_halves(mask: &BitMask, row: usize) -> Result<Option<()>, TestCaseError> {
        let options = centres();
        let mut warnings = Vec::new();
        let (kept, _, _, pieces) = drop_small_pieces(mask, options.min_piece_area, &mut warnings);
        if pieces == 0 {
            return Ok(None);
        }
        let kept = kept.unwrap_or_else(|| mask.clone());
        let whole = mesh_whole(&kept, pieces, &options, &mut warnings).unwrap();
        let Some(halves) =
            mesh_centres_in_halves(&kept, &Cut::at(&kept, row), pieces, &options).unwrap()
        else {
            return Ok(None);
        };
        prop_assert_eq!(halves.placement, BoundaryPlacement::OutsideCentres);
        prop_assert_eq!(halves.mesh.sanity_check(), Ok(()));
        prop_assert_eq!(halves.mesh.piece_count, whole.mesh.piece_count);
        prop_assert_eq!(halves.mesh.hole_count(), whole.mesh.hole_count());
        prop_assert_eq!(crate::mesh::uncovered_mask_pixels(&halves.mesh, &kept), 0);
        // Off the cut, the boundary is the whole mask's centres; on it, only the crossings.
        let (loops, _) = outside_centre_points(&trace_crack_loops(&kept));
        let y = row as f64;
        let crossings = cut_centre_loops(&loops, y, options.density).unwrap();
        let mut on_loops: Vec<(u64, u64)> = (loops.iter().flat_map(|l| &l.points))
            .map(|p| (p.x.to_bits(), p.y.to_bits()))
            .collect();
        on_loops.sort_unstable();
        let mut on_cut = 0;
        for v in halves.mesh.boundary_vertices() {
            let p = halves.mesh.positions[v as usize];
            on_cut += usize::from(p.y == y);
            prop_assert!(
                p.y == y
                    || on_loops
                        .binary_search(&(p.x.to_bits(), p.y.to_bits()))
                        .is_ok(),
                "boundary vertex {} is no outside centre (cut at {})",
                p,
                row
            );
        }
        prop_assert_eq!(on_cut, 2 * crossings.interface.intervals.len());
        Ok(Some(()))
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 64,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x0ce1_70e5),
            ..ProptestConfig::default()
        })]
        /// Discs unions and differences cut at any row: where the whole mask meshes through
        /// its centres, so do the halves, and they join into the same topology.
        #[test]
        fn centre_halves_join_into_the_masks_topology(
            (width, height) in (16usize..64, 16usize..64),
            shapes in proptest::collection::vec(
                (0.0f64..1.0, 0.0f64..1.0, 0.1f64..0.45, proptest::bool::weighted(0.7)),
                1..6,
            ),
            row_share in 0.0f64..1.0,
        ) {
            let size = width.min(height) as f64;
            let discs_px: Vec<_> = shapes
                .iter()
                .map(|&(x, y, r, add)| (x * width as f64, y * height as f64, r * size, add))
                .collect();
            let mask = discs(width, height, &discs_px);
            let row = (1 + ((height - 1) as f64 * row_share) as usize).min(height - 1);
            check_centre_halves(&mask, row)?;
        }

        /// Pixel noise cut at any row: the halves either join into the mask's topology
        /// through the centres or fall back, never a broken mesh.
        #[test]
        fn noisy_masks_cut_through_their_centres_join_or_fall_back(
            (width, height, bits) in (8usize..40, 4usize..40).prop_flat_map(|(w, h)| {
                (Just(w), Just(h), proptest::collection::vec(any::<u8>(), w * h))
            }),
            density in 64u8..230,
            row_share in 0.0f64..1.0,
        ) {
            let mask = BitMask::from_fn(width, height, |x, y| bits[y * width + x] < density);
            let row = (1 + ((height - 1) as f64 * row_share) as usize).min(height - 1);
            check_centre_halves(&mask, row)?;
        }
    }

    /// Simple shapes cut across do go through the centres (the fallback is not what the
    /// property tests above see).
    #[test]
    fn discs_rings_and_the_spiral_are_cut_through_their_centres() {
        let ring = BitMask::from_fn(60, 60, |x, y| {
            let d = ((x as f64 - 30.0).powi(2) + (y as f64 - 30.0).powi(2)).sqrt();
            (10.0..25.0).contains(&d)
        });
        let disc = crate::mesh::synth::disc(50, 40, 15.0);
        for (mask, row) in [(&ring, 30), (&ring, 12), (&disc, 20)] {
            let checked = check_centre_halves(mask, row).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(checked, Some(()), "row {row}");
        }
        let spiral = crate::mesh::synth::spiral(400, 400);
        let options = centres();
        let meshed = mesh_mask(&spiral, &options).unwrap();
        assert_eq!(meshed.stats.boundary, BoundaryPlacement::OutsideCentres);
        let row = meshed.stats.cut_row.expect("the spiral is cut");
        let checked = check_centre_halves(&spiral, row).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(checked, Some(()));
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let alone = one_thread.install(|| mesh_mask(&spiral, &options)).unwrap();
        assert_eq!(alone.mesh, meshed.mesh);
        // Every centre kept (the seam-quality preset): made whole, as it always was.
        let preset = mesh_mask(&spiral, &MeshOptions::seam_quality()).unwrap();
        assert_eq!(preset.stats.boundary, BoundaryPlacement::OutsideCentres);
        assert_eq!(preset.stats.cut_row, None);
    }

    /// A long one-pixel line has its crack edges on two lines; a cut between them would leave
    /// one half empty. Cuts lie strictly between the first and the last inside row.
    #[test]
    fn a_cut_leaves_inside_pixels_on_both_sides() {
        let line = BitMask::from_fn(4000, 4, |x, y| y == 1 && x > 10);
        let by_row = crack_edges_by_row(&line);
        assert!(by_row.iter().sum::<usize>() >= crate::mesh::split::SPLIT_MIN_CRACK_EDGES);
        assert_eq!(
            Cut::choose(&line, &by_row, 2_000_000).map(|cut| cut.row),
            None
        );
        let result = mesh_mask(&line, &MeshOptions::default()).unwrap();
        assert_eq!(result.mesh.sanity_check(), Ok(()));
        let band = BitMask::from_fn(4000, 6, |x, y| (1..5).contains(&y) && x > 10);
        let cut = Cut::choose(&band, &crack_edges_by_row(&band), 2_000_000).map(|cut| cut.row);
        assert!(cut.is_none_or(|row| (2..5).contains(&row)), "{cut:?}");
        let result = mesh_mask(&band, &MeshOptions::default()).unwrap();
        assert_eq!(result.mesh.sanity_check(), Ok(()));
    }

    /// The paper's spiral is large enough to be cut; its mesh is the join of the halves and
    /// the same on one thread as on two.
    #[test]
    fn a_large_mask_is_meshed_in_halves_the_same_on_any_thread_count() {
        let mask = crate::mesh::synth::spiral(400, 400);
        let options = MeshOptions {
            boundary: BoundaryPlacement::Cracks,
            ..MeshOptions::default()
        };
        let by_row = crack_edges_by_row(&mask);
        let cut = Cut::choose(&mask, &by_row, options.max_vertices).unwrap();
        let joined = mesh_in_halves(&mask, &cut, 1, &options).unwrap().unwrap();
        let meshed = mesh_mask(&mask, &options).unwrap();
        assert_eq!(meshed.mesh, joined.mesh);
        assert_eq!(meshed.stats.cut_row, Some(cut.row));
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let alone = one_thread.install(|| mesh_mask(&mask, &options)).unwrap();
        assert_eq!(alone.mesh, meshed.mesh);
        // Some vertex on the cut is interior: the halves were joined, not just put side by side.
        let y = cut.y();
        let interior_on_cut = (0..meshed.mesh.vertex_count())
            .filter(|&v| meshed.mesh.positions[v].y == y && !meshed.mesh.is_boundary[v])
            .count();
        assert!(interior_on_cut > 10, "{interior_on_cut}");
    }

    /// Small masks (the golden cases, most scene patches), tight vertex budgets and masks
    /// whose every balanced cut would be long (a large disc) are meshed whole.
    #[test]
    fn small_masks_tight_budgets_and_wide_insides_are_not_cut() {
        let disc = crate::mesh::synth::disc(200, 200, 90.0);
        assert!(crack_edge_count(&disc) < crate::mesh::split::SPLIT_MIN_CRACK_EDGES);
        assert_eq!(
            Cut::choose(&disc, &crack_edges_by_row(&disc), 2_000_000),
            None
        );
        let whole = mesh_mask(&disc, &MeshOptions::default()).unwrap();
        assert_eq!(whole.stats.cut_row, None);
        let spiral = crate::mesh::synth::spiral(400, 400);
        let by_row = crack_edges_by_row(&spiral);
        let edges = crack_edge_count(&spiral);
        assert!(Cut::choose(&spiral, &by_row, 2_000_000).is_some());
        assert_eq!(Cut::choose(&spiral, &by_row, 4 * edges), None);
        let wide = crate::mesh::synth::disc(2000, 2000, 990.0);
        let by_row = crack_edges_by_row(&wide);
        assert!(crack_edge_count(&wide) >= crate::mesh::split::SPLIT_MIN_CRACK_EDGES);
        assert_eq!(Cut::choose(&wide, &by_row, 2_000_000), None);
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
