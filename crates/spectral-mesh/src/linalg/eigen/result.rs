//! The result of a sparse solve and its packaging (shared by every iteration).

use super::kernels::b_orthogonality_error_cancellable;
use super::types::{EigenProgress, SparseEigenError};
use crate::cancel::CancelToken;
use crate::linalg::SparseMatrix;

/// The result of [`super::sparse_generalized_eigen`].
#[derive(Debug, Clone)]
pub struct PartialEigen {
    /// The `k` smallest eigenvalues, ascending.
    pub values: Vec<f64>,
    /// Eigenvectors, `n x k` column-major, `X^T B X = I`.
    pub vectors: Vec<f64>,
    /// Relative residuals (see [`super::relative_residuals`]).
    pub residuals: Vec<f64>,
    /// `max |X^T B X - I|`.
    pub orthogonality_error: f64,
    /// Iterations used.
    pub iterations: usize,
    /// Number of vectors solved with the factorization.
    pub solves: usize,
    /// The shift used.
    pub shift: f64,
}

/// The result of a solve from its sorted pairs `(values, vectors, residuals)`: measures
/// the B-orthogonality, reports [`EigenProgress::Finished`] and builds the
/// [`PartialEigen`] (shared by every iterative method); stops when `cancel` is set.
pub(super) fn package(
    b: &SparseMatrix,
    (values, vectors, residuals): (Vec<f64>, Vec<f64>, Vec<f64>),
    iterations: usize,
    solves: usize,
    shift: f64,
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<PartialEigen, SparseEigenError> {
    let orthogonality_error =
        crate::linalg::timing::timed(crate::linalg::timing::Phase::Check, || {
            b_orthogonality_error_cancellable(b, &vectors, values.len(), cancel)
        })?;
    crate::linalg::timing::report(iterations, solves);
    let max_residual = residuals.iter().cloned().fold(0.0, f64::max);
    progress(EigenProgress::Finished {
        iterations,
        solves,
        max_residual,
        orthogonality_error,
    });
    Ok(PartialEigen {
        values,
        vectors,
        residuals,
        orthogonality_error,
        iterations,
        solves,
        shift,
    })
}
