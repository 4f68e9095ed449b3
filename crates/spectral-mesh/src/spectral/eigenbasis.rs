//! The k smallest generalized eigenpairs of (S, B): `S X = B X Lambda`, `X^T B X = I`.

use std::borrow::Cow;
use std::sync::Arc;

use crate::cancel::CancelToken;
use crate::linalg::{
    ComponentNullSpace, ShiftInvert, SparseEigenError, SparseEigenOptions, SparseMatrix,
    b_orthogonality_error, connected_components, dense_generalized_eigen, relative_residuals,
    sparse_generalized_eigen_with,
};
use crate::operators::{Laplacian, Operators};

/// Errors of the eigenbasis computation.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum EigenError {
    /// More pairs were asked for than the mesh has vertices.
    #[error("asked for k = {k} eigenpairs but the mesh has only n = {n} vertices")]
    TooMany {
        /// Requested pairs.
        k: usize,
        /// Vertices.
        n: usize,
    },
    /// k = 0.
    #[error("k must be at least 1")]
    Zero,
    /// A numerical failure, with what failed.
    #[error("eigensolver failed: {0}")]
    Numerical(String),
    /// A Dirichlet vertex index is out of range.
    #[error("Dirichlet vertex {vertex} does not exist (the mesh has {n} vertices)")]
    DirichletOutOfRange {
        /// The offending index.
        vertex: usize,
        /// Vertices.
        n: usize,
    },
    /// The iterative solver stopped before every wanted pair converged.
    #[error(
        "the eigensolver did not converge: {converged} of {wanted} pairs after {iterations} iterations"
    )]
    NoConvergence {
        /// Converged pairs.
        converged: usize,
        /// Wanted pairs.
        wanted: usize,
        /// Iterations used.
        iterations: usize,
    },
    /// The computation was cancelled through its [`CancelToken`].
    #[error("the eigenbasis computation was cancelled")]
    Cancelled,
}

impl From<SparseEigenError> for EigenError {
    fn from(e: SparseEigenError) -> Self {
        match e {
            SparseEigenError::NoConvergence {
                converged,
                wanted,
                iterations,
            } => EigenError::NoConvergence {
                converged,
                wanted,
                iterations,
            },
            SparseEigenError::Cancelled => EigenError::Cancelled,
            other => EigenError::Numerical(other.to_string()),
        }
    }
}

pub use crate::linalg::EigenProgress;

/// Which eigensolver [`compute_eigenbasis`] uses.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum EigenMethod {
    /// Dense for small problems (or `k` close to `n`), block shift-invert otherwise.
    #[default]
    Auto,
    /// All pairs by the dense O(n^3) solver, truncated to `k` (small meshes only).
    Dense,
    /// The sparse shift-invert solver ([`crate::linalg::sparse_generalized_eigen`]: block
    /// Krylov-Schur on a sparse Cholesky factorization of `S - sigma B`).
    ShiftInvertBlock,
}

/// Parameters of [`compute_eigenbasis`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EigenParams {
    /// Number of pairs (the smallest eigenvalues). Default 100, the paper's default.
    pub k: usize,
    /// Target relative residual of every pair (see [`Eigenbasis::compute_residuals`]).
    /// Default `1e-10`.
    pub tolerance: f64,
    /// Dirichlet boundary vertices: the problem is solved on the other vertices and the
    /// eigenvectors are zero on these. `None` (default): natural boundary conditions.
    pub dirichlet: Option<Vec<usize>>,
    /// The solver. Default [`EigenMethod::Auto`].
    pub method: EigenMethod,
    /// Seed of the iterative solver's start block (results are deterministic).
    pub seed: u64,
    /// Block size of the iterative solver; `0` (default) chooses from `k`.
    pub block_size: usize,
}

impl Default for EigenParams {
    fn default() -> Self {
        Self {
            k: 100,
            tolerance: 1e-10,
            dirichlet: None,
            method: EigenMethod::Auto,
            seed: 0x5eed,
            block_size: 0,
        }
    }
}

/// Problems up to this many (free) vertices always use the dense path under
/// [`EigenMethod::Auto`].
pub const DENSE_MAX_N: usize = 300;
/// Problems up to this size use the dense path under [`EigenMethod::Auto`] when `k` is more
/// than a third of `n`.
pub const DENSE_MAX_N_LARGE_K: usize = 1500;

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
/// [`crate::linalg::ComponentNullSpace`].
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

/// The pencil a solve works on: `(S, B)` of the operators, or their block on the free
/// vertices under Dirichlet conditions.
struct Pencil<'a> {
    /// The free vertices (ascending), `None` for natural boundary conditions.
    free: Option<Vec<usize>>,
    s: Cow<'a, SparseMatrix>,
    b: Cow<'a, SparseMatrix>,
}

