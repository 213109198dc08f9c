//! Rank-1 modification of a simplicial LDLᵀ factor, in place: takes the factor (faer layout,
//! see [`symbolic`](super::symbolic)), a position `p` and a weight `σ`, and turns the factor of
//! `A` into the factor of `A + σ e_p e_pᵀ` (σ > 0 update, σ < 0 downdate).
//!
//! Algorithm: method C1 of Gill, Golub, Murray & Saunders (1974) in the sparse form of Davis &
//! Hager (1999): with `w = e_p`, for each column `j` on the elimination-tree path from `p`
//! (parent = first off-diagonal row),
//! `d̄_j = d_j + σ w_j²`, `γ = σ w_j / d̄_j`, `σ ← σ d_j / d̄_j`, and for rows `i` below the
//! diagonal `w_i ← w_i − w_j l_ij`, `l_ij ← l_ij + γ w_i`. The pattern of `w` stays inside the
//! path, so only path columns are touched and the dense scratch `w` returns to all zeros.

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
/// The pattern must satisfy the layout contract checked by
/// [`SymbolicFactor::check_layout`](super::symbolic::SymbolicFactor::check_layout).
pub fn rank1_diagonal(
    col_ptr: &[u32],
    row_idx: &[u32],
    values: &mut [f64],
    w: &mut [f64],
    p: usize,
    sigma: f64,
    floor: f64,
) -> Rank1Outcome {
    let n = w.len();
    assert!(p < n && col_ptr.len() == n + 1 && values.len() == row_idx.len());
    let mut amplification: f64 = 1.0;
    let mut sigma = sigma;
    let mut j = p;
    w[p] = 1.0;
    loop {
        let start = col_ptr[j] as usize;
        let end = col_ptr[j + 1] as usize;
        let wj = w[j];
        w[j] = 0.0;
        let d = values[start];
        let d_bar = d + sigma * wj * wj;
        if !(d_bar > floor) {
            clear_path(col_ptr, row_idx, w, j);
            return Rank1Outcome::PivotLost;
        }
        if sigma < 0.0 {
            amplification = amplification.max(d / d_bar);
        }
        let gamma = sigma * wj / d_bar;
        sigma *= d / d_bar;
        values[start] = d_bar;
        let rows = &row_idx[start + 1..end];
        let vals = &mut values[start + 1..end];
        for (&i, l) in rows.iter().zip(vals.iter_mut()) {
            // SAFETY: the layout check guarantees every row index is < n = w.len().
            let wi = unsafe { w.get_unchecked_mut(i as usize) };
            *wi -= wj * *l;
            *l += gamma * *wi;
        }
        match rows.first() {
            Some(&parent) => j = parent as usize,
            None => return Rank1Outcome::Done { amplification },
        }
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
