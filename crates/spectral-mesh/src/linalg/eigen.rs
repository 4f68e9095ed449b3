//! The sparse generalized symmetric eigensolver: the `k` smallest pairs of
//! `S x = lambda B x` with `S` symmetric positive semi-definite and `B` symmetric positive
//! definite (sparse, diagonal or the identity).
//!
//! `K = S - sigma B` with a small negative shift `sigma` (so `K` is positive definite even
//! though `S` is singular) is factored once by sparse Cholesky. Two iterations use it:
//!
//! - **Block Krylov-Schur** (the default, [`SparseAlgorithm::KrylovSchur`], in
//!   `krylov_schur.rs`): thick-restart block Lanczos on `K^-1 B`, see that module.
//! - **Block Davidson** ([`SparseAlgorithm::Davidson`], the earlier method, kept for
//!   comparison), described below.
//!
//! # Block Davidson with an exact shift-invert preconditioner
//!
//! A search space `V` (`n x m`, `V^T B V = I`) grows by blocks of `p` vectors:
//!
//! 1. Rayleigh-Ritz on the pencil itself: `H = V^T S V` (kept up to date block by block),
//!    `H y = theta y`, Ritz pairs `(theta, V y)`; residuals `r = S x - theta B x` are
//!    computed from the sparse matrices, so the reported accuracy never depends on the
//!    accuracy of the solves.
//! 2. The lowest `p` Ritz pairs that have not converged are expanded by `K^-1 r` (one
//!    multi-right-hand-side solve per block). In exact arithmetic `K^-1 r` lies in
//!    `span{x, K^-1 B x}`: this is shift-invert Krylov information, focused on the pairs
//!    that still need it.
//! 3. The new block is B-orthogonalized against `V` (classical Gram-Schmidt, twice, as
//!    matrix-matrix products) and B-orthonormalized within itself (SVQB: an eigen
//!    decomposition of its Gram matrix, dropping dependent directions).
//! 4. When `V` reaches its size limit it is restarted with its best Ritz vectors.
//!
//! Converged pairs form a prefix (soft locking). Both iterations stop only when the first
//! `k` pairs have converged **and** a Ritz value lies clearly above the `k`-th, so a
//! cluster of (near-)repeated eigenvalues cut by `k` is resolved completely before `k`
//! pairs are returned. All heavy dense work (orthogonalization, Rayleigh-Ritz, Ritz
//! vectors) is BLAS-3 through faer's matrix product, split over rows.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use rayon::prelude::*;

use super::{SparseCholesky, SparseMatrix};

/// Options of [`sparse_generalized_eigen`].
#[derive(Debug, Clone, PartialEq)]
pub struct SparseEigenOptions {
    /// Number of wanted pairs (the smallest eigenvalues).
    pub k: usize,
    /// Convergence target for the relative residual of every pair (see
    /// [`relative_residuals`]).
    pub tolerance: f64,
    /// Block size `p`; `0` picks one from `k`.
    pub block_size: usize,
    /// Largest search-space dimension before a restart; `0` picks one from `k`.
    pub max_basis: usize,
    /// The shift `sigma < 0` of `S - sigma B`; `None` picks a scale-aware one.
    pub shift: Option<f64>,
    /// Seed of the random start block (results are deterministic for a given seed).
    pub seed: u64,
    /// Iteration cap; `0` picks a generous one from `k`.
    pub max_iterations: usize,
    /// Expansion rule: `true` = block Krylov (`K^-1 B` applied to the last block added),
    /// `false` = Davidson (`K^-1` applied to the residuals of the lowest unconverged
    /// Ritz pairs).
    pub krylov: bool,
    /// Hard locking: converged Ritz pairs leave the search space (which then stays small,
    /// about 5 blocks) and new directions are only B-orthogonalized against them. Cheaper
    /// per iteration but, as measured on a 38k-vertex mesh, it needs more solves and was
    /// slower overall; `false` (default) keeps every converged vector in the Rayleigh-Ritz
    /// space (soft locking).
    pub locking: bool,
    /// The iteration: block Krylov-Schur on the shift-inverted pencil (default) or block
    /// Davidson (the fields `krylov` and `locking` only apply to Davidson).
    pub algorithm: SparseAlgorithm,
    /// Krylov-Schur only: the plain iteration, without locking converged pairs and with
    /// two full Gram-Schmidt passes per block instead of the Lanczos step plus one pass
    /// (the same answer, measured 1.2-1.7x slower; kept for comparison and as the
    /// fallback when the default run does not converge).
    pub ks_plain: bool,
}

/// The iteration used by [`sparse_generalized_eigen`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SparseAlgorithm {
    /// Thick-restart block Lanczos (Krylov-Schur) on `(S - sigma B)^-1 B`, with full
    /// B-reorthogonalization as matrix-matrix products and convergence checked on the true
    /// residuals at each restart. The fastest measured.
    #[default]
    KrylovSchur,
    /// Block Davidson with the shift-invert preconditioner (the earlier method, kept for
    /// comparison).
    Davidson,
}

impl Default for SparseEigenOptions {
    fn default() -> Self {
        Self {
            k: 100,
            tolerance: 1e-10,
            block_size: 0,
            max_basis: 0,
            shift: None,
            seed: 0x5eed,
            max_iterations: 0,
            krylov: false,
            locking: false,
            algorithm: SparseAlgorithm::KrylovSchur,
            ks_plain: false,
        }
    }
}

/// Progress of the eigensolver.
#[derive(Debug, Clone, PartialEq)]
pub enum EigenProgress {
    /// The dense path started (all pairs of an `n x n` problem).
    Dense {
        /// Problem size.
        n: usize,
    },
    /// The shifted matrix `S - sigma B` is being factored.
    Factorization {
        /// Problem size.
        n: usize,
        /// The shift.
        shift: f64,
    },
    /// One iteration finished.
    Iteration {
        /// Iteration number (from 1).
        iteration: usize,
        /// Pairs converged so far (a prefix of the spectrum).
        converged: usize,
        /// Pairs wanted.
        wanted: usize,
        /// Current search-space dimension.
        basis: usize,
    },
    /// Done.
    Finished {
        /// Iterations used.
        iterations: usize,
        /// Vectors solved with the factorization.
        solves: usize,
        /// Largest relative residual of the returned pairs.
        max_residual: f64,
        /// `max |X^T B X - I|` of the returned vectors.
        orthogonality_error: f64,
    },
}

/// Errors of the sparse eigensolver.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SparseEigenError {
    /// Bad sizes (`k = 0`, `k > n`, non-square or mismatched matrices).
    #[error("invalid eigenproblem: {0}")]
    Invalid(String),
    /// `S - sigma B` could not be factored even with larger shifts.
    #[error(
        "could not factor S - sigma B ({0}); is the mass matrix singular (unreferenced vertices?)"
    )]
    Factorization(String),
    /// The iteration cap was reached.
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
    /// NaN or infinity appeared (the matrices hold non-finite values?).
    #[error("non-finite values appeared in the eigensolver")]
    NonFinite,
}

