//! Filtered spectral distances and the generalized Green kernel (Sect. 5 of the paper;
//! `docs/MATH.md`, "Filtered spectral distances").
//!
//! With the weights `w_k = w(lambda_k)` of a [`Filter`] (`w = 1/phi`; zero eigenvalues get
//! weight 0 and are skipped):
//!
//! ```text
//! d(p,q)^2 = sum_k w_k (x_k(p) - x_k(q))^2,     G = X diag(w) X^T,
//! d(p,q)^2 = G(p,p) - 2 G(p,q) + G(q,q),        spectral function p -> G(p,p).
//! ```
//!
//! Everything is computed on the basis as given; for scale-invariant values normalise the
//! basis first ([`super::heat::normalize_basis`]). Under a uniform scaling of the shape by
//! `alpha` (eigenvalues `/ alpha^2`, eigenvectors `/ alpha`):
//! - commute-time distances are invariant,
//! - bi-harmonic distances scale by `alpha` (`d' = alpha d`),
//! - diffusion distances at time `alpha^2 t` scale by `1/alpha`,
//! - with the unit-area normalisation all of them are invariant.
//!
//! The wFEM diffusion distance of eq. 15 ([`wfem_diffusion_distances_from`]) uses
//! `S_t = B X D_t X^T B` over **all** pairs of the basis, the zero eigenvalue included (it
//! is what makes `S_t` positive definite).

use rayon::prelude::*;

use super::BasisView;
use super::filters::{Filter, FilterError, positive_weight};
use super::heat::accumulate_columns;

/// Errors of the distance functions.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum DistanceError {
    /// The filter is refused on this spectrum.
    #[error(transparent)]
    Filter(#[from] FilterError),
    /// A vertex index is out of range.
    #[error("vertex {vertex} is out of range: the mesh has {n} vertices")]
    VertexOutOfRange {
        /// The index given.
        vertex: usize,
        /// Number of vertices.
        n: usize,
    },
    /// A pair index (an embedding's component) is not in the basis.
    #[error(
        "component {component} is out of range for k = {k} pairs (valid: 0 to {})",
        .k.saturating_sub(1)
    )]
    ComponentOutOfRange {
        /// The index given.
        component: usize,
        /// Pairs in the basis.
        k: usize,
    },
    /// The time is not finite and `>= 0`.
    #[error("the diffusion time must be finite and >= 0, got {0}")]
    InvalidTime(f64),
    /// The all-pairs matrix would be too large.
    #[error("all-pairs distances need an n x n matrix; n = {n} exceeds the limit {limit}")]
    TooLarge {
        /// Vertices.
        n: usize,
        /// The limit.
        limit: usize,
    },
}

/// Largest `n` for which [`all_pairs`] builds its `n x n` matrix (8 * n^2 bytes: 800 MB at
/// the limit).
pub const ALL_PAIRS_LIMIT: usize = 10_000;

/// `basis` as a view, once each of `vertices` is checked to be one of its vertices.
fn view_at<'a>(
    basis: impl Into<BasisView<'a>>,
    vertices: &[usize],
) -> Result<BasisView<'a>, DistanceError> {
    let basis: BasisView<'a> = basis.into();
    match vertices.iter().find(|&&v| v >= basis.n) {
        Some(&vertex) => Err(DistanceError::VertexOutOfRange { vertex, n: basis.n }),
        None => Ok(basis),
    }
}

/// [`view_at`], with the `k` weights of `weights` for the basis.
fn weighed_view_at<'a, 'w>(
    basis: impl Into<BasisView<'a>>,
    vertices: &[usize],
    weights: impl Into<Weights<'w>>,
) -> Result<(BasisView<'a>, std::borrow::Cow<'w, [f64]>), DistanceError> {
    let basis = view_at(basis, vertices)?;
    let w = weights.into().of(basis)?;
    Ok((basis, w))
}

/// [`view_at`] the vertex `source`, refusing a diffusion time `t` that is not finite and
/// `>= 0`.
fn diffusion_view_at<'a>(
    basis: impl Into<BasisView<'a>>,
    source: usize,
    t: f64,
) -> Result<BasisView<'a>, DistanceError> {
    let basis = view_at(basis, &[source])?;
    if t.is_finite() && t >= 0.0 {
        Ok(basis)
    } else {
        Err(DistanceError::InvalidTime(t))
    }
}

