//! The driver: checks, the dense or sparse path, components, Dirichlet vertices, and the
//! packaging of the pairs as an [`Eigenbasis`].

use super::basis::Eigenbasis;
use super::components::solve_split;
use super::params::{EigenError, EigenMethod, EigenParams, sparse_options};
use super::pencil::{Factors, Pencil, check_cancel, dense_pairs};
use crate::cancel::CancelToken;
use crate::linalg::{
    ComponentNullSpace, EigenProgress, ShiftInvert, b_orthogonality_error, connected_components,
    relative_residuals, sparse_generalized_eigen_with,
};
use crate::operators::Operators;

/// The `k` smallest pairs of `S x = lambda B x` (S positive semi-definite, B the mass of
/// `ops`): eigenvalues ascending, eigenvectors B-orthonormal with the sign rule of
/// [`Eigenbasis::fix_signs`], residuals filled in. With `params.dirichlet` the problem is
/// solved on the free vertices and the vectors are zero on the Dirichlet ones.
///
/// **Zero eigenvalues.** A mesh with `c` connected components has `c` zero eigenvalues
/// under natural boundary conditions (any `c`, on both paths). They are returned first,
/// as exactly `0.0`, and their eigenvectors are the B-normalized component indicators
/// `1_C / sqrt(1_C^T B 1_C)` (positive on the component, zero elsewhere), in the order
/// of each component's smallest vertex index; for `k < c` these are the first `k`
/// components in that order. Components are those of the graph of the nonzero entries
/// of `S` and `B` (isolated vertices count when the mass gives them some, as `B = I`
/// does; under a mass that gives them none the problem is singular and an error). A
/// component that touches a Dirichlet vertex has no zero mode. See
/// [`ComponentNullSpace`].
///
/// **Several components** (on the sparse path) are solved one by one, each on its own
/// factorization (small ones densely), and merged: the `k` smallest eigenvalues of all
/// of them, ties in component order (see `solve_split`; 3-5x faster than one iteration
/// on the whole mesh for a few components of similar size). Vectors of different
/// components have disjoint supports.
///
/// Repeated eigenvalues are resolved: if the `k`-th eigenvalue lies in a cluster, the
/// iterative solver converges past the cluster before returning `k` pairs. Progress
/// (factorization, iterations with the converged count) goes to `progress`; with
/// several components the iterations are those of each component's solve, and one
/// `Finished` comes at the end.
pub fn compute_eigenbasis(
    ops: &Operators,
    params: &EigenParams,
    progress: &mut dyn FnMut(EigenProgress),
) -> Result<Eigenbasis, EigenError> {
    let k = params.k;
    if k == 0 {
        return Err(EigenError::Zero);
    }
    let pencil = Pencil::new(ops, params.dirichlet.as_deref())?;
    pencil.check_k(k)?;
    solve_pencil(ops, &pencil, params, None, progress, &CancelToken::new())
}

/// The `params.k` pairs of `pencil` (`1 <= k <= nf`, checked), as an eigenbasis of the
/// mesh of `ops`. With `keep`, the factorizations are taken from and kept in it (a
/// solver); without, they are made here and freed (a connected pencil's before the
/// eigenvectors are copied out). `cancel` is checked before and after the dense path
/// (not inside: at most about a second, `n <= 1500`) and throughout the sparse one.
///
/// A pencil with several connected components (of the graph of the nonzeros of `S` and
/// `B`) is solved component by component and merged (see `components::solve_split`), unless the
/// whole problem is on the dense path or its `k` pairs are component indicators.
pub(super) fn solve_pencil(
    ops: &Operators,
    pencil: &Pencil<'_>,
    params: &EigenParams,
    keep: Option<&mut Factors>,
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<Eigenbasis, EigenError> {
    check_cancel(cancel)?;
    let n = ops.n();
    let k = params.k;
    let (s, b) = (pencil.s.as_ref(), pencil.b.as_ref());
    let nf = pencil.nf();
    let opts = sparse_options(params);
    let (values, vecs, residuals) = if pencil.uses_dense(params.method, k) {
        progress(EigenProgress::Dense { n: nf });
        let (values, vecs) = dense_pairs(s, b, k, opts.effective_tolerance())?;
        check_cancel(cancel)?;
        let residuals = relative_residuals(s, b, &values, &vecs);
        let orthogonality_error = b_orthogonality_error(b, &vecs, k);
        progress(EigenProgress::Finished {
            iterations: 0,
            solves: 0,
            max_residual: residuals.iter().cloned().fold(0.0, f64::max),
            orthogonality_error,
        });
        (values, vecs, residuals)
    } else {
        let null = ComponentNullSpace::find(s, b, opts.effective_tolerance())?;
        if k <= null.count() {
            // Component indicators only: nothing to factor.
            let r = sparse_generalized_eigen_with(s, b, &opts, None, progress, cancel)?;
            (r.values, r.vectors, r.residuals)
        } else if null.components() > 1 {
            let comps = connected_components(s, b)?;
            let mut local = Factors::default();
            let (factors, kept) = match keep {
                Some(f) => (f, true),
                None => (&mut local, false),
            };
            solve_split(s, b, &comps, params, (factors, kept), progress, cancel)?
        } else {
            let factor = match keep {
                Some(f) => {
                    // The factor depends on k through its interior target only: kept
                    // while that stays the same (k within a factor of about 1.19).
                    let target = ShiftInvert::target_of(&opts);
                    if f.whole.is_none() || f.whole_target != target {
                        // The old factor goes first: two are never held at once.
                        f.whole = None;
                        f.whole = Some(ShiftInvert::for_options(s, b, &opts, progress)?);
                        f.whole_target = target;
                        f.count += 1;
                    }
                    f.whole.as_ref()
                }
                None => None,
            };
            let r = sparse_generalized_eigen_with(s, b, &opts, factor, progress, cancel)?;
            (r.values, r.vectors, r.residuals)
        }
    };
    let vectors = match &pencil.free {
        None => vecs,
        Some(f) => {
            let mut full = vec![0.0; n * k];
            for j in 0..k {
                for (q, &i) in f.iter().enumerate() {
                    full[j * n + i] = vecs[j * nf + q];
                }
            }
            full
        }
    };
    let mut basis = Eigenbasis {
        laplacian: ops.laplacian,
        n,
        values,
        vectors,
        mass: ops.mass.clone(),
        residuals,
    };
    basis.fix_signs();
    Ok(basis)
}

impl Eigenbasis {
    /// All pairs of (S, B) by the dense path (O(n^3), small meshes only), truncated to
    /// the first `k`: [`compute_eigenbasis`] with [`EigenMethod::Dense`] (the same
    /// zero-eigenvalue rule, sign rule and residuals).
    pub fn dense(ops: &Operators, k: usize) -> Result<Self, EigenError> {
        let params = EigenParams {
            k,
            method: EigenMethod::Dense,
            ..Default::default()
        };
        compute_eigenbasis(ops, &params, &mut |_| {})
    }
}