/// The result of [`sparse_generalized_eigen`].
#[derive(Debug, Clone)]
pub struct PartialEigen {
    /// The `k` smallest eigenvalues, ascending.
    pub values: Vec<f64>,
    /// Eigenvectors, `n x k` column-major, `X^T B X = I`.
    pub vectors: Vec<f64>,
    /// Relative residuals (see [`relative_residuals`]).
    pub residuals: Vec<f64>,
    /// `max |X^T B X - I|`.
    pub orthogonality_error: f64,
    /// Iterations used.
    pub iterations: usize,
    /// Number of vectors solved with the factorization.
    pub solves: usize,
    /// The shift used.
    pub shift: f64,
}

/// `max_j sum_i |A(i, j)|`, the matrix 1-norm.
pub fn norm1(a: &SparseMatrix) -> f64 {
    (0..a.ncols())
        .map(|c| a.col(c).1.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// `Y = A X` for a **symmetric** sparse `A` and `c` column-major columns `X` (`n x c`).
/// Each column is computed as `A^T x` (which equals `A x`): a gather over the stored
/// columns of `A`, with no temporaries. Parallel over columns (and over rows for a single
/// column).
pub fn sym_spmm(a: &SparseMatrix, x: &[f64], c: usize) -> Vec<f64> {
    let n = a.ncols();
    debug_assert_eq!(x.len(), n * c);
    let mut y = vec![0.0; n * c];
    sym_spmm_into(a, x, c, &mut y);
    y
}

/// [`sym_spmm`] into a caller's buffer (`y.len() >= n c`; the first `n c` entries are
/// overwritten).
pub fn sym_spmm_into(a: &SparseMatrix, x: &[f64], c: usize, y: &mut [f64]) {
    let n = a.ncols();
    if n == 0 || c == 0 {
        return;
    }
    let (cp, ri, va) = (a.col_ptr(), a.row_idx(), a.values());
    let gather = |xs: &[f64], ys: &mut [f64], base: usize| {
        for (q, yi) in ys.iter_mut().enumerate() {
            let i = base + q;
            let (lo, hi) = (cp[i], cp[i + 1]);
            let mut acc = 0.0;
            for (r, v) in ri[lo..hi].iter().zip(&va[lo..hi]) {
                acc += v * xs[*r];
            }
            *yi = acc;
        }
    };
    if c == 1 {
        y[..n]
            .par_chunks_mut(LEAF_ROWS)
            .enumerate()
            .for_each(|(chunk, yc)| gather(&x[..n], yc, chunk * LEAF_ROWS));
        return;
    }
    // Several columns: groups of 8 (then 4, 2, 1), each gathered row-major so that one
    // pass over A serves the whole group.
    let mut done = 0;
    while done < c {
        let left = c - done;
        let w = if left >= 8 {
            8
        } else if left >= 4 {
            4
        } else if left >= 2 {
            2
        } else {
            1
        };
        let xs = &x[n * done..n * (done + w)];
        let ys = &mut y[n * done..n * (done + w)];
        match w {
            8 => spmm_group::<8>(a, xs, ys),
            4 => spmm_group::<4>(a, xs, ys),
            2 => spmm_group::<2>(a, xs, ys),
            _ => spmm_group::<1>(a, xs, ys),
        }
        done += w;
    }
}

/// `Y = A X` for exactly `C` column-major columns of a symmetric `A`: `X` is copied
/// row-major, then each row of `Y` is one gather of `C`-wide rows of `X`.
fn spmm_group<const C: usize>(a: &SparseMatrix, x: &[f64], y: &mut [f64]) {
    let n = a.ncols();
    SPMM_SCRATCH.with(|cell| {
        let mut buf = cell.borrow_mut();
        if buf.len() < n * C {
            buf.resize(n * C, 0.0);
        }
        let (xr, _) = buf[..n * C].as_chunks_mut::<C>();
        spmm_group_with::<C>(a, x, y, xr);
    });
}

/// Frees this thread's [`spmm_group`] buffer (see [`super::scratch::release_all`]),
/// unless the thread is using it: [`spmm_group`] holds it across a parallel loop, during
/// which the thread may run the broadcast of another solve's `release_all` (two solves
/// side by side, as in a study).
pub(super) fn release_spmm_scratch() {
    SPMM_SCRATCH.with(|cell| {
        if let Ok(mut buf) = cell.try_borrow_mut() {
            *buf = Vec::new();
        }
    });
}

thread_local! {
    /// Row-major copy of the input block of [`spmm_group`] on this thread (reused).
    static SPMM_SCRATCH: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

fn spmm_group_with<const C: usize>(
    a: &SparseMatrix,
    x: &[f64],
    y: &mut [f64],
    xr: &mut [[f64; C]],
) {
    let n = a.ncols();
    xr.par_chunks_mut(LEAF_ROWS)
        .enumerate()
        .for_each(|(chunk, rows)| {
            let base = chunk * LEAF_ROWS;
            for (q, row) in rows.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v = x[j * n + base + q];
                }
            }
        });
    let xr = &*xr;
    // Disjoint row ranges of every output column, one list per chunk.
    let nchunks = n.div_ceil(LEAF_ROWS);
    let mut parts: Vec<Vec<&mut [f64]>> = (0..nchunks).map(|_| Vec::with_capacity(C)).collect();
    for col in y.chunks_mut(n) {
        for (ci, part) in col.chunks_mut(LEAF_ROWS).enumerate() {
            parts[ci].push(part);
        }
    }
    let (cp, ri, va) = (a.col_ptr(), a.row_idx(), a.values());
    parts
        .into_par_iter()
        .enumerate()
        .for_each(|(ci, mut cols)| {
            let base = ci * LEAF_ROWS;
            let rows = cols.first().map_or(0, |c| c.len());
            for q in 0..rows {
                let i = base + q;
                let mut acc = [0.0; C];
                for (r, v) in ri[cp[i]..cp[i + 1]].iter().zip(&va[cp[i]..cp[i + 1]]) {
                    let xr = &xr[*r];
                    for j in 0..C {
                        acc[j] += v * xr[j];
                    }
                }
                for (j, col) in cols.iter_mut().enumerate() {
                    col[q] = acc[j];
                }
            }
        });
}

/// Relative residuals of pairs `(values[j], vectors[:, j])`:
/// `||S x - lambda B x||_2 / ((||S||_1 + |lambda| ||B||_1) ||x||_2)`, a normwise backward
/// error: invariant under scaling the mesh, the matrices or the vector.
pub fn relative_residuals(
    s: &SparseMatrix,
    b: &SparseMatrix,
    values: &[f64],
    vectors: &[f64],
) -> Vec<f64> {
    let n = s.ncols();
    let k = values.len();
    if n == 0 || k == 0 {
        return Vec::new();
    }
    let sx = sym_spmm(s, &vectors[..n * k], k);
    let bx = sym_spmm(b, &vectors[..n * k], k);
    let (sn, bn) = (norm1(s), norm1(b));
    residuals_from(&sx, &bx, &vectors[..n * k], values, n, sn, bn)
}

pub(super) fn residuals_from(
    sx: &[f64],
    bx: &[f64],
    x: &[f64],
    theta: &[f64],
    n: usize,
    sn: f64,
    bn: f64,
) -> Vec<f64> {
    (0..theta.len())
        .into_par_iter()
        .map(|j| {
            let (a, b, xx) = (
                &sx[j * n..(j + 1) * n],
                &bx[j * n..(j + 1) * n],
                &x[j * n..(j + 1) * n],
            );
            let r: f64 = a
                .iter()
                .zip(b)
                .map(|(u, v)| (u - theta[j] * v).powi(2))
                .sum::<f64>()
                .sqrt();
            let xn = xx.iter().map(|v| v * v).sum::<f64>().sqrt();
            let den = (sn + theta[j].abs() * bn) * xn;
            if den > 0.0 { r / den } else { r }
        })
        .collect()
}

/// Largest number of values in the block of `B X` that [`b_orthogonality_error`] holds
/// (2^21 values: 16 MiB), unless that is less than 8 columns.
const ORTH_BLOCK_VALUES: usize = 1 << 21;

/// `max |X^T B X - I|` for `k` columns of length `n`.
pub fn b_orthogonality_error(b: &SparseMatrix, vectors: &[f64], k: usize) -> f64 {
    let n = b.ncols();
    if n == 0 || k == 0 {
        return 0.0;
    }
    orthogonality_error_by_blocks(b, vectors, k, (ORTH_BLOCK_VALUES / n).clamp(8, 64))
}

/// [`b_orthogonality_error`] with blocks of `block` columns (`n > 0`, `k > 0`).
fn orthogonality_error_by_blocks(b: &SparseMatrix, vectors: &[f64], k: usize, block: usize) -> f64 {
    let n = b.ncols();
    // By blocks of columns: `X[:, ..end]^T B X[:, blk]` is the part of the symmetric
    // `X^T B X` on and above the diagonal block, so half the products are made and only
    // one block of `B X` is held at a time: 64 columns, fewer on large meshes so that
    // the block stays within ORTH_BLOCK_VALUES (a 64-column block at 411k vertices was
    // 210 MB, the peak memory of a k = 50 solve).
    let block = block.clamp(1, k);
    let mut e: f64 = 0.0;
    let mut bx = vec![0.0; n * block];
    let mut start = 0;
    while start < k {
        let end = (start + block).min(k);
        let w = end - start;
        sym_spmm_into(b, &vectors[n * start..n * end], w, &mut bx);
        let g = gram(&vectors[..n * end], &bx[..n * w], n, end, w);
        for jj in 0..w {
            for i in 0..end {
                let t = if i == start + jj { 1.0 } else { 0.0 };
                e = e.max((g[(i, jj)] - t).abs());
            }
        }
        start = end;
    }
    e
}

pub(super) fn view(x: &[f64], n: usize, c: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(&x[..n * c], n, c)
}

/// Rows per leaf of the parallel splits (fixed: results do not depend on the thread count).
pub(super) const LEAF_ROWS: usize = 4096;

/// `B^T A` for row blocks, split recursively over rows and summed in a fixed order.
/// (Computing `(B^T A)^T` rather than `A^T B` lets the kernel read the wide `A` in place
/// and pack only the narrow `B`: measured 25-40% faster for `A` of 150-1000 columns
/// and `B` of 8-16.)
fn gram_rec(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let n = a.nrows();
    if n <= LEAF_ROWS {
        let mut g = Mat::<f64>::zeros(b.ncols(), a.ncols());
        matmul(g.as_mut(), Accum::Replace, b.transpose(), a, 1.0, Par::Seq);
        return g;
    }
    let mid = (n / 2).next_multiple_of(64).min(n);
    let (a0, a1) = a.split_at_row(mid);
    let (b0, b1) = b.split_at_row(mid);
    let (mut g0, g1) = rayon::join(|| gram_rec(a0, b0), || gram_rec(a1, b1));
    g0 += g1;
    g0
}

/// `A^T B` for column-major `A` (`n x a`) and `B` (`n x b`).
pub(super) fn gram(a: &[f64], b: &[f64], n: usize, ca: usize, cb: usize) -> Mat<f64> {
    if n == 0 || ca == 0 || cb == 0 {
        return Mat::<f64>::zeros(ca, cb);
    }
    gram_rec(view(a, n, ca), view(b, n, cb))
        .transpose()
        .to_owned()
}

/// Rows per leaf of [`matmul_rows`]: products with a thin right-hand side (`W -= V C`)
/// ran about 25% faster with 1024-row leaves than with 4096 (cache-sized blocks of `V`).
const PRODUCT_LEAF_ROWS: usize = 1024;

/// `dst (+)= alpha * lhs * rhs`, split recursively over the rows of `dst` and `lhs`.
pub(super) fn matmul_rows(
    dst: faer::MatMut<'_, f64>,
    accum: Accum,
    lhs: MatRef<'_, f64>,
    rhs: MatRef<'_, f64>,
    alpha: f64,
) {
    let n = dst.nrows();
    if n <= PRODUCT_LEAF_ROWS {
        matmul(dst, accum, lhs, rhs, alpha, Par::Seq);
        return;
    }
    let mid = (n / 2).next_multiple_of(64).min(n);
    let (d0, d1) = dst.split_at_row_mut(mid);
    let (l0, l1) = lhs.split_at_row(mid);
    rayon::join(
        || matmul_rows(d0, accum, l0, rhs, alpha),
        || matmul_rows(d1, accum, l1, rhs, alpha),
    );
}

/// `W -= V C` (`V`: `n x m`, `C`: `m x c`, `W`: `n x c`).
pub(super) fn sub_product(w: &mut [f64], v: &[f64], c: MatRef<'_, f64>, n: usize) {
    let (m, cc) = (c.nrows(), c.ncols());
    if m == 0 || cc == 0 || n == 0 {
        return;
    }
    let wm = faer::MatMut::from_column_major_slice_mut(&mut w[..n * cc], n, cc);
    matmul_rows(wm, Accum::Add, view(v, n, m), c, -1.0);
}

/// `V C` as a new column-major buffer (`n x c`).
pub(super) fn product(v: &[f64], c: MatRef<'_, f64>, n: usize) -> Vec<f64> {
    let (m, cc) = (c.nrows(), c.ncols());
    let mut out = vec![0.0; n * cc];
    if m == 0 || cc == 0 || n == 0 {
        return out;
    }
    let om = faer::MatMut::from_column_major_slice_mut(&mut out, n, cc);
    matmul_rows(om, Accum::Replace, view(v, n, m), c, 1.0);
    out
}

/// A small deterministic generator (SplitMix64).
pub(super) struct Rng(pub(super) u64);

impl Rng {
    pub(super) fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// The dense symmetric eigen-decomposition of `h` (ascending; lower triangle read).
/// Sequential: the projected matrices are small and fine-grained parallelism costs more
/// than it gains on a shared machine.
pub(super) fn sym_eig(h: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), SparseEigenError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd;
    let n = h.nrows();
    let mut u = Mat::<f64>::zeros(n, n);
    let mut d = faer::diag::Diag::<f64>::zeros(n);
    let par = Par::Seq;
    let mut mem = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        n,
        evd::ComputeEigenvectors::Yes,
        par,
        Default::default(),
    ));
    evd::self_adjoint_evd(
        h,
        d.as_mut(),
        Some(u.as_mut()),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map_err(|_| SparseEigenError::NonFinite)?;
    let vals: Vec<f64> = (0..n).map(|i| d[i]).collect();
    if vals.iter().any(|v| !v.is_finite()) {
        return Err(SparseEigenError::NonFinite);
    }
    Ok((vals, u))
}

