//! Spectral filters: the weight `w = 1/phi` applied to the Laplacian eigenvalues.
//!
//! Convention (`docs/MATH.md`, "Filters"): a filter is stored and evaluated
//! as its **weight** `w(s) = 1/phi(s)`, so that
//!
//! ```text
//! d(p,q)^2 = sum_{k: lambda_k > 0} w(lambda_k) (x_k(p) - x_k(q))^2
//! ```
//!
//! | filter | weight `w(s)` | `phi(s) = 1/w(s)` |
//! | --- | --- | --- |
//! | [`Filter::Diffusion`] | `exp(-t s)` | `exp(t s)` |
//! | [`Filter::CommuteTime`] | `1/s` | `s` |
//! | [`Filter::Biharmonic`] | `1/s^2` | `s^2` |
//! | [`Filter::Mix`] | `(1-a) exp(-t s) + a / s^2` | its inverse |
//! | [`Filter::Polynomial`] | `s^-p` | `s^p` |
//! | [`Filter::BandSuppression`] | `|prod_{i in I} (s - lambda_i)|`, exactly 0 at `i in I` | `1/|prod ...|` |
//! | [`Filter::Custom`] | the expression (kind `Weight`) or its inverse (kind `Phi`) | |
//!
//! Zero eigenvalues (one per connected component) are skipped: an eigenvalue with
//! `lambda <= ZERO_EIGENVALUE_EPS * lambda_max` (in absolute value) counts as zero and gets
//! weight 0 in [`Filter::weights`]. Every other eigenvalue must receive a strictly positive,
//! finite weight, or [`Filter::weights`] refuses the filter, naming the first failing pair.
//!
//! The band-suppression filter of the paper, `phi(s) = [prod_{i in I}(s - lambda_i)]^-1`, is
//! negative between suppressed eigenvalues; we make it positive by taking the absolute
//! value, `w(s) = |prod_{i in I}(s - lambda_i)|`. The suppressed pairs `i in I` get weight
//! exactly 0 (that is the point of the filter: their eigenvectors do not contribute); any
//! *other* pair whose eigenvalue coincides with a suppressed one gets weight 0 too and is
//! refused as not strictly positive.
//!
//! # Text syntax ([`Filter`]'s [`FromStr`](std::str::FromStr))
//!
//! - `diffusion:t=0.5` (also `heat:t=0.5`; `t` defaults to 0.5)
//! - `commute` (also `commute-time`)
//! - `biharmonic` (also `bi-harmonic`)
//! - `mix:a=0.5,t=0.5` (defaults `a = 0.5`, `t = 0.5`)
//! - `poly:p=2` (also `polynomial:p=2`)
//! - `band:1,4,5` (band suppression of eigenpairs 1, 4 and 5; 0-based, as in the basis)
//! - `custom-w:EXPR;name=value,...`: EXPR is the **weight** `w(s)`
//! - `custom-phi:EXPR;name=value,...`: EXPR is the **filter map** `phi(s)`; `w = 1/phi`
//!
//! Expressions: numbers (`1`, `2.5`, `1e-3`), the variable `s`, the constant `pi`, named
//! parameters, `+ - * / ^` (`^` binds tightest and is right-associative, `-s^2 = -(s^2)`),
//! unary minus, parentheses, and the functions `exp log sqrt abs sin cos tanh` (one
//! argument) and `pow min max` (two arguments). Example: `custom-w:exp(-s*t)/s;t=0.1`.
//! An expression may nest parentheses, function calls, signs and powers at most
//! [`MAX_EXPR_NESTING`] deep and hold at most [`MAX_EXPR_NODES`] numbers, names and
//! operations, so that parsing, evaluating and dropping it never overflow a thread's stack
//! (a server's worker threads have 2 MB).

use std::collections::BTreeMap;

mod expr;
mod text;

pub use expr::{Expr, MAX_EXPR_NESTING, MAX_EXPR_NODES};

/// Eigenvalues with `|lambda| <= ZERO_EIGENVALUE_EPS * lambda_max` count as zero (one per
/// connected component) and are skipped. The value matches pyFM's WKS cut-off.
pub const ZERO_EIGENVALUE_EPS: f64 = 1e-8;

