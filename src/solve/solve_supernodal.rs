//! Supernodal forward and back substitution with an LDLᵀ factor: takes the factor pattern
//! ([`SymbolicFactor`]: column layout and
//! [`SupernodePartition`](super::supernodes::SupernodePartition), both validated once by
//! [`SymbolicFactor::check_layout`]), the factor values with their inverse pivots, and
//! right-hand sides stored as rows of `lanes` ∈ {1, 2, 4} channels (`x[i * lanes + c]`,
//! already permuted; 3 channels are padded to 4), and overwrites `x` with the solution of
//! `L D Lᵀ x = b` in every lane. Same result as
//! [`ldlt_solve_interleaved`](super::solve::ldlt_solve_interleaved) to rounding; no
//! allocation, no scratch. This is the per-frame kernel of
//! [`PenaltyFactor`](super::PenaltyFactor); the column kernel stays as the reference.
//!
//! A supernode `b..e` is a dense panel (see [`supernodes`](super::supernodes)): its rows
//! `b..e` then the shared pattern `P`, its columns stored contiguously with per-column
//! offsets. Both sweeps take the panel's columns in blocks of up to [`BLOCK`] and walk the
//! panel's rows once per block: one row index, one load and (forward) one store of `x`
//! per row and block instead of per entry, the block's factor entries read as contiguous
//! streams, and each row of `x` (all its channels) one [`Row`]. A supernode of width 1
//! runs a plain column kernel. Narrow backward blocks keep two independent accumulators
//! per column (even and odd rows) to hide the multiply-add latency.
//!
//! The forward sweep skips a supernode whose rows of `x` are all zero when it is reached:
//! its panel would subtract exact zeros. Dirichlet right-hand sides are zero off the
//! constrained boundary, so the sweep touches only the elimination-tree reach of the
//! boundary. Skipping changes at most the sign of a zero, never a value.
//!
//! The sweeps run through [`simd`](crate::simd): compiled for this CPU's best instruction
//! set, or portable, with the same bits either way. The arithmetic order is fixed by the
//! code, never by the data, the CPU or the thread count.
//!
//! Measured and rejected (2-core machine, `bench factor`):
//! * Channel-major panels (rows gathered into per-channel scratch, SIMD down the columns,
//!   one factor load for all channels): slower than these row vectors at every threshold
//!   width tried (4–16), the gather/scatter and horizontal sums outweigh the saved
//!   broadcasts at the panel widths of 2-D meshes.
//! * Fusing the permutations into the sweeps: 10–20 % slower at 52k vertices than two
//!   vertex-order passes.
//! * Relaxed amalgamation with fewer explicit zeros: within the noise at a slower
//!   factorisation; the factor keeps faer's default.

use super::symbolic::SymbolicFactor;
use crate::simd::{self, Path, Row};

/// Columns of a panel taken together per pass over its rows.
pub const BLOCK: usize = 8;

/// Row stride for `k` channels: 1, 2 or 4 (3 is padded to 4; more than 4 channels are
/// solved in groups of 4).
pub fn lanes_for(k: usize) -> usize {
    match k {
        0 | 1 => 1,
        2 => 2,
        _ => 4,
    }
}

/// `out[j] = 1 / d_j` for every pivot of the factor (`values` in the layout of `symbolic`).
/// The solve multiplies by these instead of dividing. Whoever changes pivots keeps them
/// current (see [`PenaltyFactor`](super::PenaltyFactor), which refreshes the
/// elimination-tree path of every rank-1 switch).
///
/// # Panics
/// If `values` or `out` have the wrong length.
pub fn inverse_diagonal(symbolic: &SymbolicFactor, values: &[f64], out: &mut [f64]) {
    assert!(values.len() == symbolic.nnz_factor() && out.len() == symbolic.n());
    for (inv, &start) in out.iter_mut().zip(symbolic.col_ptr()) {
        *inv = 1.0 / values[start as usize];
    }
}

/// Solves in place on the current [`Path`]. `values` are the factor values of `symbolic`
/// ([`SymbolicFactor::nnz_factor`] of them) and `inv_diagonal` their
/// [`inverse_diagonal`]; `x` holds n rows of `lanes` channels, already in factor order.
///
/// # Panics
/// If `lanes` is not 1, 2 or 4, or if `x`, `values` or `inv_diagonal` have the wrong
/// length.
pub fn ldlt_solve_supernodal(
    symbolic: &SymbolicFactor,
    values: &[f64],
    inv_diagonal: &[f64],
    x: &mut [f64],
    lanes: usize,
) {
    ldlt_solve_supernodal_at(Path::current(), symbolic, values, inv_diagonal, x, lanes);
}