/// B-orthonormalizes the `c` columns of `w` in place (SVQB), dropping numerically dependent
/// directions. Returns the new column count; `w` is truncated accordingly.
fn svqb(w: &mut Vec<f64>, n: usize, c: usize, b: &SparseMatrix) -> Result<usize, SparseEigenError> {
    if c == 0 {
        w.clear();
        return Ok(0);
    }
    let bw = sym_spmm(b, &w[..n * c], c);
    let mut g = gram(&w[..n * c], &bw, n, c, c);
    // Scale to unit diagonal so that the drop threshold is relative per column.
    let mut d = vec![0.0; c];
    for (i, di) in d.iter_mut().enumerate() {
        let gii = g[(i, i)];
        if !gii.is_finite() {
            return Err(SparseEigenError::NonFinite);
        }
        *di = if gii > 0.0 { 1.0 / gii.sqrt() } else { 0.0 };
    }
    for j in 0..c {
        for i in 0..c {
            g[(i, j)] *= d[i] * d[j];
        }
    }
    for j in 0..c {
        for i in 0..j {
            let v = 0.5 * (g[(i, j)] + g[(j, i)]);
            g[(i, j)] = v;
            g[(j, i)] = v;
        }
    }
    let (lam, u) = sym_eig(g.as_ref())?;
    let lmax = lam.iter().cloned().fold(0.0, f64::max);
    let keep: Vec<usize> = (0..c)
        .filter(|&i| lam[i] > 1e-10 * lmax && lmax > 0.0)
        .collect();
    let mut coef = Mat::<f64>::zeros(c, keep.len());
    for (jj, &j) in keep.iter().enumerate() {
        let s = 1.0 / lam[j].sqrt();
        for i in 0..c {
            coef[(i, jj)] = d[i] * u[(i, j)] * s;
        }
    }
    let out = product(&w[..n * c], coef.as_ref(), n);
    *w = out;
    Ok(keep.len())
}

