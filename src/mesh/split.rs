//! Meshing a large mask as two halves at once: takes a mask (small pieces already dropped)
//! and gives the pixel row to cut it at, pins that cut in each half's crack loops, and joins
//! the two halves' meshes into one conforming [`Mesh`].
//!
//! spade's triangulation and refinement are most of a mask's meshing time, on one thread.
//! Cut along a pixel row, each half is traced, simplified, triangulated and refined on its
//! own thread. The *interface* — the crack edges on the cut whose pixels above and below are
//! both inside — is an edge of both halves' loops, with its ends anchored so simplification
//! keeps it straight, and subdivided at the same points whichever way a loop runs along it
//! (`subdivide_loop_sharing_row`), so both halves have its vertices bit for bit; the whole
//! mask's saddles on the cut are anchored too, so pieces touching there still touch. Refinement
//! may still split an interface edge in one half only; the join then splits the other
//! half's triangle on that edge at the same points (a fan from its third vertex), so the
//! mesh conforms.
//!
//! Which masks are cut, and where: [`Cut::choose`] (a long boundary, a short interface, rows
//! the boundary only crosses). The cut depends on the mask alone and such a mask is always
//! cut, so the mesh is the same whether the halves run on one thread or two.

use std::collections::HashMap;

use glam::DVec2;

use super::bitmask::{differing_bytes, shared_ones};
use super::contour::CrackLoop;
use super::triangulate::assemble_mesh_with_boundary;
use super::{BitMask, Mesh};

/// Masks with fewer crack edges are meshed whole: below this the two halves gain less than
/// a millisecond, and small meshes (the golden cases, most scene patches) keep the vertices
/// they always had.
pub(crate) const SPLIT_MIN_CRACK_EDGES: usize = 6000;

/// A mask is cut only when its vertex budget is at least this many times its crack edges,
/// so the joined mesh stays within the budget the whole-mask refinement would respect (see
/// `mesh_in_halves`, which falls back when it does not).
const BUDGET_PER_CRACK_EDGE: usize = 8;

/// A mask is cut only where the interface has at most 1/this of its crack edges.
const MAX_INTERFACE_SHARE: usize = 8;

/// The cut's row keeps each half's crack edges within this share of the total from an even
/// split; among those rows, the one with the fewest boundary steps on its line, then the
/// shortest interface, is taken.
const BALANCE_SLACK: f64 = 0.05;

/// Where two halves meet: the cut line and which edges on it become interior once the
/// halves are joined (for crack loops [`Cut`], for centre loops `CentreInterface`).
pub(crate) trait Interface {
    /// The cut's y coordinate.
    fn y(&self) -> f64;
    /// Whether the edge a–b lies on the interface (inside on both sides of the cut).
    fn is_interface_edge(&self, a: DVec2, b: DVec2) -> bool;
}

/// Where a mask is cut: along the line y = `row`, between pixel rows `row − 1` and `row`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Cut {
    /// First row of the lower half.
    pub row: usize,
    /// Per column x: pixels (x, row − 1) and (x, row) are both inside.
    interface: Vec<bool>,
    /// Per corner x on the cut (0..=width): a saddle of the whole mask (inside pixels touching
    /// diagonally across the cut), which each half sees as a plain corner.
    saddle: Vec<bool>,
}

