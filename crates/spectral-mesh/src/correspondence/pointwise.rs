//! Point-to-point maps and functional maps of point maps.
//!
//! - [`fmap_to_p2p`] (pyFM's `FM_to_p2p`): for each vertex `v` of shape 2, the vertex `u`
//!   of shape 1 whose embedding is nearest, with the embeddings `Phi_1 C^T` (rows of shape
//!   1) and `Phi_2` (rows of shape 2); with `adjoint`, `Phi_1` and `Phi_2 C` instead.
//! - [`fmap_to_p2p_12`]: the other way, for each vertex of shape 1 the nearest vertex of
//!   shape 2 in the same embeddings `Phi_1 C^T`, `Phi_2`.
//! - [`p2p_to_fmap`]: the functional map of a point map `p2p_21`,
//!   `C = Phi_2^T M_2 Phi_1[p2p_21, :]` (`k2 x k1`).
//!
//! Nearest neighbours come from a k-d tree (`kiddo`, exact) over the rows, padded with
//! zeros to the next supported width (padding changes no distance); beyond
//! [`KD_TREE_MAX_DIM`] columns, a parallel exhaustive search.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::{CorrespondenceError, FunctionalMap, truncate};
use crate::linalg::dense_ops::{gram, product, product_transposed};
use crate::linalg::sym_spmm;
use crate::spectral::BasisView;

/// Widest embedding searched with the k-d tree.
pub const KD_TREE_MAX_DIM: usize = 256;

fn row<const K: usize>(x: &[f64], n: usize, d: usize, i: usize) -> [f64; K] {
    let mut r = [0.0; K];
    for (q, rq) in r.iter_mut().enumerate().take(d) {
        *rq = x[q * n + i];
    }
    r
}

fn nearest_kd<const K: usize>(
    points: &[f64],
    n: usize,
    queries: &[f64],
    m: usize,
    d: usize,
    hint: Option<&[usize]>,
) -> Vec<usize> {
    let rows: Vec<[f64; K]> = (0..n).map(|i| row::<K>(points, n, d, i)).collect();
    let tree: ImmutableKdTree<f64, K> = ImmutableKdTree::new_from_slice(&rows);
    let one = std::num::NonZero::<usize>::MIN;
    (0..m)
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let q = row::<K>(queries, m, d, i);
            match hint {
                // The nearest point is no farther than the hinted one: searching within
                // that distance is exact and prunes far more in many dimensions.
                Some(h) => {
                    let j = h[i];
                    let r: f64 = q.iter().zip(&rows[j]).map(|(a, b)| (a - b) * (a - b)).sum();
                    tree.nearest_n_within::<SquaredEuclidean>(&q, r, one, true)
                        .first()
                        .map_or(j, |nb| nb.item as usize)
                }
                None => tree.nearest_one::<SquaredEuclidean>(&q).item as usize,
            }
        })
        .collect()
}

fn nearest_exhaustive(points: &[f64], n: usize, queries: &[f64], m: usize, d: usize) -> Vec<usize> {
    let pts: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..d).map(|q| points[q * n + i]).collect())
        .collect();
    (0..m)
        .into_par_iter()
        .map(|i| {
            let q: Vec<f64> = (0..d).map(|c| queries[c * m + i]).collect();
            let mut best = (f64::INFINITY, 0);
            for (j, p) in pts.iter().enumerate() {
                let dist: f64 = p.iter().zip(&q).map(|(a, b)| (a - b).powi(2)).sum();
                if dist < best.0 {
                    best = (dist, j);
                }
            }
            best.1
        })
        .collect()
}

/// For each of the `m` rows of `queries` (`m x d`, column-major), the index of the
/// nearest of the `n` rows of `points` (`n x d`) in the Euclidean distance.
pub fn nearest_rows(
    points: &[f64],
    n: usize,
    queries: &[f64],
    m: usize,
    d: usize,
) -> Result<Vec<usize>, CorrespondenceError> {
    nearest_rows_hinted(points, n, queries, m, d, None)
}

