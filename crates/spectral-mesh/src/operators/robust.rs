//! The robust Laplacian of Sharp and Crane ("A Laplacian for Nonmanifold Triangle
//! Meshes", SGP 2020) for any triangle soup: non-manifold edges, pinched vertices,
//! zero-area and duplicate triangles, several components.
//!
//! # The pipeline
//! 1. **Edge lengths.** Every distinct undirected edge `{i, j}` of the input gets its
//!    Euclidean length; nothing else of the embedding is used afterwards (the operator is
//!    intrinsic).
//! 2. **Intrinsic mollification.** With `delta = mollify_factor * mean edge length` (mean
//!    over distinct edges), every length is increased by the one smallest
//!    `epsilon >= 0` for which each triangle satisfies its triangle inequalities with a
//!    margin of at least `delta`: `epsilon = max(0, max over triangles and corners of
//!    l_k - l_i - l_j + delta)`. Zero-area triangles become thin but valid ones; a mesh
//!    whose triangles all have margins of at least `delta` is left untouched
//!    (`epsilon = 0`). This is `robust_laplacian.mesh_laplacian`'s `mollify_factor`, with
//!    the same default (`1e-5`).
//! 3. **Tufted cover.** Every triangle is doubled into two sheets of opposite orientation.
//!    Around each edge the triangles on it are ordered by the angle of their third vertex
//!    about the edge (clockwise seen along `p_i -> p_j`), and consecutive triangles are
//!    glued, one sheet of each, in a cycle; a boundary edge glues a triangle's two
//!    sheets to each other, a manifold edge gives two copies of the usual gluing. The
//!    result is a closed, oriented, edge-manifold surface (it may keep pinched vertices)
//!    with twice the input's area.
//! 4. **Intrinsic Delaunay.** Edges of the cover whose cotangent weight
//!    `(cot a + cot b) / 2` is below `-delaunay_tolerance` are flipped intrinsically (the
//!    new length comes from laying the two triangles out in the plane) until none is
//!    left; the cover's metric never changes, only its triangulation. The queue is first in,
//!    first out, all edges in order first, the four edges around a flip re-queued.
//! 5. **Matrices.** The cotangent stiffness and the barycentric lumped mass (a third of
//!    every intrinsic triangle's area to each corner) of the flipped cover, both halved
//!    (the cover has two sheets).
//!
//! # Conventions
//! - S is **positive semi-definite**, `S 1 = 0`, bit-symmetric; off the diagonal
//!   `S(i,j) = -sum of the weights of the intrinsic edges joining i and j`, all `<= 0` up
//!   to `delaunay_tolerance` (an intrinsic edge from a vertex to itself contributes nothing).
//!   This is `robust_laplacian.mesh_laplacian`'s L (same sign).
//! - B is diagonal and positive on every vertex some triangle uses; its total is the sum of
//!   the (mollified) areas of the input triangles, **each triangle counted as often as it
//!   appears** (a duplicated triangle counts twice, a zero-area one almost nothing): the
//!   cover has every triangle twice and is halved.
//! - A vertex that no triangle uses gets a zero row and column in S and B (as with the other
//!   discretizations; `robust_laplacian` instead puts 1 in L and a small mass there).
//!
//! # Relation to the other discretizations
//! On a manifold mesh that is already intrinsically Delaunay (every cotangent weight `>= 0`)
//! and whose triangles have margins of at least `delta`, no edge flips and nothing is
//! mollified: the robust pair is exactly the cotangent stiffness with the barycentric lumped
//! mass (the paper's "Voronoi-cot", [`super::Laplacian::VoronoiCot`]). Elsewhere it differs in
//! three ways, each of which is the point of it: negative cotangent weights are removed by
//! flips (so S is an M-matrix and the discrete maximum principle holds), degenerate
//! triangles are mollified instead of giving infinities, and non-manifold input is handled
//! through the cover instead of being refused.

use rayon::prelude::*;