/// B-orthogonalizes the `c` columns of `w` against the `m` columns of `v` (one classical
/// Gram-Schmidt pass as two matrix products).
fn orth_against(w: &mut [f64], v: &[f64], n: usize, m: usize, c: usize, b: &SparseMatrix) {
    if m == 0 || c == 0 {
        return;
    }
    let bw = sym_spmm(b, &w[..n * c], c);
    let coef = gram(&v[..n * m], &bw, n, m, c);
    sub_product(w, v, coef.as_ref(), n);
}

/// Makes a new block: orthogonal to `v[:, :m]`, B-orthonormal. Columns that lie in the span
/// of `v` are dropped. Returns the column count.
fn new_block(
    w: &mut Vec<f64>,
    v: &[f64],
    n: usize,
    m: usize,
    c: usize,
    b: &SparseMatrix,
) -> Result<usize, SparseEigenError> {
    // Normalize columns first (B-norm) so that "dropped" is a relative notion.
    let mut c = svqb_diag_normalize(w, n, c, b);
    orth_against(w, v, n, m, c, b);
    c = svqb(w, n, c, b)?;
    orth_against(w, v, n, m, c, b);
    svqb(w, n, c, b)
}

/// Scales each column to unit B-norm and removes zero columns; returns the count.
fn svqb_diag_normalize(w: &mut Vec<f64>, n: usize, c: usize, b: &SparseMatrix) -> usize {
    let bw = sym_spmm(b, &w[..n * c], c);
    let mut out = Vec::with_capacity(n * c);
    for j in 0..c {
        let col = &w[j * n..(j + 1) * n];
        let nb: f64 = col
            .iter()
            .zip(&bw[j * n..(j + 1) * n])
            .map(|(a, b)| a * b)
            .sum();
        if nb > 0.0 && nb.is_finite() {
            let s = 1.0 / nb.sqrt();
            out.extend(col.iter().map(|v| v * s));
        }
    }
    let c2 = out.len() / n.max(1);
    *w = out;
    c2
}

