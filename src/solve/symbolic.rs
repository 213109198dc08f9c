//! Once-per-mesh analysis: takes the lower triangle of a [`SymmetricCsc`] and gives the AMD
//! fill-reducing permutation and the simplicial LDLᵀ factor pattern (elimination tree
//! implied), computed by faer, plus a 32-bit copy of the input pattern for refactorisation.
//!
//! Layout contract read by [`update`](super::update) and [`solve`](super::solve) (faer
//! =0.24.4 simplicial LDLᵀ): column `j` of the factor occupies `col_ptr[j]..col_ptr[j+1]`;
//! its first entry has row `j` and holds `D_jj`; the remaining rows are strictly increasing
//! and hold `L_ij`, so the first of them is the elimination-tree parent of `j`.
//! [`SymbolicFactor::check_layout`] verifies this at analysis time, so the unchecked indexing
//! in the kernels cannot go out of bounds.

use super::{SolveError, SymmetricCsc};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, simplicial::SymbolicSimplicialCholesky, CholeskySymbolicParams,
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SymbolicSparseColMatRef;
use faer::Side;

/// Ordering and factor pattern of one matrix pattern.
#[derive(Debug)]
pub struct SymbolicFactor {
    pub(crate) n: usize,
    pub(crate) faer: SymbolicCholesky<u32>,
    /// `perm_fwd[position] = vertex`.
    pub(crate) perm_fwd: Vec<u32>,
    /// `perm_inv[vertex] = position` in the factor.
    pub(crate) perm_inv: Vec<u32>,
    pub(crate) a_col_ptr: Vec<u32>,
    pub(crate) a_row_idx: Vec<u32>,
    /// Full adjacency (both triangles, diagonal excluded) in factor positions:
    /// neighbours of position p are `adj_idx[adj_ptr[p]..adj_ptr[p + 1]]`.
    pub(crate) adj_ptr: Vec<u32>,
    pub(crate) adj_idx: Vec<u32>,
}

impl SymbolicFactor {
    /// AMD ordering plus simplicial symbolic factorisation of `a`'s pattern.
    pub fn analyse(a: &SymmetricCsc) -> Result<Self, SolveError> {
        a.sanity_check()?;
        let to_u32 = |v: usize| u32::try_from(v).map_err(|_| SolveError::TooLarge(a.n));
        let a_col_ptr: Vec<u32> = a
            .col_ptr
            .iter()
            .map(|&v| to_u32(v))
            .collect::<Result<_, _>>()?;
        let a_row_idx: Vec<u32> = a
            .row_idx
            .iter()
            .map(|&v| to_u32(v))
            .collect::<Result<_, _>>()?;
        // SAFETY-free: the pattern was validated by `sanity_check` (sorted, in range).
        let pattern = SymbolicSparseColMatRef::new_checked(a.n, a.n, &a_col_ptr, None, &a_row_idx);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let faer =
            factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Amd, params)
                .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?;
        let (perm_fwd, perm_inv) = match faer.perm() {
            Some(perm) => {
                let (fwd, inv) = perm.arrays();
                (fwd.to_vec(), inv.to_vec())
            }
            None => ((0..a.n as u32).collect(), (0..a.n as u32).collect()),
        };
        let (adj_ptr, adj_idx) = permuted_adjacency(a, &perm_inv);
        let this = Self {
            adj_ptr,
            adj_idx,
            n: a.n,
            faer,
            perm_fwd,
            perm_inv,
            a_col_ptr,
            a_row_idx,
        };
        this.check_layout()?;
        Ok(this)
    }

    /// Positions adjacent to position `p` in the permuted matrix (diagonal excluded).
    pub fn neighbours(&self, p: usize) -> impl Iterator<Item = usize> + '_ {
        self.adj_idx[self.adj_ptr[p] as usize..self.adj_ptr[p + 1] as usize]
            .iter()
            .map(|&q| q as usize)
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Stored entries of the factor (diagonal included).
    pub fn nnz_factor(&self) -> usize {
        self.faer.len_val()
    }

    /// `perm_inv[vertex]` = the vertex's position in the factor.
    pub fn position_of(&self, vertex: usize) -> usize {
        self.perm_inv[vertex] as usize
    }

    /// `perm_fwd[position]` = the vertex at that position.
    pub fn perm_fwd(&self) -> &[u32] {
        &self.perm_fwd
    }

    pub(crate) fn simplicial(&self) -> &SymbolicSimplicialCholesky<u32> {
        match self.faer.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => s,
            // invariant: analysis forces FORCE_SIMPLICIAL, so faer never builds a supernodal one.
            SymbolicCholeskyRaw::Supernodal(_) => unreachable!("invariant: simplicial forced"),
        }
    }

    /// Factor column pointers (see the module doc for the layout).
    pub fn col_ptr(&self) -> &[u32] {
        self.simplicial().col_ptr()
    }

    /// Factor row indices (see the module doc for the layout).
    pub fn row_idx(&self) -> &[u32] {
        self.simplicial().row_idx()
    }

    /// Verifies the layout contract in the module doc; an error here means the pinned faer
    /// version changed its representation.
    pub fn check_layout(&self) -> Result<(), SolveError> {
        let (col_ptr, row_idx) = (self.col_ptr(), self.row_idx());
        let broken = |m: String| {
            Err(SolveError::Symbolic(format!(
                "unexpected faer factor layout: {m}"
            )))
        };
        if col_ptr.len() != self.n + 1 || col_ptr[self.n] as usize != row_idx.len() {
            return broken("column pointers".into());
        }
        if self.perm_fwd.len() != self.n || self.perm_inv.len() != self.n {
            return broken("permutation length".into());
        }
        for j in 0..self.n {
            let rows = &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize];
            if rows.first() != Some(&(j as u32)) {
                return broken(format!("column {j} does not start with its diagonal"));
            }
            if rows.windows(2).any(|w| w[0] >= w[1]) || rows.iter().any(|&r| r as usize >= self.n) {
                return broken(format!("column {j} rows not strictly increasing in range"));
            }
        }
        for (pos, &v) in self.perm_fwd.iter().enumerate() {
            if v as usize >= self.n || self.perm_inv[v as usize] as usize != pos {
                return broken("permutation is not a bijection".into());
            }
        }
        Ok(())
    }
}

/// Both-triangle adjacency of `a` re-indexed by factor position.
fn permuted_adjacency(a: &SymmetricCsc, perm_inv: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut count = vec![0u32; a.n + 1];
    for j in 0..a.n {
        for &i in &a.row_idx[a.col_ptr[j] + 1..a.col_ptr[j + 1]] {
            count[perm_inv[i] as usize + 1] += 1;
            count[perm_inv[j] as usize + 1] += 1;
        }
    }
    for p in 0..a.n {
        count[p + 1] += count[p];
    }
    let mut next = count.clone();
    let mut idx = vec![0u32; count[a.n] as usize];
    for j in 0..a.n {
        for &i in &a.row_idx[a.col_ptr[j] + 1..a.col_ptr[j + 1]] {
            let (pi, pj) = (perm_inv[i] as usize, perm_inv[j] as usize);
            idx[next[pi] as usize] = pj as u32;
            next[pi] += 1;
            idx[next[pj] as usize] = pi as u32;
            next[pj] += 1;
        }
    }
    (count, idx)
}
