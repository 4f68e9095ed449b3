//! The types of the sparse eigensolver's interface: options, the choice of iteration,
//! progress reports and errors.

use crate::cancel::CancelToken;

/// Options of [`super::sparse_generalized_eigen`].
#[derive(Debug, Clone, PartialEq)]
pub struct SparseEigenOptions {
    /// Number of wanted pairs (the smallest eigenvalues).
    pub k: usize,
    /// Convergence target for the relative residual of every pair (see
    /// [`super::relative_residuals`]).
    pub tolerance: f64,
    /// Block size `p`; `0` picks one from `k`.
    pub block_size: usize,
    /// Largest search-space dimension before a restart; `0` picks one from `k`.
    pub max_basis: usize,
    /// The shift `sigma < 0` of `S - sigma B`; `None` (or a value `>= 0`) lets the solver
    /// pick one: interior from `k = 24` on, else a scale-aware one below the spectrum
    /// (see [`super::ShiftInvert::for_options`]).
    pub shift: Option<f64>,
    /// Seed of the random start block (results are deterministic for a given seed).
    pub seed: u64,
    /// Iteration cap; `0` picks a generous one from `k`.
    pub max_iterations: usize,
    /// Expansion rule: `true` = block Krylov (`K^-1 B` applied to the last block added),
    /// `false` = Davidson (`K^-1` applied to the residuals of the lowest unconverged
    /// Ritz pairs).
    pub krylov: bool,
    /// Hard locking: converged Ritz pairs leave the search space (which then stays small,
    /// about 5 blocks) and new directions are only B-orthogonalized against them. Cheaper
    /// per iteration but, as measured on a 38k-vertex mesh, it needs more solves and was
    /// slower overall; `false` (default) keeps every converged vector in the Rayleigh-Ritz
    /// space (soft locking).
    pub locking: bool,
    /// The iteration: block Krylov-Schur on the shift-inverted pencil (default) or block
    /// Davidson (the fields `krylov` and `locking` only apply to Davidson).
    pub algorithm: SparseAlgorithm,
    /// Krylov-Schur only: the plain iteration, without locking converged pairs and with
    /// two full Gram-Schmidt passes per block instead of the Lanczos step plus one pass
    /// (the same answer, measured 1.2-1.7x slower; kept for comparison and as the
    /// fallback when the default run does not converge).
    pub ks_plain: bool,
    /// Krylov-Schur only (default `true`): deflate the known null space exactly. The
    /// indicators of the connected components that `S` annihilates (see
    /// [`super::ComponentNullSpace`]) are returned as the first pairs, with eigenvalue
    /// exactly 0, and the iteration finds the `k - c` pairs after them in their
    /// B-orthogonal complement: any number `c` of components works, also `c >= k` (then
    /// no iteration runs). `false`: the whole pencil is iterated on, as before (a null
    /// cluster larger than the basis then does not converge).
    pub deflate: bool,
    /// Krylov-Schur only: vectors the iteration stays B-orthogonal to (`n x p`,
    /// column-major, B-orthonormal, B-orthogonal to the component indicators), so that
    /// the pairs returned are those of the pencil on their B-orthogonal complement: their
    /// own eigenvalues are skipped. The certificate's search for missing pairs deflates
    /// the pairs already found this way (see [`super::certify_and_complete`]); tests use
    /// it to make a solve miss an eigenvector. `None` (default): nothing.
    pub deflate_vectors: Option<std::sync::Arc<Vec<f64>>>,
    /// Krylov-Schur only: approximations of the wanted eigenvectors (`n x m`,
    /// column-major, any scaling) the iteration starts from: its start block is `Op`
    /// applied to random combinations of them plus a random part, so that pairs missing
    /// from them still enter the space. `None` (default): a random start block.
    pub start_vectors: Option<std::sync::Arc<Vec<f64>>>,
    /// Krylov-Schur only: start from the prolongated eigenvectors of a coarse space
    /// (smoothed aggregation, see `coarse.rs`) when no `start_vectors` are given and the
    /// problem is large enough for one.
    pub coarse_start: bool,
}

