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
//! streams, and each row of `x` (all its channels) one SIMD register. A supernode of width 1
//! runs a plain column kernel. Narrow backward blocks keep two independent accumulators
//! per column (even and odd rows) to hide the multiply-add latency. Because the pattern was
//! validated at analysis, the sweeps index without bounds checks.
//!
//! The forward sweep skips a supernode whose rows of `x` are all zero when it is reached:
//! its panel would subtract exact zeros. Dirichlet right-hand sides are zero off the
//! constrained boundary, so the sweep touches only the elimination-tree reach of the
//! boundary (measured with `bench factor`: solve3 0.052 → 0.046 ms at 2k vertices, about
//! 10 % at 52k). Skipping changes at most the sign of a zero, never a value.
//!
//! SIMD: on x86_64 the sweeps are compiled twice, portable (baseline ISA, separate multiply
//! and add) and with AVX2+FMA, chosen at run time by [`SimdLevel::detect`]. The arithmetic
//! order is fixed by the code, never by the data or the thread count, so a given binary on a
//! given CPU gives bit-identical results; the two levels differ from each other by rounding.
//!
//! Measured and rejected (2-core machine, `bench factor` and A/B runs in one process):
//! * Channel-major panels (rows gathered into per-channel scratch, SIMD down the columns,
//!   one factor load for all channels): slower than these row vectors at every threshold
//!   width tried (4–16), the gather/scatter and horizontal sums outweigh the saved
//!   broadcasts at the panel widths of 2-D meshes.
//! * Fusing the permutations into the sweeps (read the right-hand side when a position
//!   becomes a pivot, write it when solved): 10–20 % slower at 52k vertices than two
//!   vertex-order passes, which touch one random row of `x` per vertex instead of `k`
//!   random right-hand-side entries.
//! * Splitting the forward multiply-add chain in two, prefetching the next panel's rows of
//!   `x`: no gain.
//! * Relaxed amalgamation with fewer explicit zeros: 0–15 % faster solves at 52k, within the
//!   noise of a shared machine, at a slower factorisation; the factor keeps faer's default.

#[cfg(target_arch = "x86_64")]
use super::lanes::{Avx4, Fma1, Fma2};
use super::lanes::{Lanes, Portable};
use super::schedule::SolveSchedule;
use super::symbolic::SymbolicFactor;

/// Columns of a panel taken together per pass over its rows.
pub const BLOCK: usize = 8;

/// Instruction-set level of the solve kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdLevel {
    /// Baseline code, separate multiply and add (any target).
    Portable,
    /// AVX2 with fused multiply-add (x86_64 CPUs that have both).
    Avx2Fma,
}

impl SimdLevel {
    /// The best level this CPU supports.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
                return SimdLevel::Avx2Fma;
            }
        }
        SimdLevel::Portable
    }

    /// Whether this CPU can run the level.
    pub fn is_supported(self) -> bool {
        match self {
            SimdLevel::Portable => true,
            SimdLevel::Avx2Fma => SimdLevel::detect() == SimdLevel::Avx2Fma,
        }
    }
}

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
/// The solve multiplies by these instead of dividing: a division per unknown was ≈ 6 % of
/// a 2k-vertex solve. Whoever changes pivots keeps them current (see
/// [`PenaltyFactor`](super::PenaltyFactor), which refreshes the elimination-tree path of
/// every rank-1 switch).
///
/// # Panics
/// If `values` or `out` have the wrong length.
pub fn inverse_diagonal(symbolic: &SymbolicFactor, values: &[f64], out: &mut [f64]) {
    assert!(values.len() == symbolic.nnz_factor() && out.len() == symbolic.n());
    for (inv, &start) in out.iter_mut().zip(symbolic.col_ptr()) {
        *inv = 1.0 / values[start as usize];
    }
}

/// Solves in place at the best [`SimdLevel`] of this CPU. `values` are the factor values of
/// `symbolic` ([`SymbolicFactor::nnz_factor`] of them) and `inv_diagonal` their
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
    ldlt_solve_supernodal_at(
        SimdLevel::detect(),
        symbolic,
        values,
        inv_diagonal,
        x,
        lanes,
    );
}

