//! Cutting the loops through the outside pixel centres at a pixel row: takes the whole mask's
//! centre loops (before thinning, with the points thinning must keep) and the cut line
//! y = row, and gives each half's closed loops and the cut's *interface*, the intervals of
//! the line inside the mask's region, which both halves share.
//!
//! Crack loops are cut by the pixel grid itself (`split`); centre loops run half a pixel off
//! it, through pixel centres and quarter-pixel points, so no point lies on an integer row and
//! they are cut geometrically. Each loop edge from one side to the other gets one crossing
//! point, computed once and used by both halves. Along the line, inside and outside
//! alternate at every crossing (outside far left), so the crossings sorted by x pair up into
//! the interface intervals. A half's loop is its chains of the original loops joined by the
//! intervals, subdivided at the same points in both halves; crossings and interval points
//! are marked kept, so both halves thin their chains without moving the shared vertices.

use glam::DVec2;

use super::centre_loops::KeptLoop;
use super::split::Interface;

/// The two halves' loops (above the cut, then below) and the interface.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CutLoops {
    pub halves: [Vec<KeptLoop>; 2],
    pub interface: CentreInterface,
}

/// The interface of a cut through centre loops: the line and its inside intervals.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CentreInterface {
    y: f64,
    /// Disjoint, sorted by x: (left, right) ends.
    pub intervals: Vec<(f64, f64)>,
}

impl Interface for CentreInterface {
    fn y(&self) -> f64 {
        self.y
    }

    fn is_interface_edge(&self, a: DVec2, b: DVec2) -> bool {
        let mid = (a.x + b.x) / 2.0;
        let at = self.intervals.partition_point(|&(_, right)| right <= mid);
        a.y == self.y && b.y == self.y && self.intervals.get(at).is_some_and(|&(l, _)| l < mid)
    }
}

/// A run of one loop's points on one side of the line, from a crossing to a crossing (both
/// included, as points on the line).
struct Chain {
    below: bool,
    start: usize,
    end: usize,
    points: KeptLoop,
}

/// Cuts `loops` at y = `y` with interface edges at most `density` long; `None` when a point
/// lies on the line or two crossings coincide (the caller then meshes the mask whole).
pub(crate) fn cut_centre_loops(loops: &[KeptLoop], y: f64, density: f64) -> Option<CutLoops> {
    if loops.iter().flat_map(|l| &l.points).any(|p| p.y == y) {
        return None;
    }
    let mut crossings = Vec::new();
    let mut chains = Vec::new();
    let mut halves: [Vec<KeptLoop>; 2] = Default::default();
    for lp in loops.iter().filter(|l| !l.points.is_empty()) {
        if !chains_of(lp, y, &mut crossings, &mut chains) {
            halves[usize::from(lp.points[0].y > y)].push(lp.clone());
        }
    }
    let partner = pair_crossings(&crossings)?;
    for (below, half) in halves.iter_mut().enumerate() {
        let below = below == 1;
        half.extend(join_chains(
            &chains, below, &partner, &crossings, y, density,
        )?);
    }
    let mut intervals: Vec<(f64, f64)> = (0..crossings.len())
        .filter(|&c| crossings[c] < crossings[partner[c]])
        .map(|c| (crossings[c], crossings[partner[c]]))
        .collect();
    intervals.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    Some(CutLoops {
        halves,
        interface: CentreInterface { y, intervals },
    })
}

/// Appends `lp`'s chains and crossings; false when it does not cross the line.
fn chains_of(lp: &KeptLoop, y: f64, crossings: &mut Vec<f64>, chains: &mut Vec<Chain>) -> bool {
    let (points, n) = (&lp.points, lp.points.len());
    let crossing_edges: Vec<usize> = (0..n)
        .filter(|&i| (points[i].y > y) != (points[(i + 1) % n].y > y))
        .collect();
    if crossing_edges.is_empty() {
        return false;
    }
    let first = crossings.len();
    for &i in &crossing_edges {
        let (a, b) = (points[i], points[(i + 1) % n]);
        crossings.push(a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y));
    }
    let m = crossing_edges.len();
    for k in 0..m {
        let (from, to) = (crossing_edges[k], crossing_edges[(k + 1) % m]);
        let (start, end) = (first + k, first + (k + 1) % m);
        let mut chain = KeptLoop::default();
        chain.push(DVec2::new(crossings[start], y), true);
        // The crossing edges are distinct (a closed loop crosses an even number of times).
        let mut v = from;
        loop {
            v = (v + 1) % n;
            chain.extend_from(lp, v..v + 1);
            if v == to {
                break;
            }
        }
        chain.push(DVec2::new(crossings[end], y), true);
        let below = points[(from + 1) % n].y > y;
        chains.push(Chain {
            below,
            start,
            end,
            points: chain,
        });
    }
    true
}

/// Each crossing's partner, the other end of its interval; `None` when two coincide.
fn pair_crossings(crossings: &[f64]) -> Option<Vec<usize>> {
    let mut order: Vec<usize> = (0..crossings.len()).collect();
    order.sort_unstable_by(|&a, &b| crossings[a].total_cmp(&crossings[b]));
    if order.len() % 2 != 0 || order.windows(2).any(|w| crossings[w[0]] == crossings[w[1]]) {
        return None;
    }
    let mut partner = vec![0; crossings.len()];
    for pair in order.chunks_exact(2) {
        partner[pair[0]] = pair[1];
        partner[pair[1]] = pair[0];
    }
    Some(partner)
}

