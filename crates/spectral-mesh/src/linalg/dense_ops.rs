//! Small dense kernels over column-major slices for the callers outside `linalg/` that
//! must not name faer: the products of tall blocks (`n x k` eigenvector blocks) with
//! small matrices, and the dense solve of a symmetric positive (semi-)definite system.
//!
//! Every matrix is a column-major `&[f64]` with its shape given beside it.

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::Solve;
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

fn view(x: &[f64], rows: usize, cols: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(&x[..rows * cols], rows, cols)
}

fn view_mut(x: &mut [f64], rows: usize, cols: usize) -> MatMut<'_, f64> {
    MatMut::from_column_major_slice_mut(&mut x[..rows * cols], rows, cols)
}

/// `A B` of two views as a new column-major matrix (zeros when a dimension is 0).
fn multiply(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Vec<f64> {
    let (rows, cols) = (a.nrows(), b.ncols());
    let mut out = vec![0.0; rows * cols];
    if rows > 0 && cols > 0 && a.ncols() > 0 {
        matmul(
            view_mut(&mut out, rows, cols),
            Accum::Replace,
            a,
            b,
            1.0,
            Par::rayon(0),
        );
    }
    out
}

/// `A^T B` for `A` (`n x ca`) and `B` (`n x cb`): a `ca x cb` column-major matrix.
pub fn gram(a: &[f64], b: &[f64], n: usize, ca: usize, cb: usize) -> Vec<f64> {
    multiply(view(a, n, ca).transpose(), view(b, n, cb))
}

/// `A B` for `A` (`rows x inner`) and `B` (`inner x cols`): `rows x cols`.
pub fn product(a: &[f64], b: &[f64], rows: usize, inner: usize, cols: usize) -> Vec<f64> {
    multiply(view(a, rows, inner), view(b, inner, cols))
}

/// `A B^T` for `A` (`rows x inner`) and `B` (`cols x inner`): `rows x cols`.
pub fn product_transposed(
    a: &[f64],
    b: &[f64],
    rows: usize,
    inner: usize,
    cols: usize,
) -> Vec<f64> {
    multiply(view(a, rows, inner), view(b, cols, inner).transpose())
}

/// How [`solve_symmetric`] solved its system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SymmetricSolve {
    /// Cholesky `H = L L^T` (the matrix was numerically positive definite).
    Cholesky,
    /// Bunch-Kaufman `H = L B L^T` (Cholesky failed: semi-definite or indefinite).
    BunchKaufman,
}

/// Solves `H x = rhs` in place for a symmetric `n x n` matrix `H` (column-major; only
/// its lower triangle is read): Cholesky first, Bunch-Kaufman when Cholesky fails.
/// Returns the route taken, or `None` when the solution is not finite (a singular `H`).
pub fn solve_symmetric(h: &[f64], n: usize, rhs: &mut [f64]) -> Option<SymmetricSolve> {
    if n == 0 {
        return Some(SymmetricSolve::Cholesky);
    }
    let hm = view(h, n, n);
    let mut x = Mat::<f64>::from_fn(n, 1, |i, _| rhs[i]);
    let route = match hm.llt(Side::Lower) {
        Ok(llt) => {
            llt.solve_in_place(x.as_mut());
            SymmetricSolve::Cholesky
        }
        Err(_) => {
            hm.lblt(Side::Lower).solve_in_place(x.as_mut());
            SymmetricSolve::BunchKaufman
        }
    };
    for (i, r) in rhs.iter_mut().enumerate().take(n) {
        *r = x[(i, 0)];
    }
    rhs.iter().take(n).all(|v| v.is_finite()).then_some(route)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_match_loops() {
        let (n, ca, cb) = (7, 3, 2);
        let a: Vec<f64> = (0..n * ca).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..n * cb).map(|i| (i as f64 * 0.11).cos()).collect();
        let g = gram(&a, &b, n, ca, cb);
        for i in 0..ca {
            for j in 0..cb {
                let s: f64 = (0..n).map(|r| a[i * n + r] * b[j * n + r]).sum();
                assert!((g[j * ca + i] - s).abs() < 1e-12);
            }
        }
        // A (n x ca) times C (ca x cb), and A times (C^T)^T.
        let c: Vec<f64> = (0..ca * cb).map(|i| i as f64 - 2.0).collect();
        let p = product(&a, &c, n, ca, cb);
        let mut ct = vec![0.0; cb * ca];
        for i in 0..ca {
            for j in 0..cb {
                ct[i * cb + j] = c[j * ca + i];
            }
        }
        let q = product_transposed(&a, &ct, n, ca, cb);
        for r in 0..n {
            for j in 0..cb {
                let s: f64 = (0..ca).map(|i| a[i * n + r] * c[j * ca + i]).sum();
                assert!((p[j * n + r] - s).abs() < 1e-12);
                assert!((q[j * n + r] - s).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn symmetric_solve_takes_both_routes() {
        // Positive definite.
        let h = [4.0, 1.0, 1.0, 3.0];
        let mut x = [1.0, 2.0];
        assert_eq!(
            solve_symmetric(&h, 2, &mut x),
            Some(SymmetricSolve::Cholesky)
        );
        assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-12);
        assert!((x[0] + 3.0 * x[1] - 2.0).abs() < 1e-12);
        // Indefinite.
        let h = [1.0, 2.0, 2.0, 1.0];
        let mut x = [3.0, 3.0];
        assert_eq!(
            solve_symmetric(&h, 2, &mut x),
            Some(SymmetricSolve::BunchKaufman)
        );
        assert!((x[0] - 1.0).abs() < 1e-12 && (x[1] - 1.0).abs() < 1e-12);
    }
}
