//! The certificate that an eigenbasis skipped no eigenvalue (Sylvester's law of inertia,
//! see [`crate::linalg::certificate`]) and the completion of a basis that did.

use super::basis::Eigenbasis;
use super::params::{EigenError, EigenParams, sparse_options};
use super::pencil::Pencil;
use crate::cancel::CancelToken;
use crate::linalg::{Certificate, certify_and_complete, relative_residuals};
use crate::operators::Operators;

/// The outcome of [`certify_eigenbasis`].
#[derive(Debug, Clone)]
pub struct CertifyReport {
    /// Pairs certified (`k` of the basis).
    pub k: usize,
    /// The certificate of the basis as given.
    pub first: Certificate,
    /// The certificate of the basis returned (equal to `first` when that agreed).
    pub last: Certificate,
    /// Pairs of the returned basis that were missing from the given one.
    pub added: usize,
    /// Solves run to search for missing pairs.
    pub searches: usize,
    /// Eigenvalues of the returned basis that differ from the given ones (0: the given
    /// eigenvalues were the `k` smallest; see [`crate::linalg::Completed`]).
    pub values_changed: usize,
}

impl CertifyReport {
    /// True when the returned basis is certified: every eigenvalue below the final shift
    /// was computed.
    pub fn certified(&self) -> bool {
        self.last.agrees()
    }

    /// The report as lines of text, the same in every face (CLI, Python).
    pub fn lines(&self) -> Vec<String> {
        let describe = |c: &Certificate| {
            format!(
                "N(sigma) = {} eigenvalues below sigma = {:.9e} (negative pivots of L D L^T of S - sigma B), {} computed below it",
                c.below, c.shift, c.found
            )
        };
        let mut out = vec![format!("certificate: {}", describe(&self.first))];
        if self.first.agrees() {
            out.push(format!(
                "certified: no eigenvalue up to lambda_{} was skipped (multiplicities included)",
                self.k
            ));
            return out;
        }
        out.push(format!(
            "DISAGREES: {} more eigenvalue(s) below sigma than computed; searched {} time(s) in the B-orthogonal complement of the pairs found",
            self.first.below.abs_diff(self.first.found),
            self.searches
        ));
        out.push(format!("after the search: {}", describe(&self.last)));
        if !self.last.agrees() {
            out.push("NOT CERTIFIED: the count still disagrees".to_string());
        } else if self.values_changed == 0 {
            out.push(format!(
                "certified: the {} eigenvalues computed were the smallest; the extra ones below sigma lie past k, in the cluster of lambda_{} or within the margin above it",
                self.k, self.k
            ));
        } else {
            out.push(format!(
                "certified after completion: the solve had skipped eigenvalues; {} of the {} eigenvalues changed ({} new pairs in the basis returned)",
                self.values_changed, self.k, self.added
            ));
        }
        out
    }
}

/// Certifies that `basis` (computed for `ops` with `params`, whose Dirichlet vertices it
/// respects) holds the `k` smallest eigenvalues of the pencil, multiplicities included:
/// the number of eigenvalues below a shift just above `lambda_k`, from the inertia of
/// `S - sigma B`, against the computed ones (see [`crate::linalg::certificate`] for the
/// shift). When they disagree, the missing pairs are searched for in the B-orthogonal
/// complement of those found and the count is redone (see
/// [`crate::linalg::certify_and_complete`]); the completed basis is returned then
/// (`Some`, with its residuals and the sign rule), `None` when the given basis stands.
///
/// Cost: one sparse `L D L^T` factorization of the size of the pencil (with its own
/// ordering), about one Cholesky factorization, when the count agrees.
pub fn certify_eigenbasis(
    ops: &Operators,
    params: &EigenParams,
    basis: &Eigenbasis,
    cancel: &CancelToken,
) -> Result<(Option<Eigenbasis>, CertifyReport), EigenError> {
    let k = basis.k();
    if k == 0 {
        return Err(EigenError::Zero);
    }
    let pencil = Pencil::new(ops, params.dirichlet.as_deref())?;
    let (s, b) = (pencil.s.as_ref(), pencil.b.as_ref());
    let nf = pencil.nf();
    let n = ops.n();
    if basis.n != n {
        return Err(EigenError::Numerical(format!(
            "the basis has {} vertices, the operators {n}",
            basis.n
        )));
    }
    // The vectors on the free vertices.
    let vecs = match &pencil.free {
        None => basis.vectors.clone(),
        Some(f) => {
            let mut v = vec![0.0; nf * k];
            for j in 0..k {
                for (q, &i) in f.iter().enumerate() {
                    v[j * nf + q] = basis.vectors[j * n + i];
                }
            }
            v
        }
    };
    let opts = sparse_options(&EigenParams {
        k,
        ..params.clone()
    });
    let done = certify_and_complete(
        s,
        b,
        basis.values.clone(),
        vecs,
        k,
        &opts,
        None,
        &mut |_| {},
        cancel,
    )?;
    let report = CertifyReport {
        k,
        first: done.first,
        last: done.last,
        added: done.added,
        searches: done.searches,
        values_changed: done.values_changed,
    };
    if done.values_changed == 0 {
        return Ok((None, report));
    }
    let residuals = relative_residuals(s, b, &done.values, &done.vectors);
    let vectors = match &pencil.free {
        None => done.vectors,
        Some(f) => {
            let mut full = vec![0.0; n * k];
            for j in 0..k {
                for (q, &i) in f.iter().enumerate() {
                    full[j * n + i] = done.vectors[j * nf + q];
                }
            }
            full
        }
    };
    let mut out = Eigenbasis {
        laplacian: basis.laplacian,
        n,
        values: done.values,
        vectors,
        mass: basis.mass.clone(),
        residuals,
    };
    out.fix_signs();
    Ok((Some(out), report))
}
