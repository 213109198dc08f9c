//! Numeric LDLᵀ factorisation by faer on the pattern analysed in
//! [`symbolic`](super::symbolic): takes the matrix values (lower triangle, original order)
//! and fills the factor values in place. Runs once per mesh and whenever a guard fires.
//! A supernodal factor is compacted in place into the column layout of
//! [`faer_layout`](super::faer_layout) afterwards (one pass of `memmove`s, O(nnz)).

use super::faer_layout;
use super::symbolic::SymbolicFactor;
use super::SolveError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};

/// Reusable workspace for [`factor_numeric`], sized once per symbolic factor.
pub struct NumericWorkspace {
    stack: MemBuffer,
    /// All +1: every pivot is expected positive; faer lifts pivots ≤ ε/2 to ε.
    signs: Vec<i8>,
}

impl NumericWorkspace {
    pub fn new(symbolic: &SymbolicFactor) -> Self {
        let req = symbolic
            .faer
            .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default());
        Self {
            stack: MemBuffer::new(req),
            signs: vec![1; symbolic.n],
        }
    }
}

/// Factors the matrix with values `a_values` (pattern of `symbolic`) into `l_values`, whose
/// length must be at least [`SymbolicFactor::factor_buffer_len`]; the factor ends up in its
/// first [`SymbolicFactor::nnz_factor`] entries. Pivots at or below `epsilon / 2` are
/// replaced by `epsilon` (see the stage doc).
pub fn factor_numeric(
    symbolic: &SymbolicFactor,
    a_values: &[f64],
    l_values: &mut [f64],
    epsilon: f64,
    workspace: &mut NumericWorkspace,
) -> Result<(), SolveError> {
    let n = symbolic.n;
    let l_values = &mut l_values[..symbolic.faer.len_val()];
    let pattern =
        SymbolicSparseColMatRef::new_checked(n, n, &symbolic.a_col_ptr, None, &symbolic.a_row_idx);
    let a = SparseColMatRef::new(pattern, a_values);
    let regularization = LdltRegularization {
        dynamic_regularization_signs: Some(&workspace.signs),
        dynamic_regularization_delta: epsilon,
        dynamic_regularization_epsilon: 0.5 * epsilon,
    };
    symbolic
        .faer
        .factorize_numeric_ldlt(
            l_values,
            a,
            Side::Lower,
            regularization,
            Par::Seq,
            MemStack::new(&mut workspace.stack),
            Default::default(),
        )
        .map_err(|e| SolveError::Numeric(format!("{e:?}")))?;
    if let SymbolicCholeskyRaw::Supernodal(s) = symbolic.faer.raw() {
        faer_layout::compact_supernodes(s, &symbolic.col_ptr, l_values);
    }
    Ok(())
}