impl<'a> Pencil<'a> {
    fn new(ops: &'a Operators, dirichlet: Option<&[usize]>) -> Result<Self, EigenError> {
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
    fn nf(&self) -> usize {
        self.s.ncols()
    }

    fn check_k(&self, k: usize) -> Result<(), EigenError> {
        let nf = self.nf();
        if k > nf {
            return Err(EigenError::TooMany { k, n: nf });
        }
        Ok(())
    }

    /// True when `method` takes the dense path for `k` pairs of this pencil.
    fn uses_dense(&self, method: EigenMethod, k: usize) -> bool {
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
struct Factors {
    whole: Option<ShiftInvert>,
    parts: Vec<Option<ShiftInvert>>,
    /// Factorizations made so far.
    count: usize,
}

fn check_cancel(cancel: &CancelToken) -> Result<(), EigenError> {
    if cancel.is_cancelled() {
        Err(EigenError::Cancelled)
    } else {
        Ok(())
    }
}

/// The `params.k` pairs of `pencil` (`1 <= k <= nf`, checked), as an eigenbasis of the
/// mesh of `ops`. With `keep`, the factorizations are taken from and kept in it (a
/// solver); without, they are made here and freed (a connected pencil's before the
/// eigenvectors are copied out). `cancel` is checked before and after the dense path
/// (not inside: at most about a second, `n <= 1500`) and throughout the sparse one.
///
/// A pencil with several connected components (of the graph of the nonzeros of `S` and
/// `B`) is solved component by component and merged (see [`solve_split`]), unless the
/// whole problem is on the dense path or its `k` pairs are component indicators.
fn solve_pencil(
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
                    if f.whole.is_none() {
                        f.whole = Some(ShiftInvert::new(s, b, opts.shift, progress)?);
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

/// The first `k` pairs of `(S, B)` by the dense solver (all `n` computed), with the null
/// space given by the component indicators and eigenvalue 0, as on the sparse path
/// (unless `S` has more null vectors than indicators: then the dense basis of the zero
/// cluster is kept).
fn dense_pairs(
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

/// The sub-pencils `(S_CC, B_CC)` of the components `comps` (which partition the
/// vertices), in one pass over the matrices.
fn sub_pencils(
    s: &SparseMatrix,
    b: &SparseMatrix,
    comps: &[Vec<usize>],
) -> Vec<(SparseMatrix, SparseMatrix)> {
    let n = s.ncols();
    let mut part_of = vec![0usize; n];
    let mut local = vec![0usize; n];
    for (i, c) in comps.iter().enumerate() {
        for (q, &v) in c.iter().enumerate() {
            part_of[v] = i;
            local[v] = q;
        }
    }
    let extract = |m: &SparseMatrix| -> Vec<SparseMatrix> {
        let mut t: Vec<Vec<(usize, usize, f64)>> = vec![Vec::new(); comps.len()];
        for c in 0..n {
            let i = part_of[c];
            let (rows, vals) = m.col(c);
            for (&r, &x) in rows.iter().zip(vals) {
                // Entries between components are zeros (the components are those of
                // the nonzero entries).
                if part_of[r] == i {
                    t[i].push((local[r], local[c], x));
                }
            }
        }
        t.iter()
            .zip(comps)
            .map(|(t, c)| SparseMatrix::from_triplets(c.len(), c.len(), t))
            .collect()
    };
    extract(s).into_iter().zip(extract(b)).collect()
}

/// Eigenvalues, `nf x k` eigenvectors and relative residuals on the whole pencil.
type Pairs = (Vec<f64>, Vec<f64>, Vec<f64>);

/// Pairs of a component solved so far: values ascending, vectors `n_i x len` (the
/// component's own numbering).
struct PartPairs {
    values: Vec<f64>,
    vectors: Vec<f64>,
    /// All the component's pairs (its dense path).
    all: bool,
}

/// The `k` pairs of a pencil with several connected components `comps`, solved component
/// by component and merged (returns values, `nf x k` vectors and residuals on the whole
/// pencil).
///
/// Each component `C` is first asked for its share of the `k` pairs by Weyl's law
/// (`N(lambda)` grows like the area, so like the mass `1^T B_CC 1`): `1.2 k m_C / m + 2`.
/// Small components (`n_C <= 300`, or `k_C > n_C / 3` with `n_C <= 1500` under
/// [`EigenMethod::Auto`]) are solved densely (all their pairs), the others by the sparse
/// solver on their own factorization (in `factors`, freed at the end unless `kept`). With `lambda*` the `k`-th
/// smallest eigenvalue found, a component is complete when it returned all its pairs or
/// its largest one lies above `lambda*`; the others are solved again with more pairs
/// (`k_C lambda* / lambda_max,C`, 25% more) until all are complete. Then the eigenvalues
/// found below `lambda*` are all of them, and the `k` smallest are taken (ties: in
/// component order). Vectors of different components have disjoint supports, so the
/// result is B-orthogonal by construction.
///
/// Measured against one iteration on the whole pencil (the null space deflated): 3-5x
/// faster for a few components of similar size, where the whole iteration carries a
/// basis of `2k` vectors over all `n` rows (see BENCHMARKS.md).
fn solve_split(
    s: &SparseMatrix,
    b: &SparseMatrix,
    comps: &[Vec<usize>],
    params: &EigenParams,
    (factors, kept): (&mut Factors, bool),
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<Pairs, EigenError> {
    let nf = s.ncols();
    let k = params.k;
    let m = comps.len();
    let opts = sparse_options(params);
    let tol = opts.effective_tolerance();
    let pencils = sub_pencils(s, b, comps);
    if factors.parts.len() != m {
        factors.parts = (0..m).map(|_| None).collect();
    }
    let masses: Vec<f64> = pencils
        .iter()
        .map(|(_, bc)| bc.values().iter().sum::<f64>().max(0.0))
        .collect();
    let total: f64 = masses.iter().sum::<f64>().max(f64::MIN_POSITIVE);
    let mut want: Vec<usize> = comps
        .iter()
        .zip(&masses)
        .map(|(c, &mc)| ((1.2 * k as f64 * mc / total).ceil() as usize + 2).min(c.len()))
        .collect();
    let mut got: Vec<Option<PartPairs>> = (0..m).map(|_| None).collect();
    let (mut iterations, mut solves) = (0usize, 0usize);
    // Forwards the parts' factorizations and iterations; one `Finished` comes at the end.
    let mut forward = |e: EigenProgress| {
        if matches!(
            e,
            EigenProgress::Factorization { .. } | EigenProgress::Iteration { .. }
        ) {
            progress(e)
        }
    };
    loop {
        for i in 0..m {
            let ni = comps[i].len();
            if got[i]
                .as_ref()
                .is_some_and(|g| g.all || g.values.len() >= want[i])
            {
                continue;
            }
            check_cancel(cancel)?;
            let (sc, bc) = &pencils[i];
            let ki = want[i];
            let dense = ni <= DENSE_MAX_N
                || (params.method == EigenMethod::Auto && 3 * ki > ni && ni <= DENSE_MAX_N_LARGE_K);
            got[i] = Some(if dense {
                let (values, vectors) = dense_pairs(sc, bc, ni, tol)?;
                PartPairs {
                    values,
                    vectors,
                    all: true,
                }
            } else {
                let part_opts = SparseEigenOptions {
                    k: ki,
                    ..opts.clone()
                };
                let null = ComponentNullSpace::find(sc, bc, tol)?;
                if factors.parts[i].is_none() && ki > null.count() {
                    factors.parts[i] = Some(ShiftInvert::new(sc, bc, opts.shift, &mut forward)?);
                    factors.count += 1;
                }
                let r = sparse_generalized_eigen_with(
                    sc,
                    bc,
                    &part_opts,
                    factors.parts[i].as_ref(),
                    &mut forward,
                    cancel,
                )?;
                iterations += r.iterations;
                solves += r.solves;
                PartPairs {
                    values: r.values,
                    vectors: r.vectors,
                    all: ki == ni,
                }
            });
        }
        // lambda*: the k-th smallest eigenvalue found (infinite when fewer were found).
        let mut found: Vec<f64> = got
            .iter()
            .flatten()
            .flat_map(|g| g.values.iter().copied())
            .collect();
        let lstar = if found.len() >= k {
            found.select_nth_unstable_by(k - 1, f64::total_cmp);
            found[k - 1]
        } else {
            f64::INFINITY
        };
        let mut complete = true;
        for (i, g) in got.iter().enumerate() {
            let Some(g) = g else { continue };
            let top = g.values.last().copied().unwrap_or(f64::NEG_INFINITY);
            if g.all || top > lstar {
                continue;
            }
            complete = false;
            let len = g.values.len();
            let grown = if lstar.is_finite() && top > 0.0 {
                (len as f64 * 1.25 * lstar / top).ceil() as usize + 2
            } else {
                2 * len
            };
            want[i] = grown.max(len + 1).min(comps[i].len());
        }
        if complete {
            break;
        }
    }
    // Factors not kept and the sub-pencils go before the result is assembled.
    drop(pencils);
    if !kept {
        factors.parts.clear();
    }
    // The k smallest, ties in component order.
    let mut pairs: Vec<(f64, usize, usize)> = got
        .iter()
        .enumerate()
        .flat_map(|(i, g)| {
            g.iter()
                .flat_map(move |g| g.values.iter().enumerate().map(move |(j, &v)| (v, i, j)))
        })
        .collect();
    pairs.sort_by(|a, c| a.0.total_cmp(&c.0).then(a.1.cmp(&c.1)).then(a.2.cmp(&c.2)));
    pairs.truncate(k);
    let mut values = Vec::with_capacity(k);
    let mut vecs = vec![0.0; nf * k];
    for (col, &(v, i, j)) in vecs.chunks_mut(nf).zip(&pairs) {
        let ni = comps[i].len();
        let x = &got[i]
            .as_ref()
            .map_or(&[][..], |g| &g.vectors[j * ni..(j + 1) * ni]);
        for (&p, &xv) in comps[i].iter().zip(x.iter()) {
            col[p] = xv;
        }
        values.push(v);
    }
    drop(got);
    check_cancel(cancel)?;
    let residuals = relative_residuals(s, b, &values, &vecs);
    let orthogonality_error = b_orthogonality_error(b, &vecs, k);
    progress(EigenProgress::Finished {
        iterations,
        solves,
        max_residual: residuals.iter().cloned().fold(0.0, f64::max),
        orthogonality_error,
    });
    Ok((values, vecs, residuals))
}

/// The options of the sparse solver for `params`.
fn sparse_options(params: &EigenParams) -> SparseEigenOptions {
    SparseEigenOptions {
        k: params.k,
        tolerance: params.tolerance,
        block_size: params.block_size,
        seed: params.seed,
        ..Default::default()
    }
}

/// A generalized eigenbasis: `k` pairs, eigenvalues ascending, eigenvectors B-orthonormal
/// with a deterministic sign (see [`Eigenbasis::fix_signs`]).
#[derive(Debug, Clone)]
pub struct Eigenbasis {
    /// The discretization it was computed for.
    pub laplacian: Laplacian,
    /// Number of vertices `n`.
    pub n: usize,
    /// Eigenvalues, `k` entries, ascending.
    pub values: Vec<f64>,
    /// Eigenvectors, `n x k`, column-major (`vectors[j * n + i]` is `x_j(p_i)`).
    pub vectors: Vec<f64>,
    /// The mass matrix B the vectors are orthonormal in.
    pub mass: SparseMatrix,
    /// Relative residuals `||S x - lambda B x||_2 / ((||S||_1 + |lambda| ||B||_1) ||x||_2)`
    /// per pair (empty when not computed; on the free block for Dirichlet problems).
    pub residuals: Vec<f64>,
}

impl Eigenbasis {
    /// Number of pairs `k`.
    pub fn k(&self) -> usize {
        self.values.len()
    }

    /// Eigenvector `j` (`n` entries).
    pub fn vector(&self, j: usize) -> &[f64] {
        &self.vectors[j * self.n..(j + 1) * self.n]
    }

    /// The documented sign convention: each eigenvector is flipped so that its entry of
    /// largest magnitude is positive (ties: the lowest vertex index wins). The component
    /// indicators of the zero eigenvalues (see [`compute_eigenbasis`]) are positive and
    /// stay as they are.
    pub fn fix_signs(&mut self) {
        let n = self.n;
        for col in self.vectors.chunks_mut(n) {
            let mut best = 0;
            for i in 1..n {
                if col[i].abs() > col[best].abs() {
                    best = i;
                }
            }
            if col[best] < 0.0 {
                col.iter_mut().for_each(|v| *v = -*v);
            }
        }
    }

    /// All pairs of (S, B) by the dense path (O(n^3), small meshes only), truncated to
    /// the first `k`.
    pub fn dense(ops: &Operators, k: usize) -> Result<Self, EigenError> {
        let n = ops.n();
        if k == 0 {
            return Err(EigenError::Zero);
        }
        if k > n {
            return Err(EigenError::TooMany { k, n });
        }
        let (values, vectors) = dense_generalized_eigen(&ops.stiffness, &ops.mass)
            .map_err(|e| EigenError::Numerical(e.to_string()))?;
        let mut b = Self {
            laplacian: ops.laplacian,
            n,
            values: values[..k].to_vec(),
            vectors: vectors[..n * k].to_vec(),
            mass: ops.mass.clone(),
            residuals: Vec::new(),
        };
        b.fix_signs();
        b.residuals = b.compute_residuals(&ops.stiffness);
        Ok(b)
    }

    /// Relative residual of every pair against the stiffness `s` (positive
    /// semi-definite) and this basis' mass:
    /// `||S x - lambda B x||_2 / ((||S||_1 + |lambda| ||B||_1) ||x||_2)`, a normwise backward
    /// error that does not change when the mesh is scaled.
    pub fn compute_residuals(&self, s: &SparseMatrix) -> Vec<f64> {
        relative_residuals(s, &self.mass, &self.values, &self.vectors)
    }

    /// `max |X^T B X - I|` over the stored vectors (zero for an exactly B-orthonormal basis).
    pub fn orthogonality_error(&self) -> f64 {
        b_orthogonality_error(&self.mass, &self.vectors, self.k())
    }
}

/// A borrowed view of the first `k` pairs of an [`Eigenbasis`]: what every spectral
/// quantity (heat kernel, distances, signatures, embeddings) is computed from. A basis of
/// `K` pairs serves any `k <= K` without copying its `n x K` vectors.
#[derive(Debug, Clone, Copy)]
pub struct BasisView<'a> {
    /// The discretization the basis was computed for.
    pub laplacian: Laplacian,
    /// Number of vertices `n`.
    pub n: usize,
    /// The first `k` eigenvalues, ascending.
    pub values: &'a [f64],
    /// The first `k` eigenvectors, `n x k` column-major (`vectors[j * n + i]` = `x_j(p_i)`).
    pub vectors: &'a [f64],
    /// The mass matrix B the vectors are orthonormal in (`n x n`).
    pub mass: &'a SparseMatrix,
}

impl<'a> BasisView<'a> {
    /// Number of pairs `k` in the view.
    pub fn k(&self) -> usize {
        self.values.len()
    }

    /// Eigenvector `j` (`n` entries).
    pub fn vector(&self, j: usize) -> &'a [f64] {
        &self.vectors[j * self.n..(j + 1) * self.n]
    }
}

impl<'a> From<&'a Eigenbasis> for BasisView<'a> {
    fn from(b: &'a Eigenbasis) -> Self {
        b.view(b.k())
    }
}

impl Eigenbasis {
    /// The view of the first `min(k, self.k())` pairs.
    pub fn view(&self, k: usize) -> BasisView<'_> {
        let k = k.min(self.k());
        BasisView {
            laplacian: self.laplacian,
            n: self.n,
            values: &self.values[..k],
            vectors: &self.vectors[..k * self.n],
            mass: &self.mass,
        }
    }
}

/// Factor once, answer many `k`: holds the operators, the factorization of the shifted
/// pencil and the largest basis computed so far (geometry-central's solver pattern).
///
/// Contract: the pairs returned for a given `k` depend only on the operators, the
/// parameters and `k`, never on what was asked before: each solve that computes runs a
/// fresh iteration (the same seed, no warm start from the held vectors) on the kept
/// factorization, and gives bit for bit what [`compute_eigenbasis`] gives for the same
/// `k`. A replay that asks for the same `k` thus gets the same bits. Asking for fewer
/// pairs than held returns the held basis; use [`Eigenbasis::view`] to take its first
/// `k` pairs.
///
/// The factorization of `S - sigma B` (on the free vertices under Dirichlet conditions)
/// is made by the first solve that takes the sparse path and kept, with its shift, for
/// every later one: [`EigenSolver::factorizations`] stays 1. Problems on the dense path
/// (small `n`, see [`EigenMethod::Auto`]) need no factorization, nor does a `k` that only
/// asks for zero eigenvalues (component indicators). A mesh with several components
/// keeps one factorization per component solved on the sparse path (see
/// [`compute_eigenbasis`]). The factors' memory is held as long as the solver: about
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
    /// 0 before the first sparse solve and for dense-path problems, then 1 (or one per
    /// component solved on the sparse path).
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

#[cfg(test)]
pub(crate) mod test_meshes {
    //! Small meshes built in code for the tests.
    use crate::mesh::Mesh;

    /// An icosphere of radius `r` with `level` subdivisions (12, 42, 162, 642, ... vertices).
    pub fn icosphere(level: usize, r: f64) -> Mesh {
        crate::shapes::build_str(&format!("sphere:res={level}"))
            .unwrap()
            .map_positions(|p| [p[0] * r, p[1] * r, p[2] * r])
            .unwrap()
    }

    /// A disk of radius 1 triangulated from a polar-ish grid: `rings` rings of `6 * ring`
    /// vertices around the centre (a bordered surface).
    pub fn disk(rings: usize) -> Mesh {
        let mut p = vec![[0.0, 0.0, 0.0]];
        let mut start = vec![0usize];
        for r in 1..=rings {
            start.push(p.len());
            let m = 6 * r;
            for j in 0..m {
                let a = 2.0 * std::f64::consts::PI * j as f64 / m as f64;
                let rad = r as f64 / rings as f64;
                p.push([rad * a.cos(), rad * a.sin(), 0.0]);
            }
        }
        let mut f = Vec::new();
        // Ring 1 to the centre.
        for j in 0..6 {
            f.push([0, 1 + j, 1 + (j + 1) % 6]);
        }
        for r in 1..rings {
            let (ia, ib) = (start[r], start[r + 1]);
            let (ma, mb) = (6 * r, 6 * (r + 1));
            // Merge-walk the two rings by angle.
            let (mut a, mut b) = (0usize, 0usize);
            while a < ma || b < mb {
                let ang_a = (a + 1) as f64 / ma as f64;
                let ang_b = (b + 1) as f64 / mb as f64;
                if b < mb && (a >= ma || ang_b <= ang_a) {
                    f.push([ia + a % ma, ib + b, ib + (b + 1) % mb]);
                    b += 1;
                } else {
                    f.push([ia + a, ib + b % mb, ia + (a + 1) % ma]);
                    a += 1;
                }
            }
        }
        Mesh::new(p, f).unwrap()
    }

    /// Disjoint union of meshes (vertex indices shifted), with the given offsets.
    pub fn union(parts: &[(Mesh, [f64; 3])]) -> Mesh {
        let mut p = Vec::new();
        let mut f = Vec::new();
        for (m, off) in parts {
            let base = p.len();
            p.extend(
                m.positions()
                    .iter()
                    .map(|v| [v[0] + off[0], v[1] + off[1], v[2] + off[2]]),
            );
            f.extend(
                m.triangles()
                    .iter()
                    .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
            );
        }
        Mesh::new(p, f).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::test_meshes::*;
    use super::*;

    fn iterative(k: usize) -> EigenParams {
        EigenParams {
            k,
            method: EigenMethod::ShiftInvertBlock,
            ..Default::default()
        }
    }

    fn check_against_dense(ops: &Operators, k: usize) {
        let dense = compute_eigenbasis(
            ops,
            &EigenParams {
                k,
                method: EigenMethod::Dense,
                ..Default::default()
            },
            &mut |_| {},
        )
        .unwrap();
        let it = compute_eigenbasis(ops, &iterative(k), &mut |_| {}).unwrap();
        let scale = dense.values[k - 1].abs().max(1e-300);
        for j in 0..k {
            assert!(
                (it.values[j] - dense.values[j]).abs() <= 1e-9 * scale,
                "{}: pair {j}: {} vs dense {}",
                ops.laplacian,
                it.values[j],
                dense.values[j]
            );
        }
        assert!(
            it.residuals.iter().all(|&r| r <= 1e-8),
            "{:?}",
            it.residuals
        );
        assert_eq!(it.residuals, it.compute_residuals(&ops.stiffness));
        assert!(it.orthogonality_error() <= 1e-10);
        // Sign rule holds.
        for j in 0..k {
            let x = it.vector(j);
            let big = x
                .iter()
                .cloned()
                .fold(0.0f64, |m, v| if v.abs() > m.abs() { v } else { m });
            assert!(big > 0.0);
        }
    }

    #[test]
    fn iterative_matches_dense_for_every_mass() {
        let mesh = disk(12); // bordered, 469 vertices
        for lap in [Laplacian::Fem, Laplacian::VoronoiCot, Laplacian::Cot] {
            let ops = Operators::new(&mesh, lap);
            check_against_dense(&ops, 30);
        }
    }

    #[test]
    fn sphere_multiplicities() {
        let mesh = icosphere(3, 1.0); // 642 vertices
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let b9 = compute_eigenbasis(&ops, &iterative(9), &mut |_| {}).unwrap();
        let l = |i: usize| match i {
            0 => 0.0,
            1..=3 => 2.0,
            _ => 6.0,
        };
        for j in 0..9 {
            assert!(
                (b9.values[j] - l(j)).abs() < 0.05 * l(j).max(1.0),
                "{:?}",
                b9.values
            );
        }
        let b4 = compute_eigenbasis(&ops, &iterative(4), &mut |_| {}).unwrap();
        for j in 0..4 {
            assert!((b4.values[j] - b9.values[j]).abs() < 1e-9 * b9.values[8]);
        }
        // k = 3 cuts the l = 1 triple: still the right values.
        let b3 = compute_eigenbasis(&ops, &iterative(3), &mut |_| {}).unwrap();
        for j in 0..3 {
            assert!((b3.values[j] - b9.values[j]).abs() < 1e-9 * b9.values[8]);
        }
        assert!(b3.residuals.iter().all(|&r| r <= 1e-8));
        // Large k through many clusters agrees with dense.
        check_against_dense(&ops, 60);
    }

    #[test]
    fn components_give_zero_eigenvalues() {
        let s = icosphere(2, 1.0);
        let mesh = union(&[
            (s.clone(), [0.0; 3]),
            (s.clone(), [3.0, 0.0, 0.0]),
            (s, [0.0, 3.0, 0.0]),
        ]);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let b = compute_eigenbasis(&ops, &iterative(8), &mut |_| {}).unwrap();
        for j in 0..3 {
            assert!(b.values[j].abs() < 1e-8, "{:?}", b.values);
        }
        assert!(b.values[3] > 1.0);
        assert!(b.orthogonality_error() < 1e-10);
    }

    #[test]
    fn multiplicities_larger_than_the_block_are_complete() {
        // Three identical spheres: every eigenvalue has multiplicity 3 (2l + 1), up to 15
        // here, with blocks of 4; the result must equal the dense one pair for pair.
        let s = icosphere(2, 1.0);
        let mesh = union(&[
            (s.clone(), [0.0; 3]),
            (s.clone(), [3.0, 0.0, 0.0]),
            (s, [0.0, 3.0, 0.0]),
        ]);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let k = 40;
        let dense = compute_eigenbasis(
            &ops,
            &EigenParams {
                k,
                method: EigenMethod::Dense,
                ..Default::default()
            },
            &mut |_| {},
        )
        .unwrap();
        let it = compute_eigenbasis(
            &ops,
            &EigenParams {
                block_size: 4,
                ..iterative(k)
            },
            &mut |_| {},
        )
        .unwrap();
        for j in 0..k {
            assert!(
                (it.values[j] - dense.values[j]).abs() <= 1e-9 * dense.values[k - 1],
                "pair {j}: {} vs {}",
                it.values[j],
                dense.values[j]
            );
        }
        assert!(it.orthogonality_error() < 1e-10);
    }

    #[test]
    fn k_close_to_n_with_the_iterative_solver() {
        // k = 600 of n = 642: the Krylov space fills the whole space.
        let ops = Operators::new(&icosphere(3, 1.0), Laplacian::VoronoiCot);
        check_against_dense(&ops, 600);
    }

    #[test]
    fn davidson_and_krylov_schur_agree() {
        use crate::linalg::{SparseAlgorithm, SparseEigenOptions, sparse_generalized_eigen};
        let ops = Operators::new(&disk(12), Laplacian::Fem);
        let run = |algorithm| {
            let o = SparseEigenOptions {
                k: 25,
                algorithm,
                ..Default::default()
            };
            sparse_generalized_eigen(&ops.stiffness, &ops.mass, &o, &mut |_| {}).unwrap()
        };
        let a = run(SparseAlgorithm::KrylovSchur);
        let b = run(SparseAlgorithm::Davidson);
        for j in 0..25 {
            assert!((a.values[j] - b.values[j]).abs() <= 1e-9 * a.values[24]);
        }
        assert!(a.residuals.iter().all(|&r| r <= 1e-10));
    }

    #[test]
    fn k_larger_than_n_is_an_error() {
        let mesh = icosphere(0, 1.0);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let e = compute_eigenbasis(
            &ops,
            &EigenParams {
                k: 13,
                ..Default::default()
            },
            &mut |_| {},
        );
        assert_eq!(e.unwrap_err(), EigenError::TooMany { k: 13, n: 12 });
        // Auto on a tiny mesh with k = n works (dense path).
        let b = compute_eigenbasis(
            &ops,
            &EigenParams {
                k: 12,
                ..Default::default()
            },
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(b.k(), 12);
        // The iterative path also handles k = n.
        let b2 = compute_eigenbasis(&ops, &iterative(12), &mut |_| {}).unwrap();
        for j in 0..12 {
            assert!((b.values[j] - b2.values[j]).abs() < 1e-9 * b.values[11]);
        }
    }

    #[test]
    fn dirichlet_disk() {
        let mesh = disk(12);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let n = ops.n();
        let boundary: Vec<usize> = (n - 6 * 12..n).collect();
        let params = EigenParams {
            k: 6,
            dirichlet: Some(boundary.clone()),
            method: EigenMethod::ShiftInvertBlock,
            ..Default::default()
        };
        let b = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
        // Unit disk, Dirichlet: lambda_1 = j_{0,1}^2 = 5.783; then j_{1,1}^2 = 14.68 (x2).
        assert!((b.values[0] - 5.783).abs() < 0.1, "{:?}", b.values);
        assert!((b.values[1] - 14.68).abs() < 0.4 && (b.values[2] - 14.68).abs() < 0.4);
        for j in 0..6 {
            for &i in &boundary {
                assert_eq!(b.vector(j)[i], 0.0);
            }
        }
        assert!(b.orthogonality_error() < 1e-10);
        let dense = compute_eigenbasis(
            &ops,
            &EigenParams {
                method: EigenMethod::Dense,
                ..params.clone()
            },
            &mut |_| {},
        )
        .unwrap();
        for j in 0..6 {
            assert!((b.values[j] - dense.values[j]).abs() < 1e-9 * dense.values[5]);
        }
        let bad = EigenParams {
            dirichlet: Some(vec![n]),
            ..params
        };
        assert!(matches!(
            compute_eigenbasis(&ops, &bad, &mut |_| {}),
            Err(EigenError::DirichletOutOfRange { .. })
        ));
    }

    #[test]
    fn hard_locking_variant_agrees() {
        use crate::linalg::{SparseEigenOptions, sparse_generalized_eigen};
        let mesh = icosphere(3, 1.0);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let mk = |locking| SparseEigenOptions {
            k: 30,
            locking,
            ..Default::default()
        };
        let a =
            sparse_generalized_eigen(&ops.stiffness, &ops.mass, &mk(true), &mut |_| {}).unwrap();
        let b =
            sparse_generalized_eigen(&ops.stiffness, &ops.mass, &mk(false), &mut |_| {}).unwrap();
        for j in 0..30 {
            assert!((a.values[j] - b.values[j]).abs() < 1e-9 * b.values[29]);
        }
        assert!(a.orthogonality_error < 1e-10 && a.residuals.iter().all(|&r| r <= 1e-10));
    }

    /// Icospheres at three resolutions: the first 16 eigenvalues (l = 0..3, multiplicities
    /// 1, 3, 5, 7) approach l(l+1) with order about 2 in the edge length.
    #[test]
    fn analytic_sphere_convergence() {
        let exact = |j: usize| {
            let l = (j as f64).sqrt().floor();
            l * (l + 1.0)
        };
        let mut errs = Vec::new();
        for level in [2usize, 3, 4] {
            let ops = Operators::new(&icosphere(level, 1.0), Laplacian::Fem);
            let b = compute_eigenbasis(&ops, &iterative(16), &mut |_| {}).unwrap();
            // Each group stays within 10% of l(l+1) (coarsest mesh: 8% for l = 3).
            for j in 1..16 {
                assert!(
                    (b.values[j] - exact(j)).abs() < 0.1 * exact(j),
                    "{:?}",
                    b.values
                );
            }
            let e = (1..16)
                .map(|j| (b.values[j] - exact(j)).abs() / exact(j))
                .fold(0.0, f64::max);
            errs.push(e);
        }
        let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        eprintln!("sphere relative errors {errs:?}, orders {orders:?}");
        for o in orders {
            assert!((1.7..2.3).contains(&o), "order {o}");
        }
    }

    #[test]
    fn progress_reports_phases() {
        let mesh = icosphere(3, 1.0);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let mut events = Vec::new();
        compute_eigenbasis(&ops, &iterative(10), &mut |e| events.push(e)).unwrap();
        assert!(matches!(events[0], EigenProgress::Factorization { .. }));
        assert!(
            events
                .iter()
                .any(|e| matches!(e, EigenProgress::Iteration { .. }))
        );
        assert!(matches!(
            events.last(),
            Some(EigenProgress::Finished { .. })
        ));
    }

    fn same_bits(a: &Eigenbasis, b: &Eigenbasis) {
        assert_eq!(a.values, b.values);
        assert_eq!(a.vectors, b.vectors);
        assert_eq!(a.residuals, b.residuals);
    }

    /// Factor reuse: solve(100) then solve(200) factors once, and the 200 pairs equal, bit
    /// for bit, those of a fresh solver and of `compute_eigenbasis`.
    #[test]
    fn solver_keeps_the_factor_and_the_history_does_not_matter() {
        let ops = Arc::new(Operators::new(&icosphere(4, 1.0), Laplacian::Fem)); // 2562
        let params = EigenParams::default();
        let none = CancelToken::new();
        let mut solver = EigenSolver::new(ops.clone(), params.clone());
        assert_eq!(solver.factorizations(), 0);
        let mut events = Vec::new();
        let b100 = solver.solve(100, &mut |e| events.push(e), &none).unwrap();
        assert_eq!(b100.k(), 100);
        assert_eq!(solver.factorizations(), 1);
        assert!(matches!(events[0], EigenProgress::Factorization { .. }));
        events.clear();
        let b200 = solver.solve(200, &mut |e| events.push(e), &none).unwrap();
        assert_eq!(solver.factorizations(), 1);
        assert!(
            !events
                .iter()
                .any(|e| matches!(e, EigenProgress::Factorization { .. }))
        );
        assert!(matches!(
            events.last(),
            Some(EigenProgress::Finished { .. })
        ));
        // Fewer pairs than held: the held basis.
        let again = solver.solve(150, &mut |_| {}, &none).unwrap();
        assert!(Arc::ptr_eq(&again, &b200));
        assert!(Arc::ptr_eq(&solver.held().unwrap(), &b200));

        let mut fresh = EigenSolver::new(ops.clone(), params.clone());
        let f200 = fresh.solve(200, &mut |_| {}, &none).unwrap();
        assert_eq!(fresh.factorizations(), 1);
        same_bits(&b200, &f200);
        let direct = compute_eigenbasis(
            &ops,
            &EigenParams {
                k: 200,
                ..params.clone()
            },
            &mut |_| {},
        )
        .unwrap();
        same_bits(&b200, &direct);
        // And the first solve is the k = 100 one of compute_eigenbasis.
        let direct100 =
            compute_eigenbasis(&ops, &EigenParams { k: 100, ..params }, &mut |_| {}).unwrap();
        same_bits(&b100, &direct100);
        assert!(b200.residuals.iter().all(|&r| r <= 1e-10));
    }

    /// Under Dirichlet conditions the kept factor is the free block's.
    #[test]
    fn solver_with_dirichlet_vertices_reuses_its_factor() {
        let ops = Arc::new(Operators::new(&disk(12), Laplacian::Fem));
        let n = ops.n();
        let params = EigenParams {
            dirichlet: Some((n - 6 * 12..n).collect()),
            method: EigenMethod::ShiftInvertBlock,
            ..Default::default()
        };
        let none = CancelToken::new();
        let mut solver = EigenSolver::new(ops.clone(), params.clone());
        solver.solve(6, &mut |_| {}, &none).unwrap();
        let b = solver.solve(20, &mut |_| {}, &none).unwrap();
        assert_eq!(solver.factorizations(), 1);
        let direct =
            compute_eigenbasis(&ops, &EigenParams { k: 20, ..params }, &mut |_| {}).unwrap();
        same_bits(&b, &direct);
        assert!((b.values[0] - 5.783).abs() < 0.1);
    }

    /// Dense-path problems need no factorization; errors leave the counter alone.
    #[test]
    fn dense_solves_count_no_factorization() {
        let ops = Arc::new(Operators::new(&icosphere(2, 1.0), Laplacian::Fem)); // 162
        let none = CancelToken::new();
        let mut solver = EigenSolver::new(ops.clone(), EigenParams::default());
        let b = solver.solve(10, &mut |_| {}, &none).unwrap();
        solver.solve(40, &mut |_| {}, &none).unwrap();
        assert_eq!(solver.factorizations(), 0);
        assert_eq!(b.k(), 10);
        assert!(matches!(
            solver.solve(163, &mut |_| {}, &none),
            Err(EigenError::TooMany { k: 163, n: 162 })
        ));
        assert!(matches!(
            solver.solve(0, &mut |_| {}, &none),
            Err(EigenError::Zero)
        ));
        assert_eq!(solver.factorizations(), 0);
        assert_eq!(solver.held().unwrap().k(), 40);
    }

    /// A solve cancelled from another thread 50 ms in returns `Cancelled` (the wait is
    /// bounded generously; no assertion on speed), and the solver stays usable: the next
    /// solve gives the bits of a fresh solver, on the factor it kept.
    #[test]
    fn a_cancelled_solve_leaves_the_solver_usable() {
        let ops = Arc::new(Operators::new(&icosphere(5, 1.0), Laplacian::Fem)); // 10242
        let params = EigenParams::default();
        let token = CancelToken::new();
        let remote = token.clone();
        let (tx, rx) = std::sync::mpsc::channel();
        let mut solver = EigenSolver::new(ops.clone(), params.clone());
        let worker = std::thread::spawn(move || {
            let r = solver.solve(300, &mut |_| {}, &token).map(|b| b.k());
            let _ = tx.send((r, solver));
        });
        std::thread::sleep(std::time::Duration::from_millis(50));
        remote.cancel();
        let (r, mut solver) = rx
            .recv_timeout(std::time::Duration::from_secs(120))
            .expect("the cancelled solve returns");
        worker.join().unwrap();
        assert_eq!(r, Err(EigenError::Cancelled));
        assert!(solver.held().is_none());
        assert!(solver.factorizations() <= 1);
        // A cancelled token stops the next solve at once...
        assert!(matches!(
            solver.solve(40, &mut |_| {}, &remote),
            Err(EigenError::Cancelled)
        ));
        // ...and a fresh one gives what a fresh solver gives.
        let none = CancelToken::new();
        let b = solver.solve(40, &mut |_| {}, &none).unwrap();
        assert_eq!(solver.factorizations(), 1);
        let fresh = EigenSolver::new(ops, params)
            .solve(40, &mut |_| {}, &none)
            .unwrap();
        same_bits(&b, &fresh);
    }
}
