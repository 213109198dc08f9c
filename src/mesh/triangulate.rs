//! Constrained Delaunay triangulation and Ruppert/Chew refinement with `spade`: takes closed
//! boundary loops (outer loops positive area, holes negative, possibly touching at shared
//! vertices) and gives a [`Mesh`] of the inside. The inside is decided by parity (spade's
//! `exclude_outer_faces`), so holes and islands inside holes come out right.
//!
//! Vertices are deduplicated here by exact position, so loops that share a corner share a
//! mesh vertex; compact mesh indices follow spade's vertex order (input order, then
//! refinement order), which is deterministic.

use glam::DVec2;
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use super::simplify::doubled_signed_area;
use super::{BoundaryLoop, LoopKind, Mesh, MeshError};

/// What the refinement produced, besides the mesh.
pub struct Triangulated {
    pub mesh: Mesh,
    /// spade's `refinement_complete`: false when the vertex budget ran out.
    pub refinement_complete: bool,
}

/// New vertices refinement may add per px² of region and per boundary vertex. A graded
/// 25° mesh needs far fewer (the spiral: 0.02 per px² at density 3, 0.13 at 0.5); the
/// bound only stops refinement that does not terminate — angle limits above 30°, where
/// spade gives no guarantee, ran a 37 × 33 px box to the 2 M vertex budget in 70 s.
const REFINEMENT_VERTICES_PER_PX2: f64 = 16.0;
const REFINEMENT_VERTICES_PER_BOUNDARY_VERTEX: usize = 8;

/// The most vertices refinement may add inside `loops` (see the constants above).
fn refinement_budget(loops: &[Vec<DVec2>], boundary_vertices: usize) -> usize {
    let area: f64 = loops
        .iter()
        .map(|l| doubled_signed_area(l).abs() / 2.0)
        .sum();
    (REFINEMENT_VERTICES_PER_PX2 * area) as usize
        + REFINEMENT_VERTICES_PER_BOUNDARY_VERTEX * boundary_vertices
        + 64
}

/// How `triangulate_loops` refines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refinement {
    pub min_angle_deg: f64,
    /// Largest triangle area left, px² (`None`: no bound).
    pub max_area: Option<f64>,
    /// Budget counting every vertex spade creates.
    pub max_vertices: usize,
    /// Never split boundary edges, so every boundary vertex is an input point (angles next
    /// to the boundary may then stay below `min_angle_deg`).
    pub keep_boundary: bool,
}

impl Refinement {
    /// Angle bound and budget only; boundary edges may be split.
    pub fn new(min_angle_deg: f64, max_vertices: usize) -> Self {
        Self {
            min_angle_deg,
            max_area: None,
            max_vertices,
            keep_boundary: false,
        }
    }
}

/// Triangulates the region bounded by `loops` and refines it as `refinement` asks.
pub fn triangulate_loops(
    loops: &[Vec<DVec2>],
    refinement: &Refinement,
) -> Result<Triangulated, MeshError> {
    let Refinement {
        min_angle_deg,
        max_area,
        max_vertices,
        keep_boundary,
    } = *refinement;
    let (points, edges) = dedup_loops(loops);
    if points.len() > max_vertices {
        return Err(MeshError::VertexBudget {
            max_vertices,
            needed: points.len(),
        });
    }
    let input_count = points.len();
    let mut cdt = constrained_triangulation(&points, &edges)?;
    let additional = (max_vertices - input_count).min(refinement_budget(loops, input_count));
    let mut parameters = RefinementParameters::<f64>::new()
        .with_angle_limit(AngleLimit::from_deg(min_angle_deg))
        .exclude_outer_faces(true)
        .with_max_additional_vertices(additional);
    if let Some(area) = max_area {
        parameters = parameters.with_max_allowed_area(area);
    }
    if keep_boundary {
        parameters = parameters.keep_constraint_edges();
    }
    let result = cdt.refine(parameters);
    let mut excluded = vec![false; cdt.num_all_faces()];
    for face in &result.excluded_faces {
        excluded[face.index()] = true;
    }
    let mesh = extract_mesh(&cdt, &excluded);
    Ok(Triangulated {
        mesh,
        refinement_complete: result.refinement_complete,
    })
}

