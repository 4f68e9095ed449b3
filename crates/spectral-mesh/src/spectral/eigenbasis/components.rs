//! Meshes with several connected components: each component solved on its own (small
//! ones densely) and the pairs merged.

use super::params::{
    DENSE_MAX_N, DENSE_MAX_N_LARGE_K, EigenError, EigenMethod, EigenParams, sparse_options,
};
use super::pencil::dense_pairs;
use super::pencil::{Factors, check_cancel};
use crate::cancel::CancelToken;
use crate::linalg::{
    ComponentNullSpace, EigenProgress, ShiftInvert, SparseEigenOptions, SparseMatrix,
    b_orthogonality_error, relative_residuals, sparse_generalized_eigen_with,
};

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
pub(super) type Pairs = (Vec<f64>, Vec<f64>, Vec<f64>);

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
pub(super) fn solve_split(
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
