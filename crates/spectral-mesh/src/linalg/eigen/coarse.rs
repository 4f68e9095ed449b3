//! A start subspace from a coarse space (coarse-to-fine, in the spirit of Nasikun and
//! Hildebrandt's hierarchical subspace iteration). Off by default
//! ([`super::SparseEigenOptions::coarse_start`]): measured, it does not pay (below).
//!
//! The coarse space is a smoothed-aggregation prolongation `P` (`n x m`): the vertices
//! are grouped into aggregates (a root whose whole neighbourhood in the graph of `S` is
//! still free takes that neighbourhood; the remaining vertices join the aggregate they
//! are most strongly connected to), the indicator functions of the aggregates form the
//! tentative prolongation `P0`, and damped Jacobi steps smooth it:
//! `P = (I - omega D^-1 S)^s P0` with `D = diag(S)`, `omega = 4 / (3 rho)`, `rho` the
//! Gershgorin bound of `D^-1 S`, `s` = [`SMOOTHING_STEPS`]. `P` reproduces the constants
//! (`S 1 = 0`), so the component indicators stay in the coarse space.
//!
//! The Galerkin pencil `(P^T S P, P^T B P)` is solved for `k + k / 4 + 8` pairs with the
//! same sparse solver at a loose tolerance, and its eigenvectors, prolongated, are the
//! start vectors of the fine iteration ([`super::SparseEigenOptions::start_vectors`]).
//! The fine iteration's stopping rule and true residuals are unchanged: a poor start
//! only costs solves.
//!
//! Why it does not pay: the fine iteration grows its Krylov space by blocks from random
//! combinations of the start vectors, and the number of blocks it needs is set mostly by
//! the separation of the wanted eigenvalues (the convergence front), only
//! logarithmically by the start's accuracy. On a 26k-vertex mesh at k = 50 (168 solves
//! from a random start), exact eigenvectors perturbed by 1% still took 152 solves, and
//! this coarse space (`m = n / 15`) 160-164, while the coarse solve cost more than the
//! solves it saved.

use rayon::prelude::*;

use super::result::PartialEigen;
use super::types::{SparseEigenError, SparseEigenOptions};
use crate::linalg::SparseMatrix;

const FREE: usize = usize::MAX;

/// Damped Jacobi steps smoothing the tentative prolongation (1, 2 and 3 measured: the
/// coarse `lambda_50` of a 26k-vertex mesh was 2.1x, 1.5x and 1.4x the fine one).
const SMOOTHING_STEPS: usize = 2;

/// Tolerance of the coarse solve: its pairs are only as good as the coarse space.
const COARSE_TOLERANCE: f64 = 1e-6;

/// Aggregates of the graph of the symmetric `s`: the aggregate of each vertex and their
/// number.
pub(super) fn aggregate(s: &SparseMatrix) -> (Vec<usize>, usize) {
    let n = s.ncols();
    let mut agg = vec![FREE; n];
    let mut m = 0;
    // Roots whose whole neighbourhood is free take it.
    for i in 0..n {
        if agg[i] != FREE {
            continue;
        }
        let (rows, _) = s.col(i);
        if rows.iter().all(|&r| agg[r] == FREE) {
            for &r in rows {
                agg[r] = m;
            }
            agg[i] = m;
            m += 1;
        }
    }
    // The others join the aggregate of their most strongly connected neighbour.
    let first = agg.clone();
    for i in 0..n {
        if agg[i] != FREE {
            continue;
        }
        let (rows, vals) = s.col(i);
        let mut best = (FREE, -1.0);
        for (&r, &v) in rows.iter().zip(vals) {
            if r != i && first[r] != FREE && v.abs() > best.1 {
                best = (first[r], v.abs());
            }
        }
        agg[i] = best.0;
    }
    // Whatever is left (no aggregated neighbour): new aggregates with its free neighbours.
    for i in 0..n {
        if agg[i] != FREE {
            continue;
        }
        agg[i] = m;
        let (rows, _) = s.col(i);
        for &r in rows {
            if agg[r] == FREE {
                agg[r] = m;
            }
        }
        m += 1;
    }
    (agg, m)
}