/// The constrained Delaunay triangulation of `points` with the boundary `edges`; crossing
/// edges and merged vertices are errors.
fn constrained_triangulation(
    points: &[DVec2],
    edges: &[[usize; 2]],
) -> Result<ConstrainedDelaunayTriangulation<Point2<f64>>, MeshError> {
    let input_count = points.len();
    let spade_points: Vec<Point2<f64>> = points.iter().map(|p| Point2::new(p.x, p.y)).collect();
    // Delaunay first, constraints after: the boundary edges are (nearly) all Delaunay edges
    // already, so adding them is a walk of one step each, while spade's constraint-aware
    // sweep keeps its hull convex until the last constraint is in — about 40% more work on
    // the spiral. Both keep the input vertex order and report crossings the same way.
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(
        spade_points,
        Vec::new(),
        |_| {},
    )
    .map_err(|e| MeshError::Triangulation(format!("{e:?}")))?;
    let conflicts = edges
        .iter()
        .filter(|&&[from, to]| {
            let [from, to] = [from, to].map(FixedVertexHandle::from_index);
            cdt.try_add_constraint(from, to).is_empty()
        })
        .count();
    if conflicts > 0 {
        return Err(MeshError::IntersectingBoundary { conflicts });
    }
    if cdt.num_vertices() != input_count {
        return Err(MeshError::Triangulation(
            "spade merged boundary vertices".into(),
        ));
    }
    Ok(cdt)
}

/// Exact-position deduplication; drops zero-length edges.
fn dedup_loops(loops: &[Vec<DVec2>]) -> (Vec<DVec2>, Vec<[usize; 2]>) {
    let mut index_of = std::collections::HashMap::new();
    let mut points = Vec::new();
    let mut edges = Vec::new();
    for lp in loops {
        let ids: Vec<usize> = lp
            .iter()
            .map(|p| {
                // +0.0 folds -0.0 into 0.0 so equal positions have equal bits.
                let key = ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits());
                *index_of.entry(key).or_insert_with(|| {
                    points.push(*p);
                    points.len() - 1
                })
            })
            .collect();
        for i in 0..ids.len() {
            let (a, b) = (ids[i], ids[(i + 1) % ids.len()]);
            if a != b {
                edges.push([a, b]);
            }
        }
    }
    (points, edges)
}

/// Reads the kept faces straight from spade's topology: compact indices in spade's vertex
/// order, and the boundary as the directed edges of kept faces whose twin face is outer or
/// excluded — no search over all edges.
fn extract_mesh(cdt: &ConstrainedDelaunayTriangulation<Point2<f64>>, excluded: &[bool]) -> Mesh {
    let is_kept = |face: FixedFaceHandle<InnerTag>| !excluded[face.index()];
    let mut compact = vec![u32::MAX; cdt.num_vertices()];
    let mut kept_faces = Vec::with_capacity(cdt.num_inner_faces());
    for face in cdt.fixed_inner_faces() {
        if is_kept(face) {
            for v in cdt.face(face).vertices() {
                compact[v.fix().index()] = 0;
            }
            kept_faces.push(face);
        }
    }
    let mut positions = Vec::with_capacity(cdt.num_vertices());
    for (index, slot) in compact.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = positions.len() as u32;
            let p = cdt.vertex(FixedVertexHandle::from_index(index)).position();
            positions.push(DVec2::new(p.x, p.y));
        }
    }
    let compact_of = |v: FixedVertexHandle| compact[v.index()];
    let mut triangles = Vec::with_capacity(kept_faces.len());
    let mut boundary = Vec::new();
    for &face in &kept_faces {
        let face = cdt.face(face);
        let [a, b, c] = face.vertices().map(|v| compact_of(v.fix()));
        let area = (positions[b as usize] - positions[a as usize])
            .perp_dot(positions[c as usize] - positions[a as usize]);
        triangles.push(if area < 0.0 { [a, c, b] } else { [a, b, c] });
        for edge in face.adjacent_edges() {
            let twin_kept = edge
                .rev()
                .face()
                .as_inner()
                .is_some_and(|f| is_kept(f.fix()));
            if !twin_kept {
                let (from, to) = (compact_of(edge.from().fix()), compact_of(edge.to().fix()));
                // spade's faces are ccw (positive area), so the face is left of `edge`.
                boundary.push(if area < 0.0 { (to, from) } else { (from, to) });
            }
        }
    }
    boundary.sort_unstable();
    assemble_mesh_with_boundary(positions, triangles, boundary)
}

/// Builds pieces, boundary loops and flags for a triangle soup with consistent orientation.
pub fn assemble_mesh(positions: Vec<DVec2>, triangles: Vec<[u32; 3]>) -> Mesh {
    let boundary = boundary_edges(&triangles);
    assemble_mesh_with_boundary(positions, triangles, boundary)
}

