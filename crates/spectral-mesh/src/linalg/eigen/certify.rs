//! The certificate that no eigenvalue was skipped, multiplicities included (Sylvester's
//! law of inertia), and the search for the pairs a solve missed.
//!
//! For `B` symmetric positive definite, `S - sigma B = B^(1/2) (B^(-1/2) S B^(-1/2) -
//! sigma I) B^(1/2)` is congruent to a matrix whose eigenvalues are `lambda_i - sigma`,
//! so by Sylvester's law of inertia the number of negative eigenvalues of `S - sigma B`,
//! which is the number of negative pivots `D` of any `S - sigma B = L D L^T` with `L`
//! invertible, is the number `N(sigma)` of eigenvalues of the pencil below `sigma`
//! (counted with multiplicity). A solve whose computed eigenvalues below `sigma` number
//! exactly `N(sigma)` has skipped none of them: its `k` smallest are the pencil's `k`
//! smallest, each eigenvalue as often as its multiplicity.
//!
//! The shift is `sigma = lambda_k + max(g |lambda_k|, 1e-10 ||S||_1 / ||B||_1)` with
//! `g = 5e-4` ([`CERTIFICATE_GAP`]): half of the gap (`1e-3 lambda_k`) by which the
//! iteration's cluster rule separates `lambda_k` from the first Ritz value it treats as
//! the next cluster, so `sigma` lies above the whole cluster of `lambda_k` and, unless an
//! eigenvalue lies within `g lambda_k` above `lambda_k`, below `lambda_(k+1)`. (When
//! `lambda_k = 0`, the margin is half the solver's own shift `|sigma_0|`, far below the
//! first nonzero eigenvalue of a mesh.) A zero pivot (`sigma` an eigenvalue, to rounding)
//! moves `sigma` up by 37% of the margin and the count is redone.

use std::sync::Arc;

use super::kernels::norm1;
use super::shift_invert::{ShiftInvert, check_sizes, default_shift};
use super::types::{EigenProgress, SparseEigenError, SparseEigenOptions};
use super::{ComponentNullSpace, sparse_generalized_eigen_with};
use crate::cancel::CancelToken;
use crate::linalg::cholesky::{CholeskyError, inertia};
use crate::linalg::{SparseCholesky, SparseMatrix};

/// Relative margin of the certificate's shift above `lambda_k` (see the module
/// documentation).
pub const CERTIFICATE_GAP: f64 = 5e-4;

/// Shifts tried before a certificate gives up on zero pivots.
const SHIFT_ATTEMPTS: usize = 6;

/// Rounds of search for missing pairs before the certificate reports its disagreement.
const SEARCH_ROUNDS: usize = 6;

/// The inertia count at one shift: `N(sigma)` against the computed eigenvalues below it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Certificate {
    /// The shift `sigma`.
    pub shift: f64,
    /// `N(sigma)`: eigenvalues of the pencil below `sigma`, with multiplicity (negative
    /// pivots of the `L D L^T` factorization of `S - sigma B`).
    pub below: usize,
    /// Computed eigenvalues below `sigma`.
    pub found: usize,
    /// Shifts tried (more than one after a zero pivot).
    pub shifts_tried: usize,
}

impl Certificate {
    /// True when every eigenvalue below the shift was computed (`below == found`).
    pub fn agrees(&self) -> bool {
        self.below == self.found
    }
}

/// `N(sigma)`, the number of eigenvalues of `(S, B)` below `sigma` (`B` positive
/// definite), from the inertia of `S - sigma B` (see the module documentation). `factor`:
/// a factorization of `S - sigma_0 B` whose analysis is reused (same pattern). `None`
/// when a pivot is zero (`sigma` is an eigenvalue, to rounding).
pub fn count_below(
    s: &SparseMatrix,
    b: &SparseMatrix,
    sigma: f64,
    factor: Option<&SparseCholesky>,
) -> Result<Option<usize>, SparseEigenError> {
    check_sizes(s, b)?;
    if !sigma.is_finite() {
        return Err(SparseEigenError::NonFinite);
    }
    let a = s.add_scaled(1.0, b, -sigma);
    let r = match factor {
        Some(f) => f.inertia_of(&a),
        None => inertia(&a),
    };
    match r {
        Ok(i) => Ok(Some(i.negative)),
        Err(CholeskyError::ZeroPivot(_)) => Ok(None),
        Err(e) => Err(SparseEigenError::Factorization(e.to_string())),
    }
}

