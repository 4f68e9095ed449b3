//! Block Krylov-Schur (thick-restart block Lanczos) on the shift-inverted pencil.
//!
//! The operator is `Op = K^-1 B` with `K = S - sigma B`, factored once: by sparse
//! Cholesky for a shift below the spectrum (`sigma < 0`), as `L D L^T` for an interior
//! one (`sigma > 0`, about 0.6 of the wanted eigenvalues below it; see
//! [`super::ShiftInvert::for_options`]). `Op` is self-adjoint in the `B` inner product and its
//! eigenvalues are `theta = 1 / (lambda - sigma)`. Below the spectrum the wanted ones are
//! the largest; with an interior shift the wanted ones lie on both sides of `(0,
//! 1 / (lambda_(k+1) - sigma))`, where the unwanted ones crowd, and are farther from them
//! relative to its width: fewer Krylov steps per wanted pair. Either way the Ritz values
//! are ranked by the `lambda` they stand for (see `lambda_of`).
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
//! Between restarts the convergence is estimated after expansions as well (when
//! [`Sizes::early`] is set, see `converged_early`; from the start with an interior
//! shift, else once a restart leaves at most two blocks of wanted pairs; after an
//! estimate that says no, the next waits as `expansions_to_skip` says): the projected
//! eigenproblem of the basis as it stands and the same estimates, at the cost of two
//! sparse products with the pending block. Once they say the wanted pairs have converged, the iteration goes
//! to its restart at once, where the true residuals decide. So the number of solves
//! follows the tolerance instead of the size of the basis: measured on 6.5k-26k vertices
//! at k = 50, `1e-6` takes about half the solves of `1e-10`.
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

mod orthonormalize;

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};

use self::orthonormalize::{LanczosStep, orthonormalize};
use super::deflation::{ComponentNullSpace, DenseDeflation};
use super::dense::{LEAF_ROWS, col_dots, gram, product, small_product, sub_product, sym_eig};
use super::kernels::{residuals_from, sym_spmm, sym_spmm_into};
use super::result::{PartialEigen, package};
use super::rng::Rng;
use super::types::{EigenProgress, SparseEigenError, check};
use crate::cancel::CancelToken;
use crate::linalg::timing::{Phase, timed};
use crate::linalg::{SparseCholesky, SparseMatrix, scratch};

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
    /// Checked at every expansion, restart and row block of a rotation.
    pub cancel: &'a CancelToken,
    /// The known null space, deflated: every block is kept B-orthogonal to it (see
    /// `deflation.rs`), and `k` counts the pairs after it. `None`: nothing deflated.
    pub deflation: Option<&'a ComponentNullSpace>,
    /// Dense vectors deflated besides the indicators (see
    /// [`super::SparseEigenOptions::deflate_vectors`]).
    pub extra: Option<&'a DenseDeflation>,
    /// Dimension of the space the iteration works in: `n` minus the deflated indicators.
    pub dim: usize,
    /// Approximate eigenvectors to start from (`n x m`, column-major; see
    /// [`super::SparseEigenOptions::start_vectors`]).
    pub start: Option<&'a [f64]>,
}

impl Problem<'_> {
    /// Projects the `c` columns of `w` on the B-orthogonal complement of the deflated
    /// null space (nothing when none is deflated). Done once per new block, after its
    /// orthogonalization against the basis (which is B-orthogonal to the null space, so
    /// leaves the null-space components alone) and before its orthonormalization: the
    /// components `Op` amplified from rounding are removed to rounding again.
    fn deflate(&self, w: &mut [f64], c: usize) {
        if let Some(d) = self.deflation {
            timed(Phase::Deflate, || d.project(w, c));
        }
        if let Some(d) = self.extra {
            timed(Phase::Deflate, || d.project(w, c));
        }
    }

    /// True when something is deflated.
    fn deflates(&self) -> bool {
        self.deflation.is_some() || self.extra.is_some()
    }
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
    /// Estimate the convergence after every expansion (not only when the basis is full)
    /// and stop expanding once the wanted pairs meet the tolerance: a looser tolerance
    /// then takes fewer solves (see `converged_early`).
    pub early: bool,
}

/// A converged Ritz pair is locked when its residual estimate is below this fraction of
/// the tolerance: a margin, because a locked pair is never improved again.
const LOCK_FRACTION: f64 = 0.1;

