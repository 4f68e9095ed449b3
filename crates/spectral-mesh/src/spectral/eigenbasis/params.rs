//! What a solve is asked: the number of pairs, the tolerance, boundary conditions, the
//! method and its size limits, and the errors a solve can return.

use crate::linalg::{SparseEigenError, SparseEigenOptions};

/// Errors of the eigenbasis computation.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum EigenError {
    /// More pairs were asked for than the mesh has vertices.
    #[error("asked for k = {k} eigenpairs but the mesh has only n = {n} vertices")]
    TooMany {
        /// Requested pairs.
        k: usize,
        /// Vertices.
        n: usize,
    },
    /// k = 0.
    #[error("k must be at least 1")]
    Zero,
    /// A numerical failure, with what failed.
    #[error("eigensolver failed: {0}")]
    Numerical(String),
    /// A Dirichlet vertex index is out of range.
    #[error("Dirichlet vertex {vertex} does not exist (the mesh has {n} vertices)")]
    DirichletOutOfRange {
        /// The offending index.
        vertex: usize,
        /// Vertices.
        n: usize,
    },
    /// The iterative solver stopped before every wanted pair converged: the solver's
    /// [`SparseEigenError::NoConvergence`], with the pairs converged and wanted and the
    /// iterations used.
    #[error(transparent)]
    NoConvergence(SparseEigenError),
    /// The computation was cancelled through its [`crate::CancelToken`].
    #[error("the eigenbasis computation was cancelled")]
    Cancelled,
}

impl From<SparseEigenError> for EigenError {
    fn from(e: SparseEigenError) -> Self {
        match e {
            e @ SparseEigenError::NoConvergence { .. } => EigenError::NoConvergence(e),
            SparseEigenError::Cancelled => EigenError::Cancelled,
            other => EigenError::Numerical(other.to_string()),
        }
    }
}

/// Which eigensolver [`super::compute_eigenbasis`] uses.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum EigenMethod {
    /// Dense for small problems (or `k` close to `n`), block shift-invert otherwise.
    #[default]
    Auto,
    /// All pairs by the dense O(n^3) solver, truncated to `k` (small meshes only).
    Dense,
    /// The sparse shift-invert solver ([`crate::linalg::sparse_generalized_eigen`]: block
    /// Krylov-Schur on a sparse Cholesky factorization of `S - sigma B`).
    ShiftInvertBlock,
}

/// Parameters of [`super::compute_eigenbasis`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EigenParams {
    /// Number of pairs (the smallest eigenvalues). Default 100, the paper's default.
    pub k: usize,
    /// Target relative residual of every pair (see [`super::Eigenbasis::compute_residuals`]).
    /// Default `1e-10`.
    pub tolerance: f64,
    /// Dirichlet boundary vertices: the problem is solved on the other vertices and the
    /// eigenvectors are zero on these. `None` (default): natural boundary conditions.
    pub dirichlet: Option<Vec<usize>>,
    /// The solver. Default [`EigenMethod::Auto`].
    pub method: EigenMethod,
    /// Seed of the iterative solver's start block (results are deterministic).
    pub seed: u64,
    /// Block size of the iterative solver; `0` (default) chooses from `k`.
    pub block_size: usize,
}

impl Default for EigenParams {
    fn default() -> Self {
        Self {
            k: 100,
            tolerance: 1e-10,
            dirichlet: None,
            method: EigenMethod::Auto,
            seed: 0x5eed,
            block_size: 0,
        }
    }
}

/// Problems up to this many (free) vertices always use the dense path under
/// [`EigenMethod::Auto`].
pub const DENSE_MAX_N: usize = 300;
/// Problems up to this size use the dense path under [`EigenMethod::Auto`] when `k` is more
/// than a third of `n`.
pub const DENSE_MAX_N_LARGE_K: usize = 1500;

/// True when `method` takes the dense path for `k` pairs of a problem of `n` (free)
/// vertices: always for [`EigenMethod::Dense`], never for
/// [`EigenMethod::ShiftInvertBlock`], and under [`EigenMethod::Auto`] when
/// `n <= DENSE_MAX_N`, or `3k > n` and `n <= DENSE_MAX_N_LARGE_K`.
pub fn takes_dense_path(n: usize, k: usize, method: EigenMethod) -> bool {
    match method {
        EigenMethod::Dense => true,
        EigenMethod::ShiftInvertBlock => false,
        EigenMethod::Auto => n <= DENSE_MAX_N || (3 * k > n && n <= DENSE_MAX_N_LARGE_K),
    }
}

/// The options of the sparse solver for `params`.
pub(super) fn sparse_options(params: &EigenParams) -> SparseEigenOptions {
    SparseEigenOptions {
        k: params.k,
        tolerance: params.tolerance,
        block_size: params.block_size,
        seed: params.seed,
        ..Default::default()
    }
}
