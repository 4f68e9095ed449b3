//! The factored shifted pencil `K = S - sigma B`: built once, used by every solve of the
//! same `(S, B)` (see [`ShiftInvert`]).

use super::kernels::norm1;
use super::types::{EigenProgress, SparseAlgorithm, SparseEigenError, SparseEigenOptions};
use crate::linalg::cholesky::CholeskyAnalysis;
use crate::linalg::timing::{Phase, timed};
use crate::linalg::{SparseCholesky, SparseMatrix};

/// Attempts at factoring `S - sigma B`, the shift growing 100-fold after each failure.
const ATTEMPTS: usize = 5;

/// The smallest `k` for which a solve that factors for itself takes an interior shift
/// (see [`interior_target`]).
pub const INTERIOR_MIN_K: usize = 24;

/// The share of the `k` wanted eigenvalues an interior shift aims to have below it.
/// Measured on 26k vertices at k = 50 (fem, tolerance 1e-10, solves): 164 below the
/// spectrum; with 13, 17, 25, 31 and about 38 eigenvalues below the shift 152, 136, 124,
/// 120 and 152. The eigenvalues near `lambda_k` converge faster the closer the shift is
/// to them, those near 0 slower. Shares of 0.6 to 0.75 on the quarter-octave ladder took
/// 112-136 solves at k = 30, 120 at 50, 168-200 at 80 and 320 at 128; 0.6 took the
/// fewest in each.
const INTERIOR_SHARE: f64 = 0.6;

/// A first interior shift is kept when the eigenvalues below it number between its
/// target count divided and multiplied by this; otherwise it is moved once.
const INTERIOR_SLACK: f64 = 1.4;

/// The count of eigenvalues an interior shift aims to have below it for a solve of `k`
/// pairs: the largest power of `2^(1/4)` at most `0.6 k`, so that nearby
/// `k` (within a factor `2^(1/4)`, about 1.19) share one shift and one factor. `None` below
/// [`INTERIOR_MIN_K`] (the shift then lies below the spectrum).
pub fn interior_target(k: usize) -> Option<f64> {
    if k < INTERIOR_MIN_K {
        return None;
    }
    let quarter_octaves = (4.0 * (INTERIOR_SHARE * k as f64).log2()).floor();
    Some(2f64.powf(quarter_octaves / 4.0))
}

/// Weyl's law for a surface of area `A = 1^T B 1`: about `A lambda / (4 pi)` eigenvalues
/// lie below `lambda`, so `count` of them below `4 pi count / A` (a boundary adds some
/// under Neumann conditions and removes some under Dirichlet ones; the factor's inertia
/// tells the true count).
fn weyl_shift(b: &SparseMatrix, count: f64) -> f64 {
    4.0 * std::f64::consts::PI * count / total_mass(b)
}

/// The total mass `1^T B 1` (its magnitude, at least the smallest positive `f64`): the
/// area of a surface, the scale of both shifts.
fn total_mass(b: &SparseMatrix) -> f64 {
    b.values().iter().sum::<f64>().abs().max(f64::MIN_POSITIVE)
}

/// The factorization of `K = S - sigma B` with its shift: `L L^T` (sparse Cholesky) for
/// `sigma < 0`, `L D L^T` for an interior shift `sigma > 0` (see
/// [`ShiftInvert::for_options`]).
/// The expensive part of a sparse eigensolve; it depends on `k` only through the interior
/// target ([`ShiftInvert::target_of`]).
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
    -(1e-2 / total_mass(b)).max(1e-10 * sn / bn.max(f64::MIN_POSITIVE))
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

