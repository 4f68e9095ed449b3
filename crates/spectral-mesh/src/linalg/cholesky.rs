//! Sparse Cholesky factorization (faer, AMD ordering, supernodal) with the symbolic
//! analysis kept so that a matrix with the same pattern refactors cheaply.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;

use super::SparseMatrix;

/// Errors from the factorization.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CholeskyError {
    /// The matrix is not square.
    #[error("the matrix is not square ({0} x {1})")]
    NotSquare(usize, usize),
    /// The matrix is not (numerically) positive definite.
    #[error("the matrix is not positive definite: {0}")]
    NotPositiveDefinite(String),
    /// faer could not allocate or analyse the matrix.
    #[error("sparse factorization failed: {0}")]
    Internal(String),
}

/// A sparse `L L^T` factorization of a symmetric positive definite matrix.
///
/// Parallelism is explicit and coarse: the factorization itself runs on one thread (it is
/// cheap next to the solves that use it), and multi-right-hand-side solves split their
/// columns over the rayon pool, each part solved sequentially. This avoids fine-grained
/// spin barriers, which are very slow on a loaded machine.
#[derive(Debug, Clone)]
pub struct SparseCholesky {
    n: usize,
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

fn view(a: &SparseMatrix) -> Result<SparseColMatRef<'_, usize, f64>, CholeskyError> {
    let sym =
        SymbolicSparseColMatRef::new_checked(a.nrows(), a.ncols(), a.col_ptr(), None, a.row_idx());
    Ok(SparseColMatRef::new(sym, a.values()))
}

fn numeric(
    symbolic: &SymbolicCholesky<usize>,
    a: &SparseMatrix,
) -> Result<Vec<f64>, CholeskyError> {
    let m = view(a)?;
    let mut values = vec![0.0; symbolic.len_val()];
    let par = Par::Seq;
    let mut mem =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|e| CholeskyError::Internal(format!("{e:?}")))?;
    symbolic
        .factorize_numeric_llt::<f64>(
            &mut values,
            m,
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|e| CholeskyError::NotPositiveDefinite(format!("{e:?}")))?;
    if values.iter().any(|v| !v.is_finite()) {
        return Err(CholeskyError::NotPositiveDefinite(
            "non-finite factor".to_string(),
        ));
    }
    Ok(values)
}

impl SparseCholesky {
    /// Analyses and factors `a` (only its lower triangle is read).
    pub fn new(a: &SparseMatrix) -> Result<Self, CholeskyError> {
        if a.nrows() != a.ncols() {
            return Err(CholeskyError::NotSquare(a.nrows(), a.ncols()));
        }
        let m = view(a)?;
        let symbolic = factorize_symbolic_cholesky(
            m.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| CholeskyError::Internal(format!("{e:?}")))?;
        let values = numeric(&symbolic, a)?;
        Ok(Self {
            n: a.nrows(),
            symbolic: Arc::new(symbolic),
            values,
            col_ptr: a.col_ptr().to_vec(),
            row_idx: a.row_idx().to_vec(),
        })
    }

    /// Refactors a matrix with the same sparsity pattern, reusing the symbolic analysis
    /// (falls back to a fresh analysis when the pattern differs).
    pub fn refactor(&mut self, a: &SparseMatrix) -> Result<(), CholeskyError> {
        if a.col_ptr() != self.col_ptr.as_slice() || a.row_idx() != self.row_idx.as_slice() {
            *self = Self::new(a)?;
            return Ok(());
        }
        self.values = numeric(&self.symbolic, a)?;
        Ok(())
    }

    /// Dimension `n`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Solves `A x = b` in place for one right-hand side.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.solve_seq(b, 1);
    }

    fn solve_seq(&self, b: &mut [f64], k: usize) {
        if k == 0 || self.n == 0 {
            return;
        }
        let rhs = MatMut::from_column_major_slice_mut(b, self.n, k);
        let par = Par::Seq;
        let req = self.symbolic.solve_in_place_scratch::<f64>(k, par);
        let mut mem = MemBuffer::new(req);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut mem),
        );
    }

    /// Solves `A X = B` in place for `k` right-hand sides stored column-major
    /// (`b.len() == n * k`). The columns are split into groups solved in parallel.
    pub fn solve_many_in_place(&self, b: &mut [f64], k: usize) {
        assert_eq!(b.len(), self.n * k);
        if k == 0 || self.n == 0 {
            return;
        }
        let threads = rayon::current_num_threads().max(1);
        if threads == 1 || k == 1 {
            self.solve_seq(b, k);
            return;
        }
        // Groups of at least 4 columns (multi-RHS solves are cheaper per column), at most
        // one group per thread.
        let groups = threads.min(k.div_ceil(4)).max(1);
        let per = k.div_ceil(groups);
        b.par_chunks_mut(self.n * per).for_each(|chunk| {
            let c = chunk.len() / self.n;
            self.solve_seq(chunk, c);
        });
    }

    /// Returns `A^-1 b`.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        self.solve_in_place(&mut x);
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_spd_system() {
        // 1D Laplacian + identity: tridiagonal SPD.
        let n = 50;
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 3.0));
            if i + 1 < n {
                t.push((i, i + 1, -1.0));
                t.push((i + 1, i, -1.0));
            }
        }
        let a = SparseMatrix::from_triplets(n, n, &t);
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let b = a.mul_vec(&x_true);
        let c = SparseCholesky::new(&a).unwrap();
        let x = c.solve(&b);
        for i in 0..n {
            assert!((x[i] - x_true[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn indefinite_matrix_is_refused() {
        let a = SparseMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, -1.0)]);
        assert!(matches!(
            SparseCholesky::new(&a),
            Err(CholeskyError::NotPositiveDefinite(_))
        ));
    }
}
