//! Once-per-mesh analysis: takes the lower triangle of a [`SymmetricCsc`] and gives the AMD
//! fill-reducing permutation and the LDLᵀ factor pattern in one column-compressed layout
//! (elimination tree implied), computed by faer, plus a 32-bit copy of the input pattern for
//! refactorisation.
//!
//! faer builds either a simplicial or a supernodal factor ([`FactorMethod`]; supernodal pays
//! off on large meshes, see [`SUPERNODAL_MIN_VERTICES`]). Either way the kernels read one
//! simplicial-style column layout, whose contract with faer lives in
//! [`faer_layout`](super::faer_layout) and is checked there at analysis time.

use super::faer_layout;
use super::supernodes::SupernodePartition;
use super::{SolveError, SymmetricCsc};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};

/// Which faer numeric factorisation fills the factor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FactorMethod {
    /// Supernodal from 10 000 vertices on, simplicial below.
    #[default]
    Auto,
    /// One column at a time.
    Simplicial,
    /// faer's fundamental supernodes: the same pattern as simplicial, no stored zeros.
    Supernodal,
    /// faer's default supernode amalgamation: faster factorisation, but explicit zeros in
    /// the factor (≈10–15 % more entries) slow solves and switches down accordingly.
    SupernodalRelaxed,
}

/// Crossover of [`FactorMethod::Auto`], measured with `lapclone-bench factor` on disc meshes
/// (combinatorial Laplacian, AMD): below it faer's simplicial LDLᵀ is as fast or faster
/// (≈1 ms either way at 2k vertices), above it the supernodal one wins by a growing factor
/// (≈2× at 5e4, ≈5× at 5e5 vertices).
pub const SUPERNODAL_MIN_VERTICES: usize = 10_000;

/// faer's default amalgamation thresholds (faer =0.24.4, `sparse/linalg/mod.rs`), spelled out
/// because the default is private.
const RELAXED_SUPERNODES: &[(usize, f64)] = &[(4, 1.0), (16, 0.8), (48, 0.1), (usize::MAX, 0.05)];

/// The supernodal factorisation [`FactorMethod::Auto`] picks above the crossover. Relaxed
/// amalgamation factors ≈25 % faster than fundamental supernodes (callgrind at 52k vertices:
/// 355 M vs 468 M instructions; `bench factor` best-of: 86 vs 151 ms under load) at the price
/// of ≈13 % more stored entries, i.e. ≈11 % slower solves and switches; a large mesh is
/// factored once and switched rarely, so the factor's time decides.
pub const AUTO_SUPERNODAL: FactorMethod = FactorMethod::SupernodalRelaxed;
use faer::sparse::SymbolicSparseColMatRef;
use faer::Side;

/// Ordering and factor pattern of one matrix pattern.
#[derive(Debug)]
pub struct SymbolicFactor {
    pub(crate) n: usize,
    pub(crate) faer: SymbolicCholesky<u32>,
    /// Factor column pointers and row indices in the layout of [`faer_layout`](super::faer_layout).
    pub(crate) col_ptr: Vec<u32>,
    pub(crate) row_idx: Vec<u32>,
    /// [`refactor_cost`](Self::refactor_cost), computed once.
    refactor_cost: f64,
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
    /// Supernodes of the factor pattern, for the supernodal solve.
    pub(crate) supernodes: SupernodePartition,
}

/// faer's symbolic parameters for `method` (`Auto` picks by the matrix size `n`).
fn cholesky_params(n: usize, method: FactorMethod) -> CholeskySymbolicParams<'static> {
        let method = match method {
            FactorMethod::Auto if n >= SUPERNODAL_MIN_VERTICES => AUTO_SUPERNODAL,
            FactorMethod::Auto => FactorMethod::Simplicial,
            chosen => chosen,
        };
        let supernodal = method != FactorMethod::Simplicial;
        // `None` keeps fundamental supernodes, whose columns are exactly the simplicial ones.
        let relax = (method == FactorMethod::SupernodalRelaxed).then_some(RELAXED_SUPERNODES);
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: if supernodal {
                SupernodalThreshold::FORCE_SUPERNODAL
            } else {
                SupernodalThreshold::FORCE_SIMPLICIAL
            },
            supernodal_params: SymbolicSupernodalParams { relax },
            ..Default::default()
        }
}

impl SymbolicFactor {
    /// AMD ordering plus symbolic factorisation of `a`'s pattern ([`FactorMethod::Auto`]).
    pub fn analyse(a: &SymmetricCsc) -> Result<Self, SolveError> {
        Self::analyse_with(a, FactorMethod::Auto)
    }

