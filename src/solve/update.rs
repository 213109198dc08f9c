//! Rank-1 modification of a simplicial LDLᵀ factor, in place: takes the factor (faer layout,
//! see [`faer_layout`](super::faer_layout)), a position `p` and a weight `σ`, and turns the factor of
//! `A` into the factor of `A + σ e_p e_pᵀ` (σ > 0 update, σ < 0 downdate).
//!
//! Algorithm: method C1 of Gill, Golub, Murray & Saunders (1974) in the sparse form of Davis &
//! Hager (1999): with `w = e_p`, for each column `j` on the elimination-tree path from `p`
//! (parent = first off-diagonal row),
//! `d̄_j = d_j + σ w_j²`, `γ = σ w_j / d̄_j`, `σ ← σ d_j / d̄_j`, and for rows `i` below the
//! diagonal `w_i ← w_i − w_j l_ij`, `l_ij ← l_ij + γ w_i`. The pattern of `w` stays inside the
//! path, so only path columns are touched and the dense scratch `w` returns to all zeros.
//!
//! Exact pivot on downdates: removing a penalty α from a pivot `d_p ≈ α + d₀` by subtraction
//! would lose `log10(α / d₀)` digits. Instead the caller may pass the new pivot computed
//! directly from row p of the factor, `d̄_p = a'_pp − Σ_{k<p} l_pk² d_k` (row p lives in
//! columns k < p, which the modification does not touch), see [`pivot_from_row`]. The
//! first step then uses `σ = d̄_p − d_p` rather than −α, so the represented matrix loses
//! exactly what the stored pivot holds beyond the exact one (α plus accumulated rounding).

/// Outcome of one rank-1 modification.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rank1Outcome {
    /// Done; `amplification = max d_j / d̄_j` over the path for a downdate (1 for an update),
    /// i.e. the factor by which cancellation magnified rounding errors.
    Done { amplification: f64 },
    /// A pivot would have fallen to `floor` or below; the factor is now inconsistent and must
    /// be refactored.
    PivotLost,
}

/// Applies `A + σ e_p e_pᵀ` to the factor `(col_ptr, row_idx, values)`.
/// `w` is an all-zero scratch of length n and is all-zero again on return.
///
/// The pattern must satisfy the layout contract of [`faer_layout`](super::faer_layout).
#[allow(clippy::too_many_arguments)]
pub fn rank1_diagonal(
    col_ptr: &[u32],
    row_idx: &[u32],
    values: &mut [f64],
    w: &mut [f64],
    p: usize,
    sigma: f64,
    floor: f64,
    exact_first_pivot: Option<f64>,
) -> Rank1Outcome {
    let n = w.len();
    assert!(p < n && col_ptr.len() == n + 1 && values.len() == row_idx.len());
    let mut amplification: f64 = 1.0;
    let mut sigma = sigma;
    let mut j = p;
    w[p] = 1.0;
    let mut exact = exact_first_pivot;
    loop {
        let start = col_ptr[j] as usize;
        let end = col_ptr[j + 1] as usize;
        let wj = w[j];
        w[j] = 0.0;
        let d = values[start];
        let d_bar = match exact.take() {
            // w_p = 1: the σ that moves the *stored* d_p exactly onto the exact pivot, which
            // keeps column p consistent (l̄_ip d̄_p = l_ip d_p) and absorbs earlier rounding.
            Some(exact_pivot) => {
                sigma = exact_pivot - d;
                exact_pivot
            }
            None => d + sigma * wj * wj,
        };
        // NaN-safe: a NaN pivot is lost too.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(d_bar > floor) {
            clear_path(col_ptr, row_idx, w, j);
            return Rank1Outcome::PivotLost;
        }
        if sigma < 0.0 && j != p {
            amplification = amplification.max(d / d_bar);
        }
        let gamma = sigma * wj / d_bar;
        sigma *= d / d_bar;
        values[start] = d_bar;
        let rows = &row_idx[start + 1..end];
        let vals = &mut values[start + 1..end];
        if j == p {
            first_column(rows, vals, w, d / d_bar);
        } else {
            column_step(rows, vals, w, wj, gamma);
        }
        match rows.first() {
            Some(&parent) => j = parent as usize,
            None => return Rank1Outcome::Done { amplification },
        }
    }
}

/// The first column, where w = e_p: l̄_ip = l_ip (1 − γ) = l_ip d_p / d̄_p, written as the
/// ratio d_p / d̄_p because 1 − γ cancels catastrophically when σ ≫ d_p (a penalty update).
#[inline(always)]
fn first_column(rows: &[u32], vals: &mut [f64], w: &mut [f64], ratio: f64) {
    for (&i, l) in rows.iter().zip(vals.iter_mut()) {
        w[i as usize] = -*l;
        *l *= ratio;
    }
}

/// The C1 inner loop for one column below the diagonal.
#[inline(always)]
fn column_step(rows: &[u32], vals: &mut [f64], w: &mut [f64], wj: f64, gamma: f64) {
    for (&i, l) in rows.iter().zip(vals.iter_mut()) {
        let wi = &mut w[i as usize];
        *wi -= wj * *l;
        *l += gamma * *wi;
    }
}

/// Zeroes `w` on the path from `j` upwards after an aborted modification.
fn clear_path(col_ptr: &[u32], row_idx: &[u32], w: &mut [f64], mut j: usize) {
    loop {
        let (start, end) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
        w[j] = 0.0;
        for &i in &row_idx[start + 1..end] {
            w[i as usize] = 0.0;
        }
        if end == start + 1 {
            return;
        }
        j = row_idx[start + 1] as usize;
    }
}

/// Scratch for [`pivot_from_row`], reused across calls (no allocation per call).
#[derive(Clone, Debug, Default)]
pub struct RowScratch {
    stamp: Vec<u32>,
    current: u32,
}

impl RowScratch {
    pub fn new(n: usize) -> Self {
        Self {
            stamp: vec![0; n],
            current: 0,
        }
    }
}

/// `a_pp − Σ_{k<p} l_pk² d_k`: the pivot of position `p` for diagonal value `a_pp`, from row p
/// of the factor. The row pattern is the elimination-tree reach of the positions
/// `neighbours` (the positions < p of column p of the permuted matrix).
pub fn pivot_from_row(
    col_ptr: &[u32],
    row_idx: &[u32],
    values: &[f64],
    p: usize,
    a_pp: f64,
    neighbours: impl Iterator<Item = usize>,
    scratch: &mut RowScratch,
) -> f64 {
    scratch.current = scratch.current.wrapping_add(1);
    if scratch.current == 0 {
        scratch.stamp.iter_mut().for_each(|s| *s = 0);
        scratch.current = 1;
    }
    let mark = scratch.current;
    let mut pivot = a_pp;
    for start_node in neighbours.filter(|&i| i < p) {
        let mut k = start_node;
        // Walk up the elimination tree until p or an already-visited node.
        while k < p && scratch.stamp[k] != mark {
            scratch.stamp[k] = mark;
            let (start, end) = (col_ptr[k] as usize, col_ptr[k + 1] as usize);
            let rows = &row_idx[start + 1..end];
            if let Ok(offset) = rows.binary_search(&(p as u32)) {
                let l_pk = values[start + 1 + offset];
                pivot -= l_pk * l_pk * values[start];
            }
            match rows.first() {
                Some(&parent) => k = parent as usize,
                None => break,
            }
        }
    }
    pivot
}