/// [`ldlt_solve_supernodal`] on a chosen path (tests compare the paths).
///
/// # Panics
/// As [`ldlt_solve_supernodal`].
pub fn ldlt_solve_supernodal_at(
    path: Path,
    symbolic: &SymbolicFactor,
    values: &[f64],
    inv_diagonal: &[f64],
    x: &mut [f64],
    lanes: usize,
) {
    assert!(matches!(lanes, 1 | 2 | 4), "lanes must be 1, 2 or 4");
    assert!(
        inv_diagonal.len() == symbolic.n(),
        "one inverse pivot per unknown"
    );
    assert!(
        x.len() == symbolic.n() * lanes,
        "x must hold n rows of `lanes` values"
    );
    assert!(
        values.len() == symbolic.nnz_factor(),
        "values must match the pattern"
    );
    let factor = Factor {
        col_ptr: symbolic.col_ptr(),
        row_idx: symbolic.row_idx(),
        values,
        inv_diagonal,
        begins: symbolic.supernodes().begins(),
        row_begin: symbolic.supernodes().panel_row_begins(),
        panel_rows: symbolic.supernodes().all_panel_rows(),
    };
    match lanes {
        1 => path.run(Sweeps(&factor, Rows(simd::rows_mut::<1>(x)))),
        2 => path.run(Sweeps(&factor, Rows(simd::rows_mut::<2>(x)))),
        _ => path.run(Sweeps(&factor, Rows(simd::rows_mut::<4>(x)))),
    }
}

/// Both sweeps, as a kernel for [`Path::run`].
struct Sweeps<'f, 'a, 'x, const S: usize>(&'f Factor<'a>, Rows<'x, S>);

impl<const S: usize> simd::Kernel for Sweeps<'_, '_, '_, S> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        solve_all(self.0, self.1);
    }
}

/// The factor as the sweeps read it.
struct Factor<'a> {
    col_ptr: &'a [u32],
    row_idx: &'a [u32],
    values: &'a [f64],
    inv_diagonal: &'a [f64],
    begins: &'a [u32],
    /// Compact panel rows (see [`SupernodePartition`](super::supernodes::SupernodePartition)).
    row_begin: &'a [u32],
    panel_rows: &'a [u32],
}

impl Factor<'_> {
    /// `col_ptr[j]` as an index.
    #[inline(always)]
    fn start(&self, j: usize) -> usize {
        self.col_ptr[j] as usize
    }
}

/// The right-hand sides, one row per unknown. Bounds-checked: unchecked access measured
/// ≈ 12 % faster solves, well inside the solve's budget either way, so the crate keeps no
/// `unsafe` for it.
struct Rows<'x, const S: usize>(&'x mut [Row<S>]);

impl<const S: usize> Rows<'_, S> {
    #[inline(always)]
    fn get(&self, i: usize) -> Row<S> {
        self.0[i]
    }

    #[inline(always)]
    fn set(&mut self, i: usize, row: Row<S>) {
        self.0[i] = row
    }
}

/// Both sweeps over every supernode.
#[inline(always)]
fn solve_all<const S: usize>(factor: &Factor, mut x: Rows<S>) {
    let x = &mut x;
    let supernodes = factor.begins.len() - 1;
    for s in 0..supernodes {
        let panel = Panel::new(factor, s);
        if x.0[panel.b..panel.b + panel.w]
            .iter()
            .flatten()
            .all(|&v| v == 0.0)
        {
            continue;
        }
        if panel.w == 1 {
            column_forward(factor, panel.b, x);
        } else {
            panel_forward(factor, &panel, x);
        }
    }
    for s in (0..supernodes).rev() {
        let panel = Panel::new(factor, s);
        if panel.w == 1 {
            column_backward(factor, panel.b, x);
        } else {
            panel_backward(factor, &panel, x);
        }
    }
}