/// Squared distances from `source` with per-pair weights `w` on the vectors `x` (column-major
/// `n x k`), O(nk), parallel over blocks of rows.
fn weighted_sq_from(x: &[f64], n: usize, w: &[f64], source: usize) -> Vec<f64> {
    weighted_squares(x, n, w, Some(source))
}

/// `sum_j w_j (x_j(p) - x_j(source))^2` for every row `p` (`x_j(p)^2` without a source),
/// over the pairs with `w_j != 0`, in order. Parallel over blocks of rows; the columns are
/// taken four at a time with each row's sum in a register (the same additions in the
/// same order as one column at a time, so the same bits, in a third of the time).
fn weighted_squares(x: &[f64], n: usize, w: &[f64], source: Option<usize>) -> Vec<f64> {
    // (column, (weight, value at the source; 0 without one: x - 0 is x to the bit)).
    let used: Vec<(usize, (f64, f64))> = w
        .iter()
        .enumerate()
        .filter(|&(_, &wj)| wj != 0.0)
        .map(|(j, &wj)| (j, (wj, source.map_or(0.0, |s| x[j * n + s]))))
        .collect();
    accumulate_columns(x, n, w.len(), &used, |t, xi, (wj, xs)| {
        let e = xi - xs;
        t + wj * e * e
    })
}

/// The per-pair weights `w_k` of a distance or kernel: a [`Filter`]'s (evaluated at the
/// eigenvalues of the basis it is used with), or given (`k` entries, 0 for the pairs left
/// out; from [`Filter::weights`] or [`weights_of_pairs`], e.g. of a function given outside
/// the filter language). Every function of this module that takes weights takes either:
/// `&filter`, `&w` or `Weights::Given(&w)`.
#[derive(Debug, Clone, Copy)]
pub enum Weights<'w> {
    /// The weights of a filter.
    Filter(&'w Filter),
    /// The weights given, one per pair of the basis.
    Given(&'w [f64]),
}

impl<'w> From<&'w Filter> for Weights<'w> {
    fn from(f: &'w Filter) -> Self {
        Weights::Filter(f)
    }
}

impl<'w> From<&'w [f64]> for Weights<'w> {
    fn from(w: &'w [f64]) -> Self {
        Weights::Given(w)
    }
}

impl<'w> From<&'w Vec<f64>> for Weights<'w> {
    fn from(w: &'w Vec<f64>) -> Self {
        Weights::Given(w)
    }
}

