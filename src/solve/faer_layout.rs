//! The contract between faer and this crate's kernels, in one place: takes faer's symbolic
//! (and, after a numeric factorisation, supernodal) LDLᵀ factor and gives the one column
//! layout that the rank-1 kernel ([`update`](super::update)) and the solves
//! ([`solve_supernodal`](super::solve_supernodal), [`solve`](mod@super::solve)) read and
//! write; `check` verifies it for every analysed pattern.
//!
//! Layout: column `j` of the factor occupies `col_ptr[j]..col_ptr[j+1]`; its first entry has
//! row `j` and holds `D_jj`; the remaining rows are strictly increasing and hold `L_ij`, so
//! the first of them is the elimination-tree parent of `j`; and patterns nest along the
//! tree: every row of column `j` below its parent also occurs in the parent's column.
//!
//! What is read of faer (pinned `=0.24.4` in Cargo.toml): a simplicial factor's
//! `col_ptr`/`row_idx`/values are this layout as they stand. A supernodal factor's
//! supernode `s` covers columns `begin..end`; its values are one column-major
//! `(ncols + |P|) × ncols` block whose top square holds `D` on the diagonal and unit-lower
//! `L` below it, the bottom `|P|` rows — the supernode's pattern `P` — holding `L`. Column
//! `j` then gets the rows `j..end` of the diagonal block followed by `P` (`columns`), and
//! `compact_supernodes` moves the values there in place after each factorisation.
//! Relaxed supernodes store explicit zeros, which the kernels carry along harmlessly (they
//! stay exactly zero). `tests/solve_layout.rs` rebuilds `L·D·Lᵀ` from the converted values
//! and compares it with the matrix, so an upgrade that changes any of this fails there.

use super::supernodes::SupernodePartition;
use super::SolveError;
use faer::sparse::linalg::cholesky::{
    supernodal::SymbolicSupernodalCholesky, SymbolicCholesky, SymbolicCholeskyRaw,
};

/// The column pattern (`col_ptr`, `row_idx`) of faer's symbolic factor in this layout.
pub(super) fn columns(faer: &SymbolicCholesky<u32>) -> Result<(Vec<u32>, Vec<u32>), SolveError> {
    let s = match faer.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            return Ok((s.col_ptr().to_vec(), s.row_idx().to_vec()))
        }
        SymbolicCholeskyRaw::Supernodal(s) => s,
    };
    let n = s.nrows();
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0u32);
    let mut row_idx = Vec::new();
    for sn in 0..s.n_supernodes() {
        let (begin, end) = supernode_columns(s, sn);
        let pattern = s.supernode(sn).pattern();
        for j in begin..end {
            row_idx.extend(j as u32..end as u32);
            row_idx.extend_from_slice(pattern);
            let len = u32::try_from(row_idx.len()).map_err(|_| SolveError::TooLarge(n))?;
            col_ptr.push(len);
        }
    }
    Ok((col_ptr, row_idx))
}

/// `begin..end` of supernode `sn`.
fn supernode_columns(s: &SymbolicSupernodalCholesky<u32>, sn: usize) -> (usize, usize) {
    (
        s.supernode_begin()[sn] as usize,
        s.supernode_end()[sn] as usize,
    )
}

/// Moves each supernode's columns, minus the zero upper triangle of its diagonal block, to
/// the column layout `col_ptr`. Destinations never pass their sources ([`check`] verifies
/// it), so one forward pass works in place.
pub(super) fn compact_supernodes(
    s: &SymbolicSupernodalCholesky<u32>,
    col_ptr: &[u32],
    values: &mut [f64],
) {
    for sn in 0..s.n_supernodes() {
        let (begin, end) = supernode_columns(s, sn);
        let nrows = end - begin + s.supernode(sn).pattern().len();
        let block_start = s.col_ptr_for_val()[sn] as usize;
        for c in 0..end - begin {
            let source = block_start + c * nrows + c;
            values.copy_within(source..source + nrows - c, col_ptr[begin + c] as usize);
        }
    }
}

/// What [`check`] reads of an analysed pattern: faer's symbolic factor, the columns in this
/// module's layout, the ordering and the supernodes found in it.
pub(super) struct Analysed<'a> {
    pub faer: &'a SymbolicCholesky<u32>,
    pub col_ptr: &'a [u32],
    pub row_idx: &'a [u32],
    pub perm_fwd: &'a [u32],
    pub perm_inv: &'a [u32],
    pub supernodes: &'a SupernodePartition,
}

/// Verifies the layout (module doc) of an analysed pattern; an error means the pinned faer
/// version changed its representation.
pub(super) fn check(symbolic: Analysed) -> Result<(), SolveError> {
    let (col_ptr, row_idx) = (symbolic.col_ptr, symbolic.row_idx);
    let n = col_ptr.len().saturating_sub(1);
    let broken = |m: String| {
        Err(SolveError::Symbolic(format!(
            "unexpected faer factor layout: {m}"
        )))
    };
    if col_ptr.len() != n + 1 || col_ptr[n] as usize != row_idx.len() {
        return broken("column pointers".into());
    }
    for j in 0..n {
        let rows = &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize];
        if rows.first() != Some(&(j as u32)) {
            return broken(format!("column {j} does not start with its diagonal"));
        }
        if rows.windows(2).any(|w| w[0] >= w[1]) || rows.iter().any(|&r| r as usize >= n) {
            return broken(format!("column {j} rows not strictly increasing in range"));
        }
        if let Some(&parent) = rows.get(1) {
            let parent = parent as usize;
            let parent_rows = &row_idx[col_ptr[parent] as usize..col_ptr[parent + 1] as usize];
            if !is_sorted_subset(&rows[2..], &parent_rows[1..]) {
                return broken(format!("column {j} is not nested in its parent {parent}"));
            }
        }
    }
    let (fwd, inv) = (symbolic.perm_fwd, symbolic.perm_inv);
    if fwd.len() != n
        || inv.len() != n
        || fwd
            .iter()
            .enumerate()
            .any(|(pos, &v)| v as usize >= n || inv[v as usize] as usize != pos)
    {
        return broken("permutation is not a bijection".into());
    }
    symbolic.supernodes.sanity_check(col_ptr, row_idx)?;
    if let SymbolicCholeskyRaw::Supernodal(s) = symbolic.faer.raw() {
        for sn in 0..s.n_supernodes() {
            let (begin, end) = supernode_columns(s, sn);
            let ncols = end - begin;
            let nrows = ncols + s.supernode(sn).pattern().len();
            let block = s.col_ptr_for_val()[sn] as usize..s.col_ptr_for_val()[sn + 1] as usize;
            if block.len() != nrows * ncols || col_ptr[begin] as usize > block.start {
                return broken(format!("supernode {sn} value block"));
            }
        }
    }
    Ok(())
}

/// Whether every element of the increasing `part` occurs in the increasing `whole`.
fn is_sorted_subset(part: &[u32], whole: &[u32]) -> bool {
    let mut rest = whole.iter();
    part.iter().all(|p| rest.any(|w| w == p))
}
