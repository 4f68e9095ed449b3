//! Sparse kernels of the eigensolver: the symmetric sparse times dense product, the
//! matrix 1-norm, relative residuals and the B-orthogonality check.

use rayon::prelude::*;

use super::dense::{LEAF_ROWS, gram};
use super::types::SparseEigenError;
use crate::cancel::CancelToken;
use crate::linalg::{SparseMatrix, scratch};

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
/// row-major (into this thread's row buffer, see [`scratch::with_row_buffer`]), then each
/// row of `Y` is one gather of `C`-wide rows of `X`.
fn spmm_group<const C: usize>(a: &SparseMatrix, x: &[f64], y: &mut [f64]) {
    let n = a.ncols();
    scratch::with_row_buffer(n * C, |buf| {
        let (xr, _) = buf.as_chunks_mut::<C>();
        spmm_group_with::<C>(a, x, y, xr);
    });
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
    orthogonality_error_by_blocks(b, vectors, k, orth_block(n), None).unwrap_or(f64::NAN)
}

/// Columns per block of [`b_orthogonality_error`] for vectors of length `n > 0`.
fn orth_block(n: usize) -> usize {
    (ORTH_BLOCK_VALUES / n).clamp(8, 64)
}

/// [`b_orthogonality_error`] that stops (`Err(Cancelled)`) between two blocks once
/// `cancel` is set: at 411k vertices and k = 500 the check takes seconds.
pub(super) fn b_orthogonality_error_cancellable(
    b: &SparseMatrix,
    vectors: &[f64],
    k: usize,
    cancel: &CancelToken,
) -> Result<f64, SparseEigenError> {
    let n = b.ncols();
    if n == 0 || k == 0 {
        return Ok(0.0);
    }
    orthogonality_error_by_blocks(b, vectors, k, orth_block(n), Some(cancel))
        .ok_or(SparseEigenError::Cancelled)
}

/// [`b_orthogonality_error`] with blocks of `block` columns (`n > 0`, `k > 0`); `None`
/// when `cancel` was set before a block.
fn orthogonality_error_by_blocks(
    b: &SparseMatrix,
    vectors: &[f64],
    k: usize,
    block: usize,
    cancel: Option<&CancelToken>,
) -> Option<f64> {
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
        if cancel.is_some_and(|c| c.is_cancelled()) {
            return None;
        }
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
    Some(e)
}

#[cfg(test)]
mod tests {
    use super::super::rng::Rng;
    use super::super::tests::path_laplacian;
    use super::*;

    /// The blocked, upper-triangle-only orthogonality error equals `max |X^T B X - I|`
    /// computed in full, wherever the largest entry sits (across blocks of 64 columns,
    /// on and off the diagonal).
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
        let got8 = orthogonality_error_by_blocks(&b, &x, k, 8, None).unwrap();
        assert!(
            (got8 - want).abs() <= 1e-12 * want.max(1.0),
            "blocks of 8: {got8} against full {want}"
        );
        assert!(
            want > 0.5,
            "the test vectors should be far from orthonormal"
        );
    }
}