use super::stiffness::{assemble_laplacian, double_area_from_lengths};
use crate::linalg::SparseMatrix;
use crate::mesh::{Mesh, cross, dot, norm, sub};

/// Default relative mollification, as `robust_laplacian.mesh_laplacian(mollify_factor=1e-5)`.
pub const DEFAULT_MOLLIFY_FACTOR: f64 = 1e-5;

/// Default tolerance of the Delaunay test: an edge is flipped when its cotangent weight
/// `(cot a + cot b) / 2` is below `-1e-6`, as in geometry-central's `flipToDelaunay`, which
/// `robust_laplacian` calls (so that the two agree to rounding).
pub const DEFAULT_DELAUNAY_TOLERANCE: f64 = 1e-6;

/// Parameters of the robust Laplacian. `Default` gives `robust_laplacian`'s defaults.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RobustParams {
    /// Relative mollification: `delta = mollify_factor * mean edge length` is the margin
    /// every triangle inequality gets (see the module docs). `0` turns mollification off
    /// (zero-area triangles then contribute nothing to S). Must be finite and `>= 0`.
    pub mollify_factor: f64,
    /// An edge is flipped while its cotangent weight is below `-delaunay_tolerance`
    /// (dimensionless). `0` flips every negative weight; a small positive value avoids
    /// flipping back and forth on rounding. Must be finite and `>= 0`.
    pub delaunay_tolerance: f64,
}

impl Default for RobustParams {
    fn default() -> Self {
        Self {
            mollify_factor: DEFAULT_MOLLIFY_FACTOR,
            delaunay_tolerance: DEFAULT_DELAUNAY_TOLERANCE,
        }
    }
}

impl RobustParams {
    /// Checks that both parameters are finite and `>= 0`.
    pub fn validate(&self) -> Result<(), RobustError> {
        for (name, v) in [
            ("mollify factor", self.mollify_factor),
            ("Delaunay tolerance", self.delaunay_tolerance),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(RobustError::BadParameter(format!(
                    "the {name} must be a finite number >= 0, got {v}"
                )));
            }
        }
        Ok(())
    }
}

/// Errors of the robust and point-cloud Laplacians (bad parameters only: every mesh and
/// every point cloud is accepted).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RobustError {
    /// A parameter is out of its range.
    #[error("{0}")]
    BadParameter(String),
}

/// What the robust pipeline did, for reports and tests.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RobustStats {
    /// Triangles of the input (each duplicate counted).
    pub triangles: usize,
    /// Distinct undirected edges of the input.
    pub edges: usize,
    /// Edges with one triangle.
    pub boundary_edges: usize,
    /// Edges with three or more triangles.
    pub non_manifold_edges: usize,
    /// Mean length of the distinct edges (before mollification).
    pub mean_edge_length: f64,
    /// The length added to every edge by mollification (`0` when none was needed).
    pub mollify_epsilon: f64,
    /// Intrinsic edge flips made on the cover.
    pub flips: usize,
    /// Edges of the cover left with a weight below `-delaunay_tolerance` because they
    /// cannot be flipped (both sides are the same triangle) or the flip would be
    /// numerically meaningless.
    pub unflippable_edges: usize,
    /// Vertices that no triangle uses (zero rows in S and B).
    pub unreferenced_vertices: usize,
}

/// The robust operator pair with what was done to build it.
#[derive(Debug, Clone)]
pub struct RobustLaplacian {
    /// Stiffness S, `n x n`, positive semi-definite, `S 1 = 0`.
    pub stiffness: SparseMatrix,
    /// Lumped mass B, `n x n`, diagonal, `>= 0` (zero only at unreferenced vertices).
    pub mass: SparseMatrix,
    /// What the pipeline did.
    pub stats: RobustStats,
}

/// The robust Laplacian (S, B) of `mesh` (see the module docs).
///
/// Errors only for parameters out of range ([`RobustParams::validate`]).
pub fn robust_laplacian(
    mesh: &Mesh,
    params: &RobustParams,
) -> Result<RobustLaplacian, RobustError> {
    params.validate()?;
    Ok(robust_from_soup(Soup::of_mesh(mesh, params)))
}

