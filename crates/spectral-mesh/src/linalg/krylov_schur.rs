//! Block Krylov-Schur (thick-restart block Lanczos) on the shift-inverted pencil.
//!
//! The operator is `Op = K^-1 B` with `K = S - sigma B` (`sigma < 0`, factored once by
//! sparse Cholesky). `Op` is self-adjoint in the `B` inner product and its eigenvalues
//! `theta = 1 / (lambda - sigma)` are largest for the smallest `lambda`, where they are
//! also best separated: a handful of Krylov steps per wanted pair suffice.
//!
//! The basis `V` (`n x j`, `V^T B V = I`) grows by blocks: the newest block `Q` is
//! multiplied by `Op` (one sparse product with `B`, one multi-right-hand-side solve), the
//! result is B-orthogonalized against all of `V` and B-orthonormalized within itself
//! (SVQB). The orthogonalization is a Lanczos step, then one full pass: the coefficients
//! of `Op Q` on the earlier columns are known from the Krylov relation (the coupling row
//! `R`, nonzero only on the previous block, or on the kept Ritz vectors just after a
//! restart), so they and `Q^T B Op Q` are subtracted first at the cost of a few blocks;
//! a single classical Gram-Schmidt pass against all of `V` (matrix-matrix products) then
//! removes what rounding and the inexact solves left (about 1e-11 of the norm, measured),
//! with a second pass when that one still removed much (DGKS). The coefficients fill the
//! projected matrix `T = V^T B Op V`, so that `Op V = V T + Q_next R E^T` holds to
//! rounding error (a Krylov decomposition).
//!
//! When `V` reaches its size limit the iteration restarts (Krylov-Schur): `T = Y Theta Y^T`,
//! the Ritz vectors `V Y` of the largest `theta` are kept (computed in place, row block by
//! row block, so no second `n x m` buffer is needed), `T` becomes diagonal plus the
//! coupling row of the pending block, and expansion goes on from that block. Restarting is
//! also when convergence is checked, on the true residuals `S x - lambda B x` of the kept
//! Ritz vectors (sparse products only), so the reported accuracy never depends on the
//! accuracy of the solves or of the Krylov relation. The eigenvalues returned are the
//! Rayleigh quotients `x^T S x / x^T B x`.
//!
//! Converged pairs are locked (when [`Sizes::lock`] is set; the caller sets it from
//! k = 100): once a Ritz pair of the converged prefix has a residual estimate below a
//! tenth of the tolerance, its vector stays at the front of `V`, is no longer rotated at
//! restarts nor part of the projected eigenproblem, and its coupling to later blocks (of
//! the size of its residual) is dropped from `T`; new blocks are still orthogonalized
//! against it. Measured at k = 500 on 26k vertices: locking alone saves about 10% of the
//! time, locking with the Lanczos step 1.7x. The final check on the true residuals covers
//! locked pairs too; should one fail, the caller runs the plain iteration (no locking,
//! two full passes) instead.
//!
//! Directions that become numerically dependent (an invariant subspace was found, or `k`
//! is close to `n`) are replaced by random directions (Op applied to random vectors) B-orthogonal to the basis, so
//! eigenvalues missing from the start block can still enter the space.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};

use super::eigen::matmul_rows;
use super::eigen::{
    EigenProgress, LEAF_ROWS, PartialEigen, Rng, SparseEigenError, gram, package, residuals_from,
    sub_product, sym_eig, sym_spmm, sym_spmm_into,
};
use super::timing::{Phase, timed};
use super::{SparseCholesky, SparseMatrix, scratch};

/// The factored problem the iteration works on.
pub(super) struct Problem<'a> {
    pub s: &'a SparseMatrix,
    pub b: &'a SparseMatrix,
    pub chol: &'a SparseCholesky,
    pub shift: f64,
    pub k: usize,
    pub tol: f64,
    pub sn: f64,
    pub bn: f64,
}

/// Sizes of the iteration.
pub(super) struct Sizes {
    /// Block size.
    pub block: usize,
    /// Largest basis dimension before a restart.
    pub max_basis: usize,
    /// Restart cap.
    pub max_restarts: usize,
    /// Lock converged pairs (see the `nl` columns in [`krylov_schur`]).
    pub lock: bool,
    /// Lanczos step: subtract the known coefficients of `Op Q` before one full
    /// reorthogonalization pass, instead of two full classical Gram-Schmidt passes.
    pub local: bool,
}

/// A converged Ritz pair is locked when its residual estimate is below this fraction of
/// the tolerance: a margin, because a locked pair is never improved again.
const LOCK_FRACTION: f64 = 0.1;

/// A second Gram-Schmidt pass is made when a column keeps less than this fraction of its
/// squared B-norm after the first: the classical "twice is enough" test (Daniel, Gragg,
/// Kaufman and Stewart, with 1/sqrt(2) on the norm). A looser test (one pass unless
/// 1e-4 of the norm is left) let rounding errors build up over restarts on a sphere
/// (residuals stalled near 1e-10), so in practice two passes are made.
const SECOND_PASS_FRACTION: f64 = 0.5;

