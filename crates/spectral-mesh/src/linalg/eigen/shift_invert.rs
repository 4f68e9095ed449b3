//! The factored shifted pencil `K = S - sigma B`: built once, used by every solve of the
//! same `(S, B)` (see [`ShiftInvert`]).

use super::kernels::norm1;
use super::types::{EigenProgress, SparseEigenError};
use crate::linalg::cholesky::CholeskyAnalysis;
use crate::linalg::timing::{Phase, timed};
use crate::linalg::{SparseCholesky, SparseMatrix};

/// Attempts at factoring `S - sigma B`, the shift growing 100-fold after each failure.
const ATTEMPTS: usize = 5;

/// The sparse Cholesky factorization of `K = S - sigma B` with its shift `sigma < 0`: the
/// expensive part of a sparse eigensolve that does not depend on `k`.
///
/// Build it once with [`ShiftInvert::new`] and pass it to
/// [`super::sparse_generalized_eigen_with`] for every `k`: a solve with a given factor
/// gives, bit for bit, what the solve that builds its own factor gives (the factor depends
/// only on `S`, `B` and the shift). It must have been built from the same `S` and `B` as
/// the solve's (only the size is checked).
///
/// Memory: the factor `L` holds [`ShiftInvert::factor_len`] values (8 bytes each; about
/// 40 M at 411k mesh vertices, 320 MB), plus the analysis.
#[derive(Clone)]
pub struct ShiftInvert {
    chol: SparseCholesky,
    shift: f64,
}

impl std::fmt::Debug for ShiftInvert {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShiftInvert")
            .field("n", &self.n())
            .field("shift", &self.shift)
            .field("factor_len", &self.factor_len())
            .finish()
    }
}

/// The default shift of the pencil `(S, B)`: well below the smallest eigenvalue of
/// interest but scale-aware. The total mass `M = 1^T B 1` sets the eigenvalue scale of
/// the low modes (`lambda_2 ~ 10 / M` for a round surface; for `B = I` the same holds with
/// `M = n`), and a floor relative to `||S||_1 / ||B||_1` keeps `K` well enough
/// conditioned for Cholesky: `sigma = -max(0.01 / M, 1e-10 ||S||_1 / ||B||_1)`.
pub fn default_shift(s: &SparseMatrix, b: &SparseMatrix) -> f64 {
    let (sn, bn) = (norm1(s), norm1(b));
    shift_from(b, sn, bn)
}

fn shift_from(b: &SparseMatrix, sn: f64, bn: f64) -> f64 {
    let total_mass: f64 = b.values().iter().sum::<f64>().abs().max(f64::MIN_POSITIVE);
    -(1e-2 / total_mass).max(1e-10 * sn / bn.max(f64::MIN_POSITIVE))
}

/// The first shift tried for `(S, B)` with norms `(sn, bn)`: `shift` when it is negative,
/// else the default.
pub(super) fn first_shift(b: &SparseMatrix, shift: Option<f64>, (sn, bn): (f64, f64)) -> f64 {
    let auto_shift = shift_from(b, sn, bn);
    match shift {
        Some(s) if s < 0.0 => s,
        _ => auto_shift,
    }
}

/// Checks that `S` and `B` are square of one size; returns that size.
pub(super) fn check_sizes(s: &SparseMatrix, b: &SparseMatrix) -> Result<usize, SparseEigenError> {
    let n = s.ncols();
    if s.nrows() != n || b.nrows() != n || b.ncols() != n {
        return Err(SparseEigenError::Invalid(format!(
            "S is {} x {}, B is {} x {}",
            s.nrows(),
            s.ncols(),
            b.nrows(),
            b.ncols()
        )));
    }
    Ok(n)
}

impl ShiftInvert {
    /// Factors `S - sigma B` (`S` symmetric positive semi-definite, `B` symmetric positive
    /// definite, both `n x n`). `shift`: the `sigma < 0` to use; `None` (or a value
    /// `>= 0`) takes [`default_shift`]. When the factorization fails the shift is made 100
    /// times larger, up to 5 attempts, reusing the symbolic analysis (the pattern of
    /// `S - sigma B` does not depend on `sigma`). Each attempt is reported as
    /// [`EigenProgress::Factorization`]. Not interruptible: at 411k mesh vertices it took
    /// 2.0-2.7 s.
    pub fn new(
        s: &SparseMatrix,
        b: &SparseMatrix,
        shift: Option<f64>,
        progress: &mut dyn FnMut(EigenProgress),
    ) -> Result<Self, SparseEigenError> {
        check_sizes(s, b)?;
        let (sn, bn) = (norm1(s), norm1(b));
        if !sn.is_finite() || !bn.is_finite() {
            return Err(SparseEigenError::NonFinite);
        }
        Self::with_norms(s, b, shift, (sn, bn), progress)
    }