/// The smoothed prolongation `P = (I - omega D^-1 S) P0` (`n x m`, see the module
/// documentation) of the aggregates `agg` (`m` of them).
pub(super) fn prolongation(s: &SparseMatrix, agg: &[usize], m: usize) -> SparseMatrix {
    let n = s.ncols();
    let d = s.diag();
    let rho = (0..n)
        .map(|c| {
            let (_, vals) = s.col(c);
            let sum: f64 = vals.iter().map(|v| v.abs()).sum();
            if d[c] > 0.0 { sum / d[c] } else { 0.0 }
        })
        .fold(0.0, f64::max);
    let omega = if rho > 0.0 { 4.0 / (3.0 * rho) } else { 0.0 };
    let steps = SMOOTHING_STEPS;
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); m];
    for (i, &a) in agg.iter().enumerate() {
        members[a].push(i);
    }
    let cols: Vec<Vec<(usize, f64)>> = members
        .par_iter()
        .map(|mem| {
            // Column a: (I - omega D^-1 S)^steps indicator.
            let mut col: Vec<(usize, f64)> = mem.iter().map(|&i| (i, 1.0)).collect();
            col.sort_by_key(|e| e.0);
            for _ in 0..steps {
                let mut acc = col.clone();
                for &(i, xi) in &col {
                    let (rows, vals) = s.col(i);
                    for (&r, &v) in rows.iter().zip(vals) {
                        if d[r] > 0.0 {
                            acc.push((r, -omega * v * xi / d[r]));
                        }
                    }
                }
                acc.sort_by_key(|e| e.0);
                let mut out: Vec<(usize, f64)> = Vec::with_capacity(acc.len());
                for (r, v) in acc {
                    match out.last_mut() {
                        Some(last) if last.0 == r => last.1 += v,
                        _ => out.push((r, v)),
                    }
                }
                col = out;
            }
            col
        })
        .collect();
    from_columns(n, m, cols)
}

fn from_columns(nrows: usize, ncols: usize, cols: Vec<Vec<(usize, f64)>>) -> SparseMatrix {
    let mut col_ptr = Vec::with_capacity(ncols + 1);
    col_ptr.push(0);
    let nnz: usize = cols.iter().map(|c| c.len()).sum();
    let mut row_idx = Vec::with_capacity(nnz);
    let mut values = Vec::with_capacity(nnz);
    for c in cols {
        for (r, v) in c {
            row_idx.push(r);
            values.push(v);
        }
        col_ptr.push(row_idx.len());
    }
    SparseMatrix::from_csc(nrows, ncols, col_ptr, row_idx, values)
        .unwrap_or_else(|| SparseMatrix::from_triplets(nrows, ncols, &[]))
}

/// The Galerkin product `P^T A P` (`m x m`) of the symmetric `a`, made exactly symmetric.
pub(super) fn galerkin(p: &SparseMatrix, pt: &SparseMatrix, a: &SparseMatrix) -> SparseMatrix {
    let (n, m) = (p.nrows(), p.ncols());
    let cols: Vec<Vec<(usize, f64)>> = (0..m)
        .into_par_iter()
        .map_init(
            || (vec![0.0f64; n], Vec::new(), vec![0.0f64; m], Vec::new()),
            |(y, ytouch, z, ztouch), c| {
                // y = A p_c.
                let (prow, pval) = p.col(c);
                for (&i, &pv) in prow.iter().zip(pval) {
                    let (rows, vals) = a.col(i);
                    for (&r, &v) in rows.iter().zip(vals) {
                        if y[r] == 0.0 {
                            ytouch.push(r);
                        }
                        y[r] += pv * v;
                    }
                }
                // z = P^T y (row r of P is column r of P^T).
                for &r in ytouch.iter() {
                    let yr = y[r];
                    y[r] = 0.0;
                    let (cs, vs) = pt.col(r);
                    for (&cc, &v) in cs.iter().zip(vs) {
                        if z[cc] == 0.0 {
                            ztouch.push(cc);
                        }
                        z[cc] += v * yr;
                    }
                }
                ytouch.clear();
                ztouch.sort_unstable();
                ztouch.dedup();
                let out = ztouch.iter().map(|&cc| (cc, z[cc])).collect();
                for &cc in ztouch.iter() {
                    z[cc] = 0.0;
                }
                ztouch.clear();
                out
            },
        )
        .collect();
    let g = from_columns(m, m, cols);
    g.add_scaled(0.5, &g.transpose(), 0.5)
}