/// `sum_i w_i * (B w)_i` per column.
fn col_dots(w: &[f64], bw: &[f64], n: usize, c: usize) -> Vec<f64> {
    (0..c)
        .map(|j| {
            w[j * n..(j + 1) * n]
                .iter()
                .zip(&bw[j * n..(j + 1) * n])
                .map(|(a, b)| a * b)
                .sum()
        })
        .collect()
}

/// `B W` for the `c` columns of `w`, in a scratch buffer; `given`, when it already holds
/// `B W` (right size), is used instead (saves one sparse product), and a buffer of the
/// wrong size is handed back to the pool.
fn b_times(b: &SparseMatrix, w: &[f64], n: usize, c: usize, given: Option<Vec<f64>>) -> Vec<f64> {
    match given {
        Some(bw) if bw.len() == n * c => bw,
        other => {
            if let Some(o) = other {
                scratch::give(o);
            }
            let mut bw = scratch::take(n * c);
            sym_spmm_into(b, &w[..n * c], c, &mut bw);
            bw
        }
    }
}

/// One classical Gram-Schmidt pass: `W -= V (V^T B W)`; returns `V^T B W`. `bw_given`,
/// when present, is `B W` (saves one sparse product; handed back to the scratch pool).
fn project_once(
    w: &mut [f64],
    v: &[f64],
    n: usize,
    j: usize,
    c: usize,
    b: &SparseMatrix,
    bw_given: Option<Vec<f64>>,
) -> Mat<f64> {
    if j == 0 || c == 0 {
        if let Some(bw) = bw_given {
            scratch::give(bw);
        }
        return Mat::zeros(j, c);
    }
    let coef = timed(Phase::Gram, || {
        let bw = b_times(b, w, n, c, bw_given);
        let coef = gram(&v[..n * j], &bw, n, j, c);
        scratch::give(bw);
        coef
    });
    timed(Phase::Update, || {
        sub_product(&mut w[..n * c], v, coef.as_ref(), n)
    });
    coef
}

/// SVQB on the `c` columns of `w`: `W = Q Rq` with `Q` B-orthonormal (`kept` columns,
/// written to the front of `w`) and `Rq` (`kept x c`). The Gram matrix is scaled to unit
/// diagonal before its eigen-decomposition (so columns of very different norms keep their
/// relative accuracy) and the orthonormalization is repeated once when the first pass
/// may leave `|Q^T B Q - I|` above about `1e-12` (an ill-conditioned Gram matrix). Also
/// returns the smallest squared B-norm of the input columns. `bw_given`, when present, is
/// `B W` for the input (saves one sparse product). Columns whose squared B-norm is below `floor2`
/// (absolute), and directions below `1e-14` of the largest (relative, after scaling), are
/// dropped.
fn svqb_r(
    w: &mut [f64],
    n: usize,
    c: usize,
    b: &SparseMatrix,
    floor2: f64,
    mut bw_given: Option<Vec<f64>>,
) -> Result<(usize, Mat<f64>, f64), SparseEigenError> {
    let mut cur = c;
    let mut r = Mat::<f64>::identity(c, c);
    let mut min_diag = f64::INFINITY;
    let mut again = true;
    for pass in 0..2 {
        if cur == 0 || !again {
            break;
        }
        let bw = b_times(b, w, n, cur, bw_given.take());
        let mut g = gram(&w[..n * cur], &bw, n, cur, cur);
        if pass == 0 {
            min_diag = (0..cur).map(|i| g[(i, i)]).fold(f64::INFINITY, f64::min);
        }
        let mut d = vec![0.0; cur];
        for (i, di) in d.iter_mut().enumerate() {
            let gii = g[(i, i)];
            if !gii.is_finite() {
                return Err(SparseEigenError::NonFinite);
            }
            *di = if gii > floor2 && gii > 0.0 {
                1.0 / gii.sqrt()
            } else {
                0.0
            };
        }
        for j in 0..cur {
            for i in 0..cur {
                g[(i, j)] *= d[i] * d[j];
            }
        }
        for j in 0..cur {
            for i in 0..j {
                let a = 0.5 * (g[(i, j)] + g[(j, i)]);
                g[(i, j)] = a;
                g[(j, i)] = a;
            }
        }
        let (lam, u) = sym_eig(g.as_ref())?;
        let lmax = lam.iter().cloned().fold(0.0, f64::max);
        let keep: Vec<usize> = (0..cur)
            .rev()
            .filter(|&i| lmax > 0.0 && lam[i] > 1e-14 * lmax)
            .collect();
        let kept = keep.len();
        // One pass leaves |Q^T B Q - I| ~ eps * cond(G); repeat when that may exceed 1e-12.
        let lmin_kept = keep.last().map_or(0.0, |&i| lam[i]);
        again = lmin_kept < 1e-4 * lmax;
        // W = Q Rq with Q = W D U_k L^-1/2, Rq = L^1/2 U_k^T D^-1 (on the kept columns).
        let mut coef = Mat::<f64>::zeros(cur, kept);
        let mut rq = Mat::<f64>::zeros(kept, cur);
        for (jj, &j) in keep.iter().enumerate() {
            let sq = lam[j].sqrt();
            for i in 0..cur {
                coef[(i, jj)] = d[i] * u[(i, j)] / sq;
                rq[(jj, i)] = if d[i] > 0.0 {
                    u[(i, j)] * sq / d[i]
                } else {
                    0.0
                };
            }
        }
        scratch::give(bw);
        let mut q = scratch::take(n * kept);
        if kept > 0 {
            matmul_rows(
                MatMut::from_column_major_slice_mut(&mut q, n, kept),
                Accum::Replace,
                super::eigen::view(&w[..n * cur], n, cur),
                coef.as_ref(),
                1.0,
            );
        }
        w[..n * kept].copy_from_slice(&q);
        scratch::give(q);
        let mut r2 = Mat::<f64>::zeros(kept, c);
        matmul(
            r2.as_mut(),
            Accum::Replace,
            rq.as_ref(),
            r.as_ref(),
            1.0,
            Par::Seq,
        );
        r = r2;
        cur = kept;
    }
    Ok((cur, r, min_diag))
}

