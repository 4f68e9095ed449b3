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
//! Nearest neighbours: up to [`KD_TREE_MAX_DIM`] columns from a k-d tree (`kiddo`, exact)
//! over the rows, padded with zeros to the next supported width (padding changes no
//! distance); wider embeddings (the usual 30-100 eigenfunctions, where a k-d tree splits
//! on a few coordinates only and prunes almost nothing) from a tree of hyperplanes fitted
//! to the rows (see `nearest_tree`): a spectral embedding is a surface, two-dimensional
//! however many columns it has, and a query on or near it visits a leaf or a few.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::{CorrespondenceError, FunctionalMap, truncate};
use crate::linalg::dense_ops::{gram, product, product_transposed};
use crate::linalg::sym_spmm;
use crate::spectral::BasisView;

/// Widest embedding searched with the k-d tree.
pub const KD_TREE_MAX_DIM: usize = 16;

fn row<const K: usize>(x: &[f64], n: usize, d: usize, i: usize) -> [f64; K] {
    let mut r = [0.0; K];
    for (q, rq) in r.iter_mut().enumerate().take(d) {
        *rq = x[q * n + i];
    }
    r
}

/// One nearest-row search, checked: `m` queries (`m x d`, column-major) among `n` points
/// (`n x d`), with a guessed point for each query or none.
#[derive(Clone, Copy)]
struct Search<'a> {
    points: &'a [f64],
    n: usize,
    queries: &'a [f64],
    m: usize,
    d: usize,
    hint: Option<&'a [usize]>,
}

fn nearest_kd<const K: usize>(search: Search<'_>) -> Vec<usize> {
    let (n, m, d) = (search.n, search.m, search.d);
    let rows: Vec<[f64; K]> = (0..n).map(|i| row::<K>(search.points, n, d, i)).collect();
    let tree: ImmutableKdTree<f64, K> = ImmutableKdTree::new_from_slice(&rows);
    let one = std::num::NonZero::<usize>::MIN;
    (0..m)
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let q = row::<K>(search.queries, m, d, i);
            match search.hint {
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

/// Leaves of a projection tree hold at most this many rows (at least half as many).
const LEAF_SIZE: usize = 16;

/// The sum of `term(a_i, b_i)`, in eight lanes (the same order on every SIMD level: no
/// fused operations, so every caller gets the same bits).
#[inline(always)]
fn lane_sum(a: &[f64], b: &[f64], term: impl Fn(f64, f64) -> f64) -> f64 {
    let mut acc = [0.0f64; 8];
    let (ra, rb) = (a.chunks_exact(8).remainder(), b.chunks_exact(8).remainder());
    for (x, y) in a.chunks_exact(8).zip(b.chunks_exact(8)) {
        for l in 0..8 {
            acc[l] += term(x[l], y[l]);
        }
    }
    for (l, (x, y)) in ra.iter().zip(rb).enumerate() {
        acc[l] += term(*x, *y);
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]))
}

/// Squared Euclidean distance (see [`lane_sum`]).
#[inline(always)]
fn dist2(a: &[f64], b: &[f64]) -> f64 {
    lane_sum(a, b, |x, y| (x - y) * (x - y))
}

/// Dot product (see [`lane_sum`]).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    lane_sum(a, b, |x, y| x * y)
}

/// A node of a [`ProjectionTree`].
#[derive(Clone, Copy, Debug)]
enum Node {
    /// Gathered rows `start..end`.
    Leaf { start: usize, end: usize },
    /// Rows split by a hyperplane.
    Split(Split),
}

/// Rows split by their projection on the unit direction `dirs[dir * d..]`: those of the
/// node `left` project to at most `lo`, those of `right` to at least `hi`.
#[derive(Clone, Copy, Debug)]
struct Split {
    dir: usize,
    lo: f64,
    hi: f64,
    left: usize,
    right: usize,
}

/// A binary space partition of the rows of an `n x d` matrix by hyperplanes through the
/// median of their projection on the line through two far-apart rows (a random-projection
/// tree without the randomness): for points on a surface it adapts to the surface,
/// whatever the number of columns, where a k-d tree splits on a few coordinates only.
/// Rows are gathered row-major in the order of the leaves.
struct ProjectionTree {
    d: usize,
    rows: Vec<f64>,
    /// The original index of each gathered row.
    index: Vec<usize>,
    /// Node 0 is the root.
    nodes: Vec<Node>,
    dirs: Vec<f64>,
}