/// Start vectors for the `k` smallest pairs of `(s, b)` from the coarse space (see the
/// module documentation): `n x kc` column-major, `kc` a little more than `k`. `None` when
/// the problem is too small for a coarse space to pay, or the coarse solve fails (the
/// fine iteration then starts from random vectors as before). `solve` is the sparse
/// solver (the driver's, passed in so that this file does not import the driver).
pub(super) fn coarse_start(
    s: &SparseMatrix,
    b: &SparseMatrix,
    k: usize,
    opts: &SparseEigenOptions,
    solve: &dyn Fn(
        &SparseMatrix,
        &SparseMatrix,
        &SparseEigenOptions,
    ) -> Result<PartialEigen, SparseEigenError>,
) -> Option<Vec<f64>> {
    let n = s.ncols();
    let (agg, m) = aggregate(s);
    let kc = k + k / 4 + 8;
    if m < 4 * kc || m >= n {
        return None;
    }
    let p = prolongation(s, &agg, m);
    let pt = p.transpose();
    let sc = galerkin(&p, &pt, s);
    let bc = galerkin(&p, &pt, b);
    let tol = COARSE_TOLERANCE;
    let copts = SparseEigenOptions {
        k: kc,
        tolerance: tol,
        block_size: 0,
        max_basis: 0,
        start_vectors: None,
        deflate_vectors: None,
        coarse_start: false,
        ..opts.clone()
    };
    let r = solve(&sc, &bc, &copts);
    if crate::linalg::timing::enabled() {
        eprintln!(
            "coarse start: n {n} -> m {m} (P nnz {}, Sc nnz {}), {kc} pairs: {}",
            p.nnz(),
            sc.nnz(),
            match &r {
                Ok(r) => format!(
                    "{} solves, coarse lambda_k {:.6e}, lambda_kc {:.6e}",
                    r.solves,
                    r.values[k.min(r.values.len()) - 1],
                    r.values[r.values.len() - 1]
                ),
                Err(e) => format!("{e}"),
            }
        );
    }
    let r: Result<_, SparseEigenError> = r;
    let r = r.ok()?;
    let kc = r.values.len();
    // X0 = P Yc, column by column.
    let mut x0 = vec![0.0; n * kc];
    x0.par_chunks_mut(n)
        .zip(r.vectors.par_chunks(m))
        .for_each(|(x, y)| {
            for (a, &ya) in y.iter().enumerate() {
                if ya == 0.0 {
                    continue;
                }
                let (rows, vals) = p.col(a);
                for (&i, &v) in rows.iter().zip(vals) {
                    x[i] += v * ya;
                }
            }
        });
    Some(x0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cancel::CancelToken;
    use crate::linalg::eigen::tests::fem;
    use crate::linalg::eigen::{sparse_generalized_eigen, sparse_generalized_eigen_with};

    /// The prolongation reproduces the constants, the Galerkin pencil keeps `S`'s null
    /// space and `B`'s symmetry, and a solve started from the coarse space returns the
    /// pairs of a random start.
    #[test]
    fn the_coarse_start_keeps_constants_and_gives_the_same_pairs() {
        let (s, b) = &fem("sphere:res=4"); // 2562 vertices
        let n = s.ncols();
        let (agg, m) = aggregate(s);
        assert!(m > 50 && m < n / 4, "{m} aggregates of {n} vertices");
        assert!(agg.iter().all(|&a| a < m));
        let p = prolongation(s, &agg, m);
        let ones = p.mul_vec(&vec![1.0; m]);
        assert!(ones.iter().all(|&x| (x - 1.0).abs() < 1e-12));
        let pt = p.transpose();
        let sc = galerkin(&p, &pt, s);
        let bc = galerkin(&p, &pt, b);
        assert!(sc.mul_vec(&vec![1.0; m]).iter().all(|&x| x.abs() < 1e-9));
        assert_eq!(bc.asymmetry(), 0.0);
        let k = 20;
        let opts = SparseEigenOptions {
            k,
            ..Default::default()
        };
        let cancel = CancelToken::new();
        let solve = |sc: &SparseMatrix, bc: &SparseMatrix, o: &SparseEigenOptions| {
            sparse_generalized_eigen_with(sc, bc, o, None, &mut |_| {}, &cancel)
        };
        let x0 = coarse_start(s, b, k, &opts, &solve).expect("a coarse space");
        assert_eq!(x0.len() % n, 0);
        assert!(x0.len() / n > k);
        let plain = sparse_generalized_eigen(s, b, &opts, &mut |_| {}).unwrap();
        let coarse = sparse_generalized_eigen(
            s,
            b,
            &SparseEigenOptions {
                coarse_start: true,
                ..opts
            },
            &mut |_| {},
        )
        .unwrap();
        let lk = plain.values[k - 1];
        for (a, c) in coarse.values.iter().zip(&plain.values) {
            assert!((a - c).abs() <= 1e-9 * lk, "{a} vs {c}");
        }
        assert!(coarse.residuals.iter().all(|&r| r <= 1e-10));
    }

    /// A start subspace built to miss an eigenvector (one copy of the sphere's 5-fold
    /// eigenvalue l = 2, the others exact) still gives every pair, multiplicities
    /// included: the random part of the start block brings the missing one in.
    #[test]
    fn a_start_that_misses_an_eigenvector_still_finds_it() {
        let (s, b) = &fem("sphere:res=3"); // 642 vertices
        let n = s.ncols();
        let k = 16; // 1 + 3 + 5 + 7 = 16: the l = 3 cluster is the last
        let reference = sparse_generalized_eigen(
            s,
            b,
            &SparseEigenOptions {
                k: 30,
                ..Default::default()
            },
            &mut |_| {},
        )
        .unwrap();
        // Columns 4..9 span l = 2; drop column 6.
        let mut x0 = Vec::new();
        for j in (0..30).filter(|&j| j != 6) {
            x0.extend_from_slice(&reference.vectors[j * n..(j + 1) * n]);
        }
        for block in [4, 8] {
            let r = sparse_generalized_eigen(
                s,
                b,
                &SparseEigenOptions {
                    k,
                    block_size: block,
                    start_vectors: Some(std::sync::Arc::new(x0.clone())),
                    ..Default::default()
                },
                &mut |_| {},
            )
            .unwrap();
            let lk = reference.values[k - 1];
            for (j, (a, c)) in r.values.iter().zip(&reference.values).enumerate() {
                assert!((a - c).abs() <= 1e-9 * lk, "block {block}, {j}: {a} vs {c}");
            }
            assert!(r.residuals.iter().all(|&x| x <= 1e-10));
        }
    }
}