/// How the triangles around an edge are ordered before consecutive ones are glued.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Gluing {
    /// By angle about the edge (geometry-central's rule; copies of one triangle end up
    /// next to each other and are glued as folds).
    Angular,
    /// By angle, then copies of one triangle spread out so that consecutive faces are
    /// different triangles wherever the counts allow (copies glued in parallel sheets,
    /// not folded onto each other). The same as `Angular` when no triangle repeats.
    InterleaveCopies,
}

/// A triangle soup on raw arrays and how the robust pipeline treats it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Soup<'a> {
    /// Vertex positions.
    pub positions: &'a [[f64; 3]],
    /// Triangles indexing `positions`, three distinct vertices each.
    pub triangles: &'a [[usize; 3]],
    /// The parameters (valid ones).
    pub params: &'a RobustParams,
    /// Scale of the operators: 1 for a mesh, 1/3 for the union of local triangulations of
    /// a point cloud.
    pub factor: f64,
    /// How the triangles around an edge are glued.
    pub gluing: Gluing,
}

impl<'a> Soup<'a> {
    /// The triangles of `mesh`, unscaled, glued by angle.
    pub fn of_mesh(mesh: &'a Mesh, params: &'a RobustParams) -> Self {
        Soup {
            positions: mesh.positions(),
            triangles: mesh.triangles(),
            params,
            factor: 1.0,
            gluing: Gluing::Angular,
        }
    }
}

/// The robust pipeline on a soup.
pub(crate) fn robust_from_soup(soup: Soup<'_>) -> RobustLaplacian {
    robust_with_faces(soup, MollifyMean::Distinct, false).0
}

/// Which mean edge length sets the mollification margin `delta`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MollifyMean {
    /// The mean over distinct input edges (`robust_laplacian`'s, the default).
    Distinct,
    /// The mean over the cover's edges (an input edge with `k` triangles counted `k`
    /// times): geometry-central's heat-method solver mollifies the cover itself.
    Cover,
}

/// The intrinsic Delaunay triangulation of the tufted cover, after mollification and
/// flips: every face of the cover (both sheets) as three vertices and the intrinsic lengths
/// of its edges `[|v0 v1|, |v1 v2|, |v2 v0|]`. Its cotangent stiffness and lumped mass,
/// halved, are the robust pair.
#[derive(Debug, Clone, Default)]
pub(crate) struct IntrinsicFaces {
    /// Vertices of each face.
    pub vertices: Vec<[usize; 3]>,
    /// Intrinsic edge lengths of each face.
    pub lengths: Vec<[f64; 3]>,
    /// Mean length of the cover's edges (each edge once).
    pub mean_edge_length: f64,
}

/// [`robust_from_soup`] with the mollification mean chosen, and the cover's intrinsic
/// triangulation when `want_faces`.
pub(crate) fn robust_with_faces(
    soup: Soup<'_>,
    mean: MollifyMean,
    want_faces: bool,
) -> (RobustLaplacian, Option<IntrinsicFaces>) {
    // 6 halfedges per triangle in the cover: 32-bit indices whenever they fit.
    if soup.triangles.len().saturating_mul(6) < u32::MAX as usize
        && soup.positions.len() < u32::MAX as usize
    {
        run::<u32>(soup, mean, want_faces)
    } else {
        run::<usize>(soup, mean, want_faces)
    }
}

/// An index type for the cover's arrays.
trait Ix: Copy + Eq + Send + Sync {
    fn of(i: usize) -> Self;
    fn us(self) -> usize;
}

impl Ix for u32 {
    #[inline]
    fn of(i: usize) -> Self {
        i as u32
    }
    #[inline]
    fn us(self) -> usize {
        self as usize
    }
}

impl Ix for usize {
    #[inline]
    fn of(i: usize) -> Self {
        i
    }
    #[inline]
    fn us(self) -> usize {
        self
    }
}

