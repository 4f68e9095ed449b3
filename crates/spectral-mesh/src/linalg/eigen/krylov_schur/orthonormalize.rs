//! Orthonormalization of a new Krylov block against the basis: the Lanczos step, full
//! classical Gram-Schmidt passes (DGKS) and scaled SVQB, with random refills for
//! directions that became dependent (see the parent module).

use faer::{Accum, Mat, MatMut};

use super::super::dense::{
    col_dots, gram, matmul_rows, scaled_gram_eig, small_product, sub_product, view,
};
use super::super::kernels::{sym_spmm, sym_spmm_into};
use super::super::rng::Rng;
use super::super::types::{SparseEigenError, check};
use super::Problem;
use crate::linalg::timing::{Phase, timed};
use crate::linalg::{SparseMatrix, scratch};

/// A second Gram-Schmidt pass is made when a column keeps less than this fraction of its
/// squared B-norm after the first: the classical "twice is enough" test (Daniel, Gragg,
/// Kaufman and Stewart, with 1/sqrt(2) on the norm). A looser test (one pass unless
/// 1e-4 of the norm is left) let rounding errors build up over restarts on a sphere
/// (residuals stalled near 1e-10), so in practice two passes are made.
const SECOND_PASS_FRACTION: f64 = 0.5;

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
        let g = gram(&w[..n * cur], &bw, n, cur, cur);
        if pass == 0 {
            min_diag = (0..cur).map(|i| g[(i, i)]).fold(f64::INFINITY, f64::min);
        }
        let (d, lam, u, lmax) = scaled_gram_eig(g, floor2)?;
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
                view(&w[..n * cur], n, cur),
                coef.as_ref(),
                1.0,
            );
        }
        w[..n * kept].copy_from_slice(&q);
        scratch::give(q);
        r = small_product(rq.as_ref(), r.as_ref());
        cur = kept;
    }
    Ok((cur, r, min_diag))
}

/// What a Lanczos step needs to know about a new block `W = Op Q` (see [`orthonormalize`]).
pub(super) struct LanczosStep {
    /// First column of `V` with a known nonzero coefficient.
    pub(super) r0: usize,
    /// The known coefficients on columns `r0..j - c` (the coupling row, transposed).
    pub(super) known: Mat<f64>,
    /// `B Q` (`n x c`, column-major; from the scratch pool).
    pub(super) bq: Vec<f64>,
}

/// Turns the `c` columns stored at `v[n j ..]` (the block `W`) into a B-orthonormal block
/// `Q` orthogonal to `V = v[:, :j]`, with `W = V C + Q R`. Returns `(C, R, q)` where `q`
/// is the column count of `Q` (`R` is `q x c`). Directions of `W` that are numerically in
/// the span of `V` are replaced by random ones (zero rows of `R`), as long as the space
/// has room.
#[allow(clippy::too_many_arguments)]
pub(super) fn orthonormalize(
    v: &mut [f64],
    n: usize,
    j: usize,
    c: usize,
    pb: &Problem<'_>,
    rng: &mut Rng,
    solves: &mut usize,
    local: Option<LanczosStep>,
) -> Result<(Mat<f64>, Mat<f64>, usize), SparseEigenError> {
    let (b, chol) = (pb.b, pb.chol);
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
    if pb.deflates() {
        // The null-space components that rounding left in the block (amplified by Op)
        // go before it is orthonormalized (its B W is then stale).
        pb.deflate(w, c);
        if let Some(bw) = bw_now.take() {
            scratch::give(bw);
        }
    }
    let pre_max = pre.iter().cloned().fold(0.0, f64::max);
    let (kept, rq, min_diag) = timed(Phase::Svqb, || svqb_r(w, n, c, b, 1e-20 * pre_max, bw_now))?;
    let mut r = rq;
    let mut cur = kept;
    if j > 0 && cur > 0 && min_diag < 1e-6 * pre_max {
        // The block lost most of its norm to the projection: rounding in the two passes
        // matters, so project the orthonormalized block once more (W_in = V (C + Cp R) + Q R).
        let cp = project_once(w, basis, n, j, cur, b, None);
        pb.deflate(w, cur);
        coef += small_product(cp.as_ref(), r.as_ref());
        let (kept2, rq2, _) = svqb_r(w, n, cur, b, 0.0, None)?;
        r = small_product(rq2.as_ref(), r.as_ref());
        cur = kept2;
    }
    // Refill dropped directions with random ones (not part of W_in: zero rows of R).
    let room = pb.dim.min(n).saturating_sub(j);
    let want = c.min(room);
    if cur < want {
        let extra = want - cur;
        let mut filled = 0;
        for _attempt in 0..3 {
            check(pb.cancel)?;
            let need = extra - filled;
            if need == 0 {
                break;
            }
            let start = cur + filled;
            // Op applied to random vectors (in the range of Op, like the whole basis).
            let rnd: Vec<f64> = (0..n * need).map(|_| rng.next_f64()).collect();
            let mut brnd = sym_spmm(b, &rnd, need);
            chol.solve_many_in_place(&mut brnd, need);
            pb.deflate(&mut brnd, need);
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
                pb.deflate(&mut tpart[..n * need], need);
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
