//! faer's layout contract (`src/solve/faer_layout.rs`): for every numeric factorisation the
//! crate asks faer for, the factor values read through the column layout the kernels use
//! must rebuild `L·D·Lᵀ` = the permuted penalised matrix. Fails if a faer upgrade changes
//! how it stores a simplicial or supernodal LDLᵀ factor.

use crate::mesh_fixtures as fixtures;
use lapclone::solve::{laplacian, FactorMethod, LaplacianKind, PenaltyFactor, PenaltyOptions};

#[test]
fn every_factor_kind_rebuilds_the_matrix_through_the_column_layout() {
    let mesh = fixtures::disc(4);
    let l = laplacian(&mesh, LaplacianKind::Cotangent);
    let n = l.n;
    for method in [
        FactorMethod::Simplicial,
        FactorMethod::Supernodal,
        FactorMethod::SupernodalRelaxed,
    ] {
        let opts = PenaltyOptions {
            method,
            ..Default::default()
        };
        let mut f = PenaltyFactor::with_constrained(&l, &opts, &mesh.is_boundary).unwrap();
        // A fresh numeric factorisation, so the values are faer's, not the rank-1 kernel's.
        f.refactor().unwrap();
        let sym = f.symbolic();
        assert_eq!(
            sym.is_supernodal(),
            method != FactorMethod::Simplicial,
            "{method:?}"
        );
        sym.check_layout().unwrap();
        let (cp, ri, vals) = (sym.col_ptr(), sym.row_idx(), f.factor_values());
        assert_eq!(vals.len(), ri.len());
        let mut lower = vec![vec![0.0; n]; n];
        let mut d = vec![0.0; n];
        for j in 0..n {
            d[j] = vals[cp[j] as usize];
            assert!(d[j] > 0.0, "{method:?}: pivot {j} is {}", d[j]);
            lower[j][j] = 1.0;
            for p in cp[j] as usize + 1..cp[j + 1] as usize {
                lower[ri[p] as usize][j] = vals[p];
            }
        }
        let mut a = l.to_dense();
        for (v, row) in a.iter_mut().enumerate() {
            row[v] += f.epsilon() + if f.is_constrained(v) { f.alpha() } else { 0.0 };
        }
        let fwd = sym.perm_fwd();
        let mut worst: f64 = 0.0;
        for i in 0..n {
            for j in 0..n {
                let ldlt: f64 = (0..n).map(|k| lower[i][k] * d[k] * lower[j][k]).sum();
                let reference = a[fwd[i] as usize][fwd[j] as usize];
                worst = worst.max((ldlt - reference).abs() / f.alpha());
            }
        }
        assert!(worst <= 1e-13, "{method:?}: LDLᵀ off by {worst}");
    }
}