/// The tufted cover as an oriented halfedge mesh of a closed surface: halfedge `h` runs
/// from `tail[h]` to `tail[next[h]]`; `twin[twin[h]] = h`; `len[h] = len[twin[h]]`;
/// `edge[h] = edge[twin[h]]` and `primary[edge[h]]` is one of the two.
/// Halfedge and edge ids never change; a flip rewires `next` and `tail`.
///
/// Edge ids and primary halfedges are numbered as geometry-central numbers them in
/// `buildIntrinsicTuftedCover` (first the input edges in order of first appearance, then
/// the edges split off them), so that the flips below happen in the same order as in
/// `robust_laplacian`: where the intrinsic Delaunay triangulation is not unique (cocircular
/// or nearly cocircular configurations within the tolerance) the lumped mass depends on
/// which one is reached, and this makes the two agree to rounding.
struct Cover<I> {
    next: Vec<I>,
    twin: Vec<I>,
    tail: Vec<I>,
    len: Vec<f64>,
    edge: Vec<I>,
    primary: Vec<I>,
}

fn run<I: Ix>(
    soup: Soup<'_>,
    mollify_mean: MollifyMean,
    want_faces: bool,
) -> (RobustLaplacian, Option<IntrinsicFaces>) {
    let Soup {
        positions,
        triangles: tris,
        params,
        factor,
        gluing,
    } = soup;
    let n = positions.len();
    let m = tris.len();
    let mut stats = RobustStats {
        triangles: m,
        ..Default::default()
    };
    let mut used = vec![false; n];
    for t in tris {
        for &v in t {
            used[v] = true;
        }
    }
    stats.unreferenced_vertices = used.iter().filter(|&&u| !u).count();
    if m == 0 {
        let r = RobustLaplacian {
            stiffness: SparseMatrix::from_triplets(n, n, &[]),
            mass: SparseMatrix::diagonal(&vec![0.0; n]),
            stats,
        };
        return (r, want_faces.then(IntrinsicFaces::default));
    }

    // --- 1. Distinct edges: input halfedges sorted by their undirected key.
    let key = |h: usize| -> (usize, usize) {
        let t = &tris[h / 3];
        let (a, b) = (t[h % 3], t[(h % 3 + 1) % 3]);
        (a.min(b), a.max(b))
    };
    let mut order: Vec<I> = (0..3 * m).map(I::of).collect();
    order.par_sort_unstable_by_key(|&h| {
        let (a, b) = key(h.us());
        (a, b, h.us())
    });
    // Runs of equal keys = edges. Lengths per input halfedge.
    let mut runs: Vec<usize> = Vec::with_capacity(3 * m / 2 + 2);
    runs.push(0);
    for i in 1..3 * m {
        if key(order[i].us()) != key(order[i - 1].us()) {
            runs.push(i);
        }
    }
    runs.push(3 * m);
    let n_edges = runs.len() - 1;
    stats.edges = n_edges;
    let mut he_len = vec![0.0f64; 3 * m];
    let mut sum = 0.0;
    for r in 0..n_edges {
        let (a, b) = key(order[runs[r]].us());
        let l = norm(sub(positions[b], positions[a]));
        sum += l;
        for &h in &order[runs[r]..runs[r + 1]] {
            he_len[h.us()] = l;
        }
        match runs[r + 1] - runs[r] {
            1 => stats.boundary_edges += 1,
            2 => {}
            _ => stats.non_manifold_edges += 1,
        }
    }
    let mean = sum / n_edges as f64;
    stats.mean_edge_length = mean;

    // --- 2. Mollification.
    let mut eps = 0.0f64;
    if params.mollify_factor > 0.0 {
        let base = match mollify_mean {
            MollifyMean::Distinct => mean,
            MollifyMean::Cover => he_len.iter().sum::<f64>() / (3 * m) as f64,
        };
        let delta = base * params.mollify_factor;
        eps = (0..m)
            .into_par_iter()
            .map(|t| {
                let l = [he_len[3 * t], he_len[3 * t + 1], he_len[3 * t + 2]];
                let mut e = 0.0f64;
                for k in 0..3 {
                    e = e.max(l[(k + 2) % 3] - l[k] - l[(k + 1) % 3] + delta);
                }
                e
            })
            .reduce(|| 0.0, f64::max);
    }
    stats.mollify_epsilon = eps;

    // --- 3. Tufted cover. Front face t = (t0, t1, t2), halfedge 3t+k: t_k -> t_{k+1}.
    // Back face m+t = (t0, t2, t1); the mirror of front halfedge k is back halfedge 2-k.
    let nh = 6 * m;
    let mut cover = Cover::<I> {
        next: (0..nh)
            .map(|h| I::of(h - h % 3 + (h % 3 + 1) % 3))
            .collect(),
        twin: vec![I::of(0); nh],
        tail: Vec::with_capacity(nh),
        len: Vec::with_capacity(nh),
        edge: vec![I::of(0); nh],
        primary: Vec::new(),
    };
    for t in tris {
        cover.tail.extend(t.iter().map(|&v| I::of(v)));
    }
    for t in tris {
        cover
            .tail
            .extend([t[0], t[2], t[1]].iter().map(|&v| I::of(v)));
    }
    cover.len.extend(he_len.iter().map(|&l| l + eps));
    for t in 0..m {
        for j in 0..3 {
            cover.len.push(he_len[3 * t + (2 - j)] + eps);
        }
    }
    drop(he_len);
    glue(&mut cover, positions, tris, &order, &runs, gluing);
    drop(order);
    drop(runs);

    // --- 4. Intrinsic Delaunay flips.
    let (flips, unflippable) = flip_to_delaunay(&mut cover, params.delaunay_tolerance);
    stats.flips = flips;
    stats.unflippable_edges = unflippable;

    // --- 5. Matrices (halved: two sheets; times `factor`).
    let half = 0.5 * factor;
    let mut mass = vec![0.0f64; n];
    let mut weights: Vec<(usize, usize, f64)> = Vec::with_capacity(3 * m);
    let hcot: Vec<f64> = (0..nh)
        .into_par_iter()
        .map(|h| half_cot(&cover, h))
        .collect();
    for h in 0..nh {
        let t = cover.twin[h].us();
        if h < t {
            let (i, j) = (cover.tail[h].us(), cover.tail[t].us());
            if i != j {
                weights.push((i.min(j), i.max(j), half * (hcot[h] + hcot[t])));
            }
        }
        // Each face once, at its smallest halfedge.
        let h1 = cover.next[h].us();
        let h2 = cover.next[h1].us();
        if h < h1 && h < h2 {
            let a = 0.5 * double_area_from_lengths([cover.len[h], cover.len[h1], cover.len[h2]]);
            for e in [h, h1, h2] {
                mass[cover.tail[e].us()] += half * a / 3.0;
            }
        }
    }
    let faces = want_faces.then(|| {
        let mut f = IntrinsicFaces::default();
        for h in 0..nh {
            let h1 = cover.next[h].us();
            let h2 = cover.next[h1].us();
            if h < h1 && h < h2 {
                f.vertices
                    .push([cover.tail[h].us(), cover.tail[h1].us(), cover.tail[h2].us()]);
                f.lengths.push([cover.len[h], cover.len[h1], cover.len[h2]]);
            }
        }
        let ne = cover.primary.len();
        f.mean_edge_length = cover
            .primary
            .iter()
            .map(|&h| cover.len[h.us()])
            .sum::<f64>()
            / ne as f64;
        f
    });
    let r = RobustLaplacian {
        stiffness: assemble_laplacian(n, &weights),
        mass: SparseMatrix::diagonal(&mass),
        stats,
    };
    (r, faces)
}

