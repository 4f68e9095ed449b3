//! Linear algebra: the sparse matrix type, sparse Cholesky (with its fill-reducing
//! ordering), and the generalized symmetric eigensolvers (dense for small problems, block
//! shift-invert for large ones).
//! This is the only module that names `faer`.

pub mod cholesky;
pub mod dense_ops;
pub mod eigen;
mod ordering;
mod scratch;
pub mod sparse;
mod supernodal;
pub mod timing;

pub use cholesky::{CholeskyError, Inertia, SparseCholesky, inertia};
pub use eigen::{
    CERTIFICATE_GAP, Certificate, Completed, certificate, certify_and_complete, count_below,
};
pub use eigen::{
    ComponentNullSpace, DenseEigenError, EigenProgress, INTERIOR_MIN_K, PartialEigen, ShiftInvert,
    SparseAlgorithm, SparseEigenError, SparseEigenOptions, b_orthogonality_error,
    connected_components, default_shift, dense_generalized_eigen, interior_target, norm1,
    relative_residuals, sparse_generalized_eigen, sparse_generalized_eigen_with, sym_spmm,
    sym_spmm_into,
};
pub use sparse::SparseMatrix;

/// The dense generalized eigensolver under its former path (it lives in `eigen/dense.rs`,
/// beside the dense symmetric eigensolver the iterations use).
pub mod dense_eigen {
    pub use super::eigen::{DenseEigenError, dense_generalized_eigen};
}