/// What a Lanczos step needs to know about a new block `W = Op Q` (see [`orthonormalize`]).
struct LanczosStep {
    /// First column of `V` with a known nonzero coefficient.
    r0: usize,
    /// The known coefficients on columns `r0..j - c` (the coupling row, transposed).
    known: Mat<f64>,
    /// `B Q` (`n x c`, column-major; from the scratch pool).
    bq: Vec<f64>,
}

/// Turns the `c` columns stored at `v[n j ..]` (the block `W`) into a B-orthonormal block
/// `Q` orthogonal to `V = v[:, :j]`, with `W = V C + Q R`. Returns `(C, R, q)` where `q`
/// is the column count of `Q` (`R` is `q x c`). Directions of `W` that are numerically in
/// the span of `V` are replaced by random ones (zero rows of `R`), as long as the space
/// has room.
#[allow(clippy::too_many_arguments)]
fn orthonormalize(
    v: &mut [f64],
    n: usize,
    j: usize,
    c: usize,
    b: &SparseMatrix,
    chol: &SparseCholesky,
    rng: &mut Rng,
    solves: &mut usize,
    local: Option<LanczosStep>,
) -> Result<(Mat<f64>, Mat<f64>, usize), SparseEigenError> {
    let (basis, rest) = v.split_at_mut(n * j);
    let w = &mut rest[..n * c];
    // Classical Gram-Schmidt: W_in = V C + W, with a second pass when the first removed
    // much of some column (see SECOND_PASS_FRACTION).
    let mut coef = Mat::<f64>::zeros(j, c);
    let local = local.filter(|l| {
        j >= c
            && l.r0 + c <= j
            && l.known.nrows() == j - c - l.r0
            && l.known.ncols() == c
            && l.bq.len() == n * c
    });
    let pre: Vec<f64>;
    let mut bw_now = None;
    if let Some(LanczosStep { r0, known, bq }) = local {
        // A Lanczos step: W = Op Q for the last block Q = V[:, j - c..j], whose
        // coefficients on the earlier columns are known (`known`, rows r0..j - c; zero
        // before r0), and on Q itself are A = Q^T B W = (B Q)^T W (B Q is kept from the
        // product that made W). Subtracting them removes the bulk of W at the cost of a
        // few blocks; one full pass then reorthogonalizes against all of V (with a second
        // when it still removed much: DGKS).
        let q0 = j - c;
        let cl = timed(Phase::Local, || {
            let a = gram(&bq, w, n, c, c);
            scratch::give(bq);
            let mut cl = Mat::<f64>::zeros(j - r0, c);
            for cc in 0..c {
                for i in 0..q0 - r0 {
                    cl[(i, cc)] = known[(i, cc)];
                }
                for i in 0..c {
                    cl[(q0 - r0 + i, cc)] = a[(i, cc)];
                }
            }
            sub_product(w, &basis[n * r0..], cl.as_ref(), n);
            for cc in 0..c {
                for i in 0..j - r0 {
                    coef[(r0 + i, cc)] += cl[(i, cc)];
                }
            }
            cl
        });
        let (pre1, c2) = timed(Phase::Gram, || {
            let bw1 = b_times(b, w, n, c, None);
            let pre1 = col_dots(w, &bw1, n, c);
            let c2 = gram(&basis[..n * j], &bw1, n, j, c);
            scratch::give(bw1);
            (pre1, c2)
        });
        // The squared B-norms of the input: what the step removed (on B-orthonormal
        // columns) plus what it left.
        pre = (0..c)
            .map(|cc| pre1[cc] + (0..j - r0).map(|i| cl[(i, cc)] * cl[(i, cc)]).sum::<f64>())
            .collect();
        timed(Phase::Update, || sub_product(w, basis, c2.as_ref(), n));
        // Squared B-norms left (V is B-orthonormal): pre1 - sum_i c2_i^2.
        let lost = (0..c).any(|cc| {
            let removed: f64 = (0..j).map(|i| c2[(i, cc)] * c2[(i, cc)]).sum();
            pre1[cc] - removed < SECOND_PASS_FRACTION * pre1[cc]
        });
        coef += c2;
        if lost {
            coef += project_once(w, basis, n, j, c, b, None);
        }
    } else {
        let (bw, p) = timed(Phase::Norms, || {
            let bw = b_times(b, w, n, c, None);
            let p = col_dots(w, &bw, n, c);
            (bw, p)
        });
        pre = p;
        bw_now = Some(bw);
        if j > 0 {
            coef += project_once(w, basis, n, j, c, b, bw_now.take());
            let bw1 = timed(Phase::Gram, || b_times(b, w, n, c, None));
            let after = col_dots(w, &bw1, n, c);
            let lost = after
                .iter()
                .zip(&pre)
                .any(|(&a, &p)| a < SECOND_PASS_FRACTION * p);
            if lost {
                let c2 = gram(&basis[..n * j], &bw1, n, j, c);
                scratch::give(bw1);
                sub_product(w, basis, c2.as_ref(), n);
                coef += c2;
            } else {
                bw_now = Some(bw1);
            }
        }
    }
    if pre.iter().any(|p| !p.is_finite()) {
        return Err(SparseEigenError::NonFinite);
    }
    let pre_max = pre.iter().cloned().fold(0.0, f64::max);
    let (kept, rq, min_diag) = timed(Phase::Svqb, || svqb_r(w, n, c, b, 1e-20 * pre_max, bw_now))?;
    let mut r = rq;
    let mut cur = kept;
    if j > 0 && cur > 0 && min_diag < 1e-6 * pre_max {
        // The block lost most of its norm to the projection: rounding in the two passes
        // matters, so project the orthonormalized block once more (W_in = V (C + Cp R) + Q R).
        let cp = project_once(w, basis, n, j, cur, b, None);
        let mut add = Mat::<f64>::zeros(j, c);
        matmul(
            add.as_mut(),
            Accum::Replace,
            cp.as_ref(),
            r.as_ref(),
            1.0,
            Par::Seq,
        );
        coef += add;
        let (kept2, rq2, _) = svqb_r(w, n, cur, b, 0.0, None)?;
        let mut r2 = Mat::<f64>::zeros(kept2, c);
        matmul(
            r2.as_mut(),
            Accum::Replace,
            rq2.as_ref(),
            r.as_ref(),
            1.0,
            Par::Seq,
        );
        r = r2;
        cur = kept2;
    }
    // Refill dropped directions with random ones (not part of W_in: zero rows of R).
    let room = n.saturating_sub(j);
    let want = c.min(room);
    if cur < want {
        let extra = want - cur;
        let mut filled = 0;
        for _attempt in 0..3 {
            let need = extra - filled;
            if need == 0 {
                break;
            }
            let start = cur + filled;
            // Op applied to random vectors (in the range of Op, like the whole basis).
            let rnd: Vec<f64> = (0..n * need).map(|_| rng.next_f64()).collect();
            let mut brnd = sym_spmm(b, &rnd, need);
            chol.solve_many_in_place(&mut brnd, need);
            *solves += need;
            w[n * start..n * (start + need)].copy_from_slice(&brnd);
            let pre_t = {
                let tail = &w[n * start..n * (start + need)];
                let bt = sym_spmm(b, tail, need);
                col_dots(tail, &bt, n, need).into_iter().fold(0.0, f64::max)
            };
            for _ in 0..2 {
                project_once(
                    &mut w[n * start..n * (start + need)],
                    basis,
                    n,
                    j,
                    need,
                    b,
                    None,
                );
                // Against the columns of Q found so far.
                let (qpart, tpart) = w.split_at_mut(n * start);
                project_once(&mut tpart[..n * need], qpart, n, start, need, b, None);
            }
            let tail = &mut w[n * start..n * (start + need)];
            let (got, _, _) = svqb_r(tail, n, need, b, 1e-20 * pre_t, None)?;
            filled += got;
        }
        let total = cur + filled;
        let mut r3 = Mat::<f64>::zeros(total, c);
        for i in 0..cur {
            for q in 0..c {
                r3[(i, q)] = r[(i, q)];
            }
        }
        r = r3;
        cur = total;
    }
    Ok((coef, r, cur))
}

