//! Forward and back substitution with a simplicial LDLᵀ factor, column by column: takes the
//! factor (faer layout, see [`faer_layout`](super::faer_layout)) and `k` right-hand sides
//! stored *interleaved* (`x[i * k + c]`, row-major n×k, already permuted), and overwrites
//! them with the solution of `L D Lᵀ x = b`. The plain reference that tests and `bench`
//! compare the supernodal solve ([`solve_supernodal`](super::solve_supernodal)) against.

/// Solves in place.
///
/// # Panics
/// If `x` does not hold n rows of `k` values, or `values` does not match `row_idx`.
pub fn ldlt_solve_interleaved(
    col_ptr: &[u32],
    row_idx: &[u32],
    values: &[f64],
    x: &mut [f64],
    k: usize,
) {
    let n = col_ptr.len() - 1;
    assert!(x.len() == n * k && values.len() == row_idx.len());
    let column = |j: usize| {
        let range = col_ptr[j] as usize + 1..col_ptr[j + 1] as usize;
        row_idx[range.clone()].iter().zip(&values[range])
    };
    for j in 0..n {
        for (&i, &l) in column(j) {
            let i = i as usize;
            for c in 0..k {
                x[i * k + c] -= l * x[j * k + c];
            }
        }
    }
    for j in (0..n).rev() {
        let inv_d = 1.0 / values[col_ptr[j] as usize];
        for c in 0..k {
            x[j * k + c] *= inv_d;
        }
        for (&i, &l) in column(j) {
            let i = i as usize;
            for c in 0..k {
                x[j * k + c] -= l * x[i * k + c];
            }
        }
    }
}