/// The `k` smallest pairs of `S x = lambda B x` by block Davidson with a shift-invert
/// preconditioner (see the module documentation). `S` must be symmetric positive
/// semi-definite and `B` symmetric positive definite, both `n x n`. Works for any
/// `1 <= k <= n` (the search space is capped at `n`), but for small `n` or `k` close to
/// `n` the dense path is faster.
pub fn sparse_generalized_eigen(
    s: &SparseMatrix,
    b: &SparseMatrix,
    opts: &SparseEigenOptions,
    progress: &mut dyn FnMut(EigenProgress),
) -> Result<PartialEigen, SparseEigenError> {
    let n = s.ncols();
    let k = opts.k;
    if s.nrows() != n || b.nrows() != n || b.ncols() != n {
        return Err(SparseEigenError::Invalid(format!(
            "S is {} x {}, B is {} x {}",
            s.nrows(),
            s.ncols(),
            b.nrows(),
            b.ncols()
        )));
    }
    if k == 0 || k > n {
        return Err(SparseEigenError::Invalid(format!(
            "asked for k = {k} pairs of an n = {n} problem"
        )));
    }
    let tol = if opts.tolerance > 0.0 {
        opts.tolerance
    } else {
        1e-10
    };
    let (sn, bn) = (norm1(s), norm1(b));
    if !sn.is_finite() || !bn.is_finite() {
        return Err(SparseEigenError::NonFinite);
    }

    // Shift: well below the smallest eigenvalue of interest but scale-aware. The total
    // mass M = 1^T B 1 sets the eigenvalue scale of the low modes (lambda_2 ~ 10 / M for
    // a round surface; for B = I the same holds with M = n), and a floor relative to
    // ||S|| / ||B|| keeps K well conditioned enough for Cholesky.
    let total_mass: f64 = b.values().iter().sum::<f64>().abs().max(f64::MIN_POSITIVE);
    let auto_shift = -(1e-2 / total_mass).max(1e-10 * sn / bn.max(f64::MIN_POSITIVE));
    let mut shift = opts.shift.unwrap_or(auto_shift);
    if shift >= 0.0 {
        shift = auto_shift;
    }
    let mut chol = None;
    let mut last_err = String::new();
    for _ in 0..5 {
        progress(EigenProgress::Factorization { n, shift });
        let kmat = s.add_scaled(1.0, b, -shift);
        match super::timing::timed(super::timing::Phase::Factor, || SparseCholesky::new(&kmat)) {
            Ok(c) => {
                chol = Some(c);
                break;
            }
            Err(e) => {
                last_err = e.to_string();
                shift *= 100.0;
            }
        }
    }
    let chol = chol.ok_or(SparseEigenError::Factorization(last_err))?;

    // The random start of every iteration (and of a rerun) comes from the same seed.
    let start_rng = || Rng(opts.seed ^ 0xA5A5_5A5A_DEAD_BEEF);

    if opts.algorithm == SparseAlgorithm::KrylovSchur {
        let bs = if opts.block_size > 0 {
            opts.block_size
        } else {
            // Measured on a 38k-vertex mesh: 8 for k = 50, 16 for k = 200 (larger blocks
            // need more solves, smaller ones give thin, slow matrix products).
            (k / 12).clamp(8, 16)
        }
        .min(n);
        let max_basis = if opts.max_basis > 0 {
            opts.max_basis.max(k + 2 * bs)
        } else {
            // 2k up to k = 300, then k + 300: measured at k = 500 on 26k vertices, a
            // basis of 750-850 needed fewer solves and less time than 1000 (6.5-6.8 s
            // against 8.1 s) and less memory. At least k + 70: for k = 50 a basis of
            // 120 took the same time as 150 (256 solves against 248, at 38k to 411k
            // vertices) and 130 MiB less at 411k.
            (2 * k).min(k + 300).max(k + 70).max(k + 4 * bs)
        }
        .min(n);
        let pb = super::krylov_schur::Problem {
            s,
            b,
            chol: &chol,
            shift,
            k,
            tol,
            sn,
            bn,
        };
        let mut sizes = super::krylov_schur::Sizes {
            block: bs,
            max_basis,
            max_restarts: if opts.max_iterations > 0 {
                opts.max_iterations
            } else {
                100 + 10 * k.div_ceil(bs)
            },
            // Locking pays from about k = 100 (restarts then rotate hundreds of converged
            // vectors); at k = 50 it saved no measurable time on 26k-38k vertices, and its
            // temporaries of varying sizes raised the peak memory by 25-30 MiB on bunny00.
            lock: !opts.ks_plain && k >= 100,
            local: !opts.ks_plain,
        };
        let mut rng = start_rng();
        let mut out = super::krylov_schur::krylov_schur(&pb, &sizes, &mut rng, progress);
        if !opts.ks_plain && matches!(out, Err(SparseEigenError::NoConvergence { .. })) {
            // A locked pair is never revisited, and the single full pass trusts the
            // Krylov relation: before reporting a failure, run once more as the plain
            // iteration (no locking, two full Gram-Schmidt passes).
            sizes.lock = false;
            sizes.local = false;
            let mut rng = start_rng();
            out = super::krylov_schur::krylov_schur(&pb, &sizes, &mut rng, progress);
        }
        super::scratch::release_all();
        // The factor goes before the eigenvectors are copied out of the basis (see
        // `Converged`): the copy can then reuse its memory.
        drop(chol);
        return out.map(|pairs| pairs.finish(b, progress));
    }

    // Sizes.
    let p = if opts.block_size > 0 {
        opts.block_size
    } else {
        k.div_ceil(4).clamp(8, 48)
    }
    .min(n);
    let m_max = if opts.max_basis > 0 {
        opts.max_basis.max(k + 2 * p)
    } else {
        (5 * k / 2 + 4 * p).max(k + 8 * p)
    }
    .min(n);
    let max_iter = if opts.max_iterations > 0 {
        opts.max_iterations
    } else {
        200 + 40 * k.div_ceil(p)
    };

    let mut rng = start_rng();
    if opts.locking && !opts.krylov {
        let ctx = Ctx {
            s,
            b,
            chol: &chol,
            n,
            k,
            p,
            tol,
            sn,
            bn,
            shift,
            max_iter,
        };
        let ma_max = if opts.max_basis > 0 {
            opts.max_basis
        } else {
            (5 * p).max(p + 24)
        };
        return locked(&ctx, ma_max, &mut rng, progress);
    }
    let mut v = vec![0.0; n * m_max];
    let mut h = Mat::<f64>::zeros(m_max, m_max);
    let mut m = 0usize;
    let mut solves = 0usize;

    // Start block: K^-1 B (random), B-orthonormalized.
    let mut w: Vec<f64> = (0..n * p).map(|_| rng.next_f64()).collect();
    let mut bw = sym_spmm(b, &w, p);
    chol.solve_many_in_place(&mut bw, p);
    solves += p;
    w = bw;
    let c = new_block(&mut w, &v, n, 0, p, b)?;
    append(&mut v, &mut h, &mut m, &w, c, n, s)?;
    let mut last = (m - c, c);
    let mut restarted = false;

    let mut nconv = 0usize;
    let mut iteration = 0usize;
    loop {
        iteration += 1;
        let (theta, y) = sym_eig(h.as_ref().submatrix(0, 0, m, m))?;
        // Window of pairs to test.
        let lo = nconv.min(m);
        let hi = (lo + p).min(m);
        let win: Vec<usize> = (lo..hi).collect();
        let mut ywin = Mat::<f64>::zeros(m, win.len());
        for (jj, &j) in win.iter().enumerate() {
            for i in 0..m {
                ywin[(i, jj)] = y[(i, j)];
            }
        }
        let xw = product(&v[..n * m], ywin.as_ref(), n);
        let sx = sym_spmm(s, &xw, win.len());
        let bx = sym_spmm(b, &xw, win.len());
        let th: Vec<f64> = win.iter().map(|&j| theta[j]).collect();
        let res = residuals_from(&sx, &bx, &xw, &th, n, sn, bn);
        if res.iter().any(|r| !r.is_finite()) {
            return Err(SparseEigenError::NonFinite);
        }
        let full_space = m >= n;
        for (jj, &j) in win.iter().enumerate() {
            if j == nconv && (res[jj] <= tol || full_space) {
                nconv += 1;
            }
        }
        progress(EigenProgress::Iteration {
            iteration,
            converged: nconv.min(k),
            wanted: k,
            basis: m,
        });
        // Done when the first k are converged and the cluster at the k-th is closed.
        let cluster_closed = |nconv: usize| -> bool {
            if nconv >= n || full_space && nconv >= k {
                return true;
            }
            if nconv <= k {
                return false;
            }
            let lk = theta[k - 1];
            let gap = 1e-3 * lk.abs() + 1e-10 * sn / bn.max(f64::MIN_POSITIVE);
            theta[nconv - 1] > lk + gap
        };
        if nconv >= k && cluster_closed(nconv) {
            let mut yk = Mat::<f64>::zeros(m, k);
            for j in 0..k {
                for i in 0..m {
                    yk[(i, j)] = y[(i, j)];
                }
            }
            let x = product(&v[..n * m], yk.as_ref(), n);
            let values = theta[..k].to_vec();
            let residuals = relative_residuals(s, b, &values, &x);
            let bad = residuals.iter().position(|&r| r > tol && !full_space);
            match bad {
                None => {
                    let orthogonality_error = b_orthogonality_error(b, &x, k);
                    let max_residual = residuals.iter().cloned().fold(0.0, f64::max);
                    progress(EigenProgress::Finished {
                        iterations: iteration,
                        solves,
                        max_residual,
                        orthogonality_error,
                    });
                    return Ok(PartialEigen {
                        values,
                        vectors: x,
                        residuals,
                        orthogonality_error,
                        iterations: iteration,
                        solves,
                        shift,
                    });
                }
                Some(j) => {
                    nconv = j;
                    if iteration >= max_iter {
                        return Err(SparseEigenError::NoConvergence {
                            converged: j,
                            wanted: k,
                            iterations: iteration,
                        });
                    }
                    continue;
                }
            }
        }
        if iteration >= max_iter {
            return Err(SparseEigenError::NoConvergence {
                converged: nconv.min(k),
                wanted: k,
                iterations: iteration,
            });
        }

        // Expansion vectors: K^-1 r for the unconverged pairs of the window.
        let mut cols: Vec<usize> = (0..win.len()).filter(|&jj| res[jj] > tol).collect();
        cols.truncate(p);
        let mut c = cols.len();
        let mut w = vec![0.0; n * c.max(1)];
        for (q, &jj) in cols.iter().enumerate() {
            let t = th[jj];
            let dst = &mut w[q * n..(q + 1) * n];
            for i in 0..n {
                dst[i] = sx[jj * n + i] - t * bx[jj * n + i];
            }
        }
        if opts.krylov && last.1 > 0 && !restarted {
            // Block Krylov: K^-1 B applied to the last block added.
            c = last.1;
            w = sym_spmm(b, &v[n * last.0..n * (last.0 + c)], c);
        }
        if c > 0 {
            chol.solve_many_in_place(&mut w[..n * c], c);
            solves += c;
        }
        // Room: restart with the best Ritz vectors if needed.
        let room = m_max - m;
        if room < c.max(1) {
            let keep = (nconv + p)
                .max(k + p)
                .max(m_max / 2)
                .min(m_max - c.max(1))
                .min(m);
            let mut yk = Mat::<f64>::zeros(m, keep);
            for j in 0..keep {
                for i in 0..m {
                    yk[(i, j)] = y[(i, j)];
                }
            }
            let xk = product(&v[..n * m], yk.as_ref(), n);
            v[..n * keep].copy_from_slice(&xk);
            h.fill(0.0);
            for j in 0..keep {
                h[(j, j)] = theta[j];
            }
            m = keep;
            // The basis is no longer a Krylov space: the next block expands residuals.
            restarted = true;
        } else {
            restarted = false;
        }
        let room = m_max - m;
        if c > room {
            c = room;
            w.truncate(n * c);
        }
        let mut got = if c > 0 {
            new_block(&mut w, &v, n, m, c, b)?
        } else {
            0
        };
        if got == 0 && m < m_max {
            // No new direction: add random ones (keeps the iteration moving and is the
            // safety net for directions missing from the start block).
            let cr = p.min(m_max - m);
            w = (0..n * cr).map(|_| rng.next_f64()).collect();
            let mut bw = sym_spmm(b, &w, cr);
            chol.solve_many_in_place(&mut bw, cr);
            solves += cr;
            w = bw;
            got = new_block(&mut w, &v, n, m, cr, b)?;
        }
        append(&mut v, &mut h, &mut m, &w, got, n, s)?;
        last = (m - got, got);
    }
}

