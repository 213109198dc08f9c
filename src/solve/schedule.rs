//! Once-per-mesh two-way split of the supernodal solve: takes a factor's
//! [`SupernodePartition`] and gives a [`SolveSchedule`] — two groups of whole
//! elimination-tree subtrees, which the sweeps of
//! [`solve_supernodal`](super::solve_supernodal) take on two threads at once, and the *top*:
//! every supernode above them, which runs alone in between.
//!
//! Why it is race-free. A supernode's panel rows below its own columns are its
//! elimination-tree ancestors, in increasing order. Inside a group subtree those are first
//! ancestors in the same subtree, then (the top being closed upwards) only top supernodes.
//! So a forward panel step writes its group's own rows and top rows; the top rows of group
//! 1 go to a spill buffer instead of `x`, and are added to `x` once both groups are done
//! (group 0 writes its top rows into `x` directly). The backward sweep runs the top first,
//! then both groups, which only read top rows and write their own.
//!
//! Why it is deterministic. The split depends on the pattern alone, and the arithmetic of
//! each group, of the spill and of the merge is the same whether the groups run on one
//! thread or two — so every thread count gives the same bits. The split does change
//! rounding against the unsplit sweep (the top rows sum group 1's terms separately), which
//! is why a pattern either always uses its schedule or never ([`SolveSchedule::plan`]
//! decides from the pattern's size and balance).
//!
//! How it splits. Supernode work is its panel's entry count (what a sweep reads). Starting
//! from the roots, the heaviest remaining subtree moves its root into the top while that
//! lowers the estimated span `top + max(Σ/2, heaviest)`; the remaining subtrees then go to
//! the lighter group, heaviest first.

use super::supernodes::SupernodePartition;
use super::SolveError;
use std::collections::BinaryHeap;

/// Factors smaller than this many entries solve in one piece: below it the thread
/// hand-off costs more than half a solve (a 2k-vertex solve takes ≈ 0.05 ms).
pub const SCHEDULE_MIN_ENTRIES: usize = 1 << 18;

/// A split must promise at least this speed-up on two threads to be used.
const MIN_SPEEDUP: f64 = 1.3;

/// Whether a factor's solve follows a [`SolveSchedule`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SchedulePolicy {
    /// When the factor is large and its tree wide enough ([`SolveSchedule::plan`]).
    #[default]
    Auto,
    /// Never: one sweep over all supernodes.
    Never,
    /// Always, however small or narrow (tests use it to exercise the split on small
    /// meshes).
    Always,
}

/// Marks a supernode of the top in [`SolveSchedule::group_of`].
const TOP: u8 = 2;

/// The two-way split of one factor pattern (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SolveSchedule {
    /// Supernodes of each group, ascending (every child before its parent).
    groups: [Vec<u32>; 2],
    /// Supernodes of the top, ascending.
    top: Vec<u32>,
    /// Per supernode: 0 or 1 for a group, [`TOP`] for the top.
    group_of: Vec<u8>,
    /// Per supernode: panel rows (its columns included) that belong to its own group;
    /// the rest are top rows. A top supernode owns all its rows.
    own_rows: Vec<u32>,
    /// Work (panel entries) of group 0, group 1 and the top.
    work: [u64; 3],
}

impl SolveSchedule {
    /// The schedule of a factor pattern with `nnz` entries, or `None` when the factor is too
    /// small or its elimination tree too narrow for two threads to pay off.
    pub fn plan(partition: &SupernodePartition, nnz: usize) -> Option<Self> {
        if nnz < SCHEDULE_MIN_ENTRIES {
            return None;
        }
        let schedule = Self::split(partition);
        let [a, b, top] = schedule.work;
        let span = a.max(b) + top;
        let speedup = (a + b + top) as f64 / span.max(1) as f64;
        (speedup >= MIN_SPEEDUP).then_some(schedule)
    }

    /// The schedule `policy` asks for (see [`SchedulePolicy`]).
    pub fn choose(
        policy: SchedulePolicy,
        partition: &SupernodePartition,
        nnz: usize,
    ) -> Option<Self> {
        match policy {
            SchedulePolicy::Auto => Self::plan(partition, nnz),
            SchedulePolicy::Never => None,
            SchedulePolicy::Always => Some(Self::split(partition)),
        }
    }