/// Glues the sheets of the cover around every input edge (step 3 of the module docs) and
/// numbers the cover's edges. `order` holds the input halfedges sorted by undirected key and
/// then by index; `runs` delimits the edges in it.
fn glue<I: Ix>(
    cover: &mut Cover<I>,
    positions: &[[f64; 3]],
    tris: &[[usize; 3]],
    order: &[I],
    runs: &[usize],
    gluing: Gluing,
) {
    let m = tris.len();
    let n_edges = runs.len() - 1;
    let tail = |h: usize| tris[h / 3][h % 3];
    let tip = |h: usize| tris[h / 3][(h % 3 + 1) % 3];
    let mirror = |h: usize| 3 * (m + h / 3) + (2 - h % 3);
    // Input edges by first appearance (their smallest halfedge).
    let mut by_first: Vec<usize> = (0..n_edges).collect();
    by_first.sort_unstable_by_key(|&r| order[runs[r]].us());
    // Ids of the edges split off each input edge: k - 1 of them for k triangles.
    let mut split_base = vec![0usize; n_edges];
    let mut next_id = n_edges;
    for &r in &by_first {
        split_base[r] = next_id;
        next_id += (runs[r + 1] - runs[r]).saturating_sub(1);
    }
    cover.primary = vec![I::of(0); next_id];
    let mut ring: Vec<(f64, usize)> = Vec::new();
    let mut groups: Vec<Vec<(f64, usize)>> = Vec::new();
    let mut link: Vec<usize> = Vec::new();
    let mut removed: Vec<bool> = Vec::new();
    for (id, &r) in by_first.iter().enumerate() {
        let hs = &order[runs[r]..runs[r + 1]];
        let k = hs.len();
        // geometry-central's sibling order around the edge: first, then the others
        // backwards; the orientation reference is the first halfedge, tail s -> tip.
        let h1 = hs[0].us();
        let s = tail(h1);
        ring.clear();
        ring.push((0.0, h1));
        ring.extend(hs[1..].iter().rev().map(|&h| (0.0, h.us())));
        if k >= 2 {
            // Clockwise about p_s -> p_tip: descending atan2 in geometry-central's
            // tangent basis of the edge vector; a stable sort keeps ties in sibling order.
            let ps = positions[s];
            let (bx, by) = tangent_basis(sub(positions[tip(h1)], ps));
            for e in ring.iter_mut() {
                let opp = tris[e.1 / 3][(e.1 % 3 + 2) % 3];
                let out = unit(sub(positions[opp], ps));
                e.0 = dot(by, out).atan2(dot(bx, out));
            }
            ring.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap_or(std::cmp::Ordering::Equal));
            if gluing == Gluing::InterleaveCopies {
                let third = |h: usize| tris[h / 3][(h % 3 + 2) % 3];
                interleave_copies(&mut ring, &third, &mut groups);
            }
        }
        // The sheet of front halfedge h running s -> tip ("true") or tip -> s ("false").
        let sheet = |h: usize, forward: bool| {
            if (tail(h) == s) == forward {
                h
            } else {
                mirror(h)
            }
        };
        // Sibling cycle for the bookkeeping of e.halfedge(): positions 2j (front of the
        // j-th halfedge in sibling order) and 2j+1 (its back copy).
        let pos_of = |h: usize| -> usize {
            let front = if h < 3 * m {
                h
            } else {
                3 * (h / 3 - m) + (2 - h % 3)
            };
            let j = if front == h1 {
                0
            } else {
                // hs is ascending; sibling order is hs[0], hs[k-1], ..., hs[1].
                let i = hs.partition_point(|&x| x.us() < front);
                k - i
            };
            2 * j + usize::from(h >= 3 * m)
        };
        link.clear();
        link.extend((0..2 * k).map(|p| (p + 1) % (2 * k)));
        removed.clear();
        removed.resize(2 * k, false);
        let mut start = 0usize;
        let mut curr = sheet(ring[0].1, false);
        for i in 0..k {
            let next = sheet(ring[(i + 1) % k].1, true);
            cover.twin[curr] = I::of(next);
            cover.twin[next] = I::of(curr);
            let eid = if i + 1 < k {
                // separateToNewEdge: a new edge whose halfedge is `curr`; the input edge's
                // halfedge moves to the first survivor in sibling order.
                let (pa, pb) = (pos_of(curr), pos_of(next));
                removed[pa] = true;
                removed[pb] = true;
                while removed[start] {
                    start = link[start];
                }
                let e = split_base[r] + i;
                cover.primary[e] = I::of(curr);
                e
            } else {
                // The last pair stays on the input edge.
                let p = if k == 1 {
                    h1
                } else {
                    sheet_at(start, k, h1, hs, &mirror)
                };
                cover.primary[id] = I::of(p);
                id
            };
            cover.edge[curr] = I::of(eid);
            cover.edge[next] = I::of(eid);
            curr = sheet(ring[(i + 1) % k].1, false);
        }
    }
}

