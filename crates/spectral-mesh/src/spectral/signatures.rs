//! Point signatures from an eigenbasis: heat kernel signature (HKS), wave kernel signature
//! (WKS) and auto-diffusion function (ADF), with pyFM's conventions (see `docs/MATH.md`, "Signatures").
//!
//! - HKS: `hks_t(p) = sum_k exp(-lambda_k t) x_k(p)^2` over **all** pairs of the basis (the
//!   zero eigenvalue included, as pyFM does); scaled: divided by the heat trace
//!   `sum_k exp(-lambda_k t)`. Automatic times: `n` values geometrically spaced from
//!   `4 ln 10 / lambda_max` to `4 ln 10 / lambda_1`, `lambda_1` the first non-zero eigenvalue.
//! - WKS: pairs with `lambda <= 1e-8 lambda_max` are dropped; with `c_k(e) =
//!   exp(-(e - ln lambda_k)^2 / (2 sigma^2))`, `wks_e(p) = sum_k c_k(e) x_k(p)^2`; scaled:
//!   divided by `sum_k c_k(e)`. Automatic energies: `e_min = ln lambda_1`, `e_max = ln
//!   lambda_max`, `sigma = 7 (e_max - e_min) / n`, then `n` values evenly spaced from
//!   `e_min + 2 sigma` to `e_max - 2 sigma`.
//! - ADF: `G(p,p)` with the diffusion weight `exp(-t s)`, zero eigenvalues skipped.
//!
//! Every signature is returned as one `n`-vector per time (energy).

use super::BasisView;
use super::filters::{Filter, ZERO_EIGENVALUE_EPS};

/// Errors of the signatures.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SignatureError {
    /// The basis has no non-zero eigenvalue.
    #[error("the basis has no non-zero eigenvalue")]
    EmptySpectrum,
    /// A parameter is invalid.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
}

fn lambda_max(basis: BasisView<'_>) -> f64 {
    basis.values.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

fn first_nonzero(basis: BasisView<'_>) -> Result<(f64, f64), SignatureError> {
    let lmax = lambda_max(basis);
    if !(lmax > 0.0 && lmax.is_finite()) {
        return Err(SignatureError::EmptySpectrum);
    }
    let l1 = basis
        .values
        .iter()
        .copied()
        .filter(|v| *v > ZERO_EIGENVALUE_EPS * lmax)
        .fold(f64::INFINITY, f64::min);
    if !l1.is_finite() {
        return Err(SignatureError::EmptySpectrum);
    }
    Ok((l1, lmax))
}

/// `sum_k c_k x_k(p)^2` for all p.
fn weighted_squares(basis: BasisView<'_>, c: &[f64]) -> Vec<f64> {
    let n = basis.n;
    let mut g = vec![0.0; n];
    for (j, &cj) in c.iter().enumerate() {
        if cj != 0.0 {
            for (gi, x) in g.iter_mut().zip(&basis.vectors[j * n..(j + 1) * n]) {
                *gi += cj * x * x;
            }
        }
    }
    g
}

/// Heat kernel signature at each time in `times` (one `n`-vector per time); `scaled`
/// divides by the heat trace.
pub fn hks<'a>(basis: impl Into<BasisView<'a>>, times: &[f64], scaled: bool) -> Vec<Vec<f64>> {
    let basis: BasisView<'a> = basis.into();
    times
        .iter()
        .map(|&t| {
            let c: Vec<f64> = basis.values.iter().map(|l| (-l * t).exp()).collect();
            let mut h = weighted_squares(basis, &c);
            if scaled {
                let trace: f64 = c.iter().sum();
                if trace > 0.0 {
                    h.iter_mut().for_each(|v| *v /= trace);
                }
            }
            h
        })
        .collect()
}