/// A subtree under construction: nodes (indices local to it, 0 its root), directions,
/// and the rows' original indices in leaf order.
struct Subtree {
    nodes: Vec<Node>,
    dirs: Vec<f64>,
    index: Vec<usize>,
}

impl Subtree {
    /// Appends `other`, shifting its node, direction and row indices.
    fn append(&mut self, other: Subtree, d: usize) -> usize {
        let (node0, dir0, row0) = (
            self.nodes.len(),
            self.dirs.len() / d.max(1),
            self.index.len(),
        );
        self.nodes
            .extend(other.nodes.into_iter().map(|nd| match nd {
                Node::Leaf { start, end } => Node::Leaf {
                    start: start + row0,
                    end: end + row0,
                },
                Node::Split(sp) => Node::Split(Split {
                    dir: sp.dir + dir0,
                    left: sp.left + node0,
                    right: sp.right + node0,
                    ..sp
                }),
            }));
        self.dirs.extend(other.dirs);
        self.index.extend(other.index);
        node0
    }
}

/// Builds the subtree of the rows `idx` of the row-major `rows`.
fn build(rows: &[f64], d: usize, idx: &mut [usize]) -> Subtree {
    let len = idx.len();
    if len <= LEAF_SIZE {
        return Subtree {
            nodes: vec![Node::Leaf { start: 0, end: len }],
            dirs: Vec::new(),
            index: idx.to_vec(),
        };
    }
    let r = |i: usize| &rows[i * d..(i + 1) * d];
    // The far-apart rows among at most about 256 of them (a direction, not a bound: any
    // would do for exactness).
    let stride = (len / 256).max(1);
    let farthest = |from: &[f64]| {
        let mut best = (-1.0, idx[0]);
        for &i in idx.iter().step_by(stride) {
            let s = dist2(r(i), from);
            if s > best.0 {
                best = (s, i);
            }
        }
        best.1
    };
    let a = farthest(r(idx[0]));
    let b = farthest(r(a));
    let mut dir: Vec<f64> = r(b).iter().zip(r(a)).map(|(y, x)| y - x).collect();
    let norm = dot(&dir, &dir).sqrt();
    if norm > 0.0 {
        for w in dir.iter_mut() {
            *w /= norm;
        }
    }
    let mut keyed: Vec<(f64, usize)> = idx.iter().map(|&i| (dot(r(i), &dir), i)).collect();
    let mid = len / 2;
    keyed.select_nth_unstable_by(mid, |x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let lo = keyed[..mid]
        .iter()
        .map(|k| k.0)
        .fold(f64::NEG_INFINITY, f64::max);
    let hi = keyed[mid].0;
    for (dst, (_, i)) in idx.iter_mut().zip(keyed) {
        *dst = i;
    }
    let (l_idx, r_idx) = idx.split_at_mut(mid);
    let (left, right) = if len >= 2048 {
        rayon::join(|| build(rows, d, l_idx), || build(rows, d, r_idx))
    } else {
        (build(rows, d, l_idx), build(rows, d, r_idx))
    };
    let mut t = Subtree {
        nodes: vec![Node::Leaf { start: 0, end: 0 }],
        dirs: dir,
        index: Vec::with_capacity(len),
    };
    let left = t.append(left, d);
    let right = t.append(right, d);
    t.nodes[0] = Node::Split(Split {
        dir: 0,
        lo,
        hi,
        left,
        right,
    });
    t
}

impl ProjectionTree {
    /// The tree of the rows of the column-major `n x d` matrix `x` (`d >= 1`).
    fn new(x: &[f64], n: usize, d: usize) -> Self {
        let orig = row_major(x, n, d);
        let mut idx: Vec<usize> = (0..n).collect();
        let t = build(&orig, d, &mut idx);
        let mut rows = vec![0.0; n * d];
        rows.par_chunks_mut(d)
            .zip(&t.index)
            .for_each(|(dst, &i)| dst.copy_from_slice(&orig[i * d..(i + 1) * d]));
        Self {
            d,
            rows,
            index: t.index,
            nodes: t.nodes,
            dirs: t.dirs,
        }
    }

    fn row(&self, i: usize) -> &[f64] {
        &self.rows[i * self.d..(i + 1) * self.d]
    }
}

/// The rows of a column-major `n x d` matrix, row-major.
fn row_major(x: &[f64], n: usize, d: usize) -> Vec<f64> {
    const CHUNK: usize = 256;
    let mut out = vec![0.0; n * d];
    out.par_chunks_mut(d * CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            for (t, row) in chunk.chunks_mut(d).enumerate() {
                let i = c * CHUNK + t;
                for (q, v) in row.iter_mut().enumerate() {
                    *v = x[q * n + i];
                }
            }
        });
    out
}