/// Forward step of a single column j: `x_i −= l_ij x_j` for the rows i > j.
#[inline(always)]
fn column_forward<const S: usize>(factor: &Factor, j: usize, x: &mut Rows<S>) {
    let xj = x.get(j);
    let column = factor.start(j) + 1..factor.start(j + 1);
    for (&i, &l) in factor.row_idx[column.clone()]
        .iter()
        .zip(&factor.values[column])
    {
        let i = i as usize;
        x.set(i, simd::mul_sub(x.get(i), l, xj));
    }
}

/// Backward step of a single column j: `x_j = y_j / d_j − Σ_{i>j} l_ij x_i`.
#[inline(always)]
fn column_backward<const S: usize>(factor: &Factor, j: usize, x: &mut Rows<S>) {
    let column = factor.start(j) + 1..factor.start(j + 1);
    let rows = &factor.row_idx[column.clone()];
    let values = &factor.values[column];
    let (mut even, mut odd) = ([0.0; S], [0.0; S]);
    let mut pairs = rows.chunks_exact(2).zip(values.chunks_exact(2));
    for (r, l) in pairs.by_ref() {
        even = simd::mul_add(even, l[0], x.get(r[0] as usize));
        odd = simd::mul_add(odd, l[1], x.get(r[1] as usize));
    }
    if rows.len() % 2 == 1 {
        let k = rows.len() - 1;
        even = simd::mul_add(even, values[k], x.get(rows[k] as usize));
    }
    x.set(
        j,
        simd::scale_sub(x.get(j), factor.inv_diagonal[j], simd::add(even, odd)),
    );
}

/// One supernode's panel.
struct Panel<'a> {
    /// Panel rows: `b..e`, then the shared pattern.
    rows: &'a [u32],
    b: usize,
    w: usize,
}

impl<'a> Panel<'a> {
    #[inline(always)]
    fn new(factor: &Factor<'a>, s: usize) -> Self {
        let (b, e) = (factor.begins[s] as usize, factor.begins[s + 1] as usize);
        let (start, end) = (
            factor.row_begin[s] as usize,
            factor.row_begin[s + 1] as usize,
        );
        Self {
            rows: &factor.panel_rows[start..end],
            b,
            w: e - b,
        }
    }

    /// Panel height `w + |P|`.
    #[inline(always)]
    fn h(&self) -> usize {
        self.rows.len()
    }

    /// Column `t` of the panel from row `from` down: entry `(r, t)` is element `r − from`.
    /// Column b + t of a validated panel holds h − t entries, its first on row t.
    #[inline(always)]
    fn column<'v>(&self, factor: &Factor<'v>, t: usize, from: usize) -> &'v [f64] {
        let start = factor.start(self.b + t) - t;
        &factor.values[start + from..start + self.h()]
    }
}

/// Forward substitution through one panel (unit lower L), column blocks in order.
#[inline(always)]
fn panel_forward<const S: usize>(factor: &Factor, panel: &Panel, x: &mut Rows<S>) {
    let mut tb = 0;
    while tb < panel.w {
        let te = (tb + BLOCK).min(panel.w);
        match te - tb {
            1 => forward_block::<S, 1>(factor, panel, x, tb),
            2 => forward_block::<S, 2>(factor, panel, x, tb),
            3 => forward_block::<S, 3>(factor, panel, x, tb),
            4 => forward_block::<S, 4>(factor, panel, x, tb),
            5 => forward_block::<S, 5>(factor, panel, x, tb),
            6 => forward_block::<S, 6>(factor, panel, x, tb),
            7 => forward_block::<S, 7>(factor, panel, x, tb),
            _ => forward_block::<S, BLOCK>(factor, panel, x, tb),
        }
        tb = te;
    }
}

/// Columns `tb..tb + NB`: their triangle, then `x_r −= Σ_t L[r][t] x_t` for every row below.
#[inline(always)]
fn forward_block<const S: usize, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    x: &mut Rows<S>,
    tb: usize,
) {
    let first = panel.b + tb;
    let mut pivots = [[0.0; S]; NB];
    for t in 0..NB {
        let mut value = x.get(first + t);
        for (u, &pivot) in pivots.iter().enumerate().take(t) {
            value = simd::mul_sub(value, panel.column(factor, tb + u, tb + t)[0], pivot);
        }
        pivots[t] = value;
        x.set(first + t, value);
    }
    let below = tb + NB;
    let columns: [&[f64]; NB] = std::array::from_fn(|t| panel.column(factor, tb + t, below));
    for (k, &i) in panel.rows[below..].iter().enumerate() {
        let i = i as usize;
        let mut value = x.get(i);
        for t in 0..NB {
            value = simd::mul_sub(value, columns[t][k], pivots[t]);
        }
        x.set(i, value);
    }
}