/// Rayleigh quotients `x^T S x / x^T B x` and relative residuals (see
/// [`crate::linalg::relative_residuals`]) of the columns `cols` of the column-major `v`, 8
/// columns at a time (small temporaries). `fallback[i]` gives the eigenvalue of column
/// `cols[i]` when its `x^T B x = 0`.
fn true_residuals(
    pb: &Problem<'_>,
    v: &[f64],
    cols: &[usize],
    fallback: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), SparseEigenError> {
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
        check(pb.cancel)?;
        let w = (c - done).min(8);
        for (q, &col) in cols[done..done + w].iter().enumerate() {
            xs[q * n..(q + 1) * n].copy_from_slice(&v[col * n..(col + 1) * n]);
        }
        let xs = &xs[..n * w];
        sym_spmm_into(pb.s, xs, w, &mut sx);
        sym_spmm_into(pb.b, xs, w, &mut bx);
        // Rayleigh quotients x^T S x / x^T B x.
        let nums = col_dots(xs, &sx, n, w);
        let dens = col_dots(xs, &bx, n, w);
        let l: Vec<f64> = (0..w)
            .map(|q| {
                if dens[q] > 0.0 {
                    nums[q] / dens[q]
                } else {
                    fallback[done + q]
                }
            })
            .collect();
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
    Ok((lam, res))
}

/// `V[:, :p] = V[:, :m] Y` in place (`Y` is `m x p`, `p <= m`), row block by row block.
/// Once `cancel` is set the remaining row blocks are skipped (`V` is then garbage) and
/// `Err(Cancelled)` is returned: at 411k vertices a rotation takes seconds.
fn rotate_in_place(
    v: &mut [f64],
    n: usize,
    m: usize,
    y: MatRef<'_, f64>,
    cancel: &CancelToken,
) -> Result<(), SparseEigenError> {
    if n == 0 || m == 0 || y.ncols() == 0 {
        return Ok(());
    }
    let vm = MatMut::from_column_major_slice_mut(&mut v[..n * m], n, m);
    rotate_rec(vm, y, cancel);
    check(cancel)
}

fn rotate_rec(mut vm: MatMut<'_, f64>, y: MatRef<'_, f64>, cancel: &CancelToken) {
    let rows = vm.nrows();
    if cancel.is_cancelled() {
        return;
    }
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
    rayon::join(|| rotate_rec(a, y, cancel), || rotate_rec(bm, y, cancel));
}

/// The eigenvalue `sigma + 1 / theta` of the pencil that a Ritz value `theta` of `Op`
/// stands for. With an interior shift (`sigma > 0`, see [`ShiftInvert`]) the spectrum of
/// `Op` has a gap, `(-1 / sigma, 0)` (it would hold eigenvalues below 0, and `S` is
/// positive semi-definite): a Ritz value there is a mixture of both sides of the
/// spectrum, not an approximation of an eigenvalue, and is ranked last (infinity) so that
/// it is never taken for a wanted pair.
///
/// [`ShiftInvert`]: super::ShiftInvert
fn lambda_of(shift: f64, theta: f64) -> f64 {
    let lam = shift + 1.0 / theta;
    if shift > 0.0 && lam < -1e-6 * shift {
        f64::INFINITY
    } else {
        lam
    }
}

/// The projected eigenproblem of the active (unlocked) columns of the basis and what the
/// residual estimates need.
struct Projection {
    /// Ritz values of `Op`, descending (so the `lambda` they give ascend).
    theta: Vec<f64>,
    /// Their eigenvectors (`ma x ma`), in that order.
    y: Mat<f64>,
    /// `R_row Y` (`qc x ma`): the coupling of each Ritz vector to the pending block.
    rho: Mat<f64>,
    /// Gram matrix `Z^T Z` of `Z = K Q` (`qc x qc`), `Q` the pending block.
    gz: Mat<f64>,
    /// Gram matrix of `B Q` (`qc x qc`).
    gb: Mat<f64>,
}

impl Projection {
    /// `u^T G u` for `u` = column `i` of `rho`.
    fn quad(&self, g: &Mat<f64>, i: usize) -> f64 {
        let qc = g.nrows();
        let mut q2 = 0.0;
        for a in 0..qc {
            for c in 0..qc {
                q2 += self.rho[(a, i)] * g[(a, c)] * self.rho[(c, i)];
            }
        }
        q2.max(0.0)
    }

    /// The relative residual estimate of the Ritz vector `x = V y` of active pair `i`
    /// (eigenvalue `lam`, Euclidean norm `xn`) itself. With `Op V = V T + Q R_row`,
    /// `S x - lambda B x = -(1/theta) K Q (R_row y)`, so
    /// `||S x - lambda B x||^2 = u^T (Z^T Z) u / theta^2` with `u = R_row y`: no n-vector
    /// is touched. Used to lock pairs (a locked vector is not purified).
    fn estimate_plain(&self, pb: &Problem<'_>, i: usize, lam: f64, xn: f64) -> f64 {
        let r = self.quad(&self.gz, i).sqrt() / self.theta[i].abs();
        let den = (pb.sn + lam.abs() * pb.bn) * xn;
        if den > 0.0 { r / den } else { r }
    }