/// [`ldlt_solve_supernodal`] at a chosen level (tests compare the levels).
///
/// # Panics
/// As [`ldlt_solve_supernodal`], and if this CPU does not support `level`.
pub fn ldlt_solve_supernodal_at(
    level: SimdLevel,
    symbolic: &SymbolicFactor,
    values: &[f64],
    inv_diagonal: &[f64],
    x: &mut [f64],
    lanes: usize,
) {
    assert!(matches!(lanes, 1 | 2 | 4), "lanes must be 1, 2 or 4");
    let factor = Factor::new(level, symbolic, values, inv_diagonal, x.len(), lanes);
    match (level, lanes) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Factor::new` checked the CPU features.
        (SimdLevel::Avx2Fma, _) => unsafe { in_place_avx2(&factor, x, lanes) },
        (_, 1) => solve_all::<Portable<1>>(&factor, x),
        (_, 2) => solve_all::<Portable<2>>(&factor, x),
        _ => solve_all::<Portable<4>>(&factor, x),
    }
}

/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn in_place_avx2(factor: &Factor, x: &mut [f64], lanes: usize) {
    match lanes {
        1 => solve_all::<Fma1>(factor, x),
        2 => solve_all::<Fma2>(factor, x),
        _ => solve_all::<Avx4>(factor, x),
    }
}

/// As [`ldlt_solve_supernodal`], following the factor's [`SolveSchedule`] when it has one
/// (see [`schedule`](super::schedule)): the two subtree groups of each sweep run on two
/// threads when `threads ≥ 2`, one after the other otherwise — the same bits either way.
/// `spill` holds at least `x.len()` values, all zero; they are zero again on return.
///
/// # Panics
/// As [`ldlt_solve_supernodal`], and if `spill` is too short.
pub fn ldlt_solve_scheduled(
    symbolic: &SymbolicFactor,
    values: &[f64],
    inv_diagonal: &[f64],
    x: &mut [f64],
    lanes: usize,
    spill: &mut [f64],
    threads: usize,
) {
    let level = SimdLevel::detect();
    ldlt_solve_scheduled_at(
        level,
        symbolic,
        values,
        inv_diagonal,
        x,
        lanes,
        spill,
        threads,
    );
}

/// [`ldlt_solve_scheduled`] at a chosen level (tests compare the levels).
///
/// # Panics
/// As [`ldlt_solve_scheduled`], and if this CPU does not support `level`.
#[allow(clippy::too_many_arguments)]
pub fn ldlt_solve_scheduled_at(
    level: SimdLevel,
    symbolic: &SymbolicFactor,
    values: &[f64],
    inv_diagonal: &[f64],
    x: &mut [f64],
    lanes: usize,
    spill: &mut [f64],
    threads: usize,
) {
    let Some(schedule) = symbolic.schedule() else {
        return ldlt_solve_supernodal_at(level, symbolic, values, inv_diagonal, x, lanes);
    };
    assert!(matches!(lanes, 1 | 2 | 4), "lanes must be 1, 2 or 4");
    assert!(
        spill.len() >= x.len(),
        "spill must hold as many values as x"
    );
    let len = x.len();
    let (x, spill) = (Shared::new(x), Shared::new(&mut spill[..len]));
    let factor = || Factor::new(level, symbolic, values, inv_diagonal, len, lanes);
    let group = |g: usize| Part {
        list: schedule.group(g),
        schedule,
    };
    let top = Part {
        list: schedule.top(),
        schedule,
    };
    let phase = |part: Part, sweep: Sweep, to: Shared| {
        sweep_at(level, lanes, &factor(), part, sweep, x, to)
    };
    both(
        threads,
        || phase(group(0), Sweep::Forward, x),
        || phase(group(1), Sweep::Forward, spill),
    );
    merge_spill(schedule, symbolic, x, spill, lanes);
    phase(top, Sweep::Forward, x);
    phase(top, Sweep::Backward, x);
    both(
        threads,
        || phase(group(0), Sweep::Backward, x),
        || phase(group(1), Sweep::Backward, x),
    );
}

/// Runs `first` and `second`, on two threads of rayon's pool when `threads ≥ 2` (a
/// persistent pool: spawning threads per solve would allocate, and costs ≈ 20 µs).
fn both(threads: usize, first: impl FnOnce() + Send, second: impl FnOnce() + Send) {
    if threads >= 2 {
        rayon::join(first, second);
    } else {
        first();
        second();
    }
}

/// `x_r += spill_r`, then `spill_r = 0`, for every top row (the rows group 1 spilled to).
fn merge_spill(
    schedule: &SolveSchedule,
    symbolic: &SymbolicFactor,
    x: Shared,
    spill: Shared,
    lanes: usize,
) {
    let supernodes = symbolic.supernodes();
    for &s in schedule.top() {
        let columns = supernodes.columns(s as usize);
        let values = columns.start * lanes..columns.end * lanes;
        assert!(values.end <= x.len && values.end <= spill.len);
        // SAFETY: in bounds (asserted); no other thread runs between the two phases.
        let (x, spill) = unsafe {
            (
                std::slice::from_raw_parts_mut(x.ptr.add(values.start), values.len()),
                std::slice::from_raw_parts_mut(spill.ptr.add(values.start), values.len()),
            )
        };
        for (target, spilled) in x.iter_mut().zip(spill) {
            *target += *spilled;
            *spilled = 0.0;
        }
    }
}

/// One sweep over one part of a schedule at the given level and lane count.
fn sweep_at(
    level: SimdLevel,
    lanes: usize,
    factor: &Factor,
    part: Part,
    sweep: Sweep,
    x: Shared,
    spill: Shared,
) {
    match (level, lanes) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Factor::new` checked the CPU features.
        (SimdLevel::Avx2Fma, _) => unsafe { sweep_avx2(factor, part, sweep, x, spill, lanes) },
        (_, 1) => run_listed::<Portable<1>>(factor, part, sweep, x, spill),
        (_, 2) => run_listed::<Portable<2>>(factor, part, sweep, x, spill),
        _ => run_listed::<Portable<4>>(factor, part, sweep, x, spill),
    }
}

