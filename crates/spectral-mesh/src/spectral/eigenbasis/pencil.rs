//! The pencil a solve works on (the whole `(S, B)` or its free block under Dirichlet
//! conditions), the choice between the dense and the sparse path, and the factorizations
//! a solver keeps between solves.

use std::borrow::Cow;

use super::params::{DENSE_MAX_N, DENSE_MAX_N_LARGE_K, EigenError, EigenMethod};
use crate::cancel::CancelToken;
use crate::linalg::{ShiftInvert, SparseMatrix};
use crate::operators::Operators;

/// The pencil a solve works on: `(S, B)` of the operators, or their block on the free
/// vertices under Dirichlet conditions.
pub(super) struct Pencil<'a> {
    /// The free vertices (ascending), `None` for natural boundary conditions.
    pub(super) free: Option<Vec<usize>>,
    pub(super) s: Cow<'a, SparseMatrix>,
    pub(super) b: Cow<'a, SparseMatrix>,
}

impl<'a> Pencil<'a> {
    pub(super) fn new(ops: &'a Operators, dirichlet: Option<&[usize]>) -> Result<Self, EigenError> {
        let n = ops.n();
        let Some(d) = dirichlet else {
            return Ok(Self {
                free: None,
                s: Cow::Borrowed(&ops.stiffness),
                b: Cow::Borrowed(&ops.mass),
            });
        };
        let mut fixed = vec![false; n];
        for &v in d {
            if v >= n {
                return Err(EigenError::DirichletOutOfRange { vertex: v, n });
            }
            fixed[v] = true;
        }
        let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
        let s = ops.stiffness.submatrix(&free, &free);
        let b = ops.mass.submatrix(&free, &free);
        Ok(Self {
            free: Some(free),
            s: Cow::Owned(s),
            b: Cow::Owned(b),
        })
    }

    /// Size of the problem (free vertices).
    pub(super) fn nf(&self) -> usize {
        self.s.ncols()
    }

    pub(super) fn check_k(&self, k: usize) -> Result<(), EigenError> {
        let nf = self.nf();
        if k > nf {
            return Err(EigenError::TooMany { k, n: nf });
        }
        Ok(())
    }

    /// True when `method` takes the dense path for `k` pairs of this pencil.
    pub(super) fn uses_dense(&self, method: EigenMethod, k: usize) -> bool {
        let nf = self.nf();
        match method {
            EigenMethod::Dense => true,
            EigenMethod::ShiftInvertBlock => false,
            EigenMethod::Auto => nf <= DENSE_MAX_N || (3 * k > nf && nf <= DENSE_MAX_N_LARGE_K),
        }
    }
}

/// The factorizations a solver keeps between solves: one of the whole pencil when it is
/// connected, one per component solved on the sparse path otherwise.
#[derive(Debug, Default)]
pub(super) struct Factors {
    pub(super) whole: Option<ShiftInvert>,
    pub(super) parts: Vec<Option<ShiftInvert>>,
    /// Factorizations made so far.
    pub(super) count: usize,
}

pub(super) fn check_cancel(cancel: &CancelToken) -> Result<(), EigenError> {
    if cancel.is_cancelled() {
        Err(EigenError::Cancelled)
    } else {
        Ok(())
    }
}