impl<'w> Weights<'w> {
    /// The `k` weights for `basis` (a filter's computed, given ones checked).
    fn of(self, basis: BasisView<'_>) -> Result<std::borrow::Cow<'w, [f64]>, DistanceError> {
        Ok(match self {
            Weights::Filter(f) => f.weights(basis.values)?.into(),
            Weights::Given(w) => {
                check_weights(basis, w)?;
                w.into()
            }
        })
    }
}

/// Filtered spectral distances from `source` to every vertex (`n` values), O(nk):
/// `d(p,q) = sqrt(sum_{lambda_k > 0} w_k (x_k(p) - x_k(q))^2)`.
pub fn distances_from<'a, 'w>(
    basis: impl Into<BasisView<'a>>,
    source: usize,
    weights: impl Into<Weights<'w>>,
) -> Result<Vec<f64>, DistanceError> {
    Ok(distances_from_many(basis, &[source], weights)?.swap_remove(0))
}

/// Distances from each of `sources` (one `n`-vector per source), parallel over sources.
pub fn distances_from_many<'a, 'w>(
    basis: impl Into<BasisView<'a>>,
    sources: &[usize],
    weights: impl Into<Weights<'w>>,
) -> Result<Vec<Vec<f64>>, DistanceError> {
    let (basis, w) = weighed_view_at(basis, sources, weights)?;
    Ok(sources
        .par_iter()
        .map(|&s| {
            let mut d = weighted_sq_from(basis.vectors, basis.n, &w, s);
            d.iter_mut().for_each(|v| *v = v.sqrt());
            d
        })
        .collect())
}

/// Row-major `n x m` embedding with the pairs of non-zero weight scaled by `sqrt(w)`.
fn weighted_rows(basis: BasisView<'_>, w: &[f64]) -> (Vec<f64>, usize) {
    let n = basis.n;
    let used: Vec<usize> = (0..w.len()).filter(|&j| w[j] > 0.0).collect();
    let m = used.len();
    let mut e = vec![0.0; n * m];
    e.par_chunks_mut(m.max(1)).enumerate().for_each(|(i, row)| {
        for (c, &j) in used.iter().enumerate() {
            row[c] = w[j].sqrt() * basis.vectors[j * n + i];
        }
    });
    (e, m)
}

/// All pairwise distances, a symmetric row-major `n x n` matrix with an exact zero
/// diagonal. O(n^2 k), parallel over rows; refused above [`ALL_PAIRS_LIMIT`] vertices.
/// Each entry is computed from differences (not from the Gram matrix), so small distances
/// keep their relative accuracy.
pub fn all_pairs<'a>(
    basis: impl Into<BasisView<'a>>,
    filter: &Filter,
) -> Result<Vec<f64>, DistanceError> {
    let basis: BasisView<'a> = basis.into();
    let n = basis.n;
    if n > ALL_PAIRS_LIMIT {
        return Err(DistanceError::TooLarge {
            n,
            limit: ALL_PAIRS_LIMIT,
        });
    }
    let w = filter.weights(basis.values)?;
    let (e, m) = weighted_rows(basis, &w);
    let mut out = vec![0.0; n * n];
    out.par_chunks_mut(n).enumerate().for_each(|(i, row)| {
        let ei = &e[i * m..(i + 1) * m];
        for (j, r) in row.iter_mut().enumerate().take(i) {
            let ej = &e[j * m..(j + 1) * m];
            let s: f64 = ei.iter().zip(ej).map(|(a, b)| (a - b) * (a - b)).sum();
            *r = s.sqrt();
        }
    });
    // Mirror the lower triangle.
    for i in 0..n {
        for j in 0..i {
            out[j * n + i] = out[i * n + j];
        }
    }
    Ok(out)
}

/// The row `G(p, .)` of the generalized Green kernel `G = X diag(w) X^T` (`n` values).
pub fn green_row<'a, 'w>(
    basis: impl Into<BasisView<'a>>,
    p: usize,
    weights: impl Into<Weights<'w>>,
) -> Result<Vec<f64>, DistanceError> {
    let (basis, w) = weighed_view_at(basis, &[p], weights)?;
    let n = basis.n;
    let c: Vec<f64> = w
        .iter()
        .enumerate()
        .map(|(j, wj)| wj * basis.vectors[j * n + p])
        .collect();
    Ok(super::heat::combine_columns(basis.vectors, n, &c))
}

/// The generalized spectral function `p -> G(p,p) = sum_k w_k x_k(p)^2` (`n` values). With
/// the diffusion filter this is the auto-diffusion function.
pub fn spectral_function<'a, 'w>(
    basis: impl Into<BasisView<'a>>,
    weights: impl Into<Weights<'w>>,
) -> Result<Vec<f64>, DistanceError> {
    let (basis, w) = weighed_view_at(basis, &[], weights)?;
    Ok(weighted_squares(basis.vectors, basis.n, &w, None))
}

/// The eigenvalues a filter weighs, with their pair indices: every pair of `eigenvalues`
/// whose eigenvalue is not zero by the rule of [`Filter::weights`]
/// (`|lambda| > ZERO_EIGENVALUE_EPS * lambda_max`). A weight function given outside the
/// filter language (a Python function) is evaluated at these values, and
/// [`weights_of_pairs`] turns its values into the `k` weights.
pub fn weighted_pairs(eigenvalues: &[f64]) -> Result<(Vec<usize>, Vec<f64>), FilterError> {
    // `w = s^0 = 1` on every pair that is not zero, 0 on the zero ones: the filters' rule.
    let ones = Filter::Polynomial { p: 0.0 }.weights(eigenvalues)?;
    let used: Vec<usize> = (0..ones.len()).filter(|&j| ones[j] > 0.0).collect();
    let values = used.iter().map(|&j| eigenvalues[j]).collect();
    Ok((used, values))
}

