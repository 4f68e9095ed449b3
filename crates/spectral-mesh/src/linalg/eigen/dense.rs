//! Dense linear algebra of the eigensolvers: Gram products `A^T B` and row-split matrix
//! products (with a fixed split of the rows, so that the results do not depend on the
//! number of threads), the one dense symmetric eigensolver, and the dense generalized
//! symmetric eigensolver built on it, for small problems and as a reference:
//! `S x = lambda B x` through `B = L L^T`, `C = L^-1 S L^-T`, `C y = lambda y`,
//! `x = L^-T y`.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Accum, Mat, MatRef, Par, Side};

use super::types::SparseEigenError;
use crate::linalg::SparseMatrix;

pub(super) fn view(x: &[f64], n: usize, c: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(&x[..n * c], n, c)
}

/// Rows per leaf of the parallel splits (fixed: results do not depend on the thread count).
pub(super) const LEAF_ROWS: usize = 4096;

/// `B^T A` for row blocks, split recursively over rows and summed in a fixed order.
/// (Computing `(B^T A)^T` rather than `A^T B` lets the kernel read the wide `A` in place
/// and pack only the narrow `B`: measured 25-40% faster for `A` of 150-1000 columns
/// and `B` of 8-16.)
fn gram_rec(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let n = a.nrows();
    if n <= LEAF_ROWS {
        let mut g = Mat::<f64>::zeros(b.ncols(), a.ncols());
        matmul(g.as_mut(), Accum::Replace, b.transpose(), a, 1.0, Par::Seq);
        return g;
    }
    let mid = (n / 2).next_multiple_of(64).min(n);
    let (a0, a1) = a.split_at_row(mid);
    let (b0, b1) = b.split_at_row(mid);
    let (mut g0, g1) = rayon::join(|| gram_rec(a0, b0), || gram_rec(a1, b1));
    g0 += g1;
    g0
}

/// `A^T B` for column-major `A` (`n x a`) and `B` (`n x b`).
pub(super) fn gram(a: &[f64], b: &[f64], n: usize, ca: usize, cb: usize) -> Mat<f64> {
    if n == 0 || ca == 0 || cb == 0 {
        return Mat::<f64>::zeros(ca, cb);
    }
    gram_rec(view(a, n, ca), view(b, n, cb))
        .transpose()
        .to_owned()
}

/// Rows per leaf of [`matmul_rows`]: products with a thin right-hand side (`W -= V C`)
/// ran about 25% faster with 1024-row leaves than with 4096 (cache-sized blocks of `V`).
const PRODUCT_LEAF_ROWS: usize = 1024;

/// `dst (+)= alpha * lhs * rhs`, split recursively over the rows of `dst` and `lhs`.
pub(super) fn matmul_rows(
    dst: faer::MatMut<'_, f64>,
    accum: Accum,
    lhs: MatRef<'_, f64>,
    rhs: MatRef<'_, f64>,
    alpha: f64,
) {
    let n = dst.nrows();
    if n <= PRODUCT_LEAF_ROWS {
        matmul(dst, accum, lhs, rhs, alpha, Par::Seq);
        return;
    }
    let mid = (n / 2).next_multiple_of(64).min(n);
    let (d0, d1) = dst.split_at_row_mut(mid);
    let (l0, l1) = lhs.split_at_row(mid);
    rayon::join(
        || matmul_rows(d0, accum, l0, rhs, alpha),
        || matmul_rows(d1, accum, l1, rhs, alpha),
    );
}

/// `W -= V C` (`V`: `n x m`, `C`: `m x c`, `W`: `n x c`).
pub(super) fn sub_product(w: &mut [f64], v: &[f64], c: MatRef<'_, f64>, n: usize) {
    let (m, cc) = (c.nrows(), c.ncols());
    if m == 0 || cc == 0 || n == 0 {
        return;
    }
    let wm = faer::MatMut::from_column_major_slice_mut(&mut w[..n * cc], n, cc);
    matmul_rows(wm, Accum::Add, view(v, n, m), c, -1.0);
}

/// `V C` as a new column-major buffer (`n x c`).
pub(super) fn product(v: &[f64], c: MatRef<'_, f64>, n: usize) -> Vec<f64> {
    let (m, cc) = (c.nrows(), c.ncols());
    let mut out = vec![0.0; n * cc];
    if m == 0 || cc == 0 || n == 0 {
        return out;
    }
    let om = faer::MatMut::from_column_major_slice_mut(&mut out, n, cc);
    matmul_rows(om, Accum::Replace, view(v, n, m), c, 1.0);
    out
}

