//! How much a truncated heat expansion leaves out: the paper's Fig. 12 as a live hint.
//!
//! A heat or diffusion quantity at time `t` from the first `k` eigenpairs is the sum
//! `sum_{j < k} exp(-lambda_j t) (...)_j`. The first pair left out weighs
//! `exp(-lambda_k t)` (0-based: `lambda_k` is the `(k+1)`-th eigenvalue), the first pair
//! that varies (the smallest non-zero eigenvalue, `lambda_2` in the paper's 1-based
//! numbering) weighs `exp(-lambda_first t)`. Their ratio
//!
//! ```text
//! ratio = exp(-(lambda_k - lambda_first) t)
//! ```
//!
//! says how strongly the omitted part of the spectrum still counts against the part of
//! the field that carries its shape. When it is not small, the truncated sum rings
//! (oscillations at the wavelength of `x_k`, with spurious critical points): a larger
//! `k` or a larger `t` is needed. [`TruncationHint`] gives the ratio, whether it is above
//! [`TRUNCATION_RATIO_WARNING`], the smallest `t` that brings it below at this `k`, and an
//! estimate of the `k` that does at this `t`.
//!
//! `lambda_k` is known when the basis holds more than `k` pairs; otherwise the last pair
//! used, `lambda_{k-1} <= lambda_k`, stands in for it and the ratio is an upper bound
//! (`exact = false`). Eigenvalues are those of the analysis (of the shape scaled to unit
//! area when it normalizes), so `t` is in the same units as the request's.

use serde::Serialize;

use crate::spectral::filters::ZERO_EIGENVALUE_EPS;

/// The ratio `exp(-(lambda_k - lambda_first) t)` above which the hint warns that the
/// picture is dominated by truncation: at `1e-3` the omitted terms, each weighing a
/// thousandth of the first varying one, are already many (Weyl: the number of pairs
/// grows linearly with `lambda` on a surface), and their sum shows as ringing.
pub const TRUNCATION_RATIO_WARNING: f64 = 1e-3;

/// The weight of the first eigenpair a truncated heat expansion leaves out, against the
/// first one that varies (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruncationHint {
    /// The time of the request.
    pub t: f64,
    /// Pairs used.
    pub k: usize,
    /// The smallest non-zero eigenvalue used (`lambda_2` in the paper's numbering).
    pub lambda_first: f64,
    /// The first eigenvalue left out, `lambda_k`, when the basis holds it; otherwise
    /// `lambda_{k-1}`, the last one used (a lower bound of it).
    pub lambda_omitted: f64,
    /// True when `lambda_omitted` is `lambda_k` itself; false when it is the bound
    /// `lambda_{k-1}` (then `omitted_weight` and `ratio` are upper bounds).
    pub exact: bool,
    /// `exp(-lambda_omitted t)`.
    pub omitted_weight: f64,
    /// `exp(-lambda_first t)`.
    pub first_weight: f64,
    /// `exp(-(lambda_omitted - lambda_first) t)`: the omitted weight relative to the first
    /// varying one.
    pub ratio: f64,
    /// [`TRUNCATION_RATIO_WARNING`].
    pub threshold: f64,
    /// `ratio > threshold`: the picture is likely dominated by truncation ringing.
    pub warning: bool,
    /// The smallest `t` with `ratio <= threshold` at this `k`.
    pub t_needed: f64,
    /// An estimate of the smallest `k` with `ratio <= threshold` at this `t` (the held
    /// eigenvalues extrapolated linearly in the index, Weyl's law on a surface), capped at
    /// `n`; `None` when no larger `k` is needed.
    pub k_needed: Option<usize>,
    /// The hint in one sentence.
    pub message: String,
}