impl Cut {
    /// The cut for `mask`, whose crack edges by row are `edges_by_row`
    /// (`crack_edges_by_row`), or `None` when it is meshed whole.
    pub fn choose(mask: &BitMask, edges_by_row: &[usize], max_vertices: usize) -> Option<Cut> {
        let edges: usize = edges_by_row.iter().sum();
        let budget_allows = max_vertices / BUDGET_PER_CRACK_EDGE >= edges;
        if edges < SPLIT_MIN_CRACK_EDGES || !budget_allows {
            return None;
        }
        // above[y]: crack edges on the lines and rows above the line y.
        let above: Vec<usize> = std::iter::once(0)
            .chain(edges_by_row.iter().scan(0, |sum, &row| {
                *sum += row;
                Some(*sum)
            }))
            .collect();
        let half = edges as f64 / 2.0;
        let imbalance = |row: usize| (above[row] as f64 - half).abs();
        let (above_row, below_row) = (
            |row: usize| mask.row_bytes(row - 1),
            |row| mask.row_bytes(row),
        );
        let interface_len = |row: usize| shared_ones(above_row(row), below_row(row));
        // Boundary running along the cut ends at it in a step whose corner the cut pins, an
        // input angle refinement cannot open: rows the boundary only crosses are better.
        let steps_on_line = |row: usize| differing_bytes(above_row(row), below_row(row));
        // Rows strictly between the first and the last inside row: a half needs inside pixels.
        let ((_, first), (_, end)) = mask.inside_bounds()?;
        let rows = first + 1..end;
        let balanced = rows
            .clone()
            .min_by(|&a, &b| imbalance(a).total_cmp(&imbalance(b)))?;
        let slack = (BALANCE_SLACK * edges as f64).max(imbalance(balanced));
        let row = rows
            .filter(|&row| imbalance(row) <= slack)
            .min_by_key(|&row| {
                let closeness = row.abs_diff(balanced);
                (steps_on_line(row), interface_len(row), closeness, row)
            })?;
        // A long interface is boundary-dense meshing across the inside: it costs more
        // vertices than the halves save time (a 2000² disc: 5,746 → 8,200 vertices).
        if interface_len(row) * MAX_INTERFACE_SHARE > edges {
            return None;
        }
        Some(Cut::at(mask, row))
    }

    /// The cut at `row` (1 ≤ row < height).
    pub fn at(mask: &BitMask, row: usize) -> Cut {
        let interface = (mask.row_bytes(row - 1).iter().zip(mask.row_bytes(row)))
            .map(|(&up, &down)| up & down != 0)
            .collect();
        let (x_max, y) = (mask.width as i64, row as i64);
        let saddle = (0..=x_max)
            .map(|x| {
                let (nw, ne) = (mask.get(x - 1, y - 1), mask.get(x, y - 1));
                let (sw, se) = (mask.get(x - 1, y), mask.get(x, y));
                nw == se && ne == sw && nw != ne
            })
            .collect();
        Cut {
            row,
            interface,
            saddle,
        }
    }

    /// The rows above the cut and the rows below it, each as a mask of its own.
    pub fn halves(&self, mask: &BitMask) -> [BitMask; 2] {
        [mask.rows(0..self.row), mask.rows(self.row..mask.height)]
    }

    /// Moves a half's crack loops down by `first_row` (into the whole mask's coordinates)
    /// and pins the interface: a loop edge on the cut gets a vertex wherever it passes from
    /// interface to real boundary, and every vertex at an end of the interface or at a saddle
    /// of the whole mask becomes an anchor, so simplification keeps interface runs as they
    /// are and the pieces that touch across the cut still touch.
    pub fn pin(&self, loops: &mut [CrackLoop], first_row: f64) {
        let y = self.y();
        for lp in loops {
            let n = lp.points.len();
            let mut points = Vec::with_capacity(n + 4);
            let mut anchor = Vec::with_capacity(n + 4);
            for i in 0..n {
                let p = lp.points[i] + DVec2::new(0.0, first_row);
                let q = lp.points[(i + 1) % n] + DVec2::new(0.0, first_row);
                points.push(p);
                anchor.push(lp.anchor[i] || self.is_pinned(p));
                if p.y == y && q.y == y {
                    for x in self.changes_between(p.x as i64, q.x as i64) {
                        points.push(DVec2::new(x as f64, y));
                        anchor.push(true);
                    }
                }
            }
            lp.points = points;
            lp.anchor = anchor;
        }
    }

