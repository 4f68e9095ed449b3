//! The dense generalized symmetric eigensolver, for small problems and as a reference:
//! `S x = lambda B x` through `B = L L^T`, `C = L^-1 S L^-T`, `C y = lambda y`,
//! `x = L^-T y`.

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par, Side};

use super::SparseMatrix;

/// Errors of the dense path.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum DenseEigenError {
    /// B is not positive definite.
    #[error("the mass matrix is not positive definite (is some vertex unreferenced?)")]
    MassNotPositiveDefinite,
    /// The eigen-decomposition did not converge.
    #[error("the dense eigen-decomposition did not converge")]
    NoConvergence,
}

fn to_dense(a: &SparseMatrix, scale: f64) -> Mat<f64> {
    let mut m = Mat::<f64>::zeros(a.nrows(), a.ncols());
    for c in 0..a.ncols() {
        let (rows, vals) = a.col(c);
        for (&r, &v) in rows.iter().zip(vals) {
            m[(r, c)] = v / scale;
        }
    }
    m
}

/// All `n` generalized eigenpairs of (S, B), eigenvalues ascending, eigenvectors
/// B-orthonormal, returned as (values, column-major `n x n` vectors). O(n^3): for
/// `n` up to a few thousand.
pub fn dense_generalized_eigen(
    s: &SparseMatrix,
    b: &SparseMatrix,
) -> Result<(Vec<f64>, Vec<f64>), DenseEigenError> {
    let n = s.nrows();
    // Work on unit-scaled copies: faer's dense eigensolver is not invariant to the
    // overall scale of its input (entries near 1e-12 or 1e20 lose all accuracy), and a
    // mesh scaled by alpha scales B by alpha^2. The eigenvalues are scaled back below.
    let s_scale = s.max_abs().max(f64::MIN_POSITIVE);
    let b_scale = b.max_abs().max(f64::MIN_POSITIVE);
    let sd = to_dense(s, s_scale);
    let bd = to_dense(b, b_scale);
    let llt = bd
        .llt(Side::Lower)
        .map_err(|_| DenseEigenError::MassNotPositiveDefinite)?;
    let l = llt.L().to_owned();
    // C = L^-1 S L^-T: solve L Y = S, then L Z = Y^T (C symmetric).
    let mut y = sd;
    solve_lower_triangular_in_place(l.as_ref(), y.as_mut(), Par::rayon(0));
    let mut c = y.transpose().to_owned();
    solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), Par::rayon(0));
    // Symmetrize exactly.
    for j in 0..n {
        for i in 0..j {
            let v = 0.5 * (c[(i, j)] + c[(j, i)]);
            c[(i, j)] = v;
            c[(j, i)] = v;
        }
    }
    let evd = c
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| DenseEigenError::NoConvergence)?;
    let ratio = s_scale / b_scale;
    let values: Vec<f64> = (0..n).map(|i| evd.S()[i] * ratio).collect();
    let mut x = evd.U().to_owned();
    solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::rayon(0));
    let mut out = vec![0.0; n * n];
    // x is orthonormal in the scaled B: rescale to X^T B X = I.
    let xs = 1.0 / b_scale.sqrt();
    for j in 0..n {
        for i in 0..n {
            out[j * n + i] = x[(i, j)] * xs;
        }
    }
    Ok((values, out))
}
