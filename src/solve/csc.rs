//! The symmetric sparse matrix every solver entry point takes: the lower triangle (diagonal
//! included) in compressed sparse column form, built from (row, col, value) triplets.

use super::SolveError;

/// Lower triangle of a symmetric matrix, including the diagonal, column by column.
/// In every column row indices are strictly increasing, so the diagonal entry — always stored,
/// possibly as 0 — comes first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SymmetricCsc {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
    pub values: Vec<f64>,
}

impl SymmetricCsc {
    /// Builds the matrix from triplets of either triangle (an upper entry (i, j), i < j, is
    /// stored as (j, i)); duplicates are summed and missing diagonals become explicit zeros.
    pub fn from_triplets(n: usize, triplets: &[(usize, usize, f64)]) -> Result<Self, SolveError> {
        let mut entries: Vec<(usize, usize, f64)> = Vec::with_capacity(triplets.len() + n);
        for &(i, j, v) in triplets {
            if i >= n || j >= n {
                return Err(SolveError::InvalidMatrix(format!(
                    "entry ({i}, {j}) outside a {n}×{n} matrix"
                )));
            }
            if !v.is_finite() {
                return Err(SolveError::InvalidMatrix(format!(
                    "entry ({i}, {j}) is not finite"
                )));
            }
            let (row, col) = if i >= j { (i, j) } else { (j, i) };
            entries.push((col, row, v));
        }
        entries.extend((0..n).map(|d| (d, d, 0.0)));
        entries.sort_by_key(|e| (e.0, e.1));
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::with_capacity(entries.len());
        let mut values: Vec<f64> = Vec::with_capacity(entries.len());
        let mut last: Option<(usize, usize)> = None;
        for (col, row, v) in entries {
            if last == Some((col, row)) {
                *values.last_mut().expect("invariant: an entry was pushed") += v; // invariant: `last` is Some only after a push.
                continue;
            }
            last = Some((col, row));
            row_idx.push(row);
            values.push(v);
            col_ptr[col + 1] += 1;
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// Number of stored entries (lower triangle).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Index into `values` of the diagonal entry of column `j`.
    pub fn diagonal_index(&self, j: usize) -> usize {
        self.col_ptr[j]
    }

    /// The diagonal as a vector.
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.n).map(|j| self.values[self.col_ptr[j]]).collect()
    }

    /// `max |a_ii|`, or 1 when the diagonal is all zero (so scale-relative defaults stay positive).
    pub fn diagonal_scale(&self) -> f64 {
        let s = (0..self.n)
            .map(|j| self.values[self.col_ptr[j]].abs())
            .fold(0.0, f64::max);
        if s > 0.0 {
            s
        } else {
            1.0
        }
    }

    /// `y = A x` using both triangles.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..self.n {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                let a = self.values[p];
                y[i] += a * x[j];
                if i != j {
                    y[j] += a * x[i];
                }
            }
        }
    }

    /// Dense copy (both triangles), for tests on small matrices.
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut dense = vec![vec![0.0; self.n]; self.n];
        #[allow(clippy::needless_range_loop)] // j indexes both the pattern and the output
        for j in 0..self.n {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                dense[i][j] = self.values[p];
                dense[j][i] = self.values[p];
            }
        }
        dense
    }

    /// Checks the structural invariants documented on the type.
    pub fn sanity_check(&self) -> Result<(), SolveError> {
        let bad = |m: String| Err(SolveError::InvalidMatrix(m));
        if self.col_ptr.len() != self.n + 1 || self.col_ptr[0] != 0 {
            return bad("col_ptr must have n + 1 entries starting at 0".into());
        }
        if self.row_idx.len() != self.values.len() || self.col_ptr[self.n] != self.row_idx.len() {
            return bad("col_ptr, row_idx and values disagree on nnz".into());
        }
        for j in 0..self.n {
            let (start, end) = (self.col_ptr[j], self.col_ptr[j + 1]);
            if end <= start || self.row_idx[start] != j {
                return bad(format!("column {j} does not start with its diagonal"));
            }
            let rows = &self.row_idx[start..end];
            if rows.windows(2).any(|w| w[0] >= w[1]) || rows[rows.len() - 1] >= self.n {
                return bad(format!(
                    "column {j} rows not strictly increasing within range"
                ));
            }
            if self.values[start..end].iter().any(|v| !v.is_finite()) {
                return bad(format!("column {j} holds a non-finite value"));
            }
        }
        Ok(())
    }
}
