//! Once-per-mesh supernode partition of a factor pattern: takes the column layout of
//! [`symbolic`](super::symbolic) (`col_ptr`, `row_idx`) and gives the maximal runs of
//! columns that share their row pattern below a dense diagonal block, which the supernodal
//! solve ([`solve_supernodal`](super::solve_supernodal)) treats as dense panels.
//!
//! A supernode covers columns `b..e` (width `w = e − b`) when each column `j + 1` of the run
//! has exactly the rows of column `j` minus `j` itself; column `b` then holds rows
//! `b, b+1, …, e−1` followed by the shared off-diagonal pattern `P`, and column `j` holds
//! rows `j..e` then `P`. Its values are therefore a lower-trapezoidal panel of height
//! `w + |P|`: entry (row `r`, column `t`) of the panel, `r ≥ t`, sits at
//! `values[col_ptr[b + t] + r − t]` — a dense column-major block with per-column offsets, no
//! copy. The detection reads the pattern only, so it finds faer's fundamental supernodes
//! on a simplicial or fundamental factor and the relaxed ones (explicit zeros included) on
//! a relaxed factor alike. The values stay in the column layout, which the rank-1 kernel
//! updates in place, so the partition never goes stale.
//!
//! The partition also keeps a compact copy of every panel's row indices (its first
//! column's pattern), one supernode after another: the solve reads only those, and reading
//! them from `row_idx` would skip through it (the other columns' indices are not needed),
//! defeating the hardware prefetcher — a measured stall on every new panel.

use super::SolveError;

/// Supernode boundaries of one factor pattern (see the module doc).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SupernodePartition {
    /// Supernode `s` covers columns `begin[s]..begin[s + 1]`; `begin[0] = 0`, last = n.
    begin: Vec<u32>,
    /// Largest panel height `w + |P|` over all supernodes.
    max_height: usize,
    /// Panel rows of supernode `s` are `rows[row_begin[s]..row_begin[s + 1]]`.
    row_begin: Vec<u32>,
    rows: Vec<u32>,
}

impl SupernodePartition {
    /// Detects the maximal supernodes of the pattern `(col_ptr, row_idx)`, which must satisfy
    /// the layout contract of [`symbolic`](super::symbolic) (every column starts with its
    /// diagonal, rows strictly increasing).
    pub fn detect(col_ptr: &[u32], row_idx: &[u32]) -> Self {
        let n = col_ptr.len().saturating_sub(1);
        let column = |j: usize| &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize];
        let mut begin = vec![0u32];
        let (mut row_begin, mut rows) = (vec![0u32], Vec::new());
        let mut max_height = 0;
        let mut first = 0;
        for j in 0..n {
            let continues = j + 1 < n && column(j + 1) == &column(j)[1..];
            if !continues {
                max_height = max_height.max(column(first).len());
                rows.extend_from_slice(column(first));
                // invariant: Σ panel heights ≤ nnz, which fits u32 (checked by the caller's layout).
                row_begin
                    .push(u32::try_from(rows.len()).expect("panel rows fit u32 like the pattern"));
                begin.push((j + 1) as u32);
                first = j + 1;
            }
        }
        Self {
            begin,
            max_height,
            row_begin,
            rows,
        }
    }

    /// Panel rows of supernode `s`: its columns, then the shared pattern.
    pub fn panel_rows(&self, s: usize) -> &[u32] {
        &self.rows[self.row_begin[s] as usize..self.row_begin[s + 1] as usize]
    }

    /// Start of every supernode's panel rows in [`all_panel_rows`](Self::all_panel_rows),
    /// followed by their total.
    pub fn panel_row_begins(&self) -> &[u32] {
        &self.row_begin
    }

    /// All panel rows, supernode after supernode.
    pub fn all_panel_rows(&self) -> &[u32] {
        &self.rows
    }

    /// Number of supernodes.
    pub fn count(&self) -> usize {
        self.begin.len() - 1
    }

    /// First column of every supernode, followed by n.
    pub fn begins(&self) -> &[u32] {
        &self.begin
    }

    /// Columns `b..e` of supernode `s`.
    pub fn columns(&self, s: usize) -> std::ops::Range<usize> {
        self.begin[s] as usize..self.begin[s + 1] as usize
    }

    /// Largest panel height (`w + |P|`) of any supernode; 0 for an empty pattern.
    pub fn max_height(&self) -> usize {
        self.max_height
    }

    /// Checks that the partition covers `0..n` in order and that every supernode is a run
    /// of the kind the module doc describes in the pattern `(col_ptr, row_idx)`, and that no
    /// two neighbouring supernodes could be merged (maximality).
    pub fn sanity_check(&self, col_ptr: &[u32], row_idx: &[u32]) -> Result<(), SolveError> {
        let n = col_ptr.len().saturating_sub(1);
        let broken = |m: String| Err(SolveError::Symbolic(format!("supernode partition: {m}")));
        if self.begin.first() != Some(&0) || self.begin.last().map(|&e| e as usize) != Some(n) {
            return broken("does not cover all columns".into());
        }
        if self.begin.windows(2).any(|w| w[0] >= w[1]) && n > 0 {
            return broken("empty or unordered supernode".into());
        }
        let row_begin_ok = self.row_begin.len() == self.begin.len()
            && self.row_begin.first() == Some(&0)
            && self.row_begin.last().map(|&e| e as usize) == Some(self.rows.len())
            && self.row_begin.windows(2).all(|w| w[0] <= w[1]);
        if !row_begin_ok {
            return broken("panel row offsets are inconsistent".into());
        }
        let column = |j: usize| &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize];
        let mut max_height = 0;
        for s in 0..self.count() {
            let columns = self.columns(s);
            let (b, e) = (columns.start, columns.end);
            let head = column(b);
            if head.len() < e - b || !head.iter().take(e - b).copied().eq(b as u32..e as u32) {
                return broken(format!("supernode {s} lacks a dense diagonal block"));
            }
            for j in columns.clone() {
                if column(j) != &head[j - b..] {
                    return broken(format!("column {j} differs from supernode {s}'s pattern"));
                }
            }
            if e < n && column(e) == &column(e - 1)[1..] {
                return broken(format!("supernode {s} is not maximal"));
            }
            if self.panel_rows(s) != head {
                return broken(format!("supernode {s}'s panel rows are stale"));
            }
            max_height = max_height.max(head.len());
        }
        if max_height != self.max_height {
            return broken("max_height is stale".into());
        }
        Ok(())
    }
}