    /// The relative residual estimate of the purified Ritz vector
    /// `x' = x + Q u / theta = Op x / theta` of active pair `i` (see [`purify`]):
    /// `(S - sigma B) x' = B x / theta` gives `S x' - lambda B x' = -B Q u / theta^2`, so
    /// `||S x' - lambda B x'||^2 = u^T ((B Q)^T B Q) u / theta^4`. The plain residual is
    /// `K Q u / theta`: `K` weighs the high frequencies the pending block carries by up to
    /// `lambda_max`, `B` does not, so the purified residual is smaller by up to
    /// `lambda / lambda_max` (ARPACK purifies its shift-invert Ritz vectors the same way).
    fn estimate(&self, pb: &Problem<'_>, i: usize, lam: f64, xn: f64) -> f64 {
        let th = self.theta[i].abs();
        let r = self.quad(&self.gb, i).sqrt() / (th * th);
        let den = (pb.sn + lam.abs() * pb.bn) * xn;
        if den > 0.0 { r / den } else { r }
    }

    /// `P = R_row Y Theta^-1` for the first `a` active pairs (`qc x a`): the
    /// coefficients of the pending block in their purified vectors.
    fn purification(&self, a: usize) -> Mat<f64> {
        let qc = self.rho.nrows();
        Mat::from_fn(qc, a, |l, i| self.rho[(l, i)] / self.theta[i])
    }
}

/// Purifies the Ritz vectors in columns `nl..nl + a` of `v` in place (`undo`: reverses
/// it): `X' = (X + Q P) (I + P^T P)^(-1/2)`, with `Q` the `qc` columns of `v` from column
/// `m` on and `P` (`qc x a`) from [`Projection::purification`]. Each `x + Q p` is
/// `Op x / theta`, one step of inverse iteration for free; since `X` and `Q` are
/// B-orthonormal and B-orthogonal to each other, `(X + Q P)^T B (X + Q P) = I + P^T P`,
/// so the second factor (a rank-`qc` update, through the eigen-decomposition of the
/// `qc x qc` matrix `P P^T`) makes the columns B-orthonormal again (Loewdin: the closest
/// B-orthonormal set).
fn purify(
    v: &mut [f64],
    n: usize,
    (nl, m): (usize, usize),
    p: &Mat<f64>,
    undo: bool,
) -> Result<(), SparseEigenError> {
    let (qc, a) = (p.nrows(), p.ncols());
    if qc == 0 || a == 0 || n == 0 {
        return Ok(());
    }
    let (front, back) = v.split_at_mut(n * m);
    let x = &mut front[n * nl..n * (nl + a)];
    let q = &back[..n * qc];
    // P^T P = W diag(s) W^T, W = P^T U diag(s)^(-1/2) from P P^T = U diag(s) U^T.
    let ppt = small_product(p.as_ref(), p.transpose());
    let (s, u) = sym_eig(ppt.as_ref())?;
    let keep: Vec<usize> = (0..qc).filter(|&l| s[l] > 1e-300).collect();
    let r = keep.len();
    let mut w = Mat::<f64>::zeros(a, r);
    let mut neg_dwt = Mat::<f64>::zeros(r, a);
    for (c, &l) in keep.iter().enumerate() {
        let sq = s[l].sqrt();
        let d = if undo {
            (1.0 + s[l]).sqrt() - 1.0
        } else {
            1.0 / (1.0 + s[l]).sqrt() - 1.0
        };
        for i in 0..a {
            let wi: f64 = (0..qc).map(|t| p[(t, i)] * u[(t, l)]).sum::<f64>() / sq;
            w[(i, c)] = wi;
            neg_dwt[(c, i)] = -d * wi;
        }
    }
    if !undo {
        // X += Q P.
        let minus_p = Mat::from_fn(qc, a, |t, i| -p[(t, i)]);
        sub_product(x, q, minus_p.as_ref(), n);
    }
    if r > 0 {
        // X += (X W) diag(d) W^T.
        let xw = product(x, w.as_ref(), n);
        sub_product(x, &xw, neg_dwt.as_ref(), n);
    }
    if undo {
        sub_product(x, q, p.as_ref(), n);
    }
    Ok(())
}

