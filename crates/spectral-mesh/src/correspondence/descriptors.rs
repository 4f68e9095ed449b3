//! Descriptors for matching, chosen as pyFM's `FunctionalMapping.preprocess` chooses them:
//! `count` scaled WKS (or HKS) at the automatic energies (times) of the basis given, then
//! for each landmark `l` the scaled kernel `sum_k c_k(e) x_k(l) x_k(p)` at the same
//! energies (times), every `subsample_step`-th column kept, each column divided by its
//! `L2(M)` norm `sqrt(d^T M d)`.

use super::CorrespondenceError;
use crate::linalg::dense_ops::gram;
use crate::linalg::sym_spmm;
use crate::spectral::BasisView;
use crate::spectral::filters::ZERO_EIGENVALUE_EPS;
use crate::spectral::signatures::{hks, hks_auto_times, wks, wks_auto_energies};

/// Default number of energies (times) of the descriptors.
pub const DEFAULT_DESCRIPTOR_COUNT: usize = 100;
/// Default step of the column subsampling (pyFM's quickstart: 5, so 20 descriptors).
pub const DEFAULT_SUBSAMPLE_STEP: usize = 5;

/// Which signature.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DescriptorKind {
    /// Wave kernel signature (pyFM's default).
    #[default]
    Wks,
    /// Heat kernel signature.
    Hks,
}

crate::io::names::names_as_text!(
    DescriptorKind,
    names: [Wks => "wks", Hks => "hks"],
    aliases: [],
    unknown: |s| format!("unknown descriptor '{s}': expected wks or hks"),
);

/// Parameters of the descriptors. `Default`: WKS, 100 energies, every 5th kept.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct DescriptorParams {
    /// WKS or HKS.
    pub kind: DescriptorKind,
    /// Number of energies (times), `>= 1`.
    pub count: usize,
    /// Keep columns `0, step, 2 step, ...` (`>= 1`).
    pub subsample_step: usize,
}

impl Default for DescriptorParams {
    fn default() -> Self {
        Self {
            kind: DescriptorKind::Wks,
            count: DEFAULT_DESCRIPTOR_COUNT,
            subsample_step: DEFAULT_SUBSAMPLE_STEP,
        }
    }
}

impl DescriptorParams {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), CorrespondenceError> {
        if self.count == 0 {
            return Err(CorrespondenceError::InvalidParameter(
                "the number of descriptor energies (times) must be >= 1".into(),
            ));
        }
        if self.subsample_step == 0 {
            return Err(CorrespondenceError::InvalidParameter(
                "the descriptor subsampling step must be >= 1".into(),
            ));
        }
        Ok(())
    }
}

/// Descriptors: `p` functions on `n` vertices, `n x p` column-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Descriptors {
    /// Vertices.
    pub n: usize,
    /// Number of descriptors.
    pub p: usize,
    /// The values, column-major (`values[d * n + i]`).
    pub values: Vec<f64>,
}

impl Descriptors {
    /// Descriptor `d` (`n` values).
    pub fn column(&self, d: usize) -> &[f64] {
        &self.values[d * self.n..(d + 1) * self.n]
    }
}

/// Spectral weights `c_k` of each energy (time) and the normalizer `sum_k c_k`.
fn spectral_weights(
    basis: BasisView<'_>,
    params: &DescriptorParams,
) -> Result<Vec<Vec<f64>>, CorrespondenceError> {
    let err = |e: crate::spectral::signatures::SignatureError| {
        CorrespondenceError::Descriptors(e.to_string())
    };
    match params.kind {
        DescriptorKind::Hks => {
            let times = hks_auto_times(basis, params.count).map_err(err)?;
            Ok(times
                .iter()
                .map(|&t| basis.values.iter().map(|l| (-l * t).exp()).collect())
                .collect())
        }
        DescriptorKind::Wks => {
            let (energies, sigma) = wks_auto_energies(basis, params.count).map_err(err)?;
            let lmax = basis.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            Ok(energies
                .iter()
                .map(|&e| {
                    basis
                        .values
                        .iter()
                        .map(|&l| {
                            if l > ZERO_EIGENVALUE_EPS * lmax {
                                (-(e - l.ln()).powi(2) / (2.0 * sigma * sigma)).exp()
                            } else {
                                0.0
                            }
                        })
                        .collect()
                })
                .collect())
        }
    }
}

/// The descriptors of one shape on `basis` (all its pairs are used: pass the first `k1`),
/// with the kernels of `landmarks` appended (see the module docs).
pub fn descriptors(
    basis: BasisView<'_>,
    params: &DescriptorParams,
    landmarks: &[usize],
) -> Result<Descriptors, CorrespondenceError> {
    params.validate()?;
    let n = basis.n;
    if let Some(&bad) = landmarks.iter().find(|&&l| l >= n) {
        return Err(CorrespondenceError::InvalidParameter(format!(
            "landmark vertex {bad} does not exist (the shape has {n} vertices)"
        )));
    }
    let err = |e: crate::spectral::signatures::SignatureError| {
        CorrespondenceError::Descriptors(e.to_string())
    };
    let mut columns: Vec<Vec<f64>> = match params.kind {
        DescriptorKind::Hks => {
            let times = hks_auto_times(basis, params.count).map_err(err)?;
            hks(basis, &times, true)
        }
        DescriptorKind::Wks => {
            let (energies, sigma) = wks_auto_energies(basis, params.count).map_err(err)?;
            wks(basis, &energies, sigma, true).map_err(err)?
        }
    };
    if !landmarks.is_empty() {
        let weights = spectral_weights(basis, params)?;
        for &l in landmarks {
            for c in &weights {
                let total: f64 = c.iter().sum();
                let scale = if total > 0.0 { 1.0 / total } else { 1.0 };
                let mut col = vec![0.0; n];
                for (j, &cj) in c.iter().enumerate() {
                    let x = basis.vector(j);
                    let w = cj * x[l] * scale;
                    if w != 0.0 {
                        col.iter_mut().zip(x).for_each(|(o, xi)| *o += w * xi);
                    }
                }
                columns.push(col);
            }
        }
    }
    let kept: Vec<Vec<f64>> = columns.into_iter().step_by(params.subsample_step).collect();
    let p = kept.len();
    let mut values = Vec::with_capacity(n * p);
    for mut col in kept {
        let mc = basis.mass.mul_vec(&col);
        let norm = col.iter().zip(&mc).map(|(a, b)| a * b).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(CorrespondenceError::Descriptors(
                "a descriptor is zero everywhere (is the basis too small?)".into(),
            ));
        }
        col.iter_mut().for_each(|v| *v /= norm);
        values.extend(col);
    }
    Ok(Descriptors { n, p, values })
}

/// The coefficients `Phi^T M f` (`k x p`) of the `p` functions `f` (`n x p`, column-major)
/// in the `k` vectors of `basis`.
pub fn project(basis: BasisView<'_>, f: &[f64], p: usize) -> Result<Vec<f64>, CorrespondenceError> {
    let n = basis.n;
    if f.len() != n * p {
        return Err(CorrespondenceError::SizeMismatch(format!(
            "{} values for {p} functions on {n} vertices",
            f.len()
        )));
    }
    let mf = sym_spmm(basis.mass, f, p);
    Ok(gram(basis.vectors, &mf, n, basis.k(), p))
}
