//! [`PenaltyFactor`]: takes a Laplacian (lower-triangle [`SymmetricCsc`], symmetric positive
//! semi-definite) and keeps the LDLᵀ factor of `L + P + εI`, `P = α · diag(constrained)`,
//! switching constraints by rank-1 updates/downdates and solving multi-RHS systems in place.
//!
//! Guard rule (correct always, fast normally). A batch of switches applies all updates
//! (+α) before all downdates (−α), so every intermediate matrix is at least as positive
//! definite as the final one. The factor is rebuilt from the stored matrix and the current
//! constrained set when
//! 1. a downdate would leave a pivot `≤ ε/2` (positive definiteness lost numerically — e.g.
//!    the last constraint of a piece released), or
//! 2. the drift estimate `Σ u · max_j d_j / d̄_j` (u = 2⁻⁵³, summed over downdates since the
//!    last factorisation; `d_j / d̄_j` over the path below the start pivot — whose pivot is
//!    recomputed exactly — is how much cancellation magnified rounding) exceeds
//!    `drift_budget`, or
//! 3. the batch is so large that refactoring is cheaper: the summed path costs of its
//!    switches ([`SymbolicFactor::switch_cost`], factor entries on each elimination-tree
//!    path) exceed the estimated refactorisation cost ([`SymbolicFactor::refactor_cost`],
//!    flop count calibrated against the kernel). The estimate walks only the index arrays
//!    and stops as soon as the budget is exceeded, so it costs a fraction of the updates.
//!
//! Updates alone never trigger a refactor: they add positive terms and are stable.

use super::numeric::{factor_numeric, NumericWorkspace};
use super::solve_supernodal::{inverse_diagonal, lanes_for, ldlt_solve_supernodal};
use super::symbolic::{FactorMethod, SymbolicFactor};
use super::update::{pivot_from_row, rank1_diagonal, Rank1Outcome, RowScratch};
use super::{SolveError, SymmetricCsc};

/// Penalty and guard settings of a factor. `None` picks the default relative to the
/// diagonal scale s = max |l_ii| (α = 1e8·s, ε = 1e-12·s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PenaltyOptions {
    /// Penalty weight α; by default relative to the diagonal scale.
    pub alpha: Option<f64>,
    /// Regularisation ε; by default relative to the diagonal scale.
    pub epsilon: Option<f64>,
    /// Refactor when the accumulated downdate drift estimate exceeds this (default 1e-11).
    pub drift_budget: f64,
    /// Simplicial or supernodal numeric factorisation (default: by size).
    pub method: FactorMethod,
}

impl Default for PenaltyOptions {
    fn default() -> Self {
        Self {
            alpha: None,
            epsilon: None,
            drift_budget: DEFAULT_DRIFT_BUDGET,
            method: FactorMethod::Auto,
        }
    }
}

/// Default α relative to the diagonal scale.
pub const DEFAULT_ALPHA_RELATIVE: f64 = 1e8;
/// Default ε relative to the diagonal scale.
pub const DEFAULT_EPSILON_RELATIVE: f64 = 1e-12;
/// Default drift budget (see the module doc).
pub const DEFAULT_DRIFT_BUDGET: f64 = 1e-11;
const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;

/// How [`PenaltyFactor::solve_channels`] reads its right-hand side.
#[derive(Clone, Copy)]
enum RhsKind {
    /// As given.
    Plain,
    /// `α · value` at constrained vertices, 0 elsewhere (the input there is ignored).
    Dirichlet,
}

/// `x[position[v]][c] = rhs[c][v]` (or the Dirichlet right-hand side `α · rhs[c][v]` at
/// constrained vertices, 0 elsewhere, when `dirichlet` is given) for the `K` channels, and 0
/// in the padding lanes of rows of `L`. Walks the vertices in order: `rhs` streams, one
/// random row of `x` per vertex.
fn permute_in<const K: usize, const L: usize>(
    rhs: &[f64],
    symbolic: &SymbolicFactor,
    dirichlet: Option<(&[bool], f64)>,
    x: &mut [f64],
) {
    let n = symbolic.n();
    let columns: [&[f64]; K] = std::array::from_fn(|c| &rhs[c * n..(c + 1) * n]);
    assert!(x.len() == n * L && dirichlet.is_none_or(|(constrained, _)| constrained.len() == n));
    for (v, &p) in symbolic.perm_inv.iter().enumerate() {
        let scale = match dirichlet {
            None => 1.0,
            Some((constrained, alpha)) if constrained[v] => alpha,
            Some(_) => 0.0,
        };
        for (c, value) in x[p as usize * L..][..L].iter_mut().enumerate() {
            // The Dirichlet input is ignored, not scaled, where unconstrained (it may be NaN).
            *value = if c < K && scale != 0.0 {
                scale * columns[c][v]
            } else {
                0.0
            };
        }
    }
}