/// The `k` per-pair weights of a weight function evaluated elsewhere: `given[i]` is its
/// value at the `i`-th eigenvalue of [`weighted_pairs`]; the zero pairs get 0. Every given
/// weight must be strictly positive and finite, as [`Filter::weights`] requires of its
/// filters ([`FilterError::NotPositive`] names the first failing pair; `name` says what
/// the function was).
pub fn weights_of_pairs(
    eigenvalues: &[f64],
    given: &[f64],
    name: &str,
) -> Result<Vec<f64>, FilterError> {
    let (used, values) = weighted_pairs(eigenvalues)?;
    if given.len() != used.len() {
        return Err(FilterError::InvalidParameter(format!(
            "{name} gave {} weights for {} eigenvalues",
            given.len(),
            used.len()
        )));
    }
    let mut w = vec![0.0; eigenvalues.len()];
    for ((&j, &l), &g) in used.iter().zip(&values).zip(given) {
        w[j] = positive_weight(&name, j, l, g)?;
    }
    Ok(w)
}

/// Refuses weights that are not one per pair of the basis.
pub(super) fn check_weights(basis: BasisView<'_>, w: &[f64]) -> Result<(), DistanceError> {
    if w.len() == basis.values.len() {
        Ok(())
    } else {
        Err(FilterError::InvalidParameter(format!(
            "{} weights for a basis of {} pairs",
            w.len(),
            basis.values.len()
        ))
        .into())
    }
}

/// `B X` (column-major `n x k`) of a basis view: what [`wfem_diffusion_distances_with`]
/// reuses across sources and times. O(nnz(B) k), parallel over columns.
pub fn mass_times_vectors<'a>(basis: impl Into<BasisView<'a>>) -> Vec<f64> {
    let basis: BasisView<'a> = basis.into();
    let n = basis.n;
    let mut y = vec![0.0; n * basis.k()];
    y.par_chunks_mut(n.max(1)).enumerate().for_each(|(j, col)| {
        col.copy_from_slice(&basis.mass.mul_vec(basis.vector(j)));
    });
    y
}

/// The wFEM diffusion distances of eq. 15 from `source`:
/// `d_t(i,j)^2 = (e_i - e_j)^T S_t (e_i - e_j)`, `S_t = B X D_t X^T B`, all `k` pairs
/// (including the zero eigenvalue), O(nk + nnz(B) k).
pub fn wfem_diffusion_distances_from<'a>(
    basis: impl Into<BasisView<'a>>,
    source: usize,
    t: f64,
) -> Result<Vec<f64>, DistanceError> {
    let basis: BasisView<'a> = basis.into();
    wfem_diffusion_distances_with(basis, &mass_times_vectors(basis), source, t)
}

/// [`wfem_diffusion_distances_from`] with `B X` given (`bx`, column-major `n x K` for any
/// `K >= k`: the first `k` columns are used), O(nk).
pub fn wfem_diffusion_distances_with<'a>(
    basis: impl Into<BasisView<'a>>,
    bx: &[f64],
    source: usize,
    t: f64,
) -> Result<Vec<f64>, DistanceError> {
    let basis = diffusion_view_at(basis, source, t)?;
    let (n, k) = (basis.n, basis.k());
    assert!(bx.len() >= n * k, "B X holds fewer than k columns");
    let w: Vec<f64> = basis.values.iter().map(|l| (-l * t).exp()).collect();
    let mut d = weighted_sq_from(&bx[..n * k], n, &w, source);
    d.iter_mut().for_each(|v| *v = v.max(0.0).sqrt());
    Ok(d)
}