    fn is_interface_column(&self, x: i64) -> bool {
        usize::try_from(x)
            .ok()
            .and_then(|x| self.interface.get(x))
            .copied()
            .unwrap_or(false)
    }

    /// A point on the cut that both halves must keep: next to an interface column, or a
    /// saddle of the whole mask (its pieces touch there once joined).
    fn is_pinned(&self, p: DVec2) -> bool {
        let x = p.x as i64;
        let saddle = || usize::try_from(x).is_ok_and(|x| self.saddle.get(x) == Some(&true));
        p.y == self.y()
            && p.x == x as f64
            && (self.is_interface_column(x - 1) || self.is_interface_column(x) || saddle())
    }

    /// Corners strictly between x = `from` and `to` (in that order) where the columns on
    /// either side differ in being interface.
    fn changes_between(&self, from: i64, to: i64) -> Vec<i64> {
        let flips = |x: &i64| self.is_interface_column(x - 1) != self.is_interface_column(*x);
        if from < to {
            (from + 1..to).filter(flips).collect()
        } else {
            (to + 1..from).rev().filter(flips).collect()
        }
    }
}

impl Interface for Cut {
    fn y(&self) -> f64 {
        self.row as f64
    }

    /// Its pixels above and below are inside.
    fn is_interface_edge(&self, a: DVec2, b: DVec2) -> bool {
        let y = self.y();
        a.y == y && b.y == y && self.is_interface_column(((a.x + b.x) / 2.0).floor() as i64)
    }
}

/// The joined vertex positions (the upper half's, then the lower half's not on the cut
/// at an upper position) and each lower vertex's joined index.
fn join_vertices(interface: &impl Interface, upper: &Mesh, lower: &Mesh) -> (Vec<DVec2>, Vec<u32>) {
    let y = interface.y();
    let mut positions = upper.positions.clone();
    let mut on_cut: HashMap<u64, u32> = (upper.positions.iter().enumerate())
        .filter(|(_, p)| p.y == y)
        .map(|(v, p)| (p.x.to_bits(), v as u32))
        .collect();
    let lower_index = (lower.positions.iter())
        .map(|&p| {
            let mut add = || {
                positions.push(p);
                positions.len() as u32 - 1
            };
            match p.y == y {
                true => *on_cut.entry(p.x.to_bits()).or_insert_with(add),
                false => add(),
            }
        })
        .collect();
    (positions, lower_index)
}

/// Joins the meshes of the halves above and below the cut: vertices on the cut at the
/// same position become one, interface edges that one half split are split in the other
/// half too, and the interface edges leave the boundary.
pub(crate) fn merge(interface: &impl Interface, upper: &Mesh, lower: &Mesh) -> Mesh {
    let y = interface.y();
    let (positions, lower_index) = join_vertices(interface, upper, lower);
    let upper_index: Vec<u32> = (0..upper.positions.len() as u32).collect();
    let halves = [(upper, &upper_index), (lower, &lower_index)];
    let vertices = InterfaceVertices::of(interface, &positions, &halves);
    let mut triangles = Vec::with_capacity(upper.triangles.len() + lower.triangles.len());
    let mut boundary = Vec::new();
    for (half, index) in halves {
        let split = vertices.splits(interface, &positions, half, index);
        let on_cut = |v: &u32| positions[*v as usize].y == y;
        for t in half.triangles.iter().map(|t| t.map(|v| index[v as usize])) {
            // Only a triangle with an edge on the cut can have a split edge.
            match !split.is_empty() && t.iter().filter(|v| on_cut(v)).count() >= 2 {
                true => push_split(t, &split, &mut triangles),
                false => triangles.push(t),
            }
        }
        for (a, b) in loop_edges(half) {
            let (a, b) = (index[a as usize], index[b as usize]);
            if !interface.is_interface_edge(positions[a as usize], positions[b as usize]) {
                boundary.push((a, b));
            }
        }
    }
    let boundary = sorted_edges(&boundary, positions.len());
    assemble_mesh_with_boundary(positions, triangles, boundary)
}