/// [`nearest_rows`] with a guess for each query (`m` indices `< n`, e.g. the previous
/// ZoomOut iteration's map): the same answer up to ties, found faster when the guesses
/// are close.
pub fn nearest_rows_hinted(
    points: &[f64],
    n: usize,
    queries: &[f64],
    m: usize,
    d: usize,
    hint: Option<&[usize]>,
) -> Result<Vec<usize>, CorrespondenceError> {
    if let Some(h) = hint {
        check_p2p(h, m, n)?;
    }
    if points.len() != n * d || queries.len() != m * d {
        return Err(CorrespondenceError::SizeMismatch(format!(
            "{} point values for {n} x {d}, {} query values for {m} x {d}",
            points.len(),
            queries.len()
        )));
    }
    if n == 0 {
        return Err(CorrespondenceError::InvalidParameter(
            "no points to search".into(),
        ));
    }
    if points.iter().chain(queries).any(|v| !v.is_finite()) {
        return Err(CorrespondenceError::InvalidParameter(
            "the embedding holds a value that is not finite".into(),
        ));
    }
    Ok(match d {
        0..=8 => nearest_kd::<8>(points, n, queries, m, d, hint),
        9..=16 => nearest_kd::<16>(points, n, queries, m, d, hint),
        17..=32 => nearest_kd::<32>(points, n, queries, m, d, hint),
        33..=48 => nearest_kd::<48>(points, n, queries, m, d, hint),
        49..=64 => nearest_kd::<64>(points, n, queries, m, d, hint),
        65..=96 => nearest_kd::<96>(points, n, queries, m, d, hint),
        97..=128 => nearest_kd::<128>(points, n, queries, m, d, hint),
        129..=192 => nearest_kd::<192>(points, n, queries, m, d, hint),
        193..=KD_TREE_MAX_DIM => nearest_kd::<KD_TREE_MAX_DIM>(points, n, queries, m, d, hint),
        _ => nearest_exhaustive(points, n, queries, m, d),
    })
}

fn check_fmap<'a>(
    c: &FunctionalMap,
    basis1: BasisView<'a>,
    basis2: BasisView<'a>,
) -> Result<(BasisView<'a>, BasisView<'a>), CorrespondenceError> {
    if c.c.len() != c.k1 * c.k2 {
        return Err(CorrespondenceError::SizeMismatch(format!(
            "a {} x {} functional map with {} entries",
            c.k2,
            c.k1,
            c.c.len()
        )));
    }
    Ok((truncate(basis1, c.k1, 1)?, truncate(basis2, c.k2, 2)?))
}

/// For each vertex of shape 2, a vertex of shape 1 (see the module docs).
pub fn fmap_to_p2p(
    c: &FunctionalMap,
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
    adjoint: bool,
) -> Result<Vec<usize>, CorrespondenceError> {
    fmap_to_p2p_hinted(c, basis1, basis2, adjoint, None)
}

/// [`fmap_to_p2p`] with a guess `p2p_21` (see [`nearest_rows_hinted`]).
pub fn fmap_to_p2p_hinted(
    c: &FunctionalMap,
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
    adjoint: bool,
    hint: Option<&[usize]>,
) -> Result<Vec<usize>, CorrespondenceError> {
    let (b1, b2) = check_fmap(c, basis1, basis2)?;
    let (n1, n2) = (b1.n, b2.n);
    if adjoint {
        // Phi_2 C: n2 x k1.
        let emb2 = product(b2.vectors, &c.c, n2, c.k2, c.k1);
        nearest_rows_hinted(b1.vectors, n1, &emb2, n2, c.k1, hint)
    } else {
        // Phi_1 C^T: n1 x k2.
        let emb1 = product_transposed(b1.vectors, &c.c, n1, c.k1, c.k2);
        nearest_rows_hinted(&emb1, n1, b2.vectors, n2, c.k2, hint)
    }
}