/// The wFEM diffusion kernel matrix entries `S_t(source, .)` (`n` values) of eq. 15.
pub fn wfem_diffusion_kernel_row<'a>(
    basis: impl Into<BasisView<'a>>,
    source: usize,
    t: f64,
) -> Result<Vec<f64>, DistanceError> {
    let basis = diffusion_view_at(basis, source, t)?;
    let n = basis.n;
    // S_t e_s = B X D_t (X^T B e_s).
    let bs: Vec<f64> = {
        let mut e = vec![0.0; n];
        e[source] = 1.0;
        basis.mass.mul_vec(&e)
    };
    let mut c = super::heat::project(basis.vectors, n, &bs);
    for (cj, l) in c.iter_mut().zip(basis.values) {
        *cj *= (-l * t).exp();
    }
    Ok(basis
        .mass
        .mul_vec(&super::heat::combine_columns(basis.vectors, n, &c)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::heat::ROW_BLOCK;

    /// A weight function evaluated outside the filter language sees the filters' non-zero
    /// eigenvalues, is checked as the filters are, and gives their distances to the bit.
    #[test]
    fn weights_of_a_function_are_the_filters_weights() {
        let ev = [1e-14, 0.5, 2.0, 4.0];
        let (used, values) = weighted_pairs(&ev).unwrap();
        assert_eq!(used, vec![1, 2, 3]);
        assert_eq!(values, vec![0.5, 2.0, 4.0]);
        let given: Vec<f64> = values.iter().map(|s| 1.0 / s).collect();
        let w = weights_of_pairs(&ev, &given, "f").unwrap();
        assert_eq!(w, Filter::CommuteTime.weights(&ev).unwrap());
        match weights_of_pairs(&ev, &[1.0, -1.0, 1.0], "f").unwrap_err() {
            FilterError::NotPositive { index, value, .. } => assert_eq!((index, value), (2, 2.0)),
            e => panic!("{e}"),
        }
        assert!(weights_of_pairs(&ev, &[1.0, f64::NAN, 1.0], "f").is_err());
        assert!(weights_of_pairs(&ev, &[1.0], "f").is_err());
        assert_eq!(
            weighted_pairs(&[0.0, 0.0]).unwrap_err(),
            FilterError::EmptySpectrum
        );
        // The same weights give the same distances, Green rows and spectral functions.
        let n = 5;
        let vectors: Vec<f64> = (0..n * ev.len())
            .map(|i| ((i * 7) % 11) as f64 - 5.0)
            .collect();
        let mass = crate::linalg::SparseMatrix::identity(n);
        let basis = BasisView {
            laplacian: crate::operators::Laplacian::Fem,
            n,
            values: &ev,
            vectors: &vectors,
            mass: &mass,
        };
        let f = Filter::CommuteTime;
        assert_eq!(
            distances_from(basis, 2, &f).unwrap(),
            distances_from(basis, 2, &w).unwrap()
        );
        assert_eq!(
            green_row(basis, 1, &f).unwrap(),
            green_row(basis, 1, &w).unwrap()
        );
        assert_eq!(
            spectral_function(basis, &f).unwrap(),
            spectral_function(basis, &w).unwrap()
        );
        assert!(spectral_function(basis, &w[..3]).is_err());
    }

    /// The four-column kernel gives the bits of one column at a time (zero weights
    /// skipped), with and without a source, serial and parallel sizes.
    #[test]
    fn weighted_squares_are_one_column_at_a_time() {
        let mut rnd = crate::test_support::lcg53(3);
        let mut next = || rnd() - 0.4;
        for (n, k) in [
            (4, 2),
            (99, 11),
            (ROW_BLOCK + 5, 14),
            (2 * ROW_BLOCK + 1, 61),
        ] {
            let x: Vec<f64> = (0..n * k).map(|_| next()).collect();
            let mut w: Vec<f64> = (0..k).map(|_| next().abs() * 50.0).collect();
            w[0] = 0.0;
            w[k - 1] = 0.0;
            for source in [None, Some(0), Some(n - 1), Some(n / 2)] {
                let mut naive = vec![0.0; n];
                for (j, &wj) in w.iter().enumerate() {
                    if wj != 0.0 {
                        let xs = source.map_or(0.0, |s| x[j * n + s]);
                        for i in 0..n {
                            let e = x[j * n + i] - xs;
                            naive[i] += wj * e * e;
                        }
                    }
                }
                let got = weighted_squares(&x, n, &w, source);
                assert!(
                    got.iter()
                        .zip(&naive)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "n {n} k {k} source {source:?}"
                );
                if let Some(s) = source {
                    assert_eq!(got[s], 0.0);
                    assert_eq!(weighted_sq_from(&x, n, &w, s), got);
                }
            }
        }
    }
}