/// Reorders a ring sorted by angle so that copies of one triangle (same third vertex) are
/// not neighbours where avoidable: repeatedly the group with the most copies left that is
/// not the previous one (ties: the first in angular order). Without copies the order is
/// unchanged.
fn interleave_copies(
    ring: &mut Vec<(f64, usize)>,
    third: &impl Fn(usize) -> usize,
    groups: &mut Vec<Vec<(f64, usize)>>,
) {
    groups.clear();
    for &e in ring.iter() {
        match groups.iter_mut().find(|g| third(g[0].1) == third(e.1)) {
            Some(g) => g.push(e),
            None => groups.push(vec![e]),
        }
    }
    if groups.len() == ring.len() {
        return;
    }
    for g in groups.iter_mut() {
        g.reverse(); // pop() then takes them in their original order
    }
    ring.clear();
    let mut prev = usize::MAX;
    loop {
        let mut best = usize::MAX;
        for (i, g) in groups.iter().enumerate() {
            if i != prev && !g.is_empty() && (best == usize::MAX || g.len() > groups[best].len()) {
                best = i;
            }
        }
        if best == usize::MAX {
            // Only the previous group has copies left: they must follow each other.
            best = prev;
        }
        match groups.get_mut(best).and_then(|g| g.pop()) {
            Some(e) => ring.push(e),
            None => break,
        }
        prev = best;
    }
}