/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn sweep_avx2(
    factor: &Factor,
    part: Part,
    sweep: Sweep,
    x: Shared,
    spill: Shared,
    lanes: usize,
) {
    match lanes {
        1 => run_listed::<Fma1>(factor, part, sweep, x, spill),
        2 => run_listed::<Fma2>(factor, part, sweep, x, spill),
        _ => run_listed::<Avx4>(factor, part, sweep, x, spill),
    }
}

/// The factor as the sweeps read it.
struct Factor<'a> {
    prefetched: std::cell::Cell<usize>,
    distance: usize,
    col_ptr: &'a [u32],
    row_idx: &'a [u32],
    values: &'a [f64],
    inv_diagonal: &'a [f64],
    begins: &'a [u32],
    /// Compact panel rows (see [`SupernodePartition`](super::supernodes::SupernodePartition)).
    row_begin: &'a [u32],
    panel_rows: &'a [u32],
}

impl<'a> Factor<'a> {
    /// Checks what the unchecked sweeps rely on beyond what `check_layout` verified when
    /// `symbolic` was built (col_ptr has n + 1 increasing entries ending at nnz, every row
    /// index is < n, every supernode b..e is a panel whose column b + t holds h − t
    /// entries): the lengths of `values` and `x`, and the CPU level.
    fn new(
        level: SimdLevel,
        symbolic: &'a SymbolicFactor,
        values: &'a [f64],
        inv_diagonal: &'a [f64],
        x_len: usize,
        lanes: usize,
    ) -> Self {
        assert!(
            inv_diagonal.len() == symbolic.n(),
            "one inverse pivot per unknown"
        );
        assert!(
            x_len == symbolic.n() * lanes,
            "x must hold n rows of `lanes` values"
        );
        assert!(
            values.len() == symbolic.nnz_factor(),
            "values must match the pattern"
        );
        assert!(level.is_supported(), "SIMD level {level:?} not supported");
        Self {
            prefetched: std::cell::Cell::new(0),
            distance: if size_of_val(values) >= PREFETCH_MIN_BYTES {
                PREFETCH_DISTANCE
            } else {
                0
            },
            col_ptr: symbolic.col_ptr(),
            row_idx: symbolic.row_idx(),
            values,
            inv_diagonal,
            begins: symbolic.supernodes().begins(),
            row_begin: symbolic.supernodes().panel_row_begins(),
            panel_rows: symbolic.supernodes().all_panel_rows(),
        }
    }
}

