//! Block Davidson with an exact shift-invert preconditioner ([`super::SparseAlgorithm::Davidson`],
//! the earlier method, kept for comparison).
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
//! Converged pairs form a prefix (soft locking); [`SparseEigenOptions::locking`] selects
//! hard locking instead, and [`SparseEigenOptions::krylov`] expands by `K^-1 B` applied to
//! the last block (block Krylov) instead of the residuals.

use faer::Mat;

use super::dense::{col_dots, gram, product, scaled_gram_eig, sub_product, sym_eig};
use super::kernels::{
    b_orthogonality_error_cancellable, relative_residuals, residuals_from, sym_spmm,
};
use super::result::{PartialEigen, package};
use super::rng::Rng;
use super::types::{EigenProgress, SparseEigenError, SparseEigenOptions, check};
use crate::cancel::CancelToken;
use crate::linalg::{SparseCholesky, SparseMatrix};

/// B-orthonormalizes the `c` columns of `w` in place (SVQB), dropping numerically dependent
/// directions. Returns the new column count; `w` is truncated accordingly.
fn svqb(w: &mut Vec<f64>, n: usize, c: usize, b: &SparseMatrix) -> Result<usize, SparseEigenError> {
    if c == 0 {
        w.clear();
        return Ok(0);
    }
    let bw = sym_spmm(b, &w[..n * c], c);
    // Scaled to unit diagonal so that the drop threshold is relative per column.
    let (d, lam, u, lmax) = scaled_gram_eig(gram(&w[..n * c], &bw, n, c, c), 0.0)?;
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

/// Restarts the search space with its first `keep` Ritz vectors: the first `m` columns of
/// `v` (`n` rows; `m` the order of `y`) become `V Y[:, :keep]`, and `H` becomes
/// `diag(theta[:keep])`.
fn restart_with_ritz_vectors(
    v: &mut [f64],
    h: &mut Mat<f64>,
    y: &Mat<f64>,
    theta: &[f64],
    n: usize,
    keep: usize,
) {
    let m = y.nrows();
    let vk = product(&v[..n * m], y.as_ref().subcols(0, keep), n);
    v[..n * keep].copy_from_slice(&vk);
    h.fill(0.0);
    for (j, &t) in theta[..keep].iter().enumerate() {
        h[(j, j)] = t;
    }
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

/// Scales each column to unit B-norm and removes zero columns; returns the count.
fn svqb_diag_normalize(w: &mut Vec<f64>, n: usize, c: usize, b: &SparseMatrix) -> usize {
    let bw = sym_spmm(b, &w[..n * c], c);
    let norms2 = col_dots(w, &bw, n, c);
    let mut out = Vec::with_capacity(n * c);
    for (col, &nb) in w.chunks_exact(n.max(1)).zip(&norms2) {
        if nb > 0.0 && nb.is_finite() {
            let s = 1.0 / nb.sqrt();
            out.extend(col.iter().map(|v| v * s));
        }
    }
    let c2 = out.len() / n.max(1);
    *w = out;
    c2
}

/// The `k = opts.k` smallest pairs of `S x = lambda B x` by block Davidson, with `chol`
/// the factorization of `S - shift B`; `tol`, `sn = ||S||_1` and `bn = ||B||_1` as the
/// driver computed them. The random start comes from `rng`.
#[allow(clippy::too_many_arguments)]
pub(super) fn davidson(
    s: &SparseMatrix,
    b: &SparseMatrix,
    chol: &SparseCholesky,
    shift: f64,
    opts: &SparseEigenOptions,
    (tol, sn, bn): (f64, f64, f64),
    mut rng: Rng,
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<PartialEigen, SparseEigenError> {
    let n = s.ncols();
    let k = opts.k;
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

    if opts.locking && !opts.krylov {
        let ctx = Ctx {
            s,
            b,
            chol,
            n,
            k,
            p,
            tol,
            sn,
            bn,
            shift,
            max_iter,
            cancel,
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
    let c = new_block(&mut w, &[], 0, &v, 0, n, p, b)?;
    append(&mut v, &mut h, &mut m, &w, c, n, s)?;
    let mut last = (m - c, c);
    let mut restarted = false;

    let mut nconv = 0usize;
    let mut iteration = 0usize;
    loop {
        check(cancel)?;
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
                    let orthogonality_error = b_orthogonality_error_cancellable(b, &x, k, cancel)?;
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
            restart_with_ritz_vectors(&mut v, &mut h, &y, &theta, n, keep);
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
            new_block(&mut w, &[], 0, &v, m, n, c, b)?
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
            got = new_block(&mut w, &[], 0, &v, m, n, cr, b)?;
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
    cancel: &'a CancelToken,
}

/// Makes a new block orthogonal to `xl[:, :nl]` (the locked vectors; none without
/// locking) and `v[:, :m]`, B-orthonormal. Columns are B-normalized first, so that
/// "dropped" is a relative notion; columns that lie in the span of `xl` and `v` are
/// dropped. Returns the column count.
#[allow(clippy::too_many_arguments)]
fn new_block(
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
    let c = new_block(&mut w, &xl, 0, &v, 0, n, c0, b)?;
    append(&mut v, &mut h, &mut m, &w, c, n, s)?;

    let mut iteration = 0usize;
    loop {
        check(ctx.cancel)?;
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
                restart_with_ritz_vectors(&mut v, &mut h, &y, &theta, n, keep);
            }
            m = keep;
        }
        c = c.min(ma_max - m).min(n - nl - m);
        w.truncate(n * c);
        let mut got = if c > 0 {
            new_block(&mut w, &xl, nl, &v, m, n, c, b)?
        } else {
            0
        };
        if got == 0 && m < ma_max && nl + m < n {
            let cr = p.min(ma_max - m).min(n - nl - m);
            w = random_block(rng, cr, &mut solves);
            got = new_block(&mut w, &xl, nl, &v, m, n, cr, b)?;
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
    package(
        ctx.b,
        (values, vectors, residuals),
        iterations,
        solves,
        ctx.shift,
        progress,
        ctx.cancel,
    )
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
