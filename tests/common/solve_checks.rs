//! Shared helpers of the solver tests: takes sizes, seeds and vectors and gives deterministic
//! random numbers, a dense Cholesky reference, the relative difference the tolerances are
//! stated in, and the meshes and factor methods the kernels are checked over. Included by the
//! `solve_*` and `numeric_faults` test files with
//! `#[path = "common/solve_checks.rs"] mod checks;`.
#![allow(dead_code)]

use crate::mesh_fixtures as fixtures;
use lapclone::mesh::Mesh;
use lapclone::simd::Path;
use lapclone::solve::FactorMethod;

/// Every numeric factorisation the solver offers.
pub const METHODS: [FactorMethod; 3] = [
    FactorMethod::Simplicial,
    FactorMethod::Supernodal,
    FactorMethod::SupernodalRelaxed,
];

/// Deterministic pseudo-random numbers in [0, 1) (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// An index in `0..n`.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() * n as f64) as usize
    }

    /// A number in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// ‖a − b‖ / ‖b‖ (Euclidean), the measure every solver tolerance is stated in.
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den.max(f64::MIN_POSITIVE)).sqrt()
}

/// Dense Cholesky solve of a small SPD system (the reference).
pub fn dense_solve(a: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let n = b.len();
    let mut l = vec![vec![0.0; n]; n];
    for j in 0..n {
        let d = a[j][j] - (0..j).map(|k| l[j][k] * l[j][k]).sum::<f64>();
        assert!(d > 0.0, "reference matrix not SPD");
        l[j][j] = d.sqrt();
        for i in j + 1..n {
            let s = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            l[i][j] = s / l[j][j];
        }
    }
    let mut y = b.to_vec();
    for i in 0..n {
        y[i] = (y[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    for i in (0..n).rev() {
        y[i] = (y[i] - (i + 1..n).map(|k| l[k][i] * y[k]).sum::<f64>()) / l[i][i];
    }
    y
}

/// Both kernel paths (the vector one is the portable one on a CPU without anything better).
pub fn simd_levels() -> Vec<Path> {
    vec![Path::Portable, Path::Vector]
}

/// A disc, a grid, or a disc beside a grid (two pieces, two elimination trees), chosen by
/// `kind`: many small supernodes and a few wide ones (a disc's top separators).
pub fn mixed_mesh(kind: u8, size: usize) -> Mesh {
    match kind % 3 {
        0 => fixtures::disc(size),
        1 => fixtures::grid(size + 1, size / 2 + 1),
        _ => fixtures::disjoint_union(&fixtures::disc(size / 2 + 1), &fixtures::grid(size, 3)),
    }
}