/// Direction of a sweep.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Sweep {
    Forward,
    Backward,
}

/// The unscheduled solve: both sweeps over every supernode, every row in `x`. `x` is a
/// function argument (not a [`Shared`] view) so that the compiler knows its stores never
/// touch the factor: measured ≈ 8 % of a 2k-vertex solve.
#[inline(always)]
fn solve_all<V: Lanes>(factor: &Factor, x: &mut [f64]) {
    let shared = Shared::new(x);
    let mut x = Rows::<V>::new(shared);
    let mut spill = x;
    let supernodes = factor.begins.len() - 1;
    factor.prefetched.set(0);
    for s in 0..supernodes {
        let panel = Panel::new(factor, s);
        let own = panel.h();
        forward_step::<V, false>(factor, &panel, own, &mut x, &mut spill);
    }
    factor.prefetched.set(factor.values.len());
    for s in (0..supernodes).rev() {
        backward_step::<V, false>(factor, &Panel::new(factor, s), &mut x);
    }
}

/// One sweep over the listed supernodes (ascending) of a schedule; forward steps write the
/// panel rows past [`SolveSchedule::own_rows`] to `spill`.
#[inline(always)]
fn run_listed<V: Lanes>(factor: &Factor, part: Part, sweep: Sweep, x: Shared, spill: Shared) {
    let (mut x, mut spill) = (Rows::<V>::new(x), Rows::<V>::new(spill));
    let Part { list, schedule } = part;
    match sweep {
        Sweep::Forward => {
            factor.prefetched.set(0);
            for &s in list {
                let panel = Panel::new(factor, s as usize);
                let own = schedule.own_rows(s as usize);
                forward_step::<V, true>(factor, &panel, own, &mut x, &mut spill);
            }
        }
        Sweep::Backward => {
            factor.prefetched.set(factor.values.len());
            for &s in list.iter().rev() {
                backward_step::<V, true>(factor, &Panel::new(factor, s as usize), &mut x);
            }
        }
    }
}

/// Supernodes of one part of a schedule (a group or the top).
#[derive(Clone, Copy)]
struct Part<'a> {
    list: &'a [u32],
    schedule: &'a SolveSchedule,
}

/// One supernode of the forward sweep: panel rows `..own` to `x`, the rest to `spill`.
/// `LISTED`: the part skips supernodes, and `own` may be short of the panel height (the
/// unscheduled sweep compiles without either, as it was before schedules existed).
#[inline(always)]
fn forward_step<'a, V: Lanes, const LISTED: bool>(
    factor: &Factor,
    panel: &Panel,
    own: usize,
    x: &mut Rows<'a, V>,
    spill: &mut Rows<'a, V>,
) {
    if LISTED {
        // Other supernodes' values are skipped: prefetch from this panel on.
        factor
            .prefetched
            .set(factor.prefetched.get().max(factor.start(panel.b)));
    }
    if x.all_zero(panel.b, panel.w) {
        return;
    }
    if panel.w == 1 {
        column_forward::<V, LISTED>(factor, panel.b, own, x, spill);
    } else {
        panel_forward::<V, LISTED>(factor, panel, own, x, spill);
    }
}

/// One supernode of the backward sweep (`LISTED` as in [`forward_step`]).
#[inline(always)]
fn backward_step<V: Lanes, const LISTED: bool>(factor: &Factor, panel: &Panel, x: &mut Rows<V>) {
    if LISTED {
        factor
            .prefetched
            .set(factor.prefetched.get().min(factor.start(panel.b + panel.w)));
    }
    if panel.w == 1 {
        column_backward(factor, panel.b, x);
    } else {
        panel_backward(factor, panel, x);
    }
}

