//! [`EigenSolver`]: factor once, answer many `k`.

use std::sync::Arc;

use super::basis::Eigenbasis;
use super::params::{EigenError, EigenParams};
use super::pencil::{Factors, Pencil};
use super::solve::solve_pencil;
use crate::cancel::CancelToken;
use crate::linalg::EigenProgress;
use crate::operators::Operators;

/// Factor once, answer many `k`: holds the operators, the factorization of the shifted
/// pencil and the largest basis computed so far (geometry-central's solver pattern).
///
/// Contract: the pairs returned for a given `k` depend only on the operators, the
/// parameters and `k`, never on what was asked before: each solve that computes runs a
/// fresh iteration (the same seed, no warm start from the held vectors) on the kept
/// factorization, and gives bit for bit what [`super::compute_eigenbasis`] gives for the same
/// `k`. A replay that asks for the same `k` thus gets the same bits. Asking for fewer
/// pairs than held returns the held basis; use [`Eigenbasis::view`] to take its first
/// `k` pairs.
///
/// The factorization of `S - sigma B` (on the free vertices under Dirichlet conditions)
/// is made by the first solve that takes the sparse path and kept, with its shift, for
/// every later one with the same interior target
/// ([`crate::linalg::ShiftInvert::target_of`]: `k` within a factor of about 1.19 share
/// it); a `k` with another target factors afresh and keeps that one instead (so that the
/// pairs stay those of [`super::compute_eigenbasis`]). Problems on the dense path
/// (small `n`, see [`super::EigenMethod::Auto`]) need no factorization, nor does a `k` that only
/// asks for zero eigenvalues (component indicators). A mesh with several components
/// keeps one factorization per component solved on the sparse path (see
/// [`super::compute_eigenbasis`]). The factors' memory is held as long as the solver: about
/// 40 M values (320 MB) at 411k vertices.
#[derive(Debug)]
pub struct EigenSolver {
    ops: Arc<Operators>,
    params: EigenParams,
    basis: Option<Arc<Eigenbasis>>,
    factors: Factors,
}

impl EigenSolver {
    /// A solver of the pencil of `ops` with `params` (`params.k` is ignored: each
    /// [`EigenSolver::solve`] names its `k`). Nothing is computed yet.
    pub fn new(ops: Arc<Operators>, params: EigenParams) -> Self {
        Self {
            ops,
            params,
            basis: None,
            factors: Factors::default(),
        }
    }

    /// The operators.
    pub fn operators(&self) -> &Arc<Operators> {
        &self.ops
    }

    /// The parameters (`k` ignored).
    pub fn params(&self) -> &EigenParams {
        &self.params
    }

    /// The basis held, if any.
    pub fn held(&self) -> Option<Arc<Eigenbasis>> {
        self.basis.clone()
    }

    /// How many times the shifted pencil was factored (a counter, for tests and reports):
    /// 0 before the first sparse solve and for dense-path problems, then one per interior
    /// target solved for (one per component solved on the sparse path on a disconnected
    /// mesh).
    pub fn factorizations(&self) -> usize {
        self.factors.count
    }

    /// Values of the kept factorizations (8 bytes each, plus their symbolic analysis):
    /// 0 before the first sparse solve and on the dense path.
    pub fn factor_len(&self) -> usize {
        self.factors
            .whole
            .iter()
            .chain(self.factors.parts.iter().flatten())
            .map(|f| f.factor_len())
            .sum()
    }

    /// A basis of at least `k` pairs: the held one when it has enough, otherwise `k` pairs
    /// computed afresh on the kept factorization (see the type's contract). Progress goes
    /// to `progress` (a [`EigenProgress::Factorization`] only when the pencil is
    /// factored).
    ///
    /// `cancel` stops the computation with [`EigenError::Cancelled`]; the solver stays
    /// usable (a factorization made before the cancellation is kept). It is checked
    /// throughout the iteration (after the solves of each block, at each restart and
    /// within its rotation: within 0.5 s at 411k vertices) but not during the
    /// factorization (2.0-2.7 s at 411k vertices) nor the dense path (`n <= 1500`,
    /// about a second at most).
    pub fn solve(
        &mut self,
        k: usize,
        progress: &mut dyn FnMut(EigenProgress),
        cancel: &CancelToken,
    ) -> Result<Arc<Eigenbasis>, EigenError> {
        if k == 0 {
            return Err(EigenError::Zero);
        }
        if let Some(b) = &self.basis
            && b.k() >= k
        {
            return Ok(b.clone());
        }
        if cancel.is_cancelled() {
            return Err(EigenError::Cancelled);
        }
        let params = EigenParams {
            k,
            ..self.params.clone()
        };
        let pencil = Pencil::new(&self.ops, params.dirichlet.as_deref())?;
        pencil.check_k(k)?;
        let b = Arc::new(solve_pencil(
            &self.ops,
            &pencil,
            &params,
            Some(&mut self.factors),
            progress,
            cancel,
        )?);
        self.basis = Some(b.clone());
        Ok(b)
    }
}