struct Ctx<'a> {
    s: &'a SparseMatrix,
    b: &'a SparseMatrix,
    chol: &'a SparseCholesky,
    n: usize,
    k: usize,
    p: usize,
    tol: f64,
    sn: f64,
    bn: f64,
    shift: f64,
    max_iter: usize,
}

/// Makes a new block orthogonal to `xl[:, :nl]` and `v[:, :m]`, B-orthonormal.
#[allow(clippy::too_many_arguments)]
fn new_block_locked(
    w: &mut Vec<f64>,
    xl: &[f64],
    nl: usize,
    v: &[f64],
    m: usize,
    n: usize,
    c: usize,
    b: &SparseMatrix,
) -> Result<usize, SparseEigenError> {
    let mut c = svqb_diag_normalize(w, n, c, b);
    for _ in 0..2 {
        orth_against(w, xl, n, nl, c, b);
        orth_against(w, v, n, m, c, b);
        c = svqb(w, n, c, b)?;
    }
    Ok(c)
}

/// Block Davidson with hard locking (see [`SparseEigenOptions::locking`]).
fn locked(
    ctx: &Ctx<'_>,
    ma_max: usize,
    rng: &mut Rng,
    progress: &mut dyn FnMut(EigenProgress),
) -> Result<PartialEigen, SparseEigenError> {
    let Ctx {
        s,
        b,
        chol,
        n,
        k,
        p,
        tol,
        sn,
        bn,
        max_iter,
        ..
    } = *ctx;
    let ma_max = ma_max.max(p + 1).min(n);
    let mut xl: Vec<f64> = Vec::with_capacity(n * (k + p));
    let mut ll: Vec<f64> = Vec::new();
    let mut v = vec![0.0; n * ma_max];
    let mut h = Mat::<f64>::zeros(ma_max, ma_max);
    let mut m = 0usize;
    let mut solves = 0usize;
    let gap_abs = 1e-10 * sn / bn.max(f64::MIN_POSITIVE);

    let random_block = |rng: &mut Rng, c: usize, solves: &mut usize| -> Vec<f64> {
        let w: Vec<f64> = (0..n * c).map(|_| rng.next_f64()).collect();
        let mut bw = sym_spmm(b, &w, c);
        chol.solve_many_in_place(&mut bw, c);
        *solves += c;
        bw
    };
    let c0 = p.min(ma_max);
    let mut w = random_block(rng, c0, &mut solves);
    let c = new_block_locked(&mut w, &xl, 0, &v, 0, n, c0, b)?;
    append(&mut v, &mut h, &mut m, &w, c, n, s)?;

    let mut iteration = 0usize;
    loop {
        iteration += 1;
        let nl = ll.len();
        let (theta, y) = if m > 0 {
            sym_eig(h.as_ref().submatrix(0, 0, m, m))?
        } else {
            (Vec::new(), Mat::<f64>::zeros(0, 0))
        };
        let win = p.min(m);
        let mut ywin = Mat::<f64>::zeros(m, win);
        for j in 0..win {
            for i in 0..m {
                ywin[(i, j)] = y[(i, j)];
            }
        }
        let xw = product(&v[..n * m], ywin.as_ref(), n);
        let sx = sym_spmm(s, &xw, win);
        let bx = sym_spmm(b, &xw, win);
        let th: Vec<f64> = theta[..win].to_vec();
        let res = residuals_from(&sx, &bx, &xw, &th, n, sn, bn);
        if res.iter().any(|r| !r.is_finite()) {
            return Err(SparseEigenError::NonFinite);
        }
        let full_space = nl + m >= n;
        let mut nf = 0;
        while nf < win && (res[nf] <= tol || full_space) {
            nf += 1;
        }
        if full_space {
            nf = m;
        }
        if nf > 0 {
            // Lock: the first nf Ritz vectors leave V; V becomes the remaining Ritz basis.
            if nf <= win {
                xl.extend_from_slice(&xw[..n * nf.min(win)]);
            }
            if nf > win {
                let mut yl = Mat::<f64>::zeros(m, nf);
                for j in 0..nf {
                    for i in 0..m {
                        yl[(i, j)] = y[(i, j)];
                    }
                }
                xl.extend_from_slice(&product(&v[..n * m], yl.as_ref(), n));
            }
            ll.extend_from_slice(&theta[..nf]);
            let rest = m - nf;
            let mut yr = Mat::<f64>::zeros(m, rest);
            for j in 0..rest {
                for i in 0..m {
                    yr[(i, j)] = y[(i, nf + j)];
                }
            }
            let vr = product(&v[..n * m], yr.as_ref(), n);
            v[..n * rest].copy_from_slice(&vr);
            h.fill(0.0);
            for j in 0..rest {
                h[(j, j)] = theta[nf + j];
            }
            m = rest;
        }
        let nl = ll.len();
        progress(EigenProgress::Iteration {
            iteration,
            converged: nl.min(k),
            wanted: k,
            basis: m,
        });
        // Stop when k are locked, the cluster at the k-th is closed and nothing left in V
        // lies below it.
        if nl >= k {
            let mut sorted = ll.clone();
            sorted.sort_by(f64::total_cmp);
            let lk = sorted[k - 1];
            let gap = 1e-3 * lk.abs() + gap_abs;
            let closed = nl >= n || nl + m >= n || sorted[nl - 1] > lk + gap;
            let below = (nf..m.max(nf)).any(|j| j < theta.len() && theta[j] <= lk + gap);
            if closed && (!below || nl + m >= n) {
                return finish(ctx, xl, ll, iteration, solves, progress);
            }
        }
        if iteration >= max_iter {
            return Err(SparseEigenError::NoConvergence {
                converged: nl.min(k),
                wanted: k,
                iterations: iteration,
            });
        }
        // Expansion: K^-1 r for the unconverged pairs of the window (now at V[:, 0..]).
        let cols: Vec<usize> = (nf..win).filter(|&jj| res[jj] > tol).collect();
        let mut c = cols.len();
        let mut w = vec![0.0; n * c];
        for (q, &jj) in cols.iter().enumerate() {
            let t = th[jj];
            let dst = &mut w[q * n..(q + 1) * n];
            for i in 0..n {
                dst[i] = sx[jj * n + i] - t * bx[jj * n + i];
            }
        }
        if c > 0 {
            chol.solve_many_in_place(&mut w[..n * c], c);
            solves += c;
        }
        // Room in V: truncate to the best Ritz vectors (rotating V if it is not already
        // the Ritz basis).
        if m + c.max(1) > ma_max {
            let keep = ma_max.saturating_sub(c.max(1)).min(m);
            if nf == 0 {
                let mut yk = Mat::<f64>::zeros(m, keep);
                for j in 0..keep {
                    for i in 0..m {
                        yk[(i, j)] = y[(i, j)];
                    }
                }
                let vk = product(&v[..n * m], yk.as_ref(), n);
                v[..n * keep].copy_from_slice(&vk);
                h.fill(0.0);
                for j in 0..keep {
                    h[(j, j)] = theta[j];
                }
            }
            m = keep;
        }
        c = c.min(ma_max - m).min(n - nl - m);
        w.truncate(n * c);
        let mut got = if c > 0 {
            new_block_locked(&mut w, &xl, nl, &v, m, n, c, b)?
        } else {
            0
        };
        if got == 0 && m < ma_max && nl + m < n {
            let cr = p.min(ma_max - m).min(n - nl - m);
            w = random_block(rng, cr, &mut solves);
            got = new_block_locked(&mut w, &xl, nl, &v, m, n, cr, b)?;
        }
        append(&mut v, &mut h, &mut m, &w, got, n, s)?;
    }
}

