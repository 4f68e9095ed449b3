//! The pencil a solve works on (the whole `(S, B)` or its free block under Dirichlet
//! conditions), the choice between the dense and the sparse path, and the factorizations
//! a solver keeps between solves.

use std::borrow::Cow;

use super::params::{EigenError, EigenMethod, takes_dense_path};
use crate::cancel::CancelToken;
use crate::linalg::{ComponentNullSpace, ShiftInvert, SparseMatrix, dense_generalized_eigen};
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
        takes_dense_path(self.nf(), k, method)
    }
}

/// The factorizations a solver keeps between solves: one of the whole pencil when it is
/// connected, one per component solved on the sparse path otherwise.
#[derive(Debug, Default)]
pub(super) struct Factors {
    pub(super) whole: Option<ShiftInvert>,
    /// The interior target `whole` was made for ([`ShiftInvert::target_of`]).
    pub(super) whole_target: Option<f64>,
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

/// The first `k` pairs of `(S, B)` by the dense solver (all `n` computed), with the null
/// space given by the component indicators and eigenvalue 0, as on the sparse path
/// (unless `S` has more null vectors than indicators: then the dense basis of the zero
/// cluster is kept).
pub(super) fn dense_pairs(
    s: &SparseMatrix,
    b: &SparseMatrix,
    k: usize,
    tol: f64,
) -> Result<(Vec<f64>, Vec<f64>), EigenError> {
    let nf = s.ncols();
    let (vals, vecs) =
        dense_generalized_eigen(s, b).map_err(|e| EigenError::Numerical(e.to_string()))?;
    let mut values = vals[..k].to_vec();
    let mut vecs = vecs[..nf * k].to_vec();
    let null = ComponentNullSpace::find(s, b, tol)?;
    let c = null.count().min(k);
    let lmax = vals.last().map_or(0.0, |v| v.abs());
    if c > 0 && (null.count() == nf || vals[null.count()] > 1e-8 * lmax) {
        for (i, col) in vecs.chunks_mut(nf).take(c).enumerate() {
            col.iter_mut().for_each(|x| *x = 0.0);
            null.write_indicator(i, col);
            values[i] = 0.0;
        }
    }
    Ok((values, vecs))
}