/// Software prefetch of the factor values, this many values ahead of the sweep. The sweeps
/// read the values in (reverse) storage order, but as short interleaved column streams
/// (a block's columns) that the hardware prefetcher follows poorly: measured at 52k vertices
/// (18.5 MB of values) the solve gains ≈ 10 %, flat from 128 to 512 values ahead.
const PREFETCH_DISTANCE: usize = 256;

/// Factors smaller than this (a few times the L2 cache) stay cached between solves, where
/// the prefetch instructions only cost time (≈ 12 % at 2k vertices).
const PREFETCH_MIN_BYTES: usize = 2 << 20;

/// A hint to load the cache line of `values[p]` (a no-op off x86_64).
#[inline(always)]
fn prefetch(values: &[f64], p: usize) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: prefetching never faults; p < values.len() keeps the address in bounds anyway.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(
            values.as_ptr().add(p.min(values.len().saturating_sub(1))) as *const i8
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (values, p);
}

/// The right-hand sides as rows of `V`, indexed without bounds checks: every index passed
/// is a column or a row index of the validated pattern, hence < n. A raw view, so that the
/// two threads of a scheduled sweep (and the spill target of a panel, which may be `x`
/// itself) can hold it at once; who writes which rows is the schedule's contract.
struct Rows<'a, V> {
    ptr: *mut f64,
    len: usize,
    lanes: std::marker::PhantomData<(Shared<'a>, V)>,
}

/// A buffer of right-hand-side rows that the threads of a scheduled solve share; it is
/// only ever read and written through [`Rows`] views, under the schedule's contract.
#[derive(Clone, Copy)]
struct Shared<'a> {
    ptr: *mut f64,
    len: usize,
    borrow: std::marker::PhantomData<&'a mut [f64]>,
}

// SAFETY: a `Shared` reaches the second thread of a scheduled sweep only, which writes rows
// that no other thread touches during that phase (see [`SolveSchedule`]).
unsafe impl Send for Shared<'_> {}
// SAFETY: as for `Send`: the threads of one phase write disjoint rows.
unsafe impl Sync for Shared<'_> {}

impl<'a> Shared<'a> {
    fn new(x: &'a mut [f64]) -> Self {
        Self {
            ptr: x.as_mut_ptr(),
            len: x.len(),
            borrow: std::marker::PhantomData,
        }
    }
}

impl<V> Clone for Rows<'_, V> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<V> Copy for Rows<'_, V> {}

impl<'a, V: Lanes> Rows<'a, V> {
    #[inline(always)]
    fn new(x: Shared<'a>) -> Self {
        Self {
            ptr: x.ptr,
            len: x.len,
            lanes: std::marker::PhantomData,
        }
    }

    #[inline(always)]
    fn get(&self, i: usize) -> V {
        debug_assert!(i * V::S + V::S <= self.len);
        // SAFETY: i < n (see the type doc) and len = n · S (asserted at the entry).
        unsafe { V::load(self.ptr.add(i * V::S)) }
    }

    /// Whether rows `b..b + w` are all zero (then a forward panel step changes nothing).
    #[inline(always)]
    fn all_zero(&self, b: usize, w: usize) -> bool {
        debug_assert!((b + w) * V::S <= self.len);
        // SAFETY: as in `get`; the rows are pivot rows of the running part, which no other
        // thread writes.
        let rows = unsafe { std::slice::from_raw_parts(self.ptr.add(b * V::S), w * V::S) };
        rows.iter().all(|&v| v == 0.0)
    }

    #[inline(always)]
    fn set(&mut self, i: usize, v: V) {
        debug_assert!(i * V::S + V::S <= self.len);
        // SAFETY: as in `get`.
        unsafe { v.store(self.ptr.add(i * V::S)) }
    }
}