/// Sorts the locked pairs, keeps the first k, reports.
fn finish(
    ctx: &Ctx<'_>,
    xl: Vec<f64>,
    ll: Vec<f64>,
    iterations: usize,
    solves: usize,
    progress: &mut dyn FnMut(EigenProgress),
) -> Result<PartialEigen, SparseEigenError> {
    let (n, k) = (ctx.n, ctx.k);
    let mut order: Vec<usize> = (0..ll.len()).collect();
    order.sort_by(|&a, &b| ll[a].total_cmp(&ll[b]));
    let mut values = Vec::with_capacity(k);
    let mut vectors = Vec::with_capacity(n * k);
    for &j in order.iter().take(k) {
        values.push(ll[j]);
        vectors.extend_from_slice(&xl[j * n..(j + 1) * n]);
    }
    drop(xl);
    let residuals = relative_residuals(ctx.s, ctx.b, &values, &vectors);
    Ok(package(
        ctx.b,
        (values, vectors, residuals),
        iterations,
        solves,
        ctx.shift,
        progress,
    ))
}

/// The result of a solve from its sorted pairs `(values, vectors, residuals)`: measures
/// the B-orthogonality, reports [`EigenProgress::Finished`] and builds the
/// [`PartialEigen`] (shared by every iterative method).
pub(super) fn package(
    b: &SparseMatrix,
    (values, vectors, residuals): (Vec<f64>, Vec<f64>, Vec<f64>),
    iterations: usize,
    solves: usize,
    shift: f64,
    progress: &mut dyn FnMut(EigenProgress),
) -> PartialEigen {
    let orthogonality_error = b_orthogonality_error(b, &vectors, values.len());
    let max_residual = residuals.iter().cloned().fold(0.0, f64::max);
    progress(EigenProgress::Finished {
        iterations,
        solves,
        max_residual,
        orthogonality_error,
    });
    PartialEigen {
        values,
        vectors,
        residuals,
        orthogonality_error,
        iterations,
        solves,
        shift,
    }
}

