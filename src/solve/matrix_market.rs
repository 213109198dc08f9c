//! Writes a [`SymmetricCsc`] matrix in Matrix Market coordinate format (`lapclone mesh
//! --laplacian-out`); lapclone-bench's `matrix_market` reads it back.

use super::{SolveError, SymmetricCsc};
use std::path::Path;

/// Writes `real symmetric` coordinate format, lower triangle, 1-based, each value in the
/// shortest text that reads back exactly (integers without a point), after a `%` line of
/// `comment` if it is not empty. Atomic: a failed write leaves no partial file.
pub fn write_matrix_market(
    path: &Path,
    matrix: &SymmetricCsc,
    comment: &str,
) -> Result<(), SolveError> {
    let text = matrix_market_text(matrix, comment);
    crate::util::write_atomic(path, text.as_bytes()).map_err(
        |source| SolveError::Io {
            path: path.to_path_buf(),
            source,
        },
    )
}

/// The Matrix Market text of the symmetric matrix `m` (lower triangle, 1-based).
pub(crate) fn matrix_market_text(m: &SymmetricCsc, comment: &str) -> String {
    let mut text = String::with_capacity(32 * m.nnz() + 128);
    text.push_str("%%MatrixMarket matrix coordinate real symmetric\n");
    if !comment.is_empty() {
        text.push_str(&format!("% {comment}\n"));
    }
    text.push_str(&format!("{} {} {}\n", m.n, m.n, m.nnz()));
    for j in 0..m.n {
        for p in m.col_ptr[j]..m.col_ptr[j + 1] {
            let (row, value) = (m.row_idx[p] + 1, m.values[p]);
            text.push_str(&format!("{row} {} {value}\n", j + 1));
        }
    }
    text
}