/// The halfedge at position `p` of the sibling cycle (see `glue`).
fn sheet_at<I: Ix>(
    p: usize,
    k: usize,
    h1: usize,
    hs: &[I],
    mirror: &impl Fn(usize) -> usize,
) -> usize {
    let j = p / 2;
    let front = if j == 0 { h1 } else { hs[k - j].us() };
    if p.is_multiple_of(2) {
        front
    } else {
        mirror(front)
    }
}

/// geometry-central's `Vector3::buildTangentBasis`, operation for operation.
fn tangent_basis(v: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let d = unit(v);
    let test = if (d[0]).abs() > 0.9 {
        [0.0, 1.0, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let bx = unit(cross(test, d));
    let by = unit(cross(d, bx));
    (bx, by)
}

/// `v * (1 / |v|)`, as geometry-central normalizes.
fn unit(v: [f64; 3]) -> [f64; 3] {
    let r = 1.0 / norm(v);
    [v[0] * r, v[1] * r, v[2] * r]
}

/// `cot(angle opposite h) / 2` in h's triangle; zero for a degenerate triangle.
fn half_cot<I: Ix>(c: &Cover<I>, h: usize) -> f64 {
    let h1 = c.next[h].us();
    let h2 = c.next[h1].us();
    let (a, b, d) = (c.len[h], c.len[h1], c.len[h2]);
    let dbl = double_area_from_lengths([a, b, d]);
    if dbl.is_nan() || dbl <= f64::EPSILON * (a * a + b * b + d * d) {
        return 0.0;
    }
    // cot = (b^2 + d^2 - a^2) / (4 area) = (b^2 + d^2 - a^2) / (2 dbl).
    (b * b + d * d - a * a) / dbl / 4.0
}

/// Flips cover edges with weight below `-tol` until none is left, first in first out,
/// starting with every edge in id order; after a flip the four edges around it are queued
/// (in geometry-central's order). Returns (flips, edges left non-Delaunay because they
/// cannot be flipped).
fn flip_to_delaunay<I: Ix>(c: &mut Cover<I>, tol: f64) -> (usize, usize) {
    let ne = c.primary.len();
    let mut queue: std::collections::VecDeque<I> = (0..ne).map(I::of).collect();
    let mut in_queue = vec![true; ne];
    let mut flips = 0usize;
    // A safety net against cycling on rounding (never reached in tests: each flip lowers
    // the Dirichlet energy of every function).
    let budget = 64 * ne + 1024;
    while let Some(e) = queue.pop_front() {
        let e = e.us();
        in_queue[e] = false;
        let h = c.primary[e].us();
        let t = c.twin[h].us();
        if half_cot(c, h) + half_cot(c, t) >= -tol {
            continue;
        }
        let h1 = c.next[h].us();
        let h2 = c.next[h1].us();
        let t1 = c.next[t].us();
        let t2 = c.next[t1].us();
        let Some(l) = flipped_length(c.len[h], c.len[h1], c.len[h2], c.len[t1], c.len[t2]) else {
            continue;
        };
        // Both sides the same triangle (a vertex of degree one): no flip exists.
        if h1 == t || t1 == h {
            continue;
        }
        if flips >= budget {
            break;
        }
        // h: a -> b, h1: b -> c, h2: c -> a; t: b -> a, t1: a -> d, t2: d -> b.
        // New faces (c, d, b) = [h, t2, h1] and (d, c, a) = [t, h2, t1].
        let vc = c.tail[h2];
        let vd = c.tail[t2];
        c.next[h] = I::of(t2);
        c.next[t2] = I::of(h1);
        c.next[h1] = I::of(h);
        c.next[t] = I::of(h2);
        c.next[h2] = I::of(t1);
        c.next[t1] = I::of(t);
        c.tail[h] = vc;
        c.tail[t] = vd;
        c.len[h] = l;
        c.len[t] = l;
        flips += 1;
        for x in [t2, h1, h2, t1] {
            let x = c.edge[x].us();
            if !in_queue[x] {
                in_queue[x] = true;
                queue.push_back(I::of(x));
            }
        }
    }
    let unflippable = (0..ne)
        .filter(|&e| {
            let h = c.primary[e].us();
            half_cot(c, h) + half_cot(c, c.twin[h].us()) < -tol
        })
        .count();
    (flips, unflippable)
}

/// Length of the other diagonal of the quadrilateral made of triangles (a, b, c) and
/// (b, a, d) glued along ab: `l_ab`, `l_bc`, `l_ca`, `l_ad`, `l_db`. Lays ab on the x axis,
/// c above and d below it. `None` when a triangle is degenerate or the result is not finite.
fn flipped_length(l_ab: f64, l_bc: f64, l_ca: f64, l_ad: f64, l_db: f64) -> Option<f64> {
    if l_ab.is_nan() || l_ab <= 0.0 {
        return None;
    }
    // c = (x_c, y_c): |ac| = l_ca, |bc| = l_bc; y from the area (stable).
    let x_c = (l_ab * l_ab + l_ca * l_ca - l_bc * l_bc) / (2.0 * l_ab);
    let y_c = double_area_from_lengths([l_ab, l_bc, l_ca]) / l_ab;
    let x_d = (l_ab * l_ab + l_ad * l_ad - l_db * l_db) / (2.0 * l_ab);
    let y_d = -double_area_from_lengths([l_ab, l_db, l_ad]) / l_ab;
    let l = ((x_c - x_d).powi(2) + (y_c - y_d).powi(2)).sqrt();
    (l.is_finite() && l > 0.0).then_some(l)
}
