//! Test and benchmark meshes built directly (no mask, no mesher): takes sizes and gives
//! triangulated grids, hexagonal-ring discs and disjoint unions as complete [`Mesh`] values
//! (positions, positively oriented triangles, boundary loops, flags, pieces).
//! Shared by the library's unit tests (as `crate::mesh::fixtures`), the integration tests and
//! the benchmarks with `#[path = "…/tests/common/mesh_fixtures.rs"] mod fixtures;`.
#![allow(dead_code)]

use glam::DVec2;
use lapclone::mesh::{BoundaryLoop, LoopKind, Mesh};

/// A `cols × rows` cell grid of unit squares, each split into two triangles;
/// `(cols + 1)(rows + 1)` vertices, vertex `(i, j)` at `(i, j)` with index `j (cols + 1) + i`.
pub fn grid(cols: usize, rows: usize) -> Mesh {
    let cols = cols.max(1);
    let rows = rows.max(1);
    let index = |i: usize, j: usize| (j * (cols + 1) + i) as u32;
    let mut positions = Vec::with_capacity((cols + 1) * (rows + 1));
    for j in 0..=rows {
        for i in 0..=cols {
            positions.push(DVec2::new(i as f64, j as f64));
        }
    }
    let mut triangles = Vec::with_capacity(2 * cols * rows);
    for j in 0..rows {
        for i in 0..cols {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    let mut outer: Vec<u32> = (0..cols).map(|i| index(i, 0)).collect();
    outer.extend((0..rows).map(|j| index(cols, j)));
    outer.extend((1..=cols).rev().map(|i| index(i, rows)));
    outer.extend((1..=rows).rev().map(|j| index(0, j)));
    finish(positions, triangles, vec![outer])
}

/// A disc of `rings` hexagonal rings around a centre vertex: ring r has 6r vertices at
/// radius r, so there are `1 + 3 rings (rings + 1)` vertices.
pub fn disc(rings: usize) -> Mesh {
    let mut positions = vec![DVec2::ZERO];
    let mut ring_start = vec![0usize];
    for r in 1..=rings {
        ring_start.push(positions.len());
        let count = 6 * r;
        for k in 0..count {
            let angle = std::f64::consts::TAU * k as f64 / count as f64;
            positions.push(DVec2::new(angle.cos(), angle.sin()) * r as f64);
        }
    }
    let mut triangles = Vec::new();
    for r in 1..=rings {
        let inner: Vec<u32> = if r == 1 {
            vec![0]
        } else {
            (ring_start[r - 1]..ring_start[r - 1] + 6 * (r - 1))
                .map(|v| v as u32)
                .collect()
        };
        let outer: Vec<u32> = (ring_start[r]..ring_start[r] + 6 * r)
            .map(|v| v as u32)
            .collect();
        stitch_rings(&inner, &outer, &mut triangles);
    }
    let outer = if rings == 0 {
        Vec::new()
    } else {
        (ring_start[rings]..ring_start[rings] + 6 * rings)
            .map(|v| v as u32)
            .collect()
    };
    let loops = if outer.is_empty() {
        Vec::new()
    } else {
        vec![outer]
    };
    let mut mesh = finish(positions, triangles, loops);
    orient(&mut mesh);
    mesh
}

/// Smallest disc with at least `vertices` vertices.
pub fn disc_with_vertices(vertices: usize) -> Mesh {
    let mut rings = 0;
    while 1 + 3 * rings * (rings + 1) < vertices {
        rings += 1;
    }
    disc(rings)
}

/// Both meshes side by side (`b` shifted right of `a`) as one mesh with two pieces.
pub fn disjoint_union(a: &Mesh, b: &Mesh) -> Mesh {
    let offset = a.vertex_count() as u32;
    let shift_x = a.positions.iter().map(|p| p.x).fold(0.0, f64::max)
        - b.positions.iter().map(|p| p.x).fold(0.0, f64::min)
        + 2.0;
    let mut mesh = a.clone();
    mesh.positions
        .extend(b.positions.iter().map(|p| *p + DVec2::new(shift_x, 0.0)));
    mesh.triangles
        .extend(b.triangles.iter().map(|t| t.map(|v| v + offset)));
    mesh.is_boundary.extend_from_slice(&b.is_boundary);
    mesh.piece.extend(b.piece.iter().map(|p| p + a.piece_count));
    mesh.loops.extend(b.loops.iter().map(|l| BoundaryLoop {
        kind: l.kind,
        piece: l.piece + a.piece_count,
        vertices: l.vertices.iter().map(|v| v + offset).collect(),
    }));
    mesh.piece_count += b.piece_count;
    mesh
}

/// Walks two concentric vertex rings by angle, emitting the triangles between them.
fn stitch_rings(inner: &[u32], outer: &[u32], triangles: &mut Vec<[u32; 3]>) {
    let (m, big) = (inner.len(), outer.len());
    let (mut i, mut o) = (0usize, 0usize);
    while i < m || o < big {
        // Advance whichever ring's next vertex comes first in angle (fractions i/m vs o/big).
        let advance_inner = o == big || (i < m && (i + 1) * big < (o + 1) * m);
        if advance_inner && m > 1 {
            triangles.push([inner[i % m], inner[(i + 1) % m], outer[o % big]]);
            i += 1;
        } else {
            triangles.push([inner[i % m], outer[o % big], outer[(o + 1) % big]]);
            o += 1;
            if m == 1 && o == big {
                i = m;
            }
        }
    }
}

fn finish(positions: Vec<DVec2>, triangles: Vec<[u32; 3]>, loops: Vec<Vec<u32>>) -> Mesh {
    let n = positions.len();
    let mut is_boundary = vec![false; n];
    for l in &loops {
        for &v in l {
            is_boundary[v as usize] = true;
        }
    }
    Mesh {
        positions,
        triangles,
        loops: loops
            .into_iter()
            .map(|vertices| BoundaryLoop {
                kind: LoopKind::Outer,
                piece: 0,
                vertices,
            })
            .collect(),
        is_boundary,
        piece: vec![0; n],
        piece_count: 1,
    }
}

/// Makes every triangle and the outer loop positively oriented in raw coordinates.
fn orient(mesh: &mut Mesh) {
    let p = &mesh.positions;
    for t in &mut mesh.triangles {
        let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
        if (b - a).perp_dot(c - a) < 0.0 {
            t.swap(1, 2);
        }
    }
    for l in &mut mesh.loops {
        let area: f64 = (0..l.vertices.len())
            .map(|k| {
                let a = p[l.vertices[k] as usize];
                let b = p[l.vertices[(k + 1) % l.vertices.len()] as usize];
                a.perp_dot(b)
            })
            .sum();
        if area < 0.0 {
            l.vertices.reverse();
        }
    }
}