/// Appends the `c` B-orthonormal columns `w` (already orthogonal to `v[:, :m]`) to the
/// basis and extends `H = V^T S V`.
fn append(
    v: &mut [f64],
    h: &mut Mat<f64>,
    m: &mut usize,
    w: &[f64],
    c: usize,
    n: usize,
    s: &SparseMatrix,
) -> Result<(), SparseEigenError> {
    if c == 0 {
        return Ok(());
    }
    let m0 = *m;
    v[n * m0..n * (m0 + c)].copy_from_slice(&w[..n * c]);
    let sw = sym_spmm(s, &w[..n * c], c);
    let hc = gram(&v[..n * (m0 + c)], &sw, n, m0 + c, c);
    for j in 0..c {
        for i in 0..m0 + c {
            let val = hc[(i, j)];
            if !val.is_finite() {
                return Err(SparseEigenError::NonFinite);
            }
            h[(i, m0 + j)] = val;
            h[(m0 + j, i)] = val;
        }
    }
    // Exact symmetry of the new diagonal block.
    for j in 0..c {
        for i in 0..j {
            let a = 0.5 * (hc[(m0 + i, j)] + hc[(m0 + j, i)]);
            h[(m0 + i, m0 + j)] = a;
            h[(m0 + j, m0 + i)] = a;
        }
    }
    *m = m0 + c;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::dense_generalized_eigen;

    fn path_laplacian(n: usize) -> (SparseMatrix, SparseMatrix) {
        let mut t = Vec::new();
        let mut tb = Vec::new();
        for i in 0..n {
            if i + 1 < n {
                t.push((i, i, 1.0));
                t.push((i + 1, i + 1, 1.0));
                t.push((i, i + 1, -1.0));
                t.push((i + 1, i, -1.0));
            }
            tb.push((i, i, 1.0 + (i % 3) as f64 * 0.5));
        }
        (
            SparseMatrix::from_triplets(n, n, &t),
            SparseMatrix::from_triplets(n, n, &tb),
        )
    }

    /// The blocked, upper-triangle-only orthogonality error equals `max |X^T B X - I|`
    /// computed in full, wherever the largest entry sits (across blocks of 64 columns,
    /// on and off the diagonal).
    /// Another solve's `release_all` can reach a thread inside `spmm_group`, which holds
    /// the buffer across a parallel loop: the buffer is then left alone, not a panic.
    #[test]
    fn releasing_a_busy_spmm_buffer_is_skipped() {
        SPMM_SCRATCH.with(|cell| {
            let mut busy = cell.borrow_mut();
            busy.resize(10, 1.0);
            release_spmm_scratch();
            assert_eq!(busy.len(), 10);
        });
        release_spmm_scratch();
        SPMM_SCRATCH.with(|cell| assert_eq!(cell.borrow().capacity(), 0));
    }

    #[test]
    fn orthogonality_error_matches_the_full_product() {
        let n = 200;
        let (_, b) = path_laplacian(n);
        let k = 150;
        let mut rng = Rng(7);
        let mut x: Vec<f64> = (0..n * k).map(|_| rng.next_f64() * 0.2).collect();
        // Column 130 repeats column 3: the largest entry of |X^T B X - I| is then off the
        // diagonal, between the first and the third block.
        x.copy_within(3 * n..4 * n, 130 * n);
        let bx = sym_spmm(&b, &x, k);
        let full = |x: &[f64]| -> f64 {
            let mut e: f64 = 0.0;
            for i in 0..k {
                for j in 0..k {
                    let g: f64 = (0..n).map(|r| x[i * n + r] * bx[j * n + r]).sum();
                    let t = if i == j { 1.0 } else { 0.0 };
                    e = e.max((g - t).abs());
                }
            }
            e
        };
        let want = full(&x);
        let got = b_orthogonality_error(&b, &x, k);
        assert!(
            (got - want).abs() <= 1e-12 * want.max(1.0),
            "blocked {got} against full {want}"
        );
        // The narrower blocks of large meshes (column 130 is then 16 blocks after 3).
        let got8 = orthogonality_error_by_blocks(&b, &x, k, 8);
        assert!(
            (got8 - want).abs() <= 1e-12 * want.max(1.0),
            "blocks of 8: {got8} against full {want}"
        );
        assert!(
            want > 0.5,
            "the test vectors should be far from orthonormal"
        );
    }

    #[test]
    fn matches_dense_on_a_path_graph() {
        let (s, b) = path_laplacian(300);
        let (vals, _) = dense_generalized_eigen(&s, &b).unwrap();
        let opts = SparseEigenOptions {
            k: 20,
            ..Default::default()
        };
        let r = sparse_generalized_eigen(&s, &b, &opts, &mut |_| {}).unwrap();
        for j in 0..20 {
            assert!(
                (r.values[j] - vals[j]).abs() <= 1e-9 * vals[19],
                "{j}: {} vs {}",
                r.values[j],
                vals[j]
            );
        }
        assert!(r.residuals.iter().all(|&x| x <= 1e-10));
        assert!(r.orthogonality_error < 1e-10);
    }

    #[test]
    fn whole_spectrum_when_k_equals_n() {
        let (s, b) = path_laplacian(40);
        let (vals, _) = dense_generalized_eigen(&s, &b).unwrap();
        let opts = SparseEigenOptions {
            k: 40,
            ..Default::default()
        };
        let r = sparse_generalized_eigen(&s, &b, &opts, &mut |_| {}).unwrap();
        for j in 0..40 {
            assert!((r.values[j] - vals[j]).abs() <= 1e-9 * vals[39]);
        }
    }

    #[test]
    fn bad_sizes_are_errors() {
        let (s, b) = path_laplacian(10);
        let opts = SparseEigenOptions {
            k: 11,
            ..Default::default()
        };
        assert!(matches!(
            sparse_generalized_eigen(&s, &b, &opts, &mut |_| {}),
            Err(SparseEigenError::Invalid(_))
        ));
    }
}