impl Factor<'_> {
    /// Prefetch values up to `until + distance` (forward sweep).
    #[inline(always)]
    fn prefetch_up(&self, until: usize) {
        if self.distance == 0 {
            return;
        }
        let until = (until + self.distance).min(self.values.len());
        let mut p = self.prefetched.get();
        while p < until {
            prefetch(self.values, p);
            p += 8;
        }
        self.prefetched.set(p);
    }

    /// Prefetch values down to `until − distance` (backward sweep).
    #[inline(always)]
    fn prefetch_down(&self, until: usize) {
        if self.distance == 0 {
            return;
        }
        let until = until.saturating_sub(self.distance);
        let mut p = self.prefetched.get();
        while p > until {
            p = p.saturating_sub(8);
            prefetch(self.values, p);
        }
        self.prefetched.set(p);
    }
    /// Row index `p` of the pattern (p < nnz).
    #[inline(always)]
    fn row(&self, p: usize) -> usize {
        debug_assert!(p < self.row_idx.len());
        // SAFETY: callers pass positions inside a column of the validated pattern.
        unsafe { *self.row_idx.get_unchecked(p) as usize }
    }

    /// `1 / d_j` (j < n).
    #[inline(always)]
    fn inv_pivot(&self, j: usize) -> f64 {
        debug_assert!(j < self.inv_diagonal.len());
        // SAFETY: callers pass columns (< n); inv_diagonal.len() = n was asserted.
        unsafe { *self.inv_diagonal.get_unchecked(j) }
    }

    /// Factor value `p` (p < nnz).
    #[inline(always)]
    fn value(&self, p: usize) -> f64 {
        debug_assert!(p < self.values.len());
        // SAFETY: as in `row`; values.len() = nnz was asserted at the entry.
        unsafe { *self.values.get_unchecked(p) }
    }

    /// `col_ptr[j]` (j ≤ n).
    #[inline(always)]
    fn start(&self, j: usize) -> usize {
        debug_assert!(j < self.col_ptr.len());
        // SAFETY: callers pass columns of supernodes, ≤ n.
        unsafe { *self.col_ptr.get_unchecked(j) as usize }
    }
}

/// Forward step of a single column j: `x_i −= l_ij x_j` for the rows i > j, the column's
/// first `own` rows (j included) in `x`, the rest in `spill`.
#[inline(always)]
fn column_forward<'a, V: Lanes, const SPILL: bool>(
    factor: &Factor,
    j: usize,
    own: usize,
    x: &mut Rows<'a, V>,
    spill: &mut Rows<'a, V>,
) {
    factor.prefetch_up(factor.start(j + 1));
    let xj = x.get(j);
    let (start, end) = (factor.start(j), factor.start(j + 1));
    let split = if SPILL { start + own } else { end };
    for p in start + 1..split {
        let i = factor.row(p);
        x.set(i, x.get(i).mul_sub(factor.value(p), xj));
    }
    for p in split..end {
        let i = factor.row(p);
        spill.set(i, spill.get(i).mul_sub(factor.value(p), xj));
    }
}

/// Backward step of a single column j: `x_j = y_j / d_j − Σ_{i>j} l_ij x_i`.
#[inline(always)]
fn column_backward<V: Lanes>(factor: &Factor, j: usize, x: &mut Rows<V>) {
    factor.prefetch_down(factor.start(j));
    let (start, end) = (factor.start(j), factor.start(j + 1));
    let (mut even, mut odd) = (V::zero(), V::zero());
    let mut p = start + 1;
    while p + 2 <= end {
        even = even.mul_add(factor.value(p), x.get(factor.row(p)));
        odd = odd.mul_add(factor.value(p + 1), x.get(factor.row(p + 1)));
        p += 2;
    }
    if p < end {
        even = even.mul_add(factor.value(p), x.get(factor.row(p)));
    }
    x.set(j, x.get(j).scale_sub(factor.inv_pivot(j), even.add(odd)));
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
        debug_assert!(s + 1 < factor.begins.len() && s + 1 < factor.row_begin.len());
        // SAFETY: s < number of supernodes, and begins / row_begin both have one entry per
        // supernode plus one (validated with the pattern).
        let (b, e, start, end) = unsafe {
            (
                *factor.begins.get_unchecked(s) as usize,
                *factor.begins.get_unchecked(s + 1) as usize,
                *factor.row_begin.get_unchecked(s) as usize,
                *factor.row_begin.get_unchecked(s + 1) as usize,
            )
        };
        debug_assert!(start <= end && end <= factor.panel_rows.len());
        // SAFETY: the row offsets are increasing and end at panel_rows.len() (validated).
        let rows = unsafe { factor.panel_rows.get_unchecked(start..end) };
        Self { rows, b, w: e - b }
    }

    /// Panel height `w + |P|`.
    #[inline(always)]
    fn h(&self) -> usize {
        self.rows.len()
    }

    /// Row index of panel row r (r < h).
    #[inline(always)]
    fn row(&self, r: usize) -> usize {
        debug_assert!(r < self.rows.len());
        // SAFETY: callers pass r < h.
        unsafe { *self.rows.get_unchecked(r) as usize }
    }

    /// Entry (r, t) of the panel, r ≥ t, is `values[base(t) + r]`.
    #[inline(always)]
    fn base(&self, factor: &Factor, t: usize) -> usize {
        factor.start(self.b + t) - t
    }

    /// Factor entry (r, t), `t ≤ r < h`, given `base = base(t)`.
    #[inline(always)]
    fn entry(&self, factor: &Factor, base: usize, r: usize) -> f64 {
        // Column b + t of a validated panel holds h − t entries, so base(t) + r lies in it.
        factor.value(base + r)
    }
}