/// For each vertex of shape 1, a vertex of shape 2: nearest neighbours of the rows of
/// `Phi_1 C^T` among the rows of `Phi_2`.
pub fn fmap_to_p2p_12(
    c: &FunctionalMap,
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
) -> Result<Vec<usize>, CorrespondenceError> {
    let (b1, b2) = check_fmap(c, basis1, basis2)?;
    let emb1 = product_transposed(b1.vectors, &c.c, b1.n, c.k1, c.k2);
    nearest_rows(b2.vectors, b2.n, &emb1, b1.n, c.k2)
}

/// The functional map (`k2 x k1`) of the point map `p2p_21` (for each vertex of shape 2 a
/// vertex of shape 1): `Phi_2^T M_2 Phi_1[p2p_21, :]`.
pub fn p2p_to_fmap(
    p2p_21: &[usize],
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
    k1: usize,
    k2: usize,
) -> Result<FunctionalMap, CorrespondenceError> {
    let b1 = truncate(basis1, k1, 1)?;
    let b2 = truncate(basis2, k2, 2)?;
    let (n1, n2) = (b1.n, b2.n);
    check_p2p(p2p_21, n2, n1)?;
    let mut pulled = vec![0.0; n2 * k1];
    for j in 0..k1 {
        let x = &b1.vectors[j * n1..(j + 1) * n1];
        for (dst, &src) in pulled[j * n2..(j + 1) * n2].iter_mut().zip(p2p_21) {
            *dst = x[src];
        }
    }
    let mp = sym_spmm(b2.mass, &pulled, k1);
    Ok(FunctionalMap {
        k1,
        k2,
        c: gram(b2.vectors, &mp, n2, k2, k1),
    })
}

/// Checks that `map` has `n_from` entries, each `< n_to`.
pub(crate) fn check_p2p(
    map: &[usize],
    n_from: usize,
    n_to: usize,
) -> Result<(), CorrespondenceError> {
    if map.len() != n_from {
        return Err(CorrespondenceError::SizeMismatch(format!(
            "a point map of {} entries for a shape of {n_from} vertices",
            map.len()
        )));
    }
    if let Some((i, &v)) = map.iter().enumerate().find(|&(_, &v)| v >= n_to) {
        return Err(CorrespondenceError::InvalidParameter(format!(
            "point map entry {i} is {v}, but the other shape has {n_to} vertices"
        )));
    }
    Ok(())
}

/// Carries `p` functions on shape 1 (`n1 x p`, column-major) to shape 2 through the point
/// map: `g(v) = f(p2p_21[v])` (`n2 x p`).
pub fn transfer(
    p2p_21: &[usize],
    f: &[f64],
    n1: usize,
    p: usize,
) -> Result<Vec<f64>, CorrespondenceError> {
    if f.len() != n1 * p {
        return Err(CorrespondenceError::SizeMismatch(format!(
            "{} values for {p} functions on {n1} vertices",
            f.len()
        )));
    }
    check_p2p(p2p_21, p2p_21.len(), n1)?;
    let n2 = p2p_21.len();
    let mut g = vec![0.0; n2 * p];
    for q in 0..p {
        let src = &f[q * n1..(q + 1) * n1];
        for (dst, &u) in g[q * n2..(q + 1) * n2].iter_mut().zip(p2p_21) {
            *dst = src[u];
        }
    }
    Ok(g)
}

/// Carries `p` functions on shape 1 (`n1 x p`) to shape 2 through the functional map:
/// `Phi_2 C Phi_1^T M_1 f` (`n2 x p`).
pub fn transfer_spectral(
    c: &FunctionalMap,
    basis1: BasisView<'_>,
    basis2: BasisView<'_>,
    f: &[f64],
    p: usize,
) -> Result<Vec<f64>, CorrespondenceError> {
    let (b1, b2) = check_fmap(c, basis1, basis2)?;
    let coef1 = super::descriptors::project(b1, f, p)?;
    let coef2 = product(&c.c, &coef1, c.k2, c.k1, p);
    Ok(product(b2.vectors, &coef2, b2.n, c.k2, p))
}