impl SparseEigenOptions {
    /// The convergence target used: [`SparseEigenOptions::tolerance`], or `1e-10` when
    /// that is not positive.
    pub fn effective_tolerance(&self) -> f64 {
        if self.tolerance > 0.0 {
            self.tolerance
        } else {
            1e-10
        }
    }
}

/// The iteration used by [`super::sparse_generalized_eigen`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SparseAlgorithm {
    /// Thick-restart block Lanczos (Krylov-Schur) on `(S - sigma B)^-1 B`, with full
    /// B-reorthogonalization as matrix-matrix products and convergence checked on the true
    /// residuals at each restart. The fastest measured.
    #[default]
    KrylovSchur,
    /// Block Davidson with the shift-invert preconditioner (the earlier method, kept for
    /// comparison).
    Davidson,
}

impl Default for SparseEigenOptions {
    fn default() -> Self {
        Self {
            k: 100,
            tolerance: 1e-10,
            block_size: 0,
            max_basis: 0,
            shift: None,
            seed: 0x5eed,
            max_iterations: 0,
            krylov: false,
            locking: false,
            algorithm: SparseAlgorithm::KrylovSchur,
            ks_plain: false,
            deflate: true,
            deflate_vectors: None,
            start_vectors: None,
            coarse_start: false,
        }
    }
}

/// Progress of the eigensolver. Serialized as an object tagged by `stage` (`dense`,
/// `factorization`, `iteration`, `finished`) with the variant's fields.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "stage", rename_all = "snake_case")]
pub enum EigenProgress {
    /// The dense path started (all pairs of an `n x n` problem).
    Dense {
        /// Problem size.
        n: usize,
    },
    /// The shifted matrix `S - sigma B` is being factored.
    Factorization {
        /// Problem size.
        n: usize,
        /// The shift.
        shift: f64,
    },
    /// One iteration finished.
    Iteration {
        /// Iteration number (from 1).
        iteration: usize,
        /// Pairs converged so far (a prefix of the spectrum).
        converged: usize,
        /// Pairs wanted.
        wanted: usize,
        /// Current search-space dimension.
        basis: usize,
    },
    /// Done.
    Finished {
        /// Iterations used.
        iterations: usize,
        /// Vectors solved with the factorization.
        solves: usize,
        /// Largest relative residual of the returned pairs.
        max_residual: f64,
        /// `max |X^T B X - I|` of the returned vectors.
        orthogonality_error: f64,
    },
}

/// Errors of the sparse eigensolver.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SparseEigenError {
    /// Bad sizes (`k = 0`, `k > n`, non-square or mismatched matrices).
    #[error("invalid eigenproblem: {0}")]
    Invalid(String),
    /// `S - sigma B` could not be factored even with larger shifts.
    #[error(
        "could not factor S - sigma B ({0}); is the mass matrix singular (unreferenced vertices?)"
    )]
    Factorization(String),
    /// The iteration cap was reached.
    #[error(
        "the eigensolver did not converge: {converged} of {wanted} pairs after {iterations} iterations"
    )]
    NoConvergence {
        /// Converged pairs.
        converged: usize,
        /// Wanted pairs.
        wanted: usize,
        /// Iterations used.
        iterations: usize,
    },
    /// NaN or infinity appeared (the matrices hold non-finite values?).
    #[error("non-finite values appeared in the eigensolver")]
    NonFinite,
    /// A connected component whose indicator `S` annihilates has no mass
    /// (`1_C^T B 1_C = 0`): the mass matrix is singular (an unreferenced vertex?).
    #[error(
        "the mass matrix is singular: the component of vertex {vertex} has no mass (an unreferenced vertex?)"
    )]
    ZeroMass {
        /// The smallest vertex of that component.
        vertex: usize,
    },
    /// The solve was stopped through its [`crate::cancel::CancelToken`].
    #[error("the eigensolver was cancelled")]
    Cancelled,
}

/// [`SparseEigenError::Cancelled`] once `cancel` is set.
pub(super) fn check(cancel: &CancelToken) -> Result<(), SparseEigenError> {
    if cancel.is_cancelled() {
        Err(SparseEigenError::Cancelled)
    } else {
        Ok(())
    }
}