/// The closed loops of one half: each chain, then the interval from its end to the next
/// chain's start. `None` when an interval leads to no chain of this half (loops oriented
/// against the convention).
fn join_chains(
    chains: &[Chain],
    below: bool,
    partner: &[usize],
    crossings: &[f64],
    y: f64,
    density: f64,
) -> Option<Vec<KeptLoop>> {
    let mut starting_at = vec![usize::MAX; crossings.len()];
    for (index, chain) in chains.iter().enumerate() {
        if chain.below == below {
            starting_at[chain.start] = index;
        }
    }
    let mut used = vec![false; chains.len()];
    let mut loops = Vec::new();
    for first in (0..chains.len()).filter(|&c| chains[c].below == below) {
        if used[first] {
            continue;
        }
        let mut out = KeptLoop::default();
        let mut chain = first;
        while !used[chain] {
            used[chain] = true;
            let c = &chains[chain];
            out.extend_from(&c.points, 0..c.points.points.len());
            let next_start = partner[c.end];
            let (from, to) = (crossings[c.end], crossings[next_start]);
            for x in interval_points(from, to, density) {
                out.push(DVec2::new(x, y), true);
            }
            chain = *starting_at.get(next_start).filter(|&&i| i != usize::MAX)?;
        }
        if chain != first {
            return None;
        }
        // The last interval ends on the first chain's start, already the loop's first point.
        loops.push(out);
    }
    Some(loops)
}

/// Points strictly between `from` and `to` splitting the interval into the fewest equal
/// parts at most `density` long, computed from its left end whichever way it runs, so both
/// halves get them bit for bit.
fn interval_points(from: f64, to: f64, density: f64) -> impl Iterator<Item = f64> {
    let (left, right) = (from.min(to), from.max(to));
    let parts = ((right - left) / density).ceil().max(1.0) as usize;
    let at = move |k: usize| left + (right - left) * (k as f64 / parts as f64);
    let ks: Vec<usize> = match from < to {
        true => (1..parts).collect(),
        false => (1..parts).rev().collect(),
    };
    ks.into_iter().map(at)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::centre_loops::outside_centre_points;
    use crate::mesh::{doubled_signed_area, trace_crack_loops, BitMask};

    fn cut(mask: &BitMask, row: usize) -> CutLoops {
        let (loops, _) = outside_centre_points(&trace_crack_loops(mask));
        cut_centre_loops(&loops, row as f64, 3.0).unwrap()
    }

    fn area(loops: &[KeptLoop]) -> f64 {
        loops
            .iter()
            .map(|l| doubled_signed_area(&l.points))
            .sum::<f64>()
            / 2.0
    }

    /// A rectangle cut across: two rectangles of the right areas sharing one interval, whose
    /// ends lie on the left and right centre columns.
    #[test]
    fn a_rectangle_cut_across_gives_two_rectangles_and_one_interval() {
        let mask = BitMask::from_fn(20, 12, |x, y| (2..12).contains(&x) && (2..9).contains(&y));
        let parts = cut(&mask, 5);
        // Centre loop: x from 1.5 to 12.5, y from 1.5 to 9.5.
        assert_eq!(parts.interface.intervals, vec![(1.5, 12.5)]);
        assert_eq!(parts.halves.each_ref().map(|h| h.len()), [1, 1]);
        // The loop cuts each corner pixel diagonally (half a px² off per corner).
        assert_eq!(area(&parts.halves[0]), 11.0 * 3.5 - 1.0);
        assert_eq!(area(&parts.halves[1]), 11.0 * 4.5 - 1.0);
        for half in &parts.halves {
            let on_cut: Vec<f64> = (half[0].points.iter())
                .filter(|p| p.y == 5.0)
                .map(|p| p.x)
                .collect();
            assert_eq!(on_cut.len(), 2 + 3, "{on_cut:?}");
        }
    }

    /// A ring cut through its hole: each half is one loop (a U), and the areas add up.
    #[test]
    fn a_ring_cut_through_its_hole_gives_two_us() {
        let mask = BitMask::from_fn(30, 30, |x, y| {
            let d = ((x as f64 - 15.0).powi(2) + (y as f64 - 15.0).powi(2)).sqrt();
            (6.0..12.0).contains(&d)
        });
        let (loops, _) = outside_centre_points(&trace_crack_loops(&mask));
        let whole = area(&loops);
        let parts = cut(&mask, 15);
        assert_eq!(parts.interface.intervals.len(), 2);
        assert_eq!(parts.halves.each_ref().map(|h| h.len()), [1, 1]);
        let joined = area(&parts.halves[0]) + area(&parts.halves[1]);
        assert!((joined - whole).abs() < 1e-9, "{joined} against {whole}");
        assert!(parts
            .halves
            .iter()
            .flatten()
            .all(|l| doubled_signed_area(&l.points) > 0.0));
    }

    #[test]
    fn interface_edges_are_the_ones_inside_an_interval() {
        let interface = CentreInterface {
            y: 4.0,
            intervals: vec![(1.5, 6.0), (9.0, 12.5)],
        };
        let on = |x0: f64, x1: f64| {
            interface.is_interface_edge(DVec2::new(x0, 4.0), DVec2::new(x1, 4.0))
        };
        assert!(on(1.5, 3.0) && on(6.0, 4.5) && on(11.0, 12.5));
        assert!(!on(6.0, 9.0) && !on(0.0, 1.5) && !on(12.5, 14.0));
        assert!(!interface.is_interface_edge(DVec2::new(2.0, 4.0), DVec2::new(3.0, 4.5)));
    }
}