/// pyFM's automatic HKS times: `n_times` values geometrically spaced from
/// `4 ln 10 / lambda_max` to `4 ln 10 / lambda_1` (ascending).
pub fn hks_auto_times<'a>(
    basis: impl Into<BasisView<'a>>,
    n_times: usize,
) -> Result<Vec<f64>, SignatureError> {
    let basis: BasisView<'a> = basis.into();
    let (l1, lmax) = first_nonzero(basis)?;
    let c = 4.0 * 10f64.ln();
    Ok(geomspace(c / lmax, c / l1, n_times))
}

fn geomspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![a],
        _ => {
            let (la, lb) = (a.ln(), b.ln());
            (0..n)
                .map(|i| {
                    if i == n - 1 {
                        b
                    } else {
                        (la + (lb - la) * i as f64 / (n - 1) as f64).exp()
                    }
                })
                .collect()
        }
    }
}

fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![a],
        _ => (0..n)
            .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
            .collect(),
    }
}

/// Wave kernel signature at each energy (log-eigenvalue) in `energies` with bandwidth
/// `sigma` (one `n`-vector per energy); `scaled` divides by `sum_k c_k(e)`.
pub fn wks<'a>(
    basis: impl Into<BasisView<'a>>,
    energies: &[f64],
    sigma: f64,
    scaled: bool,
) -> Result<Vec<Vec<f64>>, SignatureError> {
    let basis: BasisView<'a> = basis.into();
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(SignatureError::InvalidParameter(format!(
            "WKS sigma must be finite and > 0, got {sigma}"
        )));
    }
    let lmax = lambda_max(basis);
    if !(lmax > 0.0 && lmax.is_finite()) {
        return Err(SignatureError::EmptySpectrum);
    }
    let logs: Vec<Option<f64>> = basis
        .values
        .iter()
        .map(|&l| (l > ZERO_EIGENVALUE_EPS * lmax).then(|| l.ln()))
        .collect();
    Ok(energies
        .iter()
        .map(|&e| {
            let c: Vec<f64> = logs
                .iter()
                .map(|lg| match lg {
                    Some(lg) => (-(e - lg).powi(2) / (2.0 * sigma * sigma)).exp(),
                    None => 0.0,
                })
                .collect();
            let mut w = weighted_squares(basis, &c);
            if scaled {
                let s: f64 = c.iter().sum();
                if s > 0.0 {
                    w.iter_mut().for_each(|v| *v /= s);
                }
            }
            w
        })
        .collect())
}

/// pyFM's automatic WKS energies and bandwidth: returns `(energies, sigma)`.
pub fn wks_auto_energies<'a>(
    basis: impl Into<BasisView<'a>>,
    n_energies: usize,
) -> Result<(Vec<f64>, f64), SignatureError> {
    let basis: BasisView<'a> = basis.into();
    if n_energies == 0 {
        return Err(SignatureError::InvalidParameter(
            "at least one WKS energy is needed".into(),
        ));
    }
    let (l1, lmax) = first_nonzero(basis)?;
    let (mut e_min, mut e_max) = (l1.ln(), lmax.ln());
    let sigma = 7.0 * (e_max - e_min) / n_energies as f64;
    if sigma.is_nan() || sigma <= 0.0 {
        return Err(SignatureError::InvalidParameter(
            "the non-zero spectrum has a single value: WKS bandwidth would be 0".into(),
        ));
    }
    e_min += 2.0 * sigma;
    e_max -= 2.0 * sigma;
    Ok((linspace(e_min, e_max, n_energies), sigma))
}

/// Auto-diffusion function `G(p,p)` with the diffusion weight `exp(-t s)` (zero
/// eigenvalues skipped), `n` values.
pub fn auto_diffusion<'a>(
    basis: impl Into<BasisView<'a>>,
    t: f64,
) -> Result<Vec<f64>, SignatureError> {
    let basis: BasisView<'a> = basis.into();
    let w = Filter::Diffusion { t }
        .weights(basis.values)
        .map_err(|e| SignatureError::InvalidParameter(e.to_string()))?;
    Ok(weighted_squares(basis, &w))
}
