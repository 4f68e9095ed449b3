//! The truncation study of the paper's Fig. 12: how far the heat-kernel basis function
//! `K_t e_i` built from the first `k` eigenpairs is from the one that uses the whole
//! spectrum, as `k` grows, for several times `t` and discretizations.
//!
//! For each Laplacian the kernel is the discretization's own wFEM-form kernel
//! `K_t = X D_t X^T B` (B = I for `cot`, the lumped mass for `voronoi-cot`, the FEM mass for
//! `fem`), so the full-spectrum kernel is `exp(-t B^-1 S)` in every case and the truncated one
//! is what `experiment diffusion-basis` computes.
//!
//! Two references (see [`TruncationReference`]):
//! - **dense** (small meshes): all `n` pairs of `(S, B)` by the dense solver; the truncated
//!   function for `k` pairs is the partial sum of the first `k` terms of the *same* expansion,
//!   so the error is exactly the tail `sum_{j >= k} exp(-lambda_j t) x_j x_j^T B e_i` and is
//!   zero (to rounding) at `k = n`;
//! - **time stepping** (larger meshes): `k_max` pairs by [`compute_eigenbasis`], and the
//!   reference [`reference_heat_time_stepping`] (extrapolated implicit Euler, no
//!   eigenvectors).
//!
//! Times are interpreted for the shape scaled to unit total mass (`1^T B 1`) when
//! [`ScaleNormalization::UnitArea`] is on (the default, as in the experiments): the kernel at
//! time `t` of the normalised shape equals the raw kernel at time `A t` (see
//! [`crate::spectral::heat`]).

use crate::Laplacian;
use crate::mesh::Mesh;
use crate::operators::Operators;
use crate::spectral::Eigenbasis;
use crate::spectral::eigenbasis::{EigenParams, compute_eigenbasis};
use crate::spectral::heat::{ScaleNormalization, reference_heat_time_stepping};

/// Errors of the truncation study.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum TruncationError {
    /// A parameter is invalid; `name` is the parameter (as on the command line).
    #[error("{name}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// The eigen-decomposition failed.
    #[error("eigenpairs ({laplacian}): {message}")]
    Eigen {
        /// The discretization.
        laplacian: &'static str,
        /// The solver's message.
        message: String,
    },
    /// The time-stepping reference failed.
    #[error("time-stepping reference ({laplacian}, t = {t}): {message}")]
    Reference {
        /// The discretization.
        laplacian: &'static str,
        /// The time.
        t: f64,
        /// The message.
        message: String,
    },
}

/// Which non-truncated reference to use.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum TruncationReference {
    /// Dense when `n <= dense_max_n`, time stepping otherwise.
    #[default]
    Auto,
    /// All pairs by the dense solver (O(n^3)).
    Dense,
    /// Extrapolated implicit Euler with this relative tolerance.
    TimeStepping {
        /// Relative tolerance of the time stepping.
        tol: f64,
    },
}

crate::defaults::declare::with_defaults! {
    /// Parameters of [`truncation_study`]. `Default`: the paper's Fig. 12 set-up: cot,
    /// voronoi-cot and fem; t = 0.01, 0.05, 0.1; k = 10, 20, 50, 100, 200 and all pairs.
    #[derive(Debug, Clone, PartialEq)]
    pub struct TruncationParams {
        /// Discretizations.
        pub laplacians: Vec<Laplacian> = vec![Laplacian::Cot, Laplacian::VoronoiCot, Laplacian::Fem],
        /// Diffusion times.
        pub times: Vec<f64> = vec![0.01, 0.05, 0.1],
        /// Numbers of pairs; values above `n` (or `usize::MAX`, "all") are clamped to `n`
        /// (time-stepping reference: to the largest computed).
        pub ks: Vec<usize> = vec![10, 20, 50, 100, 200, usize::MAX],
        /// Anchor vertex; `None`: the vertex of largest x (lowest index on ties).
        pub anchor: Option<usize> = None,
        /// Scale normalisation of the times.
        pub normalization: ScaleNormalization = ScaleNormalization::UnitArea,
        /// The reference.
        pub reference: TruncationReference = TruncationReference::Auto,
        /// Largest `n` for which [`TruncationReference::Auto`] uses the dense reference.
        pub dense_max_n: usize = 2500,
    }
}

/// One point of a curve.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TruncationRow {
    /// Discretization.
    pub laplacian: Laplacian,
    /// Time (of the normalised shape when normalisation is on).
    pub t: f64,
    /// Number of pairs used.
    pub k: usize,
    /// `max_v |K_t^(k) e_i (v) - K_t e_i (v)|`.
    pub linf_error: f64,
    /// The same divided by `max_v |K_t e_i (v)|`.
    pub linf_relative: f64,
    /// `max_v |K_t e_i (v)|` of the reference.
    pub reference_max: f64,
}

/// The result of [`truncation_study`].
#[derive(Debug, Clone, PartialEq)]
pub struct TruncationResult {
    /// Rows, grouped by Laplacian, then time, then increasing `k`.
    pub rows: Vec<TruncationRow>,
    /// The anchor used.
    pub anchor: usize,
    /// Vertex count.
    pub n: usize,
    /// Whether the dense reference was used (else time stepping).
    pub dense: bool,
    /// For the time-stepping reference: the largest estimated relative error.
    pub reference_error_estimate: f64,
}

/// Progress of [`truncation_study`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TruncationProgress {
    /// Starting the eigen-decomposition of this Laplacian (index into the list).
    Eigen {
        /// Index of the Laplacian.
        index: usize,
    },
    /// Finished this Laplacian.
    Done {
        /// Index of the Laplacian.
        index: usize,
    },
}