    /// [`ShiftInvert::new`] with the norms already computed (finite).
    pub(super) fn with_norms(
        s: &SparseMatrix,
        b: &SparseMatrix,
        shift: Option<f64>,
        (sn, bn): (f64, f64),
        progress: &mut dyn FnMut(EigenProgress),
    ) -> Result<Self, SparseEigenError> {
        let n = s.ncols();
        let mut shift = first_shift(b, shift, (sn, bn));
        let mut analysis: Option<CholeskyAnalysis> = None;
        let mut last_err = String::new();
        for _ in 0..ATTEMPTS {
            progress(EigenProgress::Factorization { n, shift });
            let kmat = s.add_scaled(1.0, b, -shift);
            if analysis.is_none() {
                match timed(Phase::Ordering, || CholeskyAnalysis::new(&kmat)) {
                    Ok(a) => analysis = Some(a),
                    Err(e) => {
                        last_err = e.to_string();
                        shift *= 100.0;
                        continue;
                    }
                }
            }
            let attempt = match &analysis {
                Some(a) => timed(Phase::Factor, || a.factor(&kmat)),
                None => continue,
            };
            match attempt {
                Ok(chol) => {
                    if crate::linalg::timing::enabled() {
                        eprintln!(
                            "factor: n = {n}, {} values of L, {} row indices, split solve {:.2} of one thread's",
                            chol.factor_len(),
                            chol.row_indices(),
                            chol.split_share()
                        );
                    }
                    return Ok(Self { chol, shift });
                }
                Err(e) => {
                    last_err = e.to_string();
                    shift *= 100.0;
                }
            }
        }
        Err(SparseEigenError::Factorization(last_err))
    }

    /// Refactors for new matrices `S` and `B` of the same sparsity patterns (a perturbed
    /// mesh with the same connectivity, say) with their own shift (as in
    /// [`ShiftInvert::new`]): the symbolic analysis is reused when the pattern of
    /// `S - sigma B` is unchanged ([`SparseCholesky::refactor`]), and the result is the
    /// same as a fresh [`ShiftInvert::new`]. On error `self` is left as it was.
    pub fn refactor(
        &mut self,
        s: &SparseMatrix,
        b: &SparseMatrix,
        shift: Option<f64>,
        progress: &mut dyn FnMut(EigenProgress),
    ) -> Result<(), SparseEigenError> {
        check_sizes(s, b)?;
        let (sn, bn) = (norm1(s), norm1(b));
        if !sn.is_finite() || !bn.is_finite() {
            return Err(SparseEigenError::NonFinite);
        }
        let sigma = first_shift(b, shift, (sn, bn));
        progress(EigenProgress::Factorization {
            n: s.ncols(),
            shift: sigma,
        });
        let kmat = s.add_scaled(1.0, b, -sigma);
        // `SparseCholesky::refactor` leaves the factor as it was when it fails.
        match timed(Phase::Factor, || self.chol.refactor(&kmat)) {
            Ok(()) => {
                self.shift = sigma;
                Ok(())
            }
            // Not positive definite with this shift: the attempts of a fresh factorization.
            Err(_) => {
                *self = Self::with_norms(s, b, shift, (sn, bn), progress)?;
                Ok(())
            }
        }
    }

    /// The shift `sigma` (negative).
    pub fn shift(&self) -> f64 {
        self.shift
    }

    /// Dimension `n`.
    pub fn n(&self) -> usize {
        self.chol.n()
    }

    /// Number of values of the factor `L` (8 bytes each).
    pub fn factor_len(&self) -> usize {
        self.chol.factor_len()
    }

    /// The factorization of `S - sigma B`.
    pub fn cholesky(&self) -> &SparseCholesky {
        &self.chol
    }
}