/// Forward substitution through one panel (unit lower L), column blocks in order; panel
/// rows `own..` go to `spill`.
#[inline(always)]
fn panel_forward<'a, V: Lanes, const SPILL: bool>(
    factor: &Factor,
    panel: &Panel,
    own: usize,
    x: &mut Rows<'a, V>,
    spill: &mut Rows<'a, V>,
) {
    let mut tb = 0;
    while tb < panel.w {
        let te = (tb + BLOCK).min(panel.w);
        let target = Targets {
            own: if SPILL { own } else { panel.h() },
            x: &mut *x,
            spill: &mut *spill,
        };
        match te - tb {
            1 => forward_block::<V, 1>(factor, panel, target, tb),
            2 => forward_block::<V, 2>(factor, panel, target, tb),
            3 => forward_block::<V, 3>(factor, panel, target, tb),
            4 => forward_block::<V, 4>(factor, panel, target, tb),
            5 => forward_block::<V, 5>(factor, panel, target, tb),
            6 => forward_block::<V, 6>(factor, panel, target, tb),
            7 => forward_block::<V, 7>(factor, panel, target, tb),
            _ => forward_block::<V, BLOCK>(factor, panel, target, tb),
        }
        tb = te;
    }
}

/// Where a forward block writes: panel rows before `own` to `x`, the rest to `spill`.
struct Targets<'r, 'a, V> {
    own: usize,
    x: &'r mut Rows<'a, V>,
    spill: &'r mut Rows<'a, V>,
}

/// Columns `tb..tb + NB`: their triangle, then `x_r −= Σ_t L[r][t] x_t` for every row below.
#[inline(always)]
fn forward_block<V: Lanes, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    target: Targets<V>,
    tb: usize,
) {
    let Targets { own, x, spill } = target;
    let first = panel.b + tb;
    factor.prefetch_up(factor.start(first + NB));
    let bases: [usize; NB] = std::array::from_fn(|t| panel.base(factor, tb + t));
    let mut pivots = [V::zero(); NB];
    for t in 0..NB {
        let mut value = x.get(first + t);
        for u in 0..t {
            value = value.mul_sub(panel.entry(factor, bases[u], tb + t), pivots[u]);
        }
        pivots[t] = value;
        x.set(first + t, value);
    }
    subtract_block(factor, panel, &bases, &pivots, tb + NB..own, x);
    subtract_block(factor, panel, &bases, &pivots, own..panel.h(), spill);
}

/// `rows_r −= Σ_t L[r][t] pivot_t` for the panel rows `r` in `range`.
#[inline(always)]
fn subtract_block<V: Lanes, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    bases: &[usize; NB],
    pivots: &[V; NB],
    range: std::ops::Range<usize>,
    rows: &mut Rows<V>,
) {
    for r in range {
        let i = panel.row(r);
        let mut value = rows.get(i);
        for t in 0..NB {
            value = value.mul_sub(panel.entry(factor, bases[t], r), pivots[t]);
        }
        rows.set(i, value);
    }
}