/// The certificate of the computed eigenvalues `values` (any order) as the `k` smallest
/// of `(S, B)`: `N(sigma)` at the shift just above the `k`-th smallest of them (see the
/// module documentation), against the number of them below it. `factor` as in
/// [`count_below`].
pub fn certificate(
    s: &SparseMatrix,
    b: &SparseMatrix,
    values: &[f64],
    k: usize,
    factor: Option<&SparseCholesky>,
) -> Result<Certificate, SparseEigenError> {
    if k == 0 || k > values.len() {
        return Err(SparseEigenError::Invalid(format!(
            "certificate of k = {k} of {} eigenvalues",
            values.len()
        )));
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let lk = sorted[k - 1];
    let (sn, bn) = (norm1(s), norm1(b));
    let floor = 1e-10 * sn / bn.max(f64::MIN_POSITIVE);
    let margin = if lk == 0.0 {
        0.5 * default_shift(s, b).abs()
    } else {
        (CERTIFICATE_GAP * lk.abs()).max(floor)
    };
    for attempt in 0..SHIFT_ATTEMPTS {
        let sigma = lk + margin * (1.0 + 0.37 * attempt as f64);
        if let Some(below) = count_below(s, b, sigma, factor)? {
            return Ok(Certificate {
                shift: sigma,
                below,
                found: sorted.iter().filter(|&&v| v < sigma).count(),
                shifts_tried: attempt + 1,
            });
        }
    }
    Err(SparseEigenError::Factorization(format!(
        "S - sigma B had a zero pivot at {SHIFT_ATTEMPTS} shifts above lambda_k = {lk:e}"
    )))
}

/// What [`certify_and_complete`] returns.
#[derive(Debug, Clone)]
pub struct Completed {
    /// The `k` smallest eigenvalues found, ascending.
    pub values: Vec<f64>,
    /// Their eigenvectors, `n x k` column-major.
    pub vectors: Vec<f64>,
    /// The certificate of the pairs given.
    pub first: Certificate,
    /// The certificate of the pairs returned (the same as `first` when it agreed).
    pub last: Certificate,
    /// Pairs of the result that the search found (missing from those given).
    pub added: usize,
    /// Solves of the search (0 when the first certificate agreed).
    pub searches: usize,
    /// Eigenvalues of the result that differ from the given ones (the `i`-th smallest of
    /// each, by more than the certificate's margin): 0 when the given eigenvalues were the
    /// `k` smallest and the count only needed pairs beyond `k` (the rest of the cluster
    /// of `lambda_k`, or eigenvalues within the margin above it).
    pub values_changed: usize,
}

/// Certifies `values`/`vectors` (`n x len`, B-orthonormal, `len >= k`) as the `k`
/// smallest pairs of `(S, B)` and, when the count disagrees, finds the missing pairs:
/// the sparse solver (`opts`, with `factor` if given) is run on the B-orthogonal
/// complement of the pairs found (deflated, see
/// [`SparseEigenOptions::deflate_vectors`]) for the missing count plus a margin, the new
/// pairs are merged, and the certificate is redone at the new `lambda_k`, up to six
/// rounds. Returns the `k` smallest pairs then held and both certificates (the last one
/// may still disagree: the caller reports it).
#[allow(clippy::too_many_arguments)]
pub fn certify_and_complete(
    s: &SparseMatrix,
    b: &SparseMatrix,
    values: Vec<f64>,
    vectors: Vec<f64>,
    k: usize,
    opts: &SparseEigenOptions,
    factor: Option<&ShiftInvert>,
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<Completed, SparseEigenError> {
    let n = check_sizes(s, b)?;
    if n == 0 || vectors.len() != n * values.len() {
        return Err(SparseEigenError::Invalid(format!(
            "{} eigenvalues but {} vector entries (n = {n})",
            values.len(),
            vectors.len()
        )));
    }
    let chol = factor.map(|f| f.cholesky());
    let mut given_sorted = values.clone();
    given_sorted.sort_by(f64::total_cmp);
    given_sorted.truncate(k);
    let (mut values, mut vectors) = (values, vectors);
    let first = certificate(s, b, &values, k, chol)?;
    let mut last = first;
    let given = values.len();
    let mut searches = 0usize;
    let tol = opts.effective_tolerance();
    let nz = ComponentNullSpace::find(s, b, tol)?.count();
    // Eigenvalues this close to 0 belong to the null space (the component indicators,
    // which the solver deflates and returns first): exactly 0 from the sparse path, to
    // rounding from the dense one.
    let zero = 1e-10 * norm1(s) / norm1(b).max(f64::MIN_POSITIVE);
    while !last.agrees() && last.below > last.found && searches < SEARCH_ROUNDS {
        super::types::check(cancel)?;
        let missing = last.below - last.found;
        // Deflate the pairs found (the indicators are deflated by the solver itself).
        let keep: Vec<usize> = (0..values.len())
            .filter(|&j| values[j].abs() > zero)
            .collect();
        let mut x = Vec::with_capacity(n * keep.len());
        for &j in &keep {
            x.extend_from_slice(&vectors[j * n..(j + 1) * n]);
        }
        let room = n.saturating_sub(nz + keep.len());
        let want = (missing + missing.div_ceil(4).max(2)).min(room);
        if want == 0 {
            break;
        }
        let search = SparseEigenOptions {
            k: nz + want,
            deflate: true,
            deflate_vectors: Some(Arc::new(x)),
            ..opts.clone()
        };
        let r = sparse_generalized_eigen_with(s, b, &search, factor, progress, cancel)?;
        searches += 1;
        // The first nz pairs returned are the indicators, in the solver's order; the
        // pairs given hold the first of them (those with eigenvalue 0).
        let held = values.iter().filter(|&&v| v.abs() <= zero).count().min(nz);
        for j in held..r.values.len() {
            values.push(r.values[j]);
            vectors.extend_from_slice(&r.vectors[j * n..(j + 1) * n]);
        }
        last = certificate(s, b, &values, k, chol)?;
    }
    // The k smallest, ascending.
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &c| values[a].total_cmp(&values[c]));
    order.truncate(k);
    let mut out = vec![0.0; n * k];
    for (col, &j) in out.chunks_mut(n).zip(&order) {
        col.copy_from_slice(&vectors[j * n..(j + 1) * n]);
    }
    let out_values: Vec<f64> = order.iter().map(|&j| values[j]).collect();
    let margin = (last.shift - out_values[k - 1]).abs();
    let values_changed = out_values
        .iter()
        .zip(&given_sorted)
        .filter(|(a, b)| (*a - *b).abs() > margin)
        .count();
    Ok(Completed {
        values: out_values,
        values_changed,
        vectors: out,
        first,
        last,
        added: order.iter().filter(|&&j| j >= given).count(),
        searches,
    })
}