/// The projected eigenproblem of columns `nl..m` of the basis (`T` there, symmetrized)
/// and the Gram matrix of `K Q` for the `qc` columns of the pending block after them.
fn project(
    pb: &Problem<'_>,
    v: &[f64],
    t: &Mat<f64>,
    rrow: &Mat<f64>,
    nl: usize,
    m: usize,
    qc: usize,
) -> Result<Projection, SparseEigenError> {
    let (s, b) = (pb.s, pb.b);
    let n = s.ncols();
    let ma = m - nl;
    let mut tm = Mat::<f64>::zeros(ma, ma);
    for c in 0..ma {
        for r in 0..ma {
            tm[(r, c)] = 0.5 * (t[(nl + r, nl + c)] + t[(nl + c, nl + r)]);
        }
    }
    let (theta_asc, y_asc) = timed(Phase::Eig, || sym_eig(tm.as_ref()))?;
    // Ascending lambda: descending theta below the spectrum; with an interior shift
    // the values below it (theta < 0) come first (see `lambda_of`).
    let mut order: Vec<usize> = (0..ma).rev().collect();
    if pb.shift > 0.0 {
        let lam: Vec<f64> = theta_asc
            .iter()
            .map(|&th| lambda_of(pb.shift, th))
            .collect();
        order.sort_by(|&a, &c| lam[a].total_cmp(&lam[c]));
    }
    let theta: Vec<f64> = order.iter().map(|&i| theta_asc[i]).collect();
    let mut y = Mat::<f64>::zeros(ma, ma);
    for (c, &src) in order.iter().enumerate() {
        for r in 0..ma {
            y[(r, c)] = y_asc[(r, src)];
        }
    }
    let rho = small_product(rrow.as_ref().submatrix(0, nl, qc, ma), y.as_ref());
    let gz = timed(Phase::Estimate, || {
        if qc > 0 {
            let q = &v[n * m..n * (m + qc)];
            let mut z = sym_spmm(s, q, qc);
            let bq = sym_spmm(b, q, qc);
            for (zi, bi) in z.iter_mut().zip(&bq) {
                *zi -= pb.shift * bi;
            }
            (gram(&z, &z, n, qc, qc), gram(&bq, &bq, n, qc, qc))
        } else {
            (Mat::<f64>::zeros(0, 0), Mat::<f64>::zeros(0, 0))
        }
    });
    let (gz, gb) = gz;
    Ok(Projection {
        theta,
        y,
        rho,
        gz,
        gb,
    })
}

/// Where the Ritz pairs stand against the tolerance (see [`assess`]).
struct Assessment {
    /// The columns in ascending `lambda` (locked and active interleave; the active ones
    /// keep their own order).
    ord: Vec<usize>,
    /// Length of the converged prefix of `ord` (estimates `<= tol`).
    nconv: usize,
    /// The estimates of that prefix.
    ests: Vec<f64>,
    /// Position in `ord` of the first Ritz value clearly above `lambda_k`, if any.
    end: Option<usize>,
    /// The estimate at `end` once the prefix reaches it (else infinity).
    est_end: f64,
}

impl Assessment {
    /// True when the `k` wanted pairs and the rest of a cluster cut by `k` have converged
    /// (by the estimates) and the first Ritz value past them is placed (see [`assess`]).
    fn wanted_converged(&self, tol: f64) -> bool {
        match self.end {
            Some(e) => self.nconv >= e && self.est_end <= tol.sqrt(),
            None => false,
        }
    }
}

/// The converged prefix of the Ritz pairs with estimated eigenvalues `lam_est` (one per
/// column) and estimates `est_of(column)`: the wanted pairs plus the rest of a cluster
/// cut by `k`, up to `end`, the first Ritz value clearly above `lambda_k` (by
/// `1e-3 lambda_k`). That one must itself be accurate enough to be placed: its Ritz value
/// error is about the square of its residual, so its estimate must be below the square
/// root of the tolerance. With `full_space` every estimate counts as converged.
fn assess(
    pb: &Problem<'_>,
    bs: usize,
    lam_est: &[f64],
    est_of: impl Fn(usize) -> f64,
    full_space: bool,
) -> Result<Assessment, SparseEigenError> {
    let total = lam_est.len();
    let k = pb.k;
    let mut ord: Vec<usize> = (0..total).collect();
    ord.sort_by(|&a, &c| lam_est[a].total_cmp(&lam_est[c]));
    let gap_of = |lk: f64| 1e-3 * lk.abs() + 1e-10 * pb.sn / pb.bn.max(f64::MIN_POSITIVE);
    let lk = lam_est[ord[k.min(total) - 1]];
    let end = (k..total).find(|&p| lam_est[ord[p]] > lk + gap_of(lk));
    // Estimates in order, up to the first one that fails (or `end`); at most a fifth
    // of k (or a block) past k when no value is clearly above lambda_k yet.
    let upto = end.unwrap_or(total.min(k + bs.max(k / 5)));
    let mut ests = Vec::with_capacity(upto);
    let mut nconv = 0;
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
    Ok(Assessment {
        ord,
        nconv,
        ests,
        end,
        est_end,
    })
}