/// The nearest-row search of a run of queries, compiled for the SIMD level pulp detects.
struct TreeSearch<'a> {
    tree: &'a ProjectionTree,
    /// Row-major queries.
    queries: &'a [f64],
    /// (query row, gathered position of its hinted point row or `usize::MAX`) to search;
    /// the answers (original point rows) overwrite the second.
    jobs: &'a mut [(usize, usize)],
    slack: f64,
}

impl pulp::WithSimd for TreeSearch<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        self.run();
    }
}

impl TreeSearch<'_> {
    #[inline(always)]
    fn run(self) {
        let t = self.tree;
        let d = t.d;
        let mut stack: Vec<(usize, f64)> = Vec::with_capacity(64);
        for job in self.jobs.iter_mut() {
            let q = &self.queries[job.0 * d..(job.0 + 1) * d];
            let mut best = if job.1 == usize::MAX {
                (f64::INFINITY, usize::MAX)
            } else {
                (dist2(q, t.row(job.1)), t.index[job.1])
            };
            let mut radius = best.0.sqrt() + self.slack;
            stack.clear();
            stack.push((0, 0.0));
            while let Some((i, lb)) = stack.pop() {
                if lb > radius {
                    continue;
                }
                match t.nodes[i] {
                    Node::Leaf { start, end } => {
                        for p in start..end {
                            let s = dist2(q, t.row(p));
                            let j = t.index[p];
                            if s < best.0 || (s == best.0 && j < best.1) {
                                best = (s, j);
                            }
                        }
                        radius = best.0.sqrt() + self.slack;
                    }
                    Node::Split(sp) => {
                        let s = dot(q, &t.dirs[sp.dir * d..(sp.dir + 1) * d]);
                        let (l_lb, r_lb) = (lb.max(s - sp.lo), lb.max(sp.hi - s));
                        // The nearer side last, to be searched first.
                        if l_lb <= r_lb {
                            stack.push((sp.right, r_lb));
                            stack.push((sp.left, l_lb));
                        } else {
                            stack.push((sp.left, l_lb));
                            stack.push((sp.right, r_lb));
                        }
                    }
                }
            }
            job.1 = best.1;
        }
    }
}

/// Exact nearest rows (the first of equally near ones) through a [`ProjectionTree`] over
/// the points: each query descends to its side of each hyperplane first and visits the
/// other side only when the hyperplane is nearer than its best row so far (the hinted
/// row's distance at the start, when hints are given), so a query lying on the surface of
/// the points visits about one leaf. The bounds carry a slack for rounding (`1e-12` of the
/// largest row norm), so pruning never drops a row the exhaustive search would choose.
/// Both cores: runs of queries in parallel, in the order of their hints when given (rows
/// near each other in the tree, for the caches).
fn nearest_tree(search: Search<'_>) -> Vec<usize> {
    let (n, m, d) = (search.n, search.m, search.d);
    if m == 0 {
        return Vec::new();
    }
    let (tree, qrows) = rayon::join(
        || ProjectionTree::new(search.points, n, d),
        || row_major(search.queries, m, d),
    );
    let max_norm = |x: &[f64]| {
        x.chunks_exact(d)
            .map(|r| dot(r, r))
            .fold(0.0, f64::max)
            .sqrt()
    };
    let slack = 1e-12 * (max_norm(&tree.rows) + max_norm(&qrows)) + f64::MIN_POSITIVE;
    let mut jobs: Vec<(usize, usize)> = match search.hint {
        Some(h) => {
            let mut rank = vec![0; n];
            for (p, &i) in tree.index.iter().enumerate() {
                rank[i] = p;
            }
            let mut j: Vec<(usize, usize)> = (0..m).map(|i| (i, rank[h[i]])).collect();
            j.sort_unstable_by_key(|&(i, p)| (p, i));
            j
        }
        None => (0..m).map(|i| (i, usize::MAX)).collect(),
    };
    let arch = pulp::Arch::new();
    jobs.par_chunks_mut(512).for_each(|run| {
        arch.dispatch(TreeSearch {
            tree: &tree,
            queries: &qrows,
            jobs: run,
            slack,
        });
    });
    let mut out = vec![0; m];
    for (i, j) in jobs {
        out[i] = j;
    }
    out
}