/// Rayleigh quotients `x^T S x / x^T B x` and relative residuals (see
/// [`super::relative_residuals`]) of the columns `cols` of the column-major `v`, 8
/// columns at a time (small temporaries). `fallback[i]` gives the eigenvalue of column
/// `cols[i]` when its `x^T B x = 0`.
fn true_residuals(
    pb: &Problem<'_>,
    v: &[f64],
    cols: &[usize],
    fallback: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let n = pb.s.ncols();
    let c = cols.len();
    let mut lam = Vec::with_capacity(c);
    let mut res = Vec::with_capacity(c);
    let width = 8.min(c);
    let mut xs = vec![0.0; n * width];
    let mut sx = vec![0.0; n * width];
    let mut bx = vec![0.0; n * width];
    let mut done = 0;
    while done < c {
        let w = (c - done).min(8);
        for (q, &col) in cols[done..done + w].iter().enumerate() {
            xs[q * n..(q + 1) * n].copy_from_slice(&v[col * n..(col + 1) * n]);
        }
        let xs = &xs[..n * w];
        sym_spmm_into(pb.s, xs, w, &mut sx);
        sym_spmm_into(pb.b, xs, w, &mut bx);
        let mut l = Vec::with_capacity(w);
        for q in 0..w {
            let col = &xs[q * n..(q + 1) * n];
            let num: f64 = col
                .iter()
                .zip(&sx[q * n..(q + 1) * n])
                .map(|(a, b)| a * b)
                .sum();
            let den: f64 = col
                .iter()
                .zip(&bx[q * n..(q + 1) * n])
                .map(|(a, b)| a * b)
                .sum();
            l.push(if den > 0.0 {
                num / den
            } else {
                fallback[done + q]
            });
        }
        res.extend(residuals_from(
            &sx[..n * w],
            &bx[..n * w],
            xs,
            &l,
            n,
            pb.sn,
            pb.bn,
        ));
        lam.extend(l);
        done += w;
    }
    (lam, res)
}