/// `rhs[c][v] = x[position[v]][c]` for the `K` channels: one pass over the vertices, one
/// random row of `x` each, `rhs` written as `K` streams.
fn permute_out<const K: usize, const L: usize>(
    x: &[f64],
    symbolic: &SymbolicFactor,
    rhs: &mut [f64],
) {
    let n = symbolic.n();
    for (v, &p) in symbolic.perm_inv.iter().enumerate() {
        let row = &x[p as usize * L..][..L];
        for c in 0..K {
            rhs[c * n + v] = row[c];
        }
    }
}

/// What one batch of switches did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SwitchStats {
    /// Constraints switched on by rank-1 updates.
    pub updates: usize,
    /// Constraints switched off by rank-1 downdates.
    pub downdates: usize,
    /// Whether a guard refactored from the matrix instead.
    pub refactored: bool,
}

/// Factor of `L + P + εI` with switchable penalty constraints. See the module doc.
pub struct PenaltyFactor {
    symbolic: SymbolicFactor,
    alpha: f64,
    epsilon: f64,
    drift_budget: f64,
    /// Values of `L + εI` in the input (lower CSC) layout.
    base_values: Vec<f64>,
    /// Scratch for `L + εI + P` at refactorisation.
    work_values: Vec<f64>,
    factor_values: Vec<f64>,
    /// `1 / d_j` of the current factor, for the solve.
    inv_diagonal: Vec<f64>,
    workspace: NumericWorkspace,
    constrained: Vec<bool>,
    constrained_count: usize,
    drift: f64,
    refactor_count: usize,
    /// Rank-1 kernel scratch, all zero between calls.
    update_scratch: Vec<f64>,
    /// Permuted right-hand sides, rows of up to 4 channels.
    solve_scratch: Vec<f64>,
    /// Per-vertex pending state of the current batch: 0 none, 1 on, 2 off.
    pending: Vec<u8>,
    touched: Vec<usize>,
    row_scratch: RowScratch,
}

impl PenaltyFactor {
    /// Analyses and factors `l + εI` with no constraint on.
    pub fn new(l: &SymmetricCsc, opts: &PenaltyOptions) -> Result<Self, SolveError> {
        Self::build(l, opts, None)
    }

    /// Analyses and factors `l + εI + P` with the constraints `constrained[v]` on (length
    /// n): one factorisation where [`new`](Self::new) followed by switching them on would
    /// cost a second (a batch that large refactors).
    pub fn with_constrained(
        l: &SymmetricCsc,
        opts: &PenaltyOptions,
        constrained: &[bool],
    ) -> Result<Self, SolveError> {
        if constrained.len() != l.n {
            return Err(SolveError::WrongLength {
                got: constrained.len(),
                expected: l.n,
            });
        }
        Self::build(l, opts, Some(constrained))
    }