/// For each of the `m` rows of `queries` (`m x d`, column-major), the index of the
/// nearest of the `n` rows of `points` (`n x d`) in the Euclidean distance (among rows at
/// the same distance, the first).
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
    let search = Search {
        points,
        n,
        queries,
        m,
        d,
        hint,
    };
    Ok(match d {
        0..=8 => nearest_kd::<8>(search),
        9..=KD_TREE_MAX_DIM => nearest_kd::<KD_TREE_MAX_DIM>(search),
        _ => nearest_tree(search),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::lcg;

    /// Every point against every query, the first of the nearest.
    fn exhaustive(points: &[f64], n: usize, queries: &[f64], m: usize, d: usize) -> Vec<usize> {
        let rows = |x: &[f64], len: usize| -> Vec<Vec<f64>> {
            (0..len)
                .map(|i| (0..d).map(|c| x[c * len + i]).collect())
                .collect()
        };
        let (p, q) = (rows(points, n), rows(queries, m));
        q.iter()
            .map(|qi| {
                let mut best = (f64::INFINITY, 0);
                for (j, pj) in p.iter().enumerate() {
                    let s = dist2(qi, pj);
                    if s < best.0 {
                        best = (s, j);
                    }
                }
                best.1
            })
            .collect()
    }

    /// Column-major `len x d` from a row function.
    fn matrix(len: usize, d: usize, mut f: impl FnMut(usize, usize) -> f64) -> Vec<f64> {
        let mut x = vec![0.0; len * d];
        for i in 0..len {
            for c in 0..d {
                x[c * len + i] = f(i, c);
            }
        }
        x
    }

    #[test]
    fn tree_search_equals_an_exhaustive_search_on_random_rows() {
        for (seed, &(n, m, d)) in [
            (1500, 1200, 17),
            (2000, 700, 40),
            (40, 3000, 100),
            (1, 9, 20),
        ]
        .iter()
        .enumerate()
        {
            let mut rnd = lcg(seed as u64 + 11);
            let mut points = matrix(n, d, |_, _| 2.0 * rnd() - 1.0);
            // Ties: the second half of the points repeats rows of the first half.
            for i in n.div_ceil(2)..n {
                for c in 0..d {
                    points[c * n + i] = points[c * n + i - n.div_ceil(2)];
                }
            }
            // Queries: random rows, copies of points (distance 0) and points moved a little.
            let queries = matrix(m, d, |i, c| match i % 3 {
                0 => 2.0 * rnd() - 1.0,
                1 => points[c * n + (i * 7) % n],
                _ => points[c * n + (i * 13) % n] + 0.01 * (rnd() - 0.5),
            });
            let want = exhaustive(&points, n, &queries, m, d);
            assert_eq!(nearest_rows(&points, n, &queries, m, d).unwrap(), want);
            let hint: Vec<usize> = (0..m).map(|i| (i * 31 + 5) % n).collect();
            let got = nearest_rows_hinted(&points, n, &queries, m, d, Some(&hint)).unwrap();
            assert_eq!(got, want, "{n} x {d} with hints");
        }
    }

    #[test]
    fn tree_search_equals_an_exhaustive_search_on_a_surface() {
        // A torus-like surface embedded in 60 dimensions by waves of rising frequency (as
        // a spectral embedding is), and queries near it: the case the pruning is for.
        let (side, d) = (70, 60);
        let n = side * side;
        let wave = |u: f64, v: f64, c: usize| {
            let f = 1.0 + (c / 4) as f64;
            let a = (c % 4) as f64 * 0.7;
            (f * u + a).sin() * (f * v - a).cos() / f
        };
        let tau = std::f64::consts::TAU;
        let points = matrix(n, d, |i, c| {
            wave(
                tau * (i / side) as f64 / side as f64,
                tau * (i % side) as f64 / side as f64,
                c,
            )
        });
        let mut rnd = lcg(5);
        let m = 3000;
        let uv: Vec<(f64, f64)> = (0..m).map(|_| (tau * rnd(), tau * rnd())).collect();
        let queries = matrix(m, d, |i, c| {
            wave(uv[i].0, uv[i].1, c) + 1e-3 * (rnd() - 0.5)
        });
        let want = exhaustive(&points, n, &queries, m, d);
        assert_eq!(nearest_rows(&points, n, &queries, m, d).unwrap(), want);
    }
}