/// True when, by the estimates, the wanted pairs have converged in the basis as it
/// stands (columns `0..j`, `nl` of them locked, a pending block of `qc` columns): the
/// iteration then goes to its restart and confirms on the true residuals. The Euclidean
/// norms of the Ritz vectors are not computed here (that would cost a rotation); those
/// of the last restart (`xn_hints`, ascending lambda) stand in, and before the first
/// restart the lower bound `||x||_2 >= 1 / sqrt(||B||_1)` of a B-normalized vector
/// (so the estimate is then an upper bound). Cost: one projected eigenproblem of the
/// basis size and two sparse products with the pending block. Also returns the largest
/// estimate of the wanted pairs (0 when they converged).
fn converged_early(
    pb: &Problem<'_>,
    v: &[f64],
    t: &Mat<f64>,
    rrow: &Mat<f64>,
    (nl, j, qc, bs): (usize, usize, usize, usize),
    xn_hints: &[f64],
) -> Result<(bool, f64), SparseEigenError> {
    let pj = project(pb, v, t, rrow, nl, j, qc)?;
    let ma = j - nl;
    let lam_est: Vec<f64> = (0..nl)
        .map(|c| t[(c, c)])
        .chain(pj.theta[..ma].iter().cloned())
        .map(|th| lambda_of(pb.shift, th))
        .collect();
    let bound = 1.0 / pb.bn.max(f64::MIN_POSITIVE).sqrt();
    // Position of each column in ascending lambda, for its norm hint.
    let mut ord: Vec<usize> = (0..lam_est.len()).collect();
    ord.sort_by(|&a, &c| lam_est[a].total_cmp(&lam_est[c]));
    let mut pos = vec![0usize; ord.len()];
    for (p, &c) in ord.iter().enumerate() {
        pos[c] = p;
    }
    let est_of = |col: usize| -> f64 {
        if col < nl {
            return 0.0;
        }
        let xn = xn_hints.get(pos[col]).copied().unwrap_or(bound);
        pj.estimate(pb, col - nl, lam_est[col], xn)
    };
    let a = assess(pb, bs, &lam_est, est_of, false)?;
    if a.wanted_converged(pb.tol) {
        return Ok((true, 0.0));
    }
    // The largest estimate of the wanted pairs (no n-vector touched: cheap next to the
    // projection above).
    let worst = a.ord[..pb.k.min(a.ord.len())]
        .iter()
        .map(|&c| est_of(c))
        .fold(0.0, f64::max);
    Ok((false, worst))
}

/// Expansions to go without an estimate between restarts after one that found the
/// wanted pairs unconverged: `now = (expansions, largest estimate)`, `prev` the first
/// estimate since the last restart. At the rate the largest estimate fell between the
/// two, half of the expansions it still needs to reach `tol`, at most 8 (none without a
/// previous estimate or a fall). An estimate costs about the solves of a block; made
/// after every expansion from the first with k + a block columns, they took 9% of the
/// command at 26k vertices, k = 50, and mostly said no. The rate is the mean since the
/// first estimate, not the last step's: the largest estimate falls in steps with
/// plateaus, and a plateau read as the rate once skipped 8 expansions (32 solves) when
/// the tolerance was a step away (104k vertices, k = 50, `1e-4`: 108 solves; 76 now).
fn expansions_to_skip(prev: Option<(usize, f64)>, now: (usize, f64), tol: f64) -> usize {
    let (x1, e1) = now;
    let Some((x0, e0)) = prev else {
        return 0;
    };
    if x1 <= x0 || !e1.is_finite() || e1 <= 0.0 || e1 >= e0 || e1 <= tol {
        return 0;
    }
    let fall = (e1 / e0).ln() / (x1 - x0) as f64;
    let need = (tol / e1).ln() / fall;
    ((need / 2.0).floor() as usize).min(8)
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
    /// How many of the pairs have an eigenvalue below `sigma`.
    pub(super) fn count_below(&self, sigma: f64) -> usize {
        self.values.iter().filter(|&&l| l < sigma).count()
    }

    /// Copies the eigenvectors out of the basis, frees it, and measures and reports the
    /// result (see [`package`]; stops when `cancel` is set). With `null`, its indicators
    /// (eigenvalue 0) come first, merged by eigenvalue with the pairs found (which come
    /// after them unless one is negative).
    pub(super) fn finish(
        self,
        b: &SparseMatrix,
        null: Option<&ComponentNullSpace>,
        progress: &mut dyn FnMut(EigenProgress),
        cancel: &CancelToken,
    ) -> Result<PartialEigen, SparseEigenError> {
        let n = self.n;
        let nz = null.map_or(0, |z| z.count());
        let total = nz + self.cols.len();
        // Entry p < nz is indicator p, entry nz + q the q-th pair found.
        let value_of = |p: usize| if p < nz { 0.0 } else { self.values[p - nz] };
        let mut order: Vec<usize> = (0..total).collect();
        order.sort_by(|&p, &q| value_of(p).total_cmp(&value_of(q)));
        let mut vectors = vec![0.0; n * total];
        let mut values = Vec::with_capacity(total);
        let mut residuals = Vec::with_capacity(total);
        for (col, &p) in vectors.chunks_mut(n.max(1)).zip(&order) {
            if let (Some(z), true) = (null, p < nz) {
                z.write_indicator(p, col);
                residuals.push(z.residual(p));
            } else {
                let c = self.cols[p - nz];
                col.copy_from_slice(&self.basis[c * n..(c + 1) * n]);
                residuals.push(self.residuals[p - nz]);
            }
            values.push(value_of(p));
        }
        drop(self.basis);
        package(
            b,
            (values, vectors, residuals),
            self.iterations,
            self.solves,
            self.shift,
            progress,
            cancel,
        )
    }
}