impl TruncationHint {
    /// The hint for a request at time `t` that uses the first `k` of `eigenvalues`
    /// (ascending, as held: at least `k` of them) on a mesh of `n` vertices. `None` when
    /// `k` is 0 or larger than the eigenvalues held, `t` is not finite and positive, or no
    /// eigenvalue used is non-zero (nothing varies).
    pub fn new(eigenvalues: &[f64], k: usize, t: f64, n: usize) -> Option<Self> {
        if k == 0 || k > eigenvalues.len() || !(t.is_finite() && t > 0.0) {
            return None;
        }
        let lmax = eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !(lmax.is_finite() && lmax > 0.0) {
            return None;
        }
        let zero = ZERO_EIGENVALUE_EPS * lmax;
        let lambda_first = *eigenvalues[..k].iter().find(|v| v.abs() > zero)?;
        let (lambda_omitted, exact) = match eigenvalues.get(k) {
            Some(&l) if k < n => (l, true),
            _ => (eigenvalues[k - 1], k >= n),
        };
        let gap = (lambda_omitted - lambda_first).max(0.0);
        let ratio = (-gap * t).exp();
        let threshold = TRUNCATION_RATIO_WARNING;
        let warning = k < n && ratio > threshold;
        let log_inv = -threshold.ln();
        let t_needed = if gap > 0.0 {
            log_inv / gap
        } else {
            f64::INFINITY
        };
        // lambda_j ~ slope * j on a surface: the slope from the largest held pair.
        let kh = eigenvalues.len();
        let slope = eigenvalues[kh - 1] / (kh - 1).max(1) as f64;
        let k_needed = if warning && slope > 0.0 {
            let want = lambda_first + log_inv / t;
            let j = (want / slope).ceil();
            let est = if j.is_finite() && j < n as f64 {
                (j as usize + 1).max(k + 1)
            } else {
                n
            };
            Some(est.min(n))
        } else {
            None
        };
        let bound = if exact { "" } else { "at most " };
        let message = if k >= n {
            format!("all {n} pairs used: nothing is truncated")
        } else if warning {
            let kn = k_needed.map_or(String::new(), |kn| format!("k >= {kn} or "));
            format!(
                "truncation dominates: the first omitted pair (lambda = {lambda_omitted:.4}) weighs {bound}{ratio:.2e} of the first varying one (lambda = {lambda_first:.4}) at t = {t}; use {kn}t >= {t_needed:.3}"
            )
        } else {
            format!(
                "the first omitted pair (lambda = {lambda_omitted:.4}) weighs {bound}{ratio:.2e} of the first varying one (lambda = {lambda_first:.4}) at t = {t}"
            )
        };
        Some(Self {
            t,
            k,
            lambda_first,
            lambda_omitted,
            exact,
            omitted_weight: (-lambda_omitted * t).exp(),
            first_weight: (-lambda_first * t).exp(),
            ratio,
            threshold,
            warning,
            t_needed,
            k_needed,
            message,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratio_bound_and_suggestions() {
        // lambda_j = 10 j: the first varying pair is 10.
        let ev: Vec<f64> = (0..50).map(|j| 10.0 * j as f64).collect();
        // k = 20 of 50 held: lambda_20 = 200 is known.
        let h = TruncationHint::new(&ev, 20, 0.01, 1000).unwrap();
        assert!(h.exact);
        assert_eq!((h.lambda_first, h.lambda_omitted), (10.0, 200.0));
        assert!((h.ratio - (-1.9f64).exp()).abs() < 1e-15);
        assert!((h.omitted_weight / h.first_weight - h.ratio).abs() < 1e-15);
        assert!(h.warning);
        // t_needed brings the ratio to the threshold.
        assert!(((-(190.0) * h.t_needed).exp() - TRUNCATION_RATIO_WARNING).abs() < 1e-12);
        // k_needed: lambda_j >= 10 + ln(1000) / 0.01 = 700.8, i.e. j = 71, k = 72.
        assert_eq!(h.k_needed, Some(72));
        assert!(h.message.contains("truncation dominates"), "{}", h.message);
        // All held pairs used: lambda_{k-1} is the bound, the ratio an upper bound.
        let b = TruncationHint::new(&ev, 50, 0.01, 1000).unwrap();
        assert!(!b.exact && b.lambda_omitted == 490.0);
        assert!(b.message.contains("at most"));
        // Large t: no warning, no k needed.
        let ok = TruncationHint::new(&ev, 20, 0.5, 1000).unwrap();
        assert!(!ok.warning && ok.k_needed.is_none());
        // k = n: nothing truncated.
        let all = TruncationHint::new(&ev, 50, 0.001, 50).unwrap();
        assert!(!all.warning && all.exact);
        // Nothing to say.
        assert!(TruncationHint::new(&ev, 1, 0.1, 1000).is_none());
        assert!(TruncationHint::new(&ev, 0, 0.1, 1000).is_none());
        assert!(TruncationHint::new(&ev, 60, 0.1, 1000).is_none());
        assert!(TruncationHint::new(&ev, 10, 0.0, 1000).is_none());
        assert!(TruncationHint::new(&ev, 10, f64::NAN, 1000).is_none());
    }
}