    /// AMD ordering plus symbolic factorisation of `a`'s pattern for the given method.
    pub fn analyse_with(a: &SymmetricCsc, method: FactorMethod) -> Result<Self, SolveError> {
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
        let params = cholesky_params(a.n, method);
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
        let (col_ptr, row_idx) = faer_layout::columns(&faer)?;
        let refactor_cost = refactor_cost(
            &col_ptr,
            matches!(faer.raw(), SymbolicCholeskyRaw::Supernodal(_)),
        );
        let supernodes = SupernodePartition::detect(&col_ptr, &row_idx);
        let this = Self {
            supernodes,
            refactor_cost,
            col_ptr,
            row_idx,
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

    /// Stored entries of the factor (diagonal included; explicit zeros of relaxed supernodes
    /// counted).
    pub fn nnz_factor(&self) -> usize {
        self.row_idx.len()
    }

    /// Length of the value buffer a numeric factorisation needs (faer's supernodal blocks
    /// are larger than the compacted layout); the factor ends up in its first
    /// [`nnz_factor`](Self::nnz_factor) entries.
    pub fn factor_buffer_len(&self) -> usize {
        self.faer.len_val().max(self.nnz_factor())
    }

    /// Estimated cost of a numeric refactorisation, in the unit of
    /// [`switch_cost`](Self::switch_cost) (factor entries a rank-1 switch touches).
    pub fn refactor_cost(&self) -> f64 {
        self.refactor_cost
    }

    /// Cost of one rank-1 switch at position `p`: the factor entries on its
    /// elimination-tree path (what the update kernel reads and writes).
    pub fn switch_cost(&self, p: usize) -> f64 {
        let (col_ptr, row_idx) = (&self.col_ptr, &self.row_idx);
        let mut entries = 0u64;
        let mut j = p;
        loop {
            let (start, end) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
            entries += (end - start) as u64;
            match row_idx.get(start + 1) {
                Some(&parent) if end > start + 1 => j = parent as usize,
                _ => return entries as f64,
            }
        }
    }

    /// Supernodes of the factor pattern (detected from `col_ptr`/`row_idx`, see
    /// [`supernodes`](super::supernodes)).
    pub fn supernodes(&self) -> &SupernodePartition {
        &self.supernodes
    }

    /// Whether faer factors this pattern supernodally.
    pub fn is_supernodal(&self) -> bool {
        matches!(self.faer.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// `perm_inv[vertex]` = the vertex's position in the factor.
    pub fn position_of(&self, vertex: usize) -> usize {
        self.perm_inv[vertex] as usize
    }

    /// `perm_fwd[position]` = the vertex at that position.
    pub fn perm_fwd(&self) -> &[u32] {
        &self.perm_fwd
    }

    /// Factor column pointers (layout: [`faer_layout`](super::faer_layout)).
    pub fn col_ptr(&self) -> &[u32] {
        &self.col_ptr
    }

    /// Factor row indices (layout: [`faer_layout`](super::faer_layout)).
    pub fn row_idx(&self) -> &[u32] {
        &self.row_idx
    }

    /// Verifies the layout contract of [`faer_layout`](super::faer_layout); an error here
    /// means the pinned faer version changed its representation.
    pub fn check_layout(&self) -> Result<(), SolveError> {
        if self.col_ptr.len() != self.n + 1 {
            return Err(SolveError::Symbolic(
                "unexpected faer factor layout: column pointers".into(),
            ));
        }
        faer_layout::check(faer_layout::Analysed {
            faer: &self.faer,
            col_ptr: &self.col_ptr,
            row_idx: &self.row_idx,
            perm_fwd: &self.perm_fwd,
            perm_inv: &self.perm_inv,
            supernodes: &self.supernodes,
        })
    }
}

/// Refactorisation cost in switch-path entries: `w · Σ_j |col_j|² + 2 · nnz`, the flop count
/// weighted by how much faster per flop faer factors than the rank-1 kernel updates.
/// Calibrated with callgrind on the disc meshes (2k–52k vertices): one path entry costs the
/// kernel ≈ 12 instructions; a factorisation ≈ 1.8 (supernodal) or ≈ 5.7 (simplicial)
/// instructions per unit of `Σ |col_j|²`, hence `w` = 0.15 or 0.5. The `2 · nnz` term covers
/// the value copy and compaction around the factorisation.
fn refactor_cost(col_ptr: &[u32], supernodal: bool) -> f64 {
    let weight = if supernodal { 0.15 } else { 0.5 };
    let squares: f64 = col_ptr
        .windows(2)
        .map(|w| {
            let len = (w[1] - w[0]) as f64;
            len * len
        })
        .sum();
    let nnz = col_ptr.last().copied().unwrap_or(0) as f64;
    weight * squares + 2.0 * nnz
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
