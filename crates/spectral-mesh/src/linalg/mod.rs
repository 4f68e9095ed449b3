//! Linear algebra: the sparse matrix type, sparse Cholesky, and the generalized
//! symmetric eigensolver. This is the only module that names `faer`.

pub mod cholesky;
pub mod sparse;

pub use cholesky::{CholeskyError, SparseCholesky};
pub use sparse::SparseMatrix;
pub mod dense_eigen;

pub use dense_eigen::{DenseEigenError, dense_generalized_eigen};