/// `V[:, :p] = V[:, :m] Y` in place (`Y` is `m x p`, `p <= m`), row block by row block.
fn rotate_in_place(v: &mut [f64], n: usize, m: usize, y: MatRef<'_, f64>) {
    if n == 0 || m == 0 || y.ncols() == 0 {
        return;
    }
    let vm = MatMut::from_column_major_slice_mut(&mut v[..n * m], n, m);
    rotate_rec(vm, y);
}

fn rotate_rec(mut vm: MatMut<'_, f64>, y: MatRef<'_, f64>) {
    let rows = vm.nrows();
    if rows <= LEAF_ROWS {
        let p = y.ncols();
        let mut buf = scratch::take(rows * p);
        let mut tmp = MatMut::from_column_major_slice_mut(&mut buf, rows, p);
        matmul(tmp.as_mut(), Accum::Replace, vm.as_ref(), y, 1.0, Par::Seq);
        vm.as_mut().submatrix_mut(0, 0, rows, p).copy_from(&tmp);
        scratch::give(buf);
        return;
    }
    let mid = (rows / 2).next_multiple_of(64).min(rows);
    let (a, bm) = vm.split_at_row_mut(mid);
    rayon::join(|| rotate_rec(a, y), || rotate_rec(bm, y));
}

/// A converged solve whose eigenvectors are still columns of the Krylov basis. Copying
/// them out holds the basis and the result at once, the peak memory of a solve, so the
/// caller first frees the factorization and the scratch buffers, whose memory the copy
/// then reuses. Measured at 411k vertices, k = 50: the copy had raised the peak by 131
/// MiB, above SciPy's; now it adds nothing.
pub(super) struct Converged {
    basis: Vec<f64>,
    n: usize,
    /// The basis columns of the pairs, in ascending eigenvalue order.
    cols: Vec<usize>,
    values: Vec<f64>,
    residuals: Vec<f64>,
    iterations: usize,
    solves: usize,
    shift: f64,
}

impl Converged {
    /// Copies the eigenvectors out of the basis, frees it, and measures and reports the
    /// result (see [`package`]).
    pub(super) fn finish(
        self,
        b: &SparseMatrix,
        progress: &mut dyn FnMut(EigenProgress),
    ) -> PartialEigen {
        let n = self.n;
        let mut vectors = Vec::with_capacity(n * self.cols.len());
        for &c in &self.cols {
            vectors.extend_from_slice(&self.basis[c * n..(c + 1) * n]);
        }
        drop(self.basis);
        super::timing::report();
        package(
            b,
            (self.values, vectors, self.residuals),
            self.iterations,
            self.solves,
            self.shift,
            progress,
        )
    }
}