    /// The split itself, whatever its balance (tests use it on small patterns).
    pub fn split(partition: &SupernodePartition) -> Self {
        let tree = Tree::new(partition);
        let (top, roots) = tree.choose_top();
        let mut group_of = vec![TOP; tree.count()];
        let mut work = [0u64; 3];
        let mut order: Vec<(u64, u32)> =
            roots.iter().map(|&r| (tree.subtree[r], r as u32)).collect();
        // Heaviest first, ties by index: the same pattern always splits the same way.
        order.sort_unstable_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
        for (weight, root) in order {
            let g = usize::from(work[1] < work[0]);
            work[g] += weight;
            tree.mark_subtree(root as usize, g as u8, &mut group_of);
        }
        work[2] = top.iter().map(|&s| tree.work[s as usize]).sum();
        let groups = [0u8, 1].map(|g| {
            (0..tree.count() as u32)
                .filter(|&s| group_of[s as usize] == g)
                .collect()
        });
        let mut top: Vec<u32> = top.into_iter().collect();
        top.sort_unstable();
        let own_rows = (0..tree.count())
            .map(|s| {
                let rows = partition.panel_rows(s);
                let g = group_of[s];
                let own = rows
                    .iter()
                    .take_while(|&&r| g == TOP || group_of[tree.owner[r as usize] as usize] == g)
                    .count();
                own as u32
            })
            .collect();
        Self {
            groups,
            top,
            group_of,
            own_rows,
            work,
        }
    }

    /// Supernodes of group `g` (0 or 1), ascending.
    pub fn group(&self, g: usize) -> &[u32] {
        &self.groups[g]
    }

    /// Supernodes of the top, ascending.
    pub fn top(&self) -> &[u32] {
        &self.top
    }

    /// Panel rows of supernode `s` that its own group writes (the rest are top rows).
    pub fn own_rows(&self, s: usize) -> usize {
        self.own_rows[s] as usize
    }

    /// Panel entries of group 0, group 1 and the top.
    pub fn work(&self) -> [u64; 3] {
        self.work
    }

    /// Checks what the threaded sweeps rely on for freedom from races: every supernode is in
    /// exactly one part, each list ascending, the top closed upwards, and every group
    /// panel's rows are its own group's rows up to `own_rows`, top rows after.
    pub fn sanity_check(&self, partition: &SupernodePartition) -> Result<(), SolveError> {
        let broken = |m: String| Err(SolveError::Symbolic(format!("solve schedule: {m}")));
        let count = partition.count();
        if self.group_of.len() != count || self.own_rows.len() != count {
            return broken("wrong number of supernodes".into());
        }
        let lists = [&self.groups[0], &self.groups[1], &self.top];
        for (part, list) in lists.iter().enumerate() {
            if list.windows(2).any(|w| w[0] >= w[1]) {
                return broken(format!("part {part} is not ascending"));
            }
            if list
                .iter()
                .any(|&s| self.group_of.get(s as usize) != Some(&(part as u8)))
            {
                return broken(format!("part {part} disagrees with the membership"));
            }
        }
        if lists.iter().map(|l| l.len()).sum::<usize>() != count {
            return broken("parts do not cover every supernode".into());
        }
        let owner = column_owners(partition);
        for s in 0..count {
            let rows = partition.panel_rows(s);
            let own = self.own_rows[s] as usize;
            let width = partition.columns(s).len();
            let part_of = |r: &u32| self.group_of[owner[*r as usize] as usize];
            let g = self.group_of[s];
            if own < width || own > rows.len() || (g == TOP && own != rows.len()) {
                return broken(format!("supernode {s} owns {own} of {} rows", rows.len()));
            }
            if rows[..own].iter().any(|r| part_of(r) != g) {
                return broken(format!("supernode {s} writes another group's rows"));
            }
            if rows[own..].iter().any(|r| part_of(r) != TOP) {
                return broken(format!("supernode {s} spills outside the top"));
            }
        }
        Ok(())
    }
}

/// `owner[column]` = the supernode holding that column.
fn column_owners(partition: &SupernodePartition) -> Vec<u32> {
    let mut owner = Vec::new();
    for s in 0..partition.count() {
        owner.extend(partition.columns(s).map(|_| s as u32));
    }
    owner
}

/// The supernodal elimination tree with per-node and per-subtree work.
struct Tree {
    owner: Vec<u32>,
    work: Vec<u64>,
    subtree: Vec<u64>,
    /// Children of `s` are `children[child_ptr[s]..child_ptr[s + 1]]`.
    child_ptr: Vec<u32>,
    children: Vec<u32>,
    roots: Vec<usize>,
}

impl Tree {
    fn new(partition: &SupernodePartition) -> Self {
        let count = partition.count();
        let owner = column_owners(partition);
        let parent: Vec<Option<usize>> = (0..count)
            .map(|s| {
                let width = partition.columns(s).len();
                partition
                    .panel_rows(s)
                    .get(width)
                    .map(|&r| owner[r as usize] as usize)
            })
            .collect();
        let work: Vec<u64> = (0..count)
            .map(|s| {
                let (w, h) = (
                    partition.columns(s).len() as u64,
                    partition.panel_rows(s).len() as u64,
                );
                w * h - w * (w - 1) / 2
            })
            .collect();
        // A parent's columns follow its children's, so one ascending pass sums subtrees.
        let mut subtree = work.clone();
        let mut child_count = vec![0u32; count + 1];
        for s in 0..count {
            if let Some(p) = parent[s] {
                subtree[p] += subtree[s];
                child_count[p + 1] += 1;
            }
        }
        let mut child_ptr = child_count;
        for s in 0..count {
            child_ptr[s + 1] += child_ptr[s];
        }
        let mut fill = child_ptr.clone();
        let mut children = vec![0u32; child_ptr[count] as usize];
        for (s, p) in parent.iter().enumerate() {
            if let Some(p) = *p {
                children[fill[p] as usize] = s as u32;
                fill[p] += 1;
            }
        }
        let roots = (0..count).filter(|&s| parent[s].is_none()).collect();
        Self {
            owner,
            work,
            subtree,
            child_ptr,
            children,
            roots,
        }
    }