/// The dense symmetric eigen-decomposition of `h` (ascending; lower triangle read), the
/// one dense symmetric eigensolver of the crate. The projected problems of the
/// iterations call it sequentially ([`sym_eig`]): they are small and fine-grained
/// parallelism costs more than it gains on a shared machine; the dense generalized path
/// ([`dense_generalized_eigen`], `n` up to a few thousand) uses every thread.
fn sym_evd(h: MatRef<'_, f64>, par: Par) -> Option<(Vec<f64>, Mat<f64>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd;
    let n = h.nrows();
    let mut u = Mat::<f64>::zeros(n, n);
    let mut d = faer::diag::Diag::<f64>::zeros(n);
    let mut mem = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        n,
        evd::ComputeEigenvectors::Yes,
        par,
        Default::default(),
    ));
    evd::self_adjoint_evd(
        h,
        d.as_mut(),
        Some(u.as_mut()),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .ok()?;
    let vals: Vec<f64> = (0..n).map(|i| d[i]).collect();
    if vals.iter().any(|v| !v.is_finite()) {
        return None;
    }
    Some((vals, u))
}

/// `sum_i w_i x_i` for each of the first `c` column pairs of the column-major `n`-row
/// blocks `w` and `x` (with `x = B w`: the squared B-norms of the columns).
pub(super) fn col_dots(w: &[f64], x: &[f64], n: usize, c: usize) -> Vec<f64> {
    (0..c)
        .map(|j| {
            w[j * n..(j + 1) * n]
                .iter()
                .zip(&x[j * n..(j + 1) * n])
                .map(|(a, b)| a * b)
                .sum()
        })
        .collect()
}

/// `A B` of two small matrices (the projected problems' sizes), sequential.
pub(super) fn small_product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.nrows(), b.ncols());
    if a.nrows() > 0 && a.ncols() > 0 && b.ncols() > 0 {
        matmul(out.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    }
    out
}

/// The eigen-decomposition of SVQB (Stathopoulos and Wu): the Gram matrix `g` of `c`
/// columns scaled to unit diagonal (`D g D`, `D = diag(1 / sqrt(g_ii))`, 0 for a diagonal
/// entry `<= floor2`) and symmetrized. Returns `D`'s diagonal, the eigenvalues (ascending),
/// the eigenvectors and the largest eigenvalue (at least 0); a non-finite diagonal entry
/// is [`SparseEigenError::NonFinite`].
pub(super) type ScaledGramEig = (Vec<f64>, Vec<f64>, Mat<f64>, f64);

/// See [`ScaledGramEig`].
pub(super) fn scaled_gram_eig(
    mut g: Mat<f64>,
    floor2: f64,
) -> Result<ScaledGramEig, SparseEigenError> {
    let c = g.nrows();
    let mut d = vec![0.0; c];
    for (i, di) in d.iter_mut().enumerate() {
        let gii = g[(i, i)];
        if !gii.is_finite() {
            return Err(SparseEigenError::NonFinite);
        }
        *di = if gii > floor2 && gii > 0.0 {
            1.0 / gii.sqrt()
        } else {
            0.0
        };
    }
    for j in 0..c {
        for i in 0..c {
            g[(i, j)] *= d[i] * d[j];
        }
    }
    for j in 0..c {
        for i in 0..j {
            let a = 0.5 * (g[(i, j)] + g[(j, i)]);
            g[(i, j)] = a;
            g[(j, i)] = a;
        }
    }
    let (lam, u) = sym_eig(g.as_ref())?;
    let lmax = lam.iter().cloned().fold(0.0, f64::max);
    Ok((d, lam, u, lmax))
}

/// [`sym_evd`] sequentially, for the small projected problems of the iterations.
pub(super) fn sym_eig(h: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), SparseEigenError> {
    sym_evd(h, Par::Seq).ok_or(SparseEigenError::NonFinite)
}

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
    let (evals, mut x) =
        sym_evd(c.as_ref(), Par::rayon(0)).ok_or(DenseEigenError::NoConvergence)?;
    let ratio = s_scale / b_scale;
    let values: Vec<f64> = evals.iter().map(|v| v * ratio).collect();
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