/// The `k` smallest pairs by block Krylov-Schur (see the module documentation).
pub(super) fn krylov_schur(
    pb: &Problem<'_>,
    sizes: &Sizes,
    rng: &mut Rng,
    progress: &mut dyn FnMut(EigenProgress),
) -> Result<Converged, SparseEigenError> {
    let (s, b, chol) = (pb.s, pb.b, pb.chol);
    let n = s.ncols();
    let k = pb.k;
    let bs = sizes.block.clamp(1, n);
    let m_max = sizes.max_basis.clamp(k.min(n), n);
    // Storage: the basis plus room for one pending block.
    let mut v = vec![0.0; n * (m_max + bs).min(n + bs)];
    let mut t = Mat::<f64>::zeros(m_max + bs, m_max + bs);
    let mut j = 0usize;
    let mut expansions = 0usize;
    let mut nconv = 0usize;

    // Start block: Op applied to a random block, B-orthonormal. Every basis vector is
    // then in the range of Op, whose high-frequency components are damped by
    // theta ~ 1 / lambda: a random start would leave white noise in the Ritz vectors that
    // the residual of S (weighted by lambda_max) sees but the residual of Op does not.
    let start = std::time::Instant::now();
    let mut w: Vec<f64> = (0..n * bs).map(|_| rng.next_f64()).collect();
    let mut bw = sym_spmm(b, &w, bs);
    chol.solve_many_in_place(&mut bw, bs);
    w = bw;
    v[..n * bs].copy_from_slice(&w);
    drop(w);
    let mut solves = bs;
    let (_, _, mut qc) = orthonormalize(&mut v, n, 0, bs, b, chol, rng, &mut solves, None)?;
    // Op V = V T + Q R_row (Q the pending block, R_row its coupling, qc x j).
    let mut rrow = Mat::<f64>::zeros(qc, 0);
    super::timing::add(Phase::Start, start.elapsed());
    let mut restarts = 0usize;

    // Locked pairs: the first `nl` columns of V are converged Ritz vectors, decoupled
    // from the iteration (T is diagonal there and their coupling to later blocks, which
    // is of the size of their residual, is dropped). New blocks are still orthogonalized
    // against them, but restarts no longer rotate them nor include them in the projected
    // eigenproblem.
    let mut nl = 0usize;
    loop {
        let full_space = j + qc > n || qc == 0;
        if j + qc > m_max || full_space {
            // ---- Restart and convergence check ----
            let m = j;
            let ma = m - nl;
            let mut tm = Mat::<f64>::zeros(ma, ma);
            for c in 0..ma {
                for r in 0..ma {
                    tm[(r, c)] = 0.5 * (t[(nl + r, nl + c)] + t[(nl + c, nl + r)]);
                }
            }
            let (theta_asc, y_asc) = timed(Phase::Eig, || sym_eig(tm.as_ref()))?;
            // Descending theta = ascending lambda.
            let theta_a: Vec<f64> = theta_asc.iter().rev().cloned().collect();
            let mut y = Mat::<f64>::zeros(ma, ma);
            for c in 0..ma {
                for r in 0..ma {
                    y[(r, c)] = y_asc[(r, ma - 1 - c)];
                }
            }
            let keep = if full_space {
                m
            } else {
                (k + (m_max - k) / 2)
                    .max(nconv + bs)
                    .min(m_max.saturating_sub(qc).max(k.min(m)))
                    .min(m)
            };
            let keep_a = keep.saturating_sub(nl).max(bs.min(ma)).min(ma);
            let total = nl + keep_a;
            // Residual estimates without touching the n-vectors: with Op V = V T + Q R_row
            // and x = V y, S x - lambda B x = -(1/theta) K Q (R_row y), so
            // ||S x - lambda B x||^2 = u^T (Z^T Z) u / theta^2 with Z = K Q, u = R_row y.
            // (R_row is zero on the locked columns.)
            let mut rho = Mat::<f64>::zeros(qc, ma);
            if qc > 0 && ma > 0 {
                matmul(
                    rho.as_mut(),
                    Accum::Replace,
                    rrow.as_ref().submatrix(0, nl, qc, ma),
                    y.as_ref(),
                    1.0,
                    Par::Seq,
                );
            }
            let gz = timed(Phase::Estimate, || {
                if qc > 0 {
                    let q = &v[n * m..n * (m + qc)];
                    let mut z = sym_spmm(s, q, qc);
                    let bq = sym_spmm(b, q, qc);
                    for (zi, bi) in z.iter_mut().zip(&bq) {
                        *zi -= pb.shift * bi;
                    }
                    gram(&z, &z, n, qc, qc)
                } else {
                    Mat::<f64>::zeros(0, 0)
                }
            });
            timed(Phase::Rotate, || {
                rotate_in_place(
                    &mut v[n * nl..],
                    n,
                    ma,
                    y.as_ref().submatrix(0, 0, ma, keep_a),
                )
            });
            let theta_all: Vec<f64> = (0..nl)
                .map(|c| t[(c, c)])
                .chain(theta_a[..keep_a].iter().cloned())
                .collect();
            let lam_est: Vec<f64> = theta_all.iter().map(|&th| pb.shift + 1.0 / th).collect();
            // Columns in ascending lambda (locked and active interleave; the active ones
            // keep their own order).
            let mut ord: Vec<usize> = (0..total).collect();
            ord.sort_by(|&a, &c| lam_est[a].total_cmp(&lam_est[c]));
            let est_of = |col: usize| -> f64 {
                if col < nl {
                    return 0.0;
                }
                let i = col - nl;
                let mut q2 = 0.0;
                for a in 0..qc {
                    for c in 0..qc {
                        q2 += rho[(a, i)] * gz[(a, c)] * rho[(c, i)];
                    }
                }
                let r = q2.max(0.0).sqrt() / theta_a[i].abs();
                let xn = v[col * n..(col + 1) * n]
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt();
                let den = (pb.sn + lam_est[col].abs() * pb.bn) * xn;
                if den > 0.0 { r / den } else { r }
            };
            // The wanted pairs plus the rest of a cluster cut by k: `end` is the first
            // Ritz value clearly above lambda_k. It must itself be accurate enough to be
            // placed (its Ritz value error is about the square of its residual).
            let gap_of = |lk: f64| 1e-3 * lk.abs() + 1e-10 * pb.sn / pb.bn.max(f64::MIN_POSITIVE);
            let lk = lam_est[ord[k.min(total) - 1]];
            let end = (k..total).find(|&p| lam_est[ord[p]] > lk + gap_of(lk));
            // Estimates in order, up to the first one that fails (or `end`).
            let upto = end.unwrap_or(total.min(k + bs.max(k / 5)));
            let mut ests = Vec::with_capacity(upto);
            nconv = 0;
            while nconv < upto {
                let e = est_of(ord[nconv]);
                if !e.is_finite() {
                    return Err(SparseEigenError::NonFinite);
                }
                if e > pb.tol && !full_space {
                    break;
                }
                ests.push(e);
                nconv += 1;
            }
            let est_end = match end {
                Some(e) if nconv >= e => est_of(ord[e]),
                _ => f64::INFINITY,
            };
            restarts += 1;
            progress(EigenProgress::Iteration {
                iteration: expansions,
                converged: nconv.min(k),
                wanted: k,
                basis: m,
            });
            let ready = match end {
                _ if full_space || keep >= n => nconv >= k,
                Some(e) => nconv >= e && est_end <= pb.tol.sqrt(),
                None => false,
            };
            if ready {
                // Confirm on the true residuals of the pairs up to `end`.
                let nres = end.unwrap_or(k).max(k).min(total);
                let cols = &ord[..nres];
                let fallback: Vec<f64> = cols.iter().map(|&c| lam_est[c]).collect();
                let (lam, res) = timed(Phase::Residual, || true_residuals(pb, &v, cols, &fallback));
                if res.iter().any(|r| !r.is_finite()) {
                    return Err(SparseEigenError::NonFinite);
                }
                let good = res
                    .iter()
                    .take_while(|&&r| r <= pb.tol || full_space)
                    .count();
                if good >= nres {
                    // Sort the first k (Rayleigh quotients may swap inside a tight cluster).
                    let mut order: Vec<usize> = (0..k).collect();
                    order.sort_by(|&a, &c| lam[a].total_cmp(&lam[c]));
                    return Ok(Converged {
                        basis: v,
                        n,
                        cols: order.iter().map(|&p| cols[p]).collect(),
                        values: order.iter().map(|&p| lam[p]).collect(),
                        residuals: order.iter().map(|&p| res[p]).collect(),
                        iterations: expansions,
                        solves,
                        shift: pb.shift,
                    });
                }
                if cols[good] < nl {
                    // A locked pair failed its true residual (its estimate was wrong);
                    // locked columns never change, so give up here and let the caller
                    // run again without locking.
                    return Err(SparseEigenError::NoConvergence {
                        converged: good.min(k),
                        wanted: k,
                        iterations: expansions,
                    });
                }
                nconv = good;
            }
            if restarts > sizes.max_restarts || full_space {
                return Err(SparseEigenError::NoConvergence {
                    converged: nconv.min(k),
                    wanted: k,
                    iterations: expansions,
                });
            }
            // Lock the active columns of the converged prefix whose estimate is well
            // below the tolerance (a prefix of the active columns, which are in ascending
            // lambda), leaving at least two blocks of active columns.
            let mut a_lock = 0usize;
            if sizes.lock {
                for (p, &c) in ord[..nconv.min(ests.len())].iter().enumerate() {
                    if c < nl {
                        continue;
                    }
                    if ests[p] > LOCK_FRACTION * pb.tol {
                        break;
                    }
                    a_lock += 1;
                }
                a_lock = a_lock.min(keep.saturating_sub(2 * bs).saturating_sub(nl));
            }
            // New projected matrix: diag(theta); the coupling of the pending block to the
            // kept Ritz vectors enters T when that block is expanded (its projection
            // coefficients), and R_row becomes rho restricted to the kept active columns.
            t.fill(0.0);
            for (c, &th) in theta_all.iter().enumerate() {
                t[(c, c)] = th;
            }
            let nl_new = nl + a_lock;
            let mut rr = Mat::<f64>::zeros(qc, total);
            for c in nl_new..total {
                for a in 0..qc {
                    rr[(a, c)] = rho[(a, c - nl)];
                }
            }
            rrow = rr;
            // Move the pending block behind the kept vectors.
            v.copy_within(n * m..n * (m + qc), n * total);
            j = total;
            nl = nl_new;
            continue;
        }

        // ---- Expansion: absorb the pending block, multiply it by Op ----
        let j0 = j;
        j += qc;
        let c = qc;
        // B Q is kept for the Lanczos step (its A = (B Q)^T W).
        let bq = {
            let (done, rest) = v.split_at_mut(n * j);
            let w = &mut rest[..n * c];
            timed(Phase::Op, || {
                sym_spmm_into(b, &done[n * j0..n * j], c, w);
                let bq = sizes.local.then(|| {
                    let mut bq = scratch::take(n * c);
                    bq.copy_from_slice(w);
                    bq
                });
                chol.solve_many_in_place(w, c);
                bq
            })
        };
        solves += c;
        expansions += 1;
        // Op V = V T + Q R_row: the coefficients of Op Q on the earlier columns are
        // R_row^T (zero before its first nonzero column r0).
        let local = if let Some(bq) = bq {
            let r0 = (0..j0)
                .find(|&col| (0..c).any(|a| rrow[(a, col)] != 0.0))
                .unwrap_or(j0);
            let mut known = Mat::<f64>::zeros(j0 - r0, c);
            for cc in 0..c {
                for i in 0..j0 - r0 {
                    known[(i, cc)] = rrow[(cc, r0 + i)];
                }
            }
            Some(LanczosStep { r0, known, bq })
        } else {
            None
        };
        let (coef, r, q) = orthonormalize(&mut v, n, j, c, b, chol, rng, &mut solves, local)?;
        for cc in 0..c {
            for rr in 0..j {
                let val = coef[(rr, cc)];
                if !val.is_finite() {
                    return Err(SparseEigenError::NonFinite);
                }
                // Coupling to locked columns is dropped (see `nl`).
                let val = if rr < nl { 0.0 } else { val };
                t[(rr, j0 + cc)] = val;
                t[(j0 + cc, rr)] = val;
            }
        }
        for cc in 0..c {
            for rr in 0..cc {
                let a = 0.5 * (coef[(j0 + rr, cc)] + coef[(j0 + cc, rr)]);
                t[(j0 + rr, j0 + cc)] = a;
                t[(j0 + cc, j0 + rr)] = a;
            }
        }
        let mut nr = Mat::<f64>::zeros(q, j);
        for cc in 0..c {
            for rr in 0..q {
                nr[(rr, j0 + cc)] = r[(rr, cc)];
            }
        }
        rrow = nr;
        qc = q;
        if expansions.is_multiple_of(2) {
            progress(EigenProgress::Iteration {
                iteration: expansions,
                converged: nconv.min(k),
                wanted: k,
                basis: j,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::eigen::norm1;
    use crate::operators::{Laplacian, Operators};

    /// Locking and the Lanczos step change the work, not the answer: every combination
    /// finds the same pairs on a sphere, with blocks (4) smaller than the multiplicities
    /// (up to 11) and k = 30 cutting the 11-fold l = 5 eigenspace, and a small basis so
    /// that there are many restarts.
    #[test]
    fn locking_and_lanczos_step_agree_with_the_plain_iteration() {
        let mesh = crate::shapes::build_str("sphere:res=3").unwrap(); // 642 vertices
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let (s, b) = (&ops.stiffness, &ops.mass);
        let shift = -0.01;
        let chol = SparseCholesky::new(&s.add_scaled(1.0, b, -shift)).unwrap();
        let pb = Problem {
            s,
            b,
            chol: &chol,
            shift,
            k: 30,
            tol: 1e-10,
            sn: norm1(s),
            bn: norm1(b),
        };
        let mut runs = Vec::new();
        for (lock, local) in [(false, false), (true, false), (false, true), (true, true)] {
            let sizes = Sizes {
                block: 4,
                max_basis: 50,
                max_restarts: 500,
                lock,
                local,
            };
            let out = krylov_schur(&pb, &sizes, &mut Rng(7), &mut |_| {})
                .unwrap()
                .finish(b, &mut |_| {});
            assert!(
                out.residuals.iter().all(|&r| r <= 1e-10),
                "lock {lock} local {local}: {:?}",
                out.residuals
            );
            assert!(out.orthogonality_error < 1e-10, "lock {lock} local {local}");
            runs.push(out.values);
        }
        let scale = runs[0][29];
        // 1 + 3 + 5 + 7 + 9 = 25 pairs below the l = 5 cluster.
        assert!(runs[0][25] > 1.2 * runs[0][24]);
        for r in &runs[1..] {
            for (a, b) in r.iter().zip(&runs[0]) {
                assert!((a - b).abs() <= 1e-9 * scale, "{r:?} vs {:?}", runs[0]);
            }
        }
    }
}