/// Errors of filters: validation on a spectrum and parsing.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum FilterError {
    /// The weight is not strictly positive and finite at an eigenvalue that is used.
    #[error(
        "filter {filter} is not strictly positive and finite on the spectrum: w({value}) = {weight} at eigenpair index {index}"
    )]
    NotPositive {
        /// The filter, as text.
        filter: String,
        /// Index of the first failing eigenpair (0-based, in the basis).
        index: usize,
        /// Its eigenvalue.
        value: f64,
        /// The weight computed there.
        weight: f64,
    },
    /// A parameter is out of its domain (e.g. `t <= 0`, `a` outside `[0, 1]`).
    #[error("invalid filter parameter: {0}")]
    InvalidParameter(String),
    /// A band-suppression index is not in the basis.
    #[error("band-suppression index {index} is out of range: the basis has {k} eigenpairs")]
    IndexOutOfRange {
        /// The offending index.
        index: usize,
        /// Number of pairs in the basis.
        k: usize,
    },
    /// The spectrum is empty or has only zero eigenvalues.
    #[error(
        "the spectrum has no non-zero eigenvalue to filter: every pair computed is a zero one (a shape with c separate pieces has c zero eigenvalues; ask for more than c pairs)"
    )]
    EmptySpectrum,
    /// The filter text could not be parsed.
    #[error("cannot parse filter '{text}': {message}")]
    Syntax {
        /// The text given.
        text: String,
        /// What is wrong.
        message: String,
    },
    /// A custom expression could not be parsed.
    #[error("expression error at character {position} of '{expr}': {message}")]
    Expression {
        /// The expression.
        expr: String,
        /// 0-based character position.
        position: usize,
        /// What is wrong.
        message: String,
    },
}

/// Whether a custom expression is the weight `w(s)` or the filter map `phi(s) = 1/w(s)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CustomKind {
    /// The expression is the weight `w(s)`.
    Weight,
    /// The expression is the paper's filter map `phi(s)`; the weight is `1/phi(s)`.
    Phi,
}

/// A spectral filter, stored as its weight `w = 1/phi` (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub enum Filter {
    /// Diffusion distance at time `t`: `w(s) = exp(-t s)`.
    Diffusion {
        /// Diffusion time, `> 0`.
        t: f64,
    },
    /// Commute-time distance: `w(s) = 1/s`.
    CommuteTime,
    /// Bi-harmonic distance: `w(s) = 1/s^2`.
    Biharmonic,
    /// The paper's mix (Fig. 14) read as weights: `w(s) = (1-a) exp(-t s) + a/s^2`.
    Mix {
        /// Blend, in `[0, 1]`: 0 = diffusion, 1 = bi-harmonic.
        a: f64,
        /// Diffusion time, `> 0` (unused when `a = 1`).
        t: f64,
    },
    /// `phi(s) = s^p`, `w(s) = s^-p`.
    Polynomial {
        /// Exponent.
        p: f64,
    },
    /// Suppresses the listed eigenpairs: `w(s) = |prod_{i} (s - lambda_i)|`, 0 at the
    /// listed pairs. Needs the spectrum, so [`Filter::weight`] returns NaN for it; use
    /// [`Filter::weights`].
    BandSuppression {
        /// 0-based eigenpair indices to suppress.
        indices: Vec<usize>,
    },
    /// A user expression in `s` and named parameters (see the module documentation).
    Custom {
        /// The expression text.
        expr: String,
        /// Named parameters the expression may use.
        params: BTreeMap<String, f64>,
        /// Whether `expr` is the weight or the filter map `phi`.
        kind: CustomKind,
    },
}

impl Default for Filter {
    /// The executable paper's default distance: bi-harmonic.
    fn default() -> Self {
        Filter::Biharmonic
    }
}

impl Filter {
    /// A custom filter, checking that the expression parses with the given parameters.
    pub fn custom(
        expr: &str,
        params: BTreeMap<String, f64>,
        kind: CustomKind,
    ) -> Result<Self, FilterError> {
        let names: Vec<&str> = params.keys().map(String::as_str).collect();
        Expr::parse(expr, &names)?;
        Ok(Filter::Custom {
            expr: expr.to_string(),
            params,
            kind,
        })
    }

    /// The weight `w(s) = 1/phi(s)` at one value `s`. No validation: may be negative,
    /// infinite or NaN (e.g. `1/s` at 0, an unparsable custom expression, or
    /// [`Filter::BandSuppression`], which needs the spectrum).
    pub fn weight(&self, s: f64) -> f64 {
        match self.evaluator() {
            Ok(ev) => ev.eval(s, &[]),
            Err(_) => f64::NAN,
        }
    }

