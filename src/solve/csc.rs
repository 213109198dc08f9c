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
        sort_by_column_then_row(n, &mut entries);
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

/// A stable sort of `(column, row, value)` entries by column, then row (what
/// `sort_by_key(|e| (e.0, e.1))` gives, so duplicates still sum in input order): a counting
/// sort by column, then an insertion sort of each column's few rows. Mesh matrices have a
/// handful of entries per column; a comparison sort of them all cost more than the
/// factorisation.
/// Longest column sorted by insertion (longer ones take the library's stable sort).
const INSERTION_SORT_MAX: usize = 32;

fn sort_by_column_then_row(n: usize, entries: &mut Vec<(usize, usize, f64)>) {
    let mut start = vec![0usize; n + 1];
    for e in entries.iter() {
        start[e.0 + 1] += 1;
    }
    for j in 0..n {
        start[j + 1] += start[j];
    }
    let mut next = start.clone();
    let mut sorted = vec![(0, 0, 0.0); entries.len()];
    for &e in entries.iter() {
        sorted[next[e.0]] = e;
        next[e.0] += 1;
    }
    for j in 0..n {
        let column = &mut sorted[start[j]..start[j + 1]];
        if column.len() > INSERTION_SORT_MAX {
            // A hub vertex (a fan of thousands of triangles): keep the sort n log n.
            column.sort_by_key(|e| e.1);
            continue;
        }
        for k in 1..column.len() {
            let mut i = k;
            while i > 0 && column[i - 1].1 > column[i].1 {
                column.swap(i - 1, i);
                i -= 1;
            }
        }
    }
    *entries = sorted;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The column sort equals the stable comparison sort it replaced, duplicates (whose
    /// values then sum in input order) and a hub column past the insertion-sort bound
    /// included.
    #[test]
    fn column_sort_matches_the_stable_sort() {
        let mut state = 0x5eed_u64;
        let mut next = |below: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize % below
        };
        for (n, count) in [(1, 0), (1, 5), (7, 40), (50, 600), (300, 3000)] {
            let mut entries: Vec<(usize, usize, f64)> = (0..count)
                .map(|k| {
                    // Column 0 is a hub: half the entries.
                    let col = if k % 2 == 0 { 0 } else { next(n) };
                    (col, next(n), k as f64)
                })
                .collect();
            let mut expected = entries.clone();
            expected.sort_by_key(|e| (e.0, e.1));
            sort_by_column_then_row(n, &mut entries);
            assert_eq!(entries, expected, "n {n}, {count} entries");
        }
    }
}
