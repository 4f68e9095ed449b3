//! Computing an eigenbasis from the command line, with a progress bar.

use std::time::Instant;

use anyhow::Result;
use spectral_mesh::linalg::EigenProgress;
use spectral_mesh::spectral::Eigenbasis;
use spectral_mesh::spectral::eigenbasis::{EigenParams, compute_eigenbasis};
use spectral_mesh::{Mesh, Operators};

use crate::progress;

/// A computed basis and how long it took.
pub struct TimedBasis {
    /// The basis.
    pub basis: Eigenbasis,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Assembles the operators and computes `params.k` pairs, showing progress on stderr
/// when it is a terminal.
pub fn compute(
    mesh: &Mesh,
    laplacian: spectral_mesh::Laplacian,
    params: &EigenParams,
) -> Result<TimedBasis> {
    let ops = Operators::new(mesh, laplacian);
    let bar = progress::bar(params.k as u64, "eigenpairs");
    let t0 = Instant::now();
    let mut cb = |p: EigenProgress| match p {
        EigenProgress::Dense { .. } => bar.set_message("dense eigen"),
        EigenProgress::Factorization { .. } => bar.set_message("factoring"),
        EigenProgress::Iteration { converged, .. } => {
            bar.set_message("iterating");
            bar.set_position(converged as u64);
        }
        _ => {}
    };
    let basis = compute_eigenbasis(&ops, params, &mut cb)?;
    bar.finish_and_clear();
    Ok(TimedBasis {
        basis,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Largest residual and B-orthonormality error of a basis, for summaries.
pub fn quality(b: &Eigenbasis) -> (f64, f64) {
    let res = b.residuals.iter().fold(0.0f64, |a, &r| a.max(r));
    // max |X^T B X - I| over the pairs (O(n k^2)).
    let n = b.n;
    let k = b.k();
    let bx: Vec<Vec<f64>> = (0..k).map(|j| b.mass.mul_vec(b.vector(j))).collect();
    let mut orth = 0.0f64;
    for i in 0..k {
        for (j, bxj) in bx.iter().enumerate() {
            let d: f64 = (0..n).map(|r| b.vector(i)[r] * bxj[r]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            orth = orth.max((d - want).abs());
        }
    }
    (res, orth)
}