    fn evaluator(&self) -> Result<Evaluator<'_>, FilterError> {
        Ok(match self {
            Filter::Custom { expr, params, kind } => {
                let names: Vec<&str> = params.keys().map(String::as_str).collect();
                let e = Expr::parse(expr, &names)?;
                Evaluator::Custom {
                    e,
                    values: params.values().copied().collect(),
                    kind: *kind,
                }
            }
            f => Evaluator::Builtin(f),
        })
    }

    /// Checks the parameters of the built-in filters.
    pub fn validate_parameters(&self) -> Result<(), FilterError> {
        let bad = |m: String| Err(FilterError::InvalidParameter(m));
        match *self {
            Filter::Diffusion { t } if !(t.is_finite() && t > 0.0) => {
                bad(format!("diffusion time t must be finite and > 0, got {t}"))
            }
            Filter::Mix { a, t } => {
                if !(0.0..=1.0).contains(&a) {
                    bad(format!("mix blend a must be in [0, 1], got {a}"))
                } else if !(t.is_finite() && t > 0.0) {
                    bad(format!("mix time t must be finite and > 0, got {t}"))
                } else {
                    Ok(())
                }
            }
            Filter::Polynomial { p } if !p.is_finite() => {
                bad(format!("polynomial exponent p must be finite, got {p}"))
            }
            _ => Ok(()),
        }
    }

    /// Weights of the spectrum `eigenvalues` (`k` entries, one per pair).
    ///
    /// Zero eigenvalues (`|lambda| <= ZERO_EIGENVALUE_EPS * lambda_max`) get weight 0 (they
    /// are skipped), as do the suppressed pairs of [`Filter::BandSuppression`]. Every other
    /// weight must be strictly positive and finite, or the filter is refused with
    /// [`FilterError::NotPositive`] naming the first failing pair.
    pub fn weights(&self, eigenvalues: &[f64]) -> Result<Vec<f64>, FilterError> {
        self.validate_parameters()?;
        let lmax = eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !lmax.is_finite() || lmax <= 0.0 {
            return Err(FilterError::EmptySpectrum);
        }
        let zero = |v: f64| v.abs() <= ZERO_EIGENVALUE_EPS * lmax;
        let mut suppressed = vec![false; eigenvalues.len()];
        let mut band: Vec<f64> = Vec::new();
        if let Filter::BandSuppression { indices } = self {
            for &i in indices {
                if i >= eigenvalues.len() {
                    return Err(FilterError::IndexOutOfRange {
                        index: i,
                        k: eigenvalues.len(),
                    });
                }
                suppressed[i] = true;
                band.push(eigenvalues[i]);
            }
        }
        let ev = self.evaluator()?;
        let mut out = Vec::with_capacity(eigenvalues.len());
        let mut any = false;
        for (i, &l) in eigenvalues.iter().enumerate() {
            if zero(l) || suppressed[i] {
                out.push(0.0);
                continue;
            }
            any = true;
            out.push(positive_weight(self, i, l, ev.eval(l, &band))?);
        }
        if !any {
            return Err(FilterError::EmptySpectrum);
        }
        Ok(out)
    }
}

/// `weight`, the weight of the pair `index` (eigenvalue `value`) under `filter`, when it is
/// strictly positive and finite; otherwise [`FilterError::NotPositive`].
pub(crate) fn positive_weight(
    filter: &dyn std::fmt::Display,
    index: usize,
    value: f64,
    weight: f64,
) -> Result<f64, FilterError> {
    if weight.is_finite() && weight > 0.0 {
        Ok(weight)
    } else {
        Err(FilterError::NotPositive {
            filter: filter.to_string(),
            index,
            value,
            weight,
        })
    }
}

enum Evaluator<'a> {
    Builtin(&'a Filter),
    Custom {
        e: Expr,
        values: Vec<f64>,
        kind: CustomKind,
    },
}

impl Evaluator<'_> {
    fn eval(&self, s: f64, band: &[f64]) -> f64 {
        match self {
            Evaluator::Builtin(f) => match **f {
                Filter::Diffusion { t } => (-t * s).exp(),
                Filter::CommuteTime => 1.0 / s,
                Filter::Biharmonic => 1.0 / (s * s),
                Filter::Mix { a, t } => (1.0 - a) * (-t * s).exp() + a / (s * s),
                Filter::Polynomial { p } => s.powf(-p),
                Filter::BandSuppression { .. } => {
                    if band.is_empty() {
                        f64::NAN
                    } else {
                        band.iter().map(|l| s - l).product::<f64>().abs()
                    }
                }
                Filter::Custom { .. } => f64::NAN,
            },
            Evaluator::Custom { e, values, kind } => {
                let v = e.eval(s, values);
                match kind {
                    CustomKind::Weight => v,
                    CustomKind::Phi => 1.0 / v,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