/// Weight of the random part of a start block built from start vectors (relative to
/// their combination): what keeps eigenvectors missing from the start vectors within
/// reach of the iteration (measured: the same solve counts as with `1e-8`, within a
/// block, on 26k vertices at k = 50).
const START_NOISE: f64 = 1e-2;

/// Replaces the random block `w` (`n x bs`, entries uniform in `[-1, 1)`) by random
/// combinations of the `m` columns of `x0`, each scaled to unit Euclidean norm, plus
/// [`START_NOISE`] times `w` scaled to about unit Euclidean norm per column.
fn start_from(w: &mut [f64], x0: &[f64], n: usize, bs: usize, rng: &mut Rng) {
    let m = x0.len() / n;
    let eta = START_NOISE;
    let norms: Vec<f64> = x0
        .chunks(n)
        .map(|c| {
            c.iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt()
                .max(f64::MIN_POSITIVE)
        })
        .collect();
    // Noise: entries uniform in [-1, 1), Euclidean norm ~ sqrt(n / 3) per column.
    let scale = eta / (n as f64 / 3.0).sqrt();
    for col in 0..bs {
        let g: Vec<f64> = (0..m).map(|i| rng.next_f64() / norms[i]).collect();
        let wc = &mut w[col * n..(col + 1) * n];
        for x in wc.iter_mut() {
            *x *= scale;
        }
        for (i, &gi) in g.iter().enumerate() {
            for (x, &y) in wc.iter_mut().zip(&x0[i * n..(i + 1) * n]) {
                *x += gi * y;
            }
        }
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
    check(pb.cancel)?;
    let n = s.ncols();
    // The dimension of the space (n minus the deflated null space).
    let dim = pb.dim.min(n);
    let k = pb.k;
    let bs = sizes.block.clamp(1, dim);
    let m_max = sizes.max_basis.clamp(k.min(dim), dim);
    // Storage: the basis plus room for one pending block.
    let mut v = vec![0.0; n * (m_max + bs).min(dim + bs)];
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
    if let Some(x0) = pb.start.filter(|x| n > 0 && x.len() >= n) {
        start_from(&mut w, x0, n, bs, rng);
    }
    let mut bw = sym_spmm(b, &w, bs);
    chol.solve_many_in_place(&mut bw, bs);
    w = bw;
    v[..n * bs].copy_from_slice(&w);
    drop(w);
    let mut solves = bs;
    let (_, _, mut qc) = orthonormalize(&mut v, n, 0, bs, pb, rng, &mut solves, None)?;
    // Op V = V T + Q R_row (Q the pending block, R_row its coupling, qc x j).
    let mut rrow = Mat::<f64>::zeros(qc, 0);
    crate::linalg::timing::add(Phase::Start, start.elapsed());
    let mut restarts = 0usize;

    // Locked pairs: the first `nl` columns of V are converged Ritz vectors, decoupled
    // from the iteration (T is diagonal there and their coupling to later blocks, which
    // is of the size of their residual, is dropped). New blocks are still orthogonalized
    // against them, but restarts no longer rotate them nor include them in the projected
    // eigenproblem.
    let mut nl = 0usize;
    // Between restarts the convergence is estimated after each expansion (see
    // `converged_early`) once the last restart left at most two blocks of wanted pairs
    // unconverged (`near`; an estimate costs about as much as the solves of a block, so
    // it is not made while many pairs are missing): `check_now` sends the iteration to
    // the restart and its check before the basis is full, `quiet` counts the expansions
    // without such an estimate after one that the check did not confirm, and `xn_hints`
    // holds the Euclidean norms of the Ritz vectors of the last restart (ascending
    // lambda). With an interior shift the wanted pairs converge together, often before
    // the first restart (26k vertices, k = 50: all of them within 120 solves at 1e-10
    // and 100 at 1e-6), so the estimates start as soon as the basis holds k + a block.
    let mut near = pb.shift > 0.0;
    let mut check_now = false;
    let mut quiet = 0usize;
    // The expansion count and largest wanted estimate of the first estimate since the
    // last restart that said no (see `expansions_to_skip`).
    let mut first_estimate: Option<(usize, f64)> = None;
    let mut xn_hints: Vec<f64> = Vec::new();
    loop {
        check(pb.cancel)?;
        let full_space = j + qc > dim || qc == 0;
        if j + qc > m_max || full_space || check_now {
            // ---- Restart and convergence check ----
            let forced = check_now && j + qc <= m_max && !full_space;
            check_now = false;
            first_estimate = None;
            let m = j;
            let ma = m - nl;
            let pj = project(pb, &v, &t, &rrow, nl, m, qc)?;
            check(pb.cancel)?;
            // A check between restarts keeps every Ritz vector (the basis is not full).
            let keep = if full_space || forced {
                m
            } else {
                (k + (m_max - k) / 2)
                    .max(nconv + bs)
                    .min(m_max.saturating_sub(qc).max(k.min(m)))
                    .min(m)
            };
            let keep_a = keep.saturating_sub(nl).max(bs.min(ma)).min(ma);
            let total = nl + keep_a;
            timed(Phase::Rotate, || {
                rotate_in_place(
                    &mut v[n * nl..],
                    n,
                    ma,
                    pj.y.as_ref().submatrix(0, 0, ma, keep_a),
                    pb.cancel,
                )
            })?;
            let theta_all: Vec<f64> = (0..nl)
                .map(|c| t[(c, c)])
                .chain(pj.theta[..keep_a].iter().cloned())
                .collect();
            let lam_est: Vec<f64> = theta_all
                .iter()
                .map(|&th| lambda_of(pb.shift, th))
                .collect();
            // The Euclidean norms of the Ritz vectors (in the estimates' scale), kept as
            // hints for the checks between restarts.
            let xn_of = |col: usize| {
                v[col * n..(col + 1) * n]
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt()
            };
            let est_of = |col: usize| -> f64 {
                if col < nl {
                    return 0.0;
                }
                pj.estimate(pb, col - nl, lam_est[col], xn_of(col))
            };
            let assessment = assess(pb, bs, &lam_est, est_of, full_space)?;
            nconv = assessment.nconv;
            near = k.saturating_sub(nconv) <= 2 * bs;
            let (ord, ests, end) = (&assessment.ord, &assessment.ests, assessment.end);
            xn_hints = ord.iter().map(|&c| xn_of(c)).collect();
            restarts += 1;
            if crate::linalg::timing::enabled() {
                let worst = assessment.ests.iter().cloned().fold(0.0, f64::max);
                let first_bad = assessment
                    .ord
                    .get(nconv)
                    .filter(|&&c| c >= nl)
                    .map(|&c| pj.estimate(pb, c - nl, lam_est[c], xn_hints[nconv]));
                eprintln!(
                    "restart {restarts}{}: basis {m}, solves {solves}, converged {nconv} of {k} (end {:?}, est_end {:.1e}, worst converged {worst:.1e}, next {:.1e})",
                    if forced { " (early)" } else { "" },
                    end,
                    assessment.est_end,
                    first_bad.unwrap_or(f64::NAN),
                );
            }
            progress(EigenProgress::Iteration {
                iteration: expansions,
                converged: nconv.min(k),
                wanted: k,
                basis: m,
            });
            let ready = if full_space || keep >= dim {
                nconv >= k
            } else {
                assessment.wanted_converged(pb.tol)
            };
            if ready {
                // Purify the active candidates (locked ones stay as they are) and confirm
                // on the true residuals of the pairs up to `end`.
                let nres = end.unwrap_or(k).max(k).min(total);
                let cols = &ord[..nres];
                // The active candidates are the first active columns (in ascending lambda).
                let a = cols.iter().filter(|&&c| c >= nl).count();
                debug_assert!(cols.iter().all(|&c| c < nl + a));
                let pmat = pj.purification(a);
                timed(Phase::Residual, || purify(&mut v, n, (nl, m), &pmat, false))?;
                let fallback: Vec<f64> = cols.iter().map(|&c| lam_est[c]).collect();
                let (lam, res) =
                    timed(Phase::Residual, || true_residuals(pb, &v, cols, &fallback))?;
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
                // Back to the Ritz vectors, which the Krylov relation holds for.
                timed(Phase::Residual, || purify(&mut v, n, (nl, m), &pmat, true))?;
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
            if forced {
                // The estimate between restarts was too optimistic: no new one for two
                // expansions.
                quiet = 2;
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
                    // A locked vector is not purified: its own residual must be small.
                    let plain = pj.estimate_plain(pb, c - nl, lam_est[c], xn_hints[p]);
                    if plain > LOCK_FRACTION * pb.tol {
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
                    rr[(a, c)] = pj.rho[(a, c - nl)];
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
        // The solves of a block are the longest step that cannot be interrupted (about
        // 0.4 s for 16 columns at 411k vertices).
        if pb.cancel.is_cancelled() {
            if let Some(bq) = bq {
                scratch::give(bq);
            }
            return Err(SparseEigenError::Cancelled);
        }
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
        let (coef, r, q) = orthonormalize(&mut v, n, j, c, pb, rng, &mut solves, local)?;
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
        // Between restarts: stop expanding as soon as the estimates say the wanted pairs
        // have converged (a loose tolerance is then met with fewer solves than a full
        // basis takes), confirmed by the restart's check on the true residuals.
        if quiet > 0 {
            quiet -= 1;
        } else if sizes.early && near && j + qc <= m_max && qc > 0 && j >= (k + bs).min(dim) {
            let (converged, worst) = timed(Phase::Estimate, || {
                converged_early(pb, &v, &t, &rrow, (nl, j, qc, bs), &xn_hints)
            })?;
            check_now = converged;
            if crate::linalg::timing::enabled() {
                eprintln!(
                    "estimate at basis {j}, solves {solves}: {}",
                    if converged {
                        "converged".to_string()
                    } else {
                        format!("largest wanted {worst:.1e}")
                    }
                );
            }
            if !converged {
                quiet = expansions_to_skip(first_estimate, (expansions, worst), pb.tol);
                first_estimate.get_or_insert((expansions, worst));
            }
        }
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

    /// The skip between estimates follows the fall of the largest estimate: half the
    /// expansions still needed at that rate, at most 8, none without a fall.
    #[test]
    fn estimates_skip_expansions_at_the_rate_they_fall() {
        let tol = 1e-10;
        assert_eq!(expansions_to_skip(None, (11, 1e-3), tol), 0);
        // A tenfold fall per expansion, 1e-3 -> 1e-10: 7 more expansions, half of them.
        assert_eq!(expansions_to_skip(Some((10, 1e-2)), (11, 1e-3), tol), 3);
        // The same fall over two expansions: 14 more, half of them; a slow fall: 8.
        assert_eq!(expansions_to_skip(Some((9, 1e-2)), (11, 1e-3), tol), 7);
        assert_eq!(expansions_to_skip(Some((10, 1e-2)), (11, 0.9e-2), tol), 8);
        // No fall, or nothing left to gain: estimate again at once.
        assert_eq!(expansions_to_skip(Some((10, 1e-3)), (11, 2e-3), tol), 0);
        assert_eq!(expansions_to_skip(Some((10, 1e-3)), (11, 1e-11), tol), 0);
        assert_eq!(
            expansions_to_skip(Some((10, 1e-3)), (11, f64::INFINITY), tol),
            0
        );
    }

    /// Ritz values rank by the eigenvalue they stand for; with an interior shift one in
    /// the gap `(-1 / sigma, 0)` of the spectrum of `Op` (an eigenvalue below 0) ranks last.
    #[test]
    fn ritz_values_rank_by_the_eigenvalue_they_stand_for() {
        assert_eq!(lambda_of(-0.5, 2.0), 0.0);
        assert_eq!(lambda_of(-0.5, 0.5), 1.5);
        let sigma = 10.0;
        assert_eq!(lambda_of(sigma, -0.1), 0.0);
        assert_eq!(lambda_of(sigma, -1.0), 9.0);
        assert_eq!(lambda_of(sigma, 0.5), 12.0);
        assert_eq!(lambda_of(sigma, -0.05), f64::INFINITY);
        assert_eq!(lambda_of(sigma, 0.0), f64::INFINITY);
    }
    use crate::linalg::eigen::norm1;
    use crate::linalg::eigen::tests::fem;

    /// Locking and the Lanczos step change the work, not the answer: every combination
    /// finds the same pairs on a sphere, with blocks (4) smaller than the multiplicities
    /// (up to 11) and k = 30 cutting the 11-fold l = 5 eigenspace, and a small basis so
    /// that there are many restarts.
    #[test]
    fn locking_and_lanczos_step_agree_with_the_plain_iteration() {
        let (s, b) = &fem("sphere:res=3"); // 642 vertices
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
            cancel: &CancelToken::new(),
            deflation: None,
            extra: None,
            dim: s.ncols(),
            start: None,
        };
        let mut runs = Vec::new();
        for (lock, local) in [(false, false), (true, false), (false, true), (true, true)] {
            let sizes = Sizes {
                block: 4,
                max_basis: 50,
                max_restarts: 500,
                lock,
                local,
                early: true,
            };
            let out = krylov_schur(&pb, &sizes, &mut Rng(7), &mut |_| {})
                .unwrap()
                .finish(b, None, &mut |_| {}, pb.cancel)
                .unwrap();
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
