//! Solve stage: takes a [`Mesh`](crate::mesh::Mesh) (or a Laplacian read from Matrix Market)
//! and gives a factored penalised Laplacian `L + P + εI` whose constraints switch on and off
//! by rank-1 updates/downdates of the factor, with multi-RHS in-place solves.
//!
//! Work is split as in faer: [`symbolic`] (AMD ordering, elimination tree, factor pattern,
//! its [`supernodes`] — once per mesh), [`numeric`] (LDLᵀ values — once, and again only when
//! a guard fires), [`update`] (the rank-1 kernel, per constraint change) and
//! [`solve_supernodal`] (forward/back substitution over dense supernode panels, per frame,
//! on one thread; [`solve`](mod@solve) keeps the column-by-column reference). [`penalty`]
//! ties them together in [`PenaltyFactor`]. One value array serves all kernels: the
//! supernodal solve reads the column layout the rank-1 kernel updates, so no conversion
//! follows a switch; [`faer_layout`] holds that layout's contract with faer.
//!
//! # Numerical rules (documented here once, used throughout)
//! * **Penalty α.** Default `α = 1e8 · s`, `s = max |l_ii|` (1 if the matrix is zero). At a
//!   constrained row `(Lf)_v + α (f_v − c_v) = 0`, so `|f_v − c_v| ≤ l_vv · range(f) / α
//!   ≤ 1e-8 · range` — well inside the 1e-6 target. A naive downdate would subtract α from a
//!   pivot ≈ α and lose `log10(α / d)` digits (≈ 1e-9 relative drift per downdate at this α);
//!   [`update`] avoids both cancellations (the new pivot is recomputed from its factor row,
//!   and the first column is rescaled by `d / d̄` instead of `1 − γ`), so drift stays at
//!   rounding level (10,000 random switches: ≈ 1e-15 from a fresh factorisation) and a large
//!   α costs nothing.
//! * **Regularisation ε.** `ε = 1e-12 · s` is added to every diagonal entry, and faer's
//!   dynamic regularisation replaces any pivot below `ε/2` by `ε`. A piece of the mesh with no
//!   constraint therefore factors without failure and maps a zero right-hand side to a zero
//!   membrane (its solution for a non-zero right-hand side is ill-posed and scales as 1/ε).
//!   With constraints present the shift perturbs solutions by ≈ ε / λ_min relative.
//! * **Guards** (see [`penalty`]): a pivot that would become ≤ `ε/2` during a downdate, an
//!   accumulated drift estimate `Σ u · max_j d_j / d̄_j` (u = 2⁻⁵³, over downdates since the
//!   last factorisation) above `PenaltyOptions::drift_budget` (default 1e-11), or a batch
//!   whose summed elimination-path cost exceeds the estimated refactorisation cost triggers
//!   a refactorisation from the stored matrix and the current constrained set.

pub mod csc;
pub mod faer_layout;
pub mod laplacian;
pub mod matrix_market;
pub mod numeric;
pub mod penalty;
#[allow(clippy::module_inception)]
pub mod solve;
pub mod solve_supernodal;
pub mod supernodes;
pub mod symbolic;
pub mod update;

pub use csc::SymmetricCsc;
pub use laplacian::{laplacian, LaplacianKind};
pub(crate) use matrix_market::matrix_market_text;
pub use matrix_market::write_matrix_market;
pub use penalty::{PenaltyFactor, PenaltyOptions, SwitchStats};
pub use symbolic::FactorMethod;

use std::path::PathBuf;

/// Everything that can go wrong in the solve stage.
// Each variant's `#[error]` text says what it is and names its fields.
#[allow(missing_docs)]
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}:{line}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("matrix is not valid: {0}")]
    InvalidMatrix(String),
    #[error("matrix of dimension {0} is too large for 32-bit factor indices")]
    TooLarge(usize),
    #[error("vertex {vertex} is out of range for a matrix of dimension {n}")]
    VertexOutOfRange { vertex: usize, n: usize },
    #[error("constrained set has length {got}, expected {expected}")]
    WrongLength { got: usize, expected: usize },
    #[error("penalty weight α = {0} must be finite and positive")]
    BadAlpha(f64),
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    #[error("numeric factorisation failed: {0}")]
    Numeric(String),
}
