//! Forward and back substitution with a simplicial LDLᵀ factor: takes the factor (faer layout,
//! see [`symbolic`](super::symbolic)) and `k` right-hand sides stored *interleaved*
//! (`x[i * k + c]`, row-major n×k, already permuted), and overwrites them with the solution of
//! `L D Lᵀ x = b`. Interleaving makes each factor entry drive all k channels at once.
//! No allocation. The reference kernel: [`PenaltyFactor`](super::PenaltyFactor) solves with
//! [`solve_supernodal`](super::solve_supernodal), which tests compare against this one.

/// Solves in place. The pattern must satisfy the layout contract checked by
/// [`SymbolicFactor::check_layout`](super::symbolic::SymbolicFactor::check_layout).
pub fn ldlt_solve_interleaved(
    col_ptr: &[u32],
    row_idx: &[u32],
    values: &[f64],
    x: &mut [f64],
    k: usize,
) {
    let n = col_ptr.len() - 1;
    assert!(x.len() == n * k && values.len() == row_idx.len());
    match k {
        0 => {}
        1 => solve_fixed::<1>(col_ptr, row_idx, values, x),
        2 => solve_fixed::<2>(col_ptr, row_idx, values, x),
        3 => solve_fixed::<3>(col_ptr, row_idx, values, x),
        4 => solve_fixed::<4>(col_ptr, row_idx, values, x),
        _ => solve_general(col_ptr, row_idx, values, x, k),
    }
}

#[inline(always)]
fn solve_fixed<const K: usize>(col_ptr: &[u32], row_idx: &[u32], values: &[f64], x: &mut [f64]) {
    let n = col_ptr.len() - 1;
    let xp = x.as_mut_ptr();
    // Forward: L y = b, column by column.
    for j in 0..n {
        let (start, end) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
        // SAFETY: j < n and x.len() == n * K.
        let xj: [f64; K] = unsafe { *(xp.add(j * K) as *const [f64; K]) };
        for (&i, &l) in row_idx[start + 1..end].iter().zip(&values[start + 1..end]) {
            // SAFETY: the layout check guarantees i < n, and i != j (i > j).
            let xi = unsafe { &mut *(xp.add(i as usize * K) as *mut [f64; K]) };
            for c in 0..K {
                xi[c] -= l * xj[c];
            }
        }
    }
    // Diagonal and backward: x_j = y_j / d_j − Σ_{i>j} l_ij x_i.
    for j in (0..n).rev() {
        let (start, end) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
        let inv_d = 1.0 / values[start];
        let mut acc = [0.0f64; K];
        for (&i, &l) in row_idx[start + 1..end].iter().zip(&values[start + 1..end]) {
            // SAFETY: as above.
            let xi = unsafe { &*(xp.add(i as usize * K) as *const [f64; K]) };
            for c in 0..K {
                acc[c] += l * xi[c];
            }
        }
        // SAFETY: j < n.
        let xj = unsafe { &mut *(xp.add(j * K) as *mut [f64; K]) };
        for c in 0..K {
            xj[c] = xj[c] * inv_d - acc[c];
        }
    }
}

fn solve_general(col_ptr: &[u32], row_idx: &[u32], values: &[f64], x: &mut [f64], k: usize) {
    let n = col_ptr.len() - 1;
    for j in 0..n {
        let (start, end) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
        for (&i, &l) in row_idx[start + 1..end].iter().zip(&values[start + 1..end]) {
            let i = i as usize;
            for c in 0..k {
                x[i * k + c] -= l * x[j * k + c];
            }
        }
    }
    for j in (0..n).rev() {
        let (start, end) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
        let inv_d = 1.0 / values[start];
        for c in 0..k {
            x[j * k + c] *= inv_d;
        }
        for (&i, &l) in row_idx[start + 1..end].iter().zip(&values[start + 1..end]) {
            let i = i as usize;
            for c in 0..k {
                x[j * k + c] -= l * x[i * k + c];
            }
        }
    }
}