/// Every joined vertex at an end of an interface edge of either half, by x.
struct InterfaceVertices(Vec<(f64, u32)>);

impl InterfaceVertices {
    fn of(cut: &impl Interface, positions: &[DVec2], halves: &[(&Mesh, &Vec<u32>); 2]) -> Self {
        let mut vertices = Vec::new();
        for (half, index) in halves {
            for (a, b) in loop_edges(half) {
                let (a, b) = (index[a as usize], index[b as usize]);
                let (pa, pb) = (positions[a as usize], positions[b as usize]);
                if cut.is_interface_edge(pa, pb) {
                    vertices.extend([(pa.x, a), (pb.x, b)]);
                }
            }
        }
        vertices.sort_unstable_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
        vertices.dedup();
        InterfaceVertices(vertices)
    }

    /// For each interface edge a → b of `half` (joined indices) with interface vertices
    /// strictly between its ends: those vertices, from a to b.
    fn splits(
        &self,
        cut: &impl Interface,
        positions: &[DVec2],
        half: &Mesh,
        index: &[u32],
    ) -> HashMap<(u32, u32), Vec<u32>> {
        let mut splits = HashMap::new();
        for (a, b) in loop_edges(half) {
            let (a, b) = (index[a as usize], index[b as usize]);
            let (xa, xb) = (positions[a as usize].x, positions[b as usize].x);
            if !cut.is_interface_edge(positions[a as usize], positions[b as usize]) {
                continue;
            }
            let (lo, hi) = (xa.min(xb), xa.max(xb));
            let first = self.0.partition_point(|&(x, _)| x <= lo);
            let last = self.0.partition_point(|&(x, _)| x < hi);
            let mut between: Vec<u32> = self.0[first..last].iter().map(|&(_, v)| v).collect();
            if xa > xb {
                between.reverse();
            }
            if !between.is_empty() {
                splits.insert((a, b), between);
            }
        }
        splits
    }
}

/// Pushes triangle `t`, or the fan that splits it along an edge listed in `split`.
fn push_split(t: [u32; 3], split: &HashMap<(u32, u32), Vec<u32>>, out: &mut Vec<[u32; 3]>) {
    for k in 0..3 {
        let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        if let Some(between) = split.get(&(a, b)) {
            let mut from = a;
            for &v in between.iter().chain(std::iter::once(&b)) {
                out.push([from, v, c]);
                from = v;
            }
            return;
        }
    }
    out.push(t);
}

/// `edges` sorted by (from, to): a counting sort by the first vertex, then each vertex's few
/// edges by the second (a comparison sort of the joined boundary cost as much as the rest
/// of the join).
fn sorted_edges(edges: &[(u32, u32)], vertex_count: usize) -> Vec<(u32, u32)> {
    let mut start = vec![0usize; vertex_count + 1];
    for &(from, _) in edges {
        start[from as usize + 1] += 1;
    }
    for v in 0..vertex_count {
        start[v + 1] += start[v];
    }
    let mut next = start.clone();
    let mut sorted = vec![(0, 0); edges.len()];
    for &edge in edges {
        sorted[next[edge.0 as usize]] = edge;
        next[edge.0 as usize] += 1;
    }
    for v in 0..vertex_count {
        sorted[start[v]..start[v + 1]].sort_unstable();
    }
    sorted
}

/// The directed boundary edges of `mesh`, loop by loop.
fn loop_edges(mesh: &Mesh) -> impl Iterator<Item = (u32, u32)> + '_ {
    mesh.loops.iter().flat_map(|lp| {
        let n = lp.vertices.len();
        (0..n).map(move |i| (lp.vertices[i], lp.vertices[(i + 1) % n]))
    })
}