/// [`assemble_mesh`] with the boundary edges already known (sorted, as [`boundary_edges`]
/// gives them).
pub(crate) fn assemble_mesh_with_boundary(
    positions: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    boundary: Vec<(u32, u32)>,
) -> Mesh {
    let (piece, piece_count) = label_pieces(positions.len(), &triangles);
    let mut loops = boundary_loops(&positions, &boundary);
    for lp in &mut loops {
        lp.piece = piece[lp.vertices[0] as usize];
    }
    loops.sort_by(|a, b| {
        let key = |l: &BoundaryLoop| {
            let p = positions[l.vertices[0] as usize];
            (l.piece, l.kind == LoopKind::Hole, p.y, p.x)
        };
        let (ka, kb) = (key(a), key(b));
        (ka.0, ka.1)
            .cmp(&(kb.0, kb.1))
            .then(ka.2.total_cmp(&kb.2))
            .then(ka.3.total_cmp(&kb.3))
    });
    let mut is_boundary = vec![false; positions.len()];
    for lp in &loops {
        for &v in &lp.vertices {
            is_boundary[v as usize] = true;
        }
    }
    Mesh {
        positions,
        triangles,
        loops,
        is_boundary,
        piece,
        piece_count,
    }
}

/// Vertex-connectivity pieces, numbered in order of their smallest vertex.
pub(crate) fn label_pieces(vertex_count: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, u32) {
    let mut parent: Vec<u32> = (0..vertex_count as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for t in triangles {
        for k in 1..3 {
            let (ra, rb) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    let mut id_of_root = vec![u32::MAX; vertex_count];
    let mut piece = vec![0u32; vertex_count];
    let mut count = 0u32;
    for v in 0..vertex_count as u32 {
        let root = find(&mut parent, v) as usize;
        if id_of_root[root] == u32::MAX {
            id_of_root[root] = count;
            count += 1;
        }
        piece[v as usize] = id_of_root[root];
    }
    (piece, count)
}

/// Directed edges of the triangles whose reverse is not an edge, sorted.
pub(crate) fn boundary_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut directed: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    directed.sort_unstable();
    directed
        .iter()
        .copied()
        .filter(|&(a, b)| directed.binary_search(&(b, a)).is_err())
        .collect()
}

/// Chains boundary edges into loops. At a vertex with several outgoing boundary edges (two
/// pieces of inside touching at a point) it takes the one with the smallest
/// counter-clockwise angle from the incoming edge's reverse, which joins the two touching
/// wedges into one loop — the same choice as the crack tracer's saddle rule.
fn boundary_loops(positions: &[DVec2], edges: &[(u32, u32)]) -> Vec<BoundaryLoop> {
    let mut used = vec![false; edges.len()];
    let first_out = |v: u32| edges.partition_point(|&(a, _)| a < v);
    let mut loops = Vec::new();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut vertices = Vec::new();
        let mut current = start;
        loop {
            used[current] = true;
            let (from, to) = edges[current];
            vertices.push(from);
            let out_edges = first_out(to)..first_out(to + 1);
            let mut unused = out_edges.clone().filter(|&k| !used[k]);
            let best = match (unused.next(), unused.next()) {
                (Some(only), None) => Some(only),
                (None, _) => None,
                _ => sharpest_turn(positions, edges, &used, out_edges, from, to),
            };
            match best {
                Some(next) => current = next,
                None => break,
            }
        }
        let first = (0..vertices.len())
            .min_by(|&i, &j| {
                let (p, q) = (
                    positions[vertices[i] as usize],
                    positions[vertices[j] as usize],
                );
                p.y.total_cmp(&q.y)
                    .then(p.x.total_cmp(&q.x))
                    .then(i.cmp(&j))
            })
            .unwrap_or(0);
        vertices.rotate_left(first);
        let pts: Vec<DVec2> = vertices.iter().map(|&v| positions[v as usize]).collect();
        let kind = if super::simplify::doubled_signed_area(&pts) > 0.0 {
            LoopKind::Outer
        } else {
            LoopKind::Hole
        };
        loops.push(BoundaryLoop {
            kind,
            piece: 0,
            vertices,
        });
    }
    loops
}

/// Among the unused boundary edges leaving `to`, the one with the smallest counter-clockwise
/// angle from the reverse of the incoming edge `from → to`.
fn sharpest_turn(
    positions: &[DVec2],
    edges: &[(u32, u32)],
    used: &[bool],
    out_edges: std::ops::Range<usize>,
    from: u32,
    to: u32,
) -> Option<usize> {
    let back = positions[from as usize] - positions[to as usize];
    let mut best: Option<(usize, f64)> = None;
    for k in out_edges.filter(|&k| !used[k]) {
        let out = positions[edges[k].1 as usize] - positions[to as usize];
        let mut angle = back.perp_dot(out).atan2(back.dot(out));
        if angle <= 0.0 {
            angle += std::f64::consts::TAU;
        }
        if best.is_none_or(|(_, a)| angle < a) {
            best = Some((k, angle));
        }
    }
    best.map(|(k, _)| k)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Found by tests/fuzz_mesh.rs: a 34.9° angle limit on a small box refined until the
    /// 2 M vertex budget (70 s); the size-based bound now stops it at a few thousand.
    #[test]
    fn refinement_beyond_30_degrees_stops_at_the_size_bound() {
        let mut boundary = Vec::new();
        crate::mesh::simplify::subdivide_loop(&square(0.0, 0.0, 12.0), 0.45, &mut boundary);
        let loops = vec![boundary];
        let input = loops[0].len();
        let t = triangulate_loops(&loops, &Refinement::new(34.9, 2_000_000)).unwrap();
        t.mesh.sanity_check().unwrap();
        let bound = input + refinement_budget(&loops, input);
        assert!(
            t.mesh.vertex_count() <= bound,
            "{} vertices, bound {bound}",
            t.mesh.vertex_count()
        );
    }

    fn square(x0: f64, y0: f64, s: f64) -> Vec<DVec2> {
        vec![
            DVec2::new(x0, y0),
            DVec2::new(x0 + s, y0),
            DVec2::new(x0 + s, y0 + s),
            DVec2::new(x0, y0 + s),
        ]
    }

    #[test]
    fn square_with_hole_meshes_with_one_hole() {
        let mut hole = square(3.0, 3.0, 4.0);
        hole.reverse();
        let t = triangulate_loops(
            &[square(0.0, 0.0, 10.0), hole],
            &Refinement::new(25.0, 10_000),
        )
        .unwrap();
        assert!(t.refinement_complete);
        t.mesh.sanity_check().unwrap();
        assert_eq!((t.mesh.piece_count, t.mesh.hole_count()), (1, 1));
        let area: f64 = t
            .mesh
            .triangles
            .iter()
            .map(|tr| {
                let p = tr.map(|v| t.mesh.positions[v as usize]);
                0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0])
            })
            .sum();
        assert!((area - 84.0).abs() < 1e-9, "{area}");
    }

    #[test]
    fn squares_touching_at_a_corner_share_a_vertex_and_one_loop() {
        let t = triangulate_loops(
            &[square(0.0, 0.0, 1.0), square(1.0, 1.0, 1.0)],
            &Refinement::new(25.0, 1000),
        )
        .unwrap();
        t.mesh.sanity_check().unwrap();
        assert_eq!(t.mesh.vertex_count(), 7);
        assert_eq!((t.mesh.piece_count, t.mesh.loops.len()), (1, 1));
    }

    #[test]
    fn topology_extraction_matches_the_triangle_soup_path() {
        use crate::mesh::{mesh_mask, synth, MeshOptions};
        let masks = [
            synth::spiral(200, 180),
            synth::nested(160, 160),
            synth::comb(160, 100, 6, 2),
            synth::speckle(64, 64, 0.35, 3),
        ];
        for mask in &masks {
            let mesh = mesh_mask(mask, &MeshOptions::default()).unwrap().mesh;
            let soup = assemble_mesh(mesh.positions.clone(), mesh.triangles.clone());
            assert_eq!(mesh, soup);
        }
    }

    #[test]
    fn crossing_loops_are_an_error() {
        let err = triangulate_loops(
            &[square(0.0, 0.0, 4.0), square(2.0, 2.0, 4.0)],
            &Refinement::new(25.0, 1000),
        );
        assert!(matches!(err, Err(MeshError::IntersectingBoundary { .. })));
    }

    #[test]
    fn budget_below_boundary_is_an_error() {
        let err = triangulate_loops(&[square(0.0, 0.0, 4.0)], &Refinement::new(25.0, 3));
        assert!(matches!(
            err,
            Err(MeshError::VertexBudget { needed: 4, .. })
        ));
    }
}