/// Backward substitution through one panel: `x_t = y_t / d_t − Σ_{r>t} L[r][t] x_r`,
/// column blocks from the last.
#[inline(always)]
fn panel_backward<V: Lanes>(factor: &Factor, panel: &Panel, x: &mut Rows<V>) {
    let mut te = panel.w;
    while te > 0 {
        let tb = te.saturating_sub(BLOCK);
        match te - tb {
            1 => backward_block::<V, 1>(factor, panel, x, tb),
            2 => backward_block::<V, 2>(factor, panel, x, tb),
            3 => backward_block::<V, 3>(factor, panel, x, tb),
            4 => backward_block::<V, 4>(factor, panel, x, tb),
            5 => backward_block_single::<V, 5>(factor, panel, x, tb),
            6 => backward_block_single::<V, 6>(factor, panel, x, tb),
            7 => backward_block_single::<V, 7>(factor, panel, x, tb),
            _ => backward_block_single::<V, BLOCK>(factor, panel, x, tb),
        }
        te = tb;
    }
}

/// Columns `tb..tb + NB`: dot products with every row below the block (even and odd rows
/// in separate accumulators), then the block's triangle from its last column.
#[inline(always)]
fn backward_block<V: Lanes, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    x: &mut Rows<V>,
    tb: usize,
) {
    let h = panel.h();
    factor.prefetch_down(factor.start(panel.b + tb));
    let bases: [usize; NB] = std::array::from_fn(|t| panel.base(factor, tb + t));
    let mut even = [V::zero(); NB];
    let mut odd = [V::zero(); NB];
    let mut r = tb + NB;
    while r + 2 <= h {
        let (x0, x1) = (x.get(panel.row(r)), x.get(panel.row(r + 1)));
        for t in 0..NB {
            even[t] = even[t].mul_add(panel.entry(factor, bases[t], r), x0);
            odd[t] = odd[t].mul_add(panel.entry(factor, bases[t], r + 1), x1);
        }
        r += 2;
    }
    if r < h {
        let x0 = x.get(panel.row(r));
        for t in 0..NB {
            even[t] = even[t].mul_add(panel.entry(factor, bases[t], r), x0);
        }
    }
    finish_backward_block(
        factor,
        panel,
        x,
        tb,
        &bases,
        std::array::from_fn(|t| even[t].add(odd[t])),
    );
}

/// As [`backward_block`] with one accumulator per column (enough independent chains once
/// the block is wide).
#[inline(always)]
fn backward_block_single<V: Lanes, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    x: &mut Rows<V>,
    tb: usize,
) {
    factor.prefetch_down(factor.start(panel.b + tb));
    let bases: [usize; NB] = std::array::from_fn(|t| panel.base(factor, tb + t));
    let mut acc = [V::zero(); NB];
    for r in tb + NB..panel.h() {
        let xr = x.get(panel.row(r));
        for t in 0..NB {
            acc[t] = acc[t].mul_add(panel.entry(factor, bases[t], r), xr);
        }
    }
    finish_backward_block(factor, panel, x, tb, &bases, acc);
}

/// `x_t = y_t / d_t − below[t] − Σ_{u ∈ t+1..NB} L[u][t] x_u` from the block's last column.
#[inline(always)]
fn finish_backward_block<V: Lanes, const NB: usize>(
    factor: &Factor,
    panel: &Panel,
    x: &mut Rows<V>,
    tb: usize,
    bases: &[usize; NB],
    below: [V; NB],
) {
    let first = panel.b + tb;
    let mut solved = [V::zero(); NB];
    for t in (0..NB).rev() {
        let inv_d = factor.inv_pivot(first + t);
        let mut value = x.get(first + t).scale_sub(inv_d, below[t]);
        for (u, &later) in solved.iter().enumerate().skip(t + 1) {
            value = value.mul_sub(panel.entry(factor, bases[t], tb + u), later);
        }
        solved[t] = value;
        x.set(first + t, value);
    }
}