    fn count(&self) -> usize {
        self.work.len()
    }

    fn children(&self, s: usize) -> impl Iterator<Item = usize> + '_ {
        self.children[self.child_ptr[s] as usize..self.child_ptr[s + 1] as usize]
            .iter()
            .map(|&c| c as usize)
    }

    /// Moves the heaviest subtree's root into the top while the estimated span
    /// `top + max(Σ/2, heaviest)` of the remaining subtrees drops; gives the top and the
    /// remaining roots at the best point.
    fn choose_top(&self) -> (Vec<u32>, Vec<usize>) {
        let mut heap: BinaryHeap<(u64, std::cmp::Reverse<usize>)> = self
            .roots
            .iter()
            .map(|&r| (self.subtree[r], std::cmp::Reverse(r)))
            .collect();
        let mut below: u64 = heap.iter().map(|e| e.0).sum();
        let (mut top, mut top_work) = (Vec::new(), 0u64);
        let span = |top_work: u64, below: u64, heaviest: u64| top_work + (below / 2).max(heaviest);
        let mut best = (span(0, below, heap.peek().map_or(0, |e| e.0)), 0usize);
        while let Some((_, std::cmp::Reverse(s))) = heap.pop() {
            top.push(s as u32);
            top_work += self.work[s];
            below -= self.work[s];
            for c in self.children(s) {
                heap.push((self.subtree[c], std::cmp::Reverse(c)));
            }
            let here = span(top_work, below, heap.peek().map_or(0, |e| e.0));
            if here < best.0 {
                best = (here, top.len());
            }
            if top_work >= best.0 {
                break;
            }
        }
        top.truncate(best.1);
        let in_top: std::collections::HashSet<u32> = top.iter().copied().collect();
        let mut roots = Vec::new();
        for &r in &self.roots {
            self.collect_roots(r, &in_top, &mut roots);
        }
        (top, roots)
    }

    /// The subtrees hanging below the top under `s` (`s` itself if it is not in the top).
    fn collect_roots(
        &self,
        s: usize,
        in_top: &std::collections::HashSet<u32>,
        out: &mut Vec<usize>,
    ) {
        let mut stack = vec![s];
        while let Some(s) = stack.pop() {
            if in_top.contains(&(s as u32)) {
                stack.extend(self.children(s));
            } else {
                out.push(s);
            }
        }
    }

    fn mark_subtree(&self, root: usize, group: u8, group_of: &mut [u8]) {
        let mut stack = vec![root];
        while let Some(s) = stack.pop() {
            group_of[s] = group;
            stack.extend(self.children(s));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::symbolic::SymbolicFactor;
    use crate::solve::{fixtures, laplacian, LaplacianKind};

    fn disc_partition() -> SupernodePartition {
        let l = laplacian(&fixtures::disc(12), LaplacianKind::Combinatorial);
        SymbolicFactor::analyse(&l).unwrap().supernodes().clone()
    }

    #[test]
    fn the_race_check_rejects_a_group_panel_writing_top_rows_in_place() {
        let partition = disc_partition();
        let mut schedule = SolveSchedule::split(&partition);
        schedule.sanity_check(&partition).unwrap();
        let spilling = (0..partition.count())
            .find(|&s| {
                schedule.group_of[s] != TOP
                    && (schedule.own_rows[s] as usize) < partition.panel_rows(s).len()
            })
            .expect("some group panel spills into the top");
        schedule.own_rows[spilling] += 1;
        assert!(schedule.sanity_check(&partition).is_err());
    }

    #[test]
    fn the_race_check_rejects_a_supernode_in_the_wrong_group() {
        let partition = disc_partition();
        let mut schedule = SolveSchedule::split(&partition);
        let moved = schedule.groups[0].pop().expect("group 0 is not empty");
        schedule.groups[1].push(moved);
        schedule.groups[1].sort_unstable();
        assert!(schedule.sanity_check(&partition).is_err());
        schedule.group_of[moved as usize] = 1;
        // Now consistent as lists, but the moved subtree root's children still write its
        // rows from group 0.
        assert!(schedule.sanity_check(&partition).is_err());
    }
}