    fn build(
        l: &SymmetricCsc,
        opts: &PenaltyOptions,
        constrained: Option<&[bool]>,
    ) -> Result<Self, SolveError> {
        let symbolic = SymbolicFactor::analyse_with(l, opts.method)?;
        let scale = l.diagonal_scale();
        let alpha = opts.alpha.unwrap_or(DEFAULT_ALPHA_RELATIVE * scale);
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(SolveError::BadAlpha(alpha));
        }
        let epsilon = opts.epsilon.unwrap_or(DEFAULT_EPSILON_RELATIVE * scale);
        if !(epsilon.is_finite() && epsilon > 0.0) {
            return Err(SolveError::InvalidMatrix(format!(
                "regularisation ε = {epsilon} must be positive"
            )));
        }
        let mut base_values = l.values.clone();
        for j in 0..l.n {
            base_values[l.diagonal_index(j)] += epsilon;
        }
        let n = l.n;
        let workspace = NumericWorkspace::new(&symbolic);
        let mut this = Self {
            factor_values: vec![0.0; symbolic.factor_buffer_len()],
            inv_diagonal: vec![0.0; n],
            work_values: base_values.clone(),
            base_values,
            symbolic,
            alpha,
            epsilon,
            drift_budget: opts.drift_budget,
            workspace,
            constrained: constrained.map_or_else(|| vec![false; n], <[bool]>::to_vec),
            constrained_count: constrained.map_or(0, |c| c.iter().filter(|&&on| on).count()),
            drift: 0.0,
            refactor_count: 0,
            update_scratch: vec![0.0; n],
            solve_scratch: vec![0.0; 4 * n],
            pending: vec![0; n],
            touched: Vec::new(),
            row_scratch: RowScratch::new(n),
        };
        this.factor_current()?;
        Ok(this)
    }

    pub fn n(&self) -> usize {
        self.symbolic.n()
    }

    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    pub fn is_constrained(&self, v: usize) -> bool {
        self.constrained[v]
    }

    pub fn constrained_count(&self) -> usize {
        self.constrained_count
    }

    pub fn constrained(&self) -> &[bool] {
        &self.constrained
    }

    /// How often a guard rebuilt the factor (the initial factorisation does not count).
    pub fn refactor_count(&self) -> usize {
        self.refactor_count
    }

    /// Current drift estimate since the last factorisation.
    pub fn drift_estimate(&self) -> f64 {
        self.drift
    }

    /// Stored entries of the factor.
    pub fn nnz_factor(&self) -> usize {
        self.symbolic.nnz_factor()
    }

    /// The symbolic part (ordering and pattern).
    pub fn symbolic(&self) -> &SymbolicFactor {
        &self.symbolic
    }

    /// Factor values in the layout documented in [`faer_layout`](super::faer_layout).
    pub fn factor_values(&self) -> &[f64] {
        &self.factor_values[..self.symbolic.nnz_factor()]
    }

    /// Batch switch: each `(vertex, on)`; a vertex named twice takes its last state.
    /// Applies updates before downdates; guarded (automatic refactorisation, see module doc).
    pub fn switch(&mut self, changes: &[(usize, bool)]) -> Result<SwitchStats, SolveError> {
        let n = self.n();
        if let Some(&(vertex, _)) = changes.iter().find(|c| c.0 >= n) {
            return Err(SolveError::VertexOutOfRange { vertex, n });
        }
        for &(v, on) in changes {
            if self.pending[v] == 0 {
                self.touched.push(v);
            }
            self.pending[v] = if on { 1 } else { 2 };
        }
        self.apply_pending()
    }

    /// Makes the constrained set equal to `wanted` (length n), switching only the differences.
    pub fn set_constrained(&mut self, wanted: &[bool]) -> Result<SwitchStats, SolveError> {
        if wanted.len() != self.n() {
            return Err(SolveError::WrongLength {
                got: wanted.len(),
                expected: self.n(),
            });
        }
        for (v, &on) in wanted.iter().enumerate() {
            if on != self.constrained[v] {
                self.touched.push(v);
                self.pending[v] = if on { 1 } else { 2 };
            }
        }
        self.apply_pending()
    }

    /// Forces a refactorisation from the stored matrix and the current constrained set.
    pub fn refactor(&mut self) -> Result<(), SolveError> {
        self.refactor_count += 1;
        self.factor_current()
    }

    /// Solves `(L + P + εI) X = B` in place; `rhs` is column-major n×k. Channels go through
    /// the supernodal kernel in groups of up to 4, each group as one SIMD row per unknown
    /// (scratch for 4 channels is allocated with the factor, so no solve allocates).
    ///
    /// # Panics
    /// If `rhs.len() != n * k` (a programming error, not an input error).
    pub fn solve_in_place(&mut self, rhs: &mut [f64], k: usize) {
        assert_eq!(
            rhs.len(),
            self.n() * k,
            "solve_in_place: rhs must be n×k column-major"
        );
        self.solve_channels(rhs, k, RhsKind::Plain);
    }

    /// Dirichlet convenience: on entry `values` (column-major n×k) holds the wanted value at
    /// constrained rows (other rows ignored); on exit the membrane, ≈ those values there.
    pub fn solve_dirichlet(&mut self, values: &mut [f64], k: usize) {
        assert_eq!(
            values.len(),
            self.n() * k,
            "solve_dirichlet: values must be n×k column-major"
        );
        self.solve_channels(values, k, RhsKind::Dirichlet);
    }

    /// Permutes `rhs` (column-major n×k) into rows of up to 4 channels, solves, and
    /// permutes the solution back.
    fn solve_channels(&mut self, rhs: &mut [f64], k: usize, kind: RhsKind) {
        let n = self.n();
        for group in (0..k).step_by(4) {
            let channels = (k - group).min(4);
            let lanes = lanes_for(channels);
            if self.solve_scratch.len() < n * lanes {
                self.solve_scratch.resize(n * lanes, 0.0);
            }
            let x = &mut self.solve_scratch[..n * lanes];
            let rhs = &mut rhs[group * n..(group + channels) * n];
            let symbolic = &self.symbolic;
            let kind = match kind {
                RhsKind::Plain => None,
                RhsKind::Dirichlet => Some((&self.constrained[..], self.alpha)),
            };
            match channels {
                1 => permute_in::<1, 1>(rhs, symbolic, kind, x),
                2 => permute_in::<2, 2>(rhs, symbolic, kind, x),
                3 => permute_in::<3, 4>(rhs, symbolic, kind, x),
                _ => permute_in::<4, 4>(rhs, symbolic, kind, x),
            }
            ldlt_solve_supernodal(
                symbolic,
                &self.factor_values[..symbolic.nnz_factor()],
                &self.inv_diagonal,
                x,
                lanes,
            );
            match channels {
                1 => permute_out::<1, 1>(x, symbolic, rhs),
                2 => permute_out::<2, 2>(x, symbolic, rhs),
                3 => permute_out::<3, 4>(x, symbolic, rhs),
                _ => permute_out::<4, 4>(x, symbolic, rhs),
            }
        }
    }

    fn factor_current(&mut self) -> Result<(), SolveError> {
        self.work_values.copy_from_slice(&self.base_values);
        for (v, &on) in self.constrained.iter().enumerate() {
            if on {
                self.work_values[self.symbolic.a_col_ptr[v] as usize] += self.alpha;
            }
        }
        self.drift = 0.0;
        factor_numeric(
            &self.symbolic,
            &self.work_values,
            &mut self.factor_values,
            self.epsilon,
            &mut self.workspace,
        )?;
        inverse_diagonal(
            &self.symbolic,
            &self.factor_values[..self.symbolic.nnz_factor()],
            &mut self.inv_diagonal,
        );
        Ok(())
    }

    /// Refreshes `inv_diagonal` along the elimination-tree path from position `p` (the
    /// pivots a rank-1 modification at `p` changed).
    fn refresh_inverse_pivots(&mut self, p: usize) {
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        let mut j = p;
        loop {
            let (start, end) = (col_ptr[j] as usize, col_ptr[j + 1] as usize);
            self.inv_diagonal[j] = 1.0 / self.factor_values[start];
            if end == start + 1 {
                return;
            }
            j = row_idx[start + 1] as usize;
        }
    }

    /// Applies the batch recorded in `pending`/`touched`, then clears them.
    fn apply_pending(&mut self) -> Result<SwitchStats, SolveError> {
        let mut stats = SwitchStats::default();
        let mut touched = std::mem::take(&mut self.touched);
        touched.sort_unstable();
        for &v in &touched {
            let on = self.pending[v] == 1;
            if on != self.constrained[v] {
                if on {
                    stats.updates += 1;
                } else {
                    stats.downdates += 1;
                }
            }
        }
        let mut needs_refactor = self.batch_costs_more_than_refactor(&touched);
        for pass_on in [true, false] {
            for &v in &touched {
                let on = self.pending[v] == 1;
                if on != pass_on || on == self.constrained[v] {
                    continue;
                }
                self.constrained[v] = on;
                if on {
                    self.constrained_count += 1;
                } else {
                    self.constrained_count -= 1;
                }
                if !needs_refactor {
                    needs_refactor = !self.modify(v, on);
                }
            }
        }
        for &v in &touched {
            self.pending[v] = 0;
        }
        touched.clear();
        self.touched = touched;
        if needs_refactor || self.drift > self.drift_budget {
            stats.refactored = true;
            self.refactor()?;
        }
        Ok(stats)
    }

    /// Rule 3 of the module doc: Σ path costs of the real switches > refactorisation cost.
    fn batch_costs_more_than_refactor(&self, touched: &[usize]) -> bool {
        let budget = self.symbolic.refactor_cost();
        let mut cost = 0.0;
        for &v in touched {
            if (self.pending[v] == 1) != self.constrained[v] {
                cost += self.symbolic.switch_cost(self.symbolic.position_of(v));
                if cost > budget {
                    return true;
                }
            }
        }
        false
    }

    /// One rank-1 modification; false when the factor was lost and must be rebuilt.
    fn modify(&mut self, v: usize, on: bool) -> bool {
        let p = self.symbolic.position_of(v);
        let sigma = if on { self.alpha } else { -self.alpha };
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        let factor_values = &mut self.factor_values[..row_idx.len()];
        let exact_pivot = (!on).then(|| {
            let a_pp = self.base_values[self.symbolic.a_col_ptr[v] as usize];
            let neighbours = self.symbolic.neighbours(p);
            pivot_from_row(
                col_ptr,
                row_idx,
                factor_values,
                p,
                a_pp,
                neighbours,
                &mut self.row_scratch,
            )
        });
        match rank1_diagonal(
            col_ptr,
            row_idx,
            factor_values,
            &mut self.update_scratch,
            p,
            sigma,
            0.5 * self.epsilon,
            exact_pivot,
        ) {
            Rank1Outcome::Done { amplification } => {
                if !on {
                    self.drift += UNIT_ROUNDOFF * amplification;
                }
                self.refresh_inverse_pivots(p);
                true
            }
            Rank1Outcome::PivotLost => false,
        }
    }
}