/// Backward substitution through one panel: `x_t = y_t / d_t − Σ_{r>t} L[r][t] x_r`,
/// column blocks from the last.
#[inline(always)]
fn panel_backward<const S: usize>(factor: &Factor, panel: &Panel, x: &mut Rows<S>) {
    let mut te = panel.w;
    while te > 0 {
        let tb = te.saturating_sub(BLOCK);
        match te - tb {
            1 => backward_block::<S, 1>(factor, panel, x, tb),
            2 => backward_block::<S, 2>(factor, panel, x, tb),
            3 => backward_block::<S, 3>(factor, panel, x, tb),
            4 => backward_block::<S, 4>(factor, panel, x, tb),
            5 => backward_block_single::<S, 5>(factor, panel, x, tb),
            6 => backward_block_single::<S, 6>(factor, panel, x, tb),
            7 => backward_block_single::<S, 7>(factor, panel, x, tb),
            _ => backward_block_single::<S, BLOCK>(factor, panel, x, tb),
        }
        te = tb;
    }
}

/// Columns `tb..tb + NB`: dot products with every row below the block (even and odd rows
/// in separate accumulators), then the block's triangle from its last column.
#[inline(always)]
fn backward_block<const S: usize, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    x: &mut Rows<S>,
    tb: usize,
) {
    let below = tb + NB;
    let columns: [&[f64]; NB] = std::array::from_fn(|t| panel.column(factor, tb + t, below));
    let rows = &panel.rows[below..];
    let mut even = [[0.0; S]; NB];
    let mut odd = [[0.0; S]; NB];
    let pairs = rows.len() / 2;
    for k in 0..pairs {
        let (x0, x1) = (x.get(rows[2 * k] as usize), x.get(rows[2 * k + 1] as usize));
        for t in 0..NB {
            even[t] = simd::mul_add(even[t], columns[t][2 * k], x0);
            odd[t] = simd::mul_add(odd[t], columns[t][2 * k + 1], x1);
        }
    }
    if rows.len() % 2 == 1 {
        let k = rows.len() - 1;
        let x0 = x.get(rows[k] as usize);
        for t in 0..NB {
            even[t] = simd::mul_add(even[t], columns[t][k], x0);
        }
    }
    let below: [Row<S>; NB] = std::array::from_fn(|t| simd::add(even[t], odd[t]));
    finish_backward_block(factor, panel, x, tb, below);
}

/// As [`backward_block`] with one accumulator per column (enough independent chains once
/// the block is wide).
#[inline(always)]
fn backward_block_single<const S: usize, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    x: &mut Rows<S>,
    tb: usize,
) {
    let below = tb + NB;
    let columns: [&[f64]; NB] = std::array::from_fn(|t| panel.column(factor, tb + t, below));
    let mut acc = [[0.0; S]; NB];
    for (k, &r) in panel.rows[below..].iter().enumerate() {
        let xr = x.get(r as usize);
        for t in 0..NB {
            acc[t] = simd::mul_add(acc[t], columns[t][k], xr);
        }
    }
    finish_backward_block(factor, panel, x, tb, acc);
}

/// `x_t = y_t / d_t − below[t] − Σ_{u ∈ t+1..NB} L[u][t] x_u` from the block's last column.
#[inline(always)]
fn finish_backward_block<const S: usize, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    x: &mut Rows<S>,
    tb: usize,
    below: [Row<S>; NB],
) {
    let first = panel.b + tb;
    let mut solved = [[0.0; S]; NB];
    for t in (0..NB).rev() {
        let column = panel.column(factor, tb + t, tb);
        let inv_d = factor.inv_diagonal[first + t];
        let mut value = simd::scale_sub(x.get(first + t), inv_d, below[t]);
        for (u, &later) in solved.iter().enumerate().skip(t + 1) {
            value = simd::mul_sub(value, column[u], later);
        }
        solved[t] = value;
        x.set(first + t, value);
    }
}