fn vertex_of_largest_x(mesh: &Mesh) -> usize {
    let p = mesh.positions();
    (0..p.len()).fold(0, |best, i| if p[i][0] > p[best][0] { i } else { best })
}

/// `(B x_j)[anchor]` for every column of `basis` (B symmetric: column `anchor` of B).
fn anchor_coefficients(basis: &Eigenbasis, anchor: usize) -> Vec<f64> {
    let (rows, vals) = basis.mass.col(anchor);
    (0..basis.k())
        .map(|j| {
            let x = basis.vector(j);
            rows.iter().zip(vals).map(|(&r, &v)| v * x[r]).sum()
        })
        .collect()
}

/// Runs the study (see the module documentation). Rows come in the order of
/// `params.laplacians`, then `params.times`, then the sorted, de-duplicated clamped `ks`.
pub fn truncation_study(
    mesh: &Mesh,
    params: &TruncationParams,
    progress: &mut dyn FnMut(TruncationProgress),
) -> Result<TruncationResult, TruncationError> {
    let n = mesh.n_vertices();
    let bad = |name, reason: String| TruncationError::InvalidParameter { name, reason };
    if params.laplacians.is_empty() {
        return Err(bad("laplacian", "give at least one Laplacian".into()));
    }
    if params.times.is_empty() {
        return Err(bad("t", "give at least one time".into()));
    }
    if let Some(&t) = params.times.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
        return Err(bad("t", format!("{t}: times must be positive numbers")));
    }
    if params.ks.is_empty() || params.ks.contains(&0) {
        return Err(bad("k", "give numbers of pairs >= 1".into()));
    }
    let anchor = params.anchor.unwrap_or_else(|| vertex_of_largest_x(mesh));
    if anchor >= n {
        return Err(bad(
            "anchor",
            format!("{anchor}: the mesh has only {n} vertices"),
        ));
    }
    let dense = match params.reference {
        TruncationReference::Dense => true,
        TruncationReference::TimeStepping { tol } => {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(bad("tolerance", format!("{tol}: must be > 0")));
            }
            false
        }
        TruncationReference::Auto => n <= params.dense_max_n,
    };
    let k_max_wanted = params.ks.iter().copied().max().unwrap_or(1);
    let mut rows = Vec::new();
    let mut estimate = 0.0f64;
    for (li, &lap) in params.laplacians.iter().enumerate() {
        progress(TruncationProgress::Eigen { index: li });
        let ops = Operators::new(mesh, lap);
        let eig_err = |message: String| TruncationError::Eigen {
            laplacian: lap.name(),
            message,
        };
        let basis = if dense {
            Eigenbasis::dense(&ops, n).map_err(|e| eig_err(e.to_string()))?
        } else {
            let k = k_max_wanted.min(n.saturating_sub(1)).max(1);
            let ep = EigenParams {
                k,
                ..EigenParams::default()
            };
            compute_eigenbasis(&ops, &ep, &mut |_| {}).map_err(|e| eig_err(e.to_string()))?
        };
        let total: f64 = ops.mass.values().iter().sum();
        let scale = match params.normalization {
            ScaleNormalization::UnitArea if total > 0.0 && total.is_finite() => total,
            _ => 1.0,
        };
        let kb = basis.k();
        let mut ks: Vec<usize> = params.ks.iter().map(|&k| k.min(kb)).collect();
        ks.sort_unstable();
        ks.dedup();
        let coef = anchor_coefficients(&basis, anchor);
        for &t in &params.times {
            let te = t * scale;
            let reference: Vec<f64> = if dense {
                partial_sum(&basis, &coef, te, n)
            } else {
                let mut e = vec![0.0; n];
                e[anchor] = 1.0;
                let tol = match params.reference {
                    TruncationReference::TimeStepping { tol } => tol,
                    _ => 1e-10,
                };
                let sol = reference_heat_time_stepping(&ops, &e, te, tol).map_err(|e| {
                    TruncationError::Reference {
                        laplacian: lap.name(),
                        t,
                        message: e.to_string(),
                    }
                })?;
                estimate = estimate.max(sol.estimated_error);
                sol.values
            };
            let rmax = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            // Accumulate the expansion term by term and record the error at each k.
            let mut acc = vec![0.0; n];
            let mut next = 0;
            for &k in &ks {
                while next < k {
                    let c = coef[next] * (-basis.values[next] * te).exp();
                    if c != 0.0 {
                        for (a, x) in acc.iter_mut().zip(basis.vector(next)) {
                            *a += c * x;
                        }
                    }
                    next += 1;
                }
                let err = acc
                    .iter()
                    .zip(&reference)
                    .fold(0.0f64, |m, (a, r)| m.max((a - r).abs()));
                rows.push(TruncationRow {
                    laplacian: lap,
                    t,
                    k,
                    linf_error: err,
                    linf_relative: if rmax > 0.0 { err / rmax } else { err },
                    reference_max: rmax,
                });
            }
        }
        progress(TruncationProgress::Done { index: li });
    }
    Ok(TruncationResult {
        rows,
        anchor,
        n,
        dense,
        reference_error_estimate: estimate,
    })
}

/// `sum_j coef_j exp(-lambda_j t) x_j` over every column of `basis`.
fn partial_sum(basis: &Eigenbasis, coef: &[f64], t: f64, n: usize) -> Vec<f64> {
    let mut acc = vec![0.0; n];
    for (j, (&cj, &l)) in coef.iter().zip(&basis.values).enumerate() {
        let c = cj * (-l * t).exp();
        if c != 0.0 {
            for (a, x) in acc.iter_mut().zip(basis.vector(j)) {
                *a += c * x;
            }
        }
    }
    acc
}