/// The norms `(||S||_1, ||B||_1)` of a pencil of checked sizes (see [`check_sizes`]);
/// an error when either is not finite.
fn checked_norms(s: &SparseMatrix, b: &SparseMatrix) -> Result<(f64, f64), SparseEigenError> {
    check_sizes(s, b)?;
    let (sn, bn) = (norm1(s), norm1(b));
    if !sn.is_finite() || !bn.is_finite() {
        return Err(SparseEigenError::NonFinite);
    }
    Ok((sn, bn))
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
        let (sn, bn) = checked_norms(s, b)?;
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
        let (sn, bn) = checked_norms(s, b)?;
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

    /// The shift `sigma` (negative, or positive for an interior shift, see
    /// [`ShiftInvert::for_options`]).
    pub fn shift(&self) -> f64 {
        self.shift
    }

    /// The factor for an interior `target` count of [`ShiftInvert::target_of`] (norms
    /// `(sn, bn)`): with `Some(c)`, an interior shift with about `c` eigenvalues below
    /// it, factored as `L D L^T`. Its first value comes from Weyl's law and the count
    /// below it from the factor's pivots; a count off the target by more than
    /// [`INTERIOR_SLACK`] moves the shift once, in proportion (the analysis is reused).
    /// With `None`, or when that misses too (or a pivot is zero), the shift below the
    /// spectrum of [`ShiftInvert::new`] (`shift` if negative).
    ///
    /// Why: `Op = (S - sigma B)^-1 B` maps the wanted eigenvalues on both sides of
    /// `sigma` far from the unwanted ones (which crowd near 0), so the Krylov iteration
    /// needs fewer solves: at 26k vertices, k = 50, 120 instead of 164.
    pub(super) fn for_target(
        s: &SparseMatrix,
        b: &SparseMatrix,
        target: Option<f64>,
        shift: Option<f64>,
        norms: (f64, f64),
        progress: &mut dyn FnMut(EigenProgress),
    ) -> Result<Self, SparseEigenError> {
        if let Some(c) = target
            && let Some(f) = Self::interior_for(s, b, c, progress)?
        {
            return Ok(f);
        }
        Self::with_norms(s, b, shift, norms, progress)
    }

    /// The factor a solve with `opts` that factors for itself makes
    /// ([`super::sparse_generalized_eigen`]): from the target of
    /// [`ShiftInvert::target_of`], an interior shift with about that many eigenvalues
    /// below it, factored as `L D L^T` (the shift from Weyl's law, moved once when the
    /// pivots count more than 1.4 times too many or too few), else the shift below the
    /// spectrum of [`ShiftInvert::new`] (see docs/MATH.md, "Route"). Given to [`super::sparse_generalized_eigen_with`] with
    /// the same options, it gives the same pairs, bit for bit. Two options with the same
    /// target (and the same `shift`) get the same factor.
    pub fn for_options(
        s: &SparseMatrix,
        b: &SparseMatrix,
        opts: &SparseEigenOptions,
        progress: &mut dyn FnMut(EigenProgress),
    ) -> Result<Self, SparseEigenError> {
        let norms = checked_norms(s, b)?;
        Self::for_target(s, b, Self::target_of(opts), opts.shift, norms, progress)
    }

    /// What the factor of [`ShiftInvert::for_options`] depends on besides `S`, `B` and
    /// `opts.shift`: the interior target count (`None`: a shift below the spectrum, for
    /// an explicit negative shift, Davidson, or `k` below [`INTERIOR_MIN_K`]). A solver
    /// that keeps a factor for several `k` reuses it while this stays the same.
    pub fn target_of(opts: &SparseEigenOptions) -> Option<f64> {
        match opts.shift {
            Some(s) if s < 0.0 => None,
            _ if opts.algorithm != SparseAlgorithm::KrylovSchur => None,
            _ => interior_target(opts.k),
        }
    }

    /// The interior factor of [`ShiftInvert::for_target`] with target count `c`, if one
    /// fits.
    fn interior_for(
        s: &SparseMatrix,
        b: &SparseMatrix,
        c: f64,
        progress: &mut dyn FnMut(EigenProgress),
    ) -> Result<Option<Self>, SparseEigenError> {
        let n = check_sizes(s, b)?;
        let mut sigma = weyl_shift(b, c);
        if !sigma.is_finite() || sigma <= 0.0 {
            return Ok(None);
        }
        let mut kmat = s.add_scaled(1.0, b, -sigma);
        let Ok(analysis) = timed(Phase::Ordering, || CholeskyAnalysis::new(&kmat)) else {
            return Ok(None);
        };
        // The count stays below k: c is at most 0.6 k, so 1.4 c < k.
        let fits = |below: usize| {
            let m = below as f64;
            m <= INTERIOR_SLACK * c && m * INTERIOR_SLACK >= c
        };
        for attempt in 0..2 {
            progress(EigenProgress::Factorization { n, shift: sigma });
            if attempt > 0 {
                kmat = s.add_scaled(1.0, b, -sigma);
            }
            let Ok(chol) = timed(Phase::Factor, || analysis.factor_indefinite(&kmat)) else {
                return Ok(None);
            };
            let f = Self { chol, shift: sigma };
            let below = f.below().unwrap_or(0);
            if crate::linalg::timing::enabled() {
                eprintln!(
                    "factor (L D L^T at {sigma:e}, target {c:.1}): n = {n}, {} values of L, {below} eigenvalues below",
                    f.factor_len(),
                );
            }
            if fits(below) {
                return Ok(Some(f));
            }
            // Move the shift in proportion (Weyl: the count grows linearly), at most 8x.
            let m = (below as f64).max(c / 8.0);
            sigma *= c / m;
        }
        Ok(None)
    }

    /// The number of eigenvalues of the pencil below the shift, with multiplicity, for an
    /// interior shift (from the signs of the pivots); `None` for a shift below the
    /// spectrum (`S - sigma B` positive definite: none).
    pub fn below(&self) -> Option<usize> {
        self.chol.inertia().map(|i| i.negative)
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
