//! The point-cloud Laplacian of Sharp and Crane ("A Laplacian for Nonmanifold Triangle
//! Meshes", SGP 2020, Sect. 5): local triangulations of k-nearest neighbourhoods, their
//! union, then the robust pipeline of [`super::robust`].
//!
//! # The pipeline
//! 1. **Neighbours.** The `k` nearest other points of every point (kd-tree, `k = 30` by
//!    default, at most `n - 1`).
//! 2. **Tangent plane.** The normal is the direction of least variance (PCA) of the point
//!    and its neighbours about **their centroid** `(p_i + sum_j p_j) / (k + 1)`; or, with
//!    [`NormalSource::FromCloud`], the cloud's own normal where it is non-zero.
//! 3. **Local triangulation.** The neighbours are projected on the tangent plane and
//!    triangulated (2D Delaunay, exact predicates); the triangles that contain the centre
//!    point (its star) are kept. Neighbours that project onto the same 2D point as one
//!    nearer to the centre are left out of that neighbourhood.
//! 4. **Union** ([`TriangleUnion`]). Every point contributes its star, so a triangle is
//!    found once by each of its corners whose local triangulation contains it: three times
//!    where the neighbouring triangulations agree. By default a *consensus* triangulation
//!    is built from them: first the triangles all three corners found, then the disputed
//!    ones (a near-cocircular quadrilateral split one way in one tangent plane and the other
//!    way in the next), those whose circumball holds the fewest neighbouring points first
//!    (the 3D Delaunay criterion, which does not depend on any tangent plane), each kept
//!    only while it attaches to the surface built so far and none of its edges gets a
//!    third triangle; small holes left are ear-clipped. Where that set still has holes
//!    (noisy scans, whose local triangulations disagree a lot) the local triangles it left
//!    out are added there with weight `c/3` (`c` = corners that found them), as copies
//!    glued in parallel sheets. The robust pipeline (tufted cover, mollification, intrinsic
//!    Delaunay) then runs on the 3D triangles.
//! 5. **Points without a triangle** (a neighbourhood that is collinear in the tangent
//!    plane, or coincident with the point): such a point is attached to its nearest
//!    neighbour by one edge of weight 1 and gets the mass `pi r^2 / (k + 1)` (`r` = the
//!    distance to its farthest neighbour), so that the pencil (S, B) stays regular and the
//!    point's mode sits high in the spectrum. They are counted in
//!    [`PointCloudStats::isolated_points`].
//!
//! # Where `robust_laplacian.point_cloud_laplacian` 1.1.0 goes wrong, and what we do instead
//! Measured on uniform random points on the unit sphere (see `docs/point-clouds.md`).
//! - **Biased centroid.** It divides the sum of the *neighbours only* by `k + 1`, so its
//!   PCA centre is pulled towards the origin by `p_i / (k + 1)`. On the unit sphere that
//!   offset (1/31 at `k = 30`) lies along the normal; once the neighbourhood is small
//!   enough, the least-variance direction becomes a tangent one and the neighbours are
//!   projected onto a plane nearly perpendicular to the surface. With its formula 0% of
//!   the normals are off by more than 25 degrees at 5k points, 31% at 20k, 100% at 80k:
//!   this is why its mass falls (12.54, 11.71, 6.85 against 4 pi = 12.57) and its
//!   eigenvalues get worse as the cloud gets denser (and why translating the cloud changes
//!   its result). We use the true centroid.
//! - **Folded copies.** It feeds every star's triangles, with multiplicity, to the tufted
//!   cover and divides by 3. Around an edge the three copies of a triangle sit at the same
//!   angle, so the cover glues them to each other as folds, and the intrinsic Delaunay
//!   flips across those folds lower the Dirichlet energy: its eigenvalues are about 5% off
//!   at every density even with 60 neighbours, where its mass is right. Our consensus
//!   triangulation has no copies; its eigenvalues on the sphere are as good as those of the
//!   exact Delaunay triangulation of the same points (their convex hull).

use std::collections::HashMap;
use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

use super::robust::{
    DEFAULT_DELAUNAY_TOLERANCE, DEFAULT_MOLLIFY_FACTOR, Gluing, RobustError, RobustParams,
    RobustStats, Soup, robust_from_soup,
};
use super::stiffness::assemble_laplacian;
use crate::linalg::SparseMatrix;
use crate::mesh::{PointCloud, add, cross, dot, norm, normalize, scale, sorted_triangle, sub};

/// Default neighbourhood size, as `robust_laplacian.point_cloud_laplacian(n_neighbors=30)`.
pub const DEFAULT_NEIGHBORS: usize = 30;

/// Where the tangent plane of each point comes from.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum NormalSource {
    /// PCA of the point and its neighbours (ignores the cloud's normals).
    #[default]
    Estimate,
    /// The cloud's normal where it has a non-zero one, PCA elsewhere.
    FromCloud,
}

/// How the local stars are combined into the triangle soup the robust pipeline runs on.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum TriangleUnion {
    /// The consensus set (see [`TriangleUnion::ConsensusOnly`]) wherever it is consistent,
    /// and in its holes the local triangles it left out, weighted by how many corners
    /// found them (copies glued in parallel sheets). The default: on clean samplings it is
    /// one consistent triangulation; on noisy scans, where the local triangulations
    /// disagree a lot, it stays connected.
    #[default]
    Consensus,
    /// One consistent triangle set: the triangles found by all three corners, then the
    /// others (fewest points in their circumball first, then by count and shape), each
    /// kept only while it attaches to the surface built so far and none of its edges gets
    /// a third triangle; small holes are then ear-clipped. Fragments noisy scans.
    ConsensusOnly,
    /// Every star's triangles with multiplicity (a triangle found by `c` corners is present
    /// `c` times), the operator divided by 3: `robust_laplacian`'s rule, for comparison.
    /// The tufted cover folds the copies of a triangle onto each other and the intrinsic
    /// flips across those folds lower the eigenvalues (about 5% on the sphere, at every
    /// density).
    Multiplicity,
    /// As [`TriangleUnion::Multiplicity`] but the copies glued in parallel sheets: no fold
    /// bias, but a triangle some corners missed still counts only in part (about 0.2% of
    /// the area missing on the sphere, at every density).
    Interleaved,
}

/// Parameters of the point-cloud Laplacian. `Default` gives `robust_laplacian`'s defaults
/// (30 neighbours, mollify factor `1e-5`) and the consensus union.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointCloudParams {
    /// Neighbours per point, `k >= 2` (fewer are used when the cloud has fewer points).
    pub neighbors: usize,
    /// Relative mollification of the robust pipeline ([`RobustParams::mollify_factor`]).
    pub mollify_factor: f64,
    /// Delaunay tolerance of the robust pipeline ([`RobustParams::delaunay_tolerance`]).
    pub delaunay_tolerance: f64,
    /// Where the tangent planes come from.
    pub normals: NormalSource,
    /// How the local stars are combined.
    pub union: TriangleUnion,
}

impl Default for PointCloudParams {
    fn default() -> Self {
        Self {
            neighbors: DEFAULT_NEIGHBORS,
            mollify_factor: DEFAULT_MOLLIFY_FACTOR,
            delaunay_tolerance: DEFAULT_DELAUNAY_TOLERANCE,
            normals: NormalSource::Estimate,
            union: TriangleUnion::Consensus,
        }
    }
}

impl PointCloudParams {
    /// The robust-pipeline part of the parameters.
    pub fn robust(&self) -> RobustParams {
        RobustParams {
            mollify_factor: self.mollify_factor,
            delaunay_tolerance: self.delaunay_tolerance,
        }
    }

    /// Checks the ranges (`neighbors >= 2`, see [`RobustParams::validate`]).
    pub fn validate(&self) -> Result<(), RobustError> {
        if self.neighbors < 2 {
            return Err(RobustError::BadParameter(format!(
                "the number of neighbours must be at least 2, got {}",
                self.neighbors
            )));
        }
        self.robust().validate()
    }
}

/// What the point-cloud pipeline did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct PointCloudStats {
    /// Neighbours used per point (`min(k, n - 1)`).
    pub neighbors: usize,
    /// Triangles in the union of the local stars, with multiplicity.
    pub local_triangles: usize,
    /// Distinct triangles among them.
    pub distinct_triangles: usize,
    /// Distinct triangles found by all three of their corners.
    pub agreed_triangles: usize,
    /// Triangles given to the robust pipeline (copies counted).
    pub triangles: usize,
    /// Points whose tangent plane came from the cloud's normals.
    pub given_normals_used: usize,
    /// Points in no triangle, attached to their nearest neighbour (see the module docs).
    pub isolated_points: Vec<usize>,
    /// What the robust pipeline did on the union.
    pub robust: RobustStats,
}

/// The point-cloud operator pair with what was done to build it.
#[derive(Debug, Clone)]
pub struct PointCloudLaplacian {
    /// Stiffness S, `n x n`, positive semi-definite, `S 1 = 0`.
    pub stiffness: SparseMatrix,
    /// Lumped mass B, `n x n`, diagonal, positive (see the module docs for the
    /// exception of fully coincident neighbourhoods).
    pub mass: SparseMatrix,
    /// What the pipeline did.
    pub stats: PointCloudStats,
    /// The distinct triangles the robust pipeline ran on (each sorted ascending, in order
    /// of first appearance; orientation arbitrary): the connectivity of `S` apart from the
    /// attachments of [`PointCloudStats::isolated_points`].
    pub triangles: Vec<[usize; 3]>,
}

/// The k nearest other points of every point, nearest first (ties by index), `n` lists of
/// `min(k, n - 1)` indices.
pub fn nearest_neighbors(points: &[[f64; 3]], k: usize) -> Vec<Vec<usize>> {
    let n = points.len();
    let k = k.min(n.saturating_sub(1));
    let Some(q) = NonZero::new(k + 1) else {
        return vec![Vec::new(); n];
    };
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(points);
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut found: Vec<(f64, usize)> = tree
                .nearest_n::<SquaredEuclidean>(&points[i], q)
                .into_iter()
                .map(|nb| (nb.distance, nb.item as usize))
                .filter(|&(_, j)| j != i)
                .collect();
            found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            found.truncate(k);
            found.into_iter().map(|(_, j)| j).collect()
        })
        .collect()
}

/// The unit normal of least variance of `pts` about their centroid.
pub fn pca_normal(pts: impl Iterator<Item = [f64; 3]> + Clone) -> [f64; 3] {
    let mut c = [0.0; 3];
    let mut count = 0.0;
    for p in pts.clone() {
        c = add(c, p);
        count += 1.0;
    }
    if count == 0.0 {
        return [0.0, 0.0, 1.0];
    }
    c = scale(c, 1.0 / count);
    let mut a = [[0.0f64; 3]; 3];
    for p in pts {
        let d = sub(p, c);
        for r in 0..3 {
            for s in 0..3 {
                a[r][s] += d[r] * d[s];
            }
        }
    }
    smallest_eigenvector(a)
}

/// Eigenvector of the smallest eigenvalue of a symmetric 3x3 matrix (cyclic Jacobi).
pub(crate) fn smallest_eigenvector(mut a: [[f64; 3]; 3]) -> [f64; 3] {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let scale_ = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
    if !scale_.is_finite() || scale_ <= 0.0 {
        return [0.0, 0.0, 1.0];
    }
    for _sweep in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off <= 1e-300 || off <= 1e-18 * scale_ {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A <- J^T A J with the rotation in the (p, q) plane.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for k in 0..3 {
                let (vkp, vkq) = (v[k][p], v[k][q]);
                v[k][p] = c * vkp - s * vkq;
                v[k][q] = s * vkp + c * vkq;
            }
        }
    }
    let mut best = 0;
    for i in 1..3 {
        if a[i][i] < a[best][best] {
            best = i;
        }
    }
    let e = normalize([v[0][best], v[1][best], v[2][best]]);
    if norm(e) > 0.0 { e } else { [0.0, 0.0, 1.0] }
}

/// A neighbour in a local 2D triangulation (position in the tangent plane, local index).
#[derive(Debug, Clone, Copy)]
struct Local {
    pos: Point2<f64>,
    idx: usize,
}

impl HasPosition for Local {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

/// The triangles of the 2D Delaunay triangulation of `nb` (projected on the plane through
/// `p` with unit normal `normal`) that contain `p`, as global index triples `(i, a, b)`.
fn local_star(
    i: usize,
    p: [f64; 3],
    normal: [f64; 3],
    nb: &[usize],
    points: &[[f64; 3]],
    out: &mut Vec<[usize; 3]>,
) {
    let len_scale = nb
        .iter()
        .map(|&j| norm(sub(points[j], p)))
        .fold(0.0f64, f64::max);
    if !len_scale.is_finite() || len_scale <= 0.0 {
        return;
    }
    let e1 = perpendicular(normal);
    let e2 = cross(normal, e1);
    let mut locals = Vec::with_capacity(nb.len() + 1);
    locals.push(Local {
        pos: Point2::new(0.0, 0.0),
        idx: usize::MAX,
    });
    for (k, &j) in nb.iter().enumerate() {
        let d = scale(sub(points[j], p), 1.0 / len_scale);
        let pos = spade::mitigate_underflow(Point2::new(dot(d, e1), dot(d, e2)));
        locals.push(Local { pos, idx: k });
    }
    // Neighbours that project onto the centre are left out (the centre must stay itself);
    // among coincident neighbours the triangulation keeps one.
    locals.retain(|l| l.idx == usize::MAX || l.pos.x != 0.0 || l.pos.y != 0.0);
    let Ok(tri) = DelaunayTriangulation::<Local>::bulk_load(locals) else {
        return;
    };
    if tri.num_vertices() < 3 {
        return;
    }
    let Some(centre) = tri.vertices().find(|v| v.data().idx == usize::MAX) else {
        return;
    };
    for e in centre.out_edges() {
        if let Some(f) = e.face().as_inner() {
            let vs = f.vertices();
            let mut others = vs.iter().map(|v| v.data().idx).filter(|&x| x != usize::MAX);
            if let (Some(a), Some(b)) = (others.next(), others.next()) {
                out.push([i, nb[a], nb[b]]);
            }
        }
    }
}

/// A unit vector perpendicular to the unit vector `d`.
fn perpendicular(d: [f64; 3]) -> [f64; 3] {
    let t = if d[0].abs() > 0.9 {
        [0.0, 1.0, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    normalize(cross(t, d))
}

/// The tangent-plane normal of every point (unit), and how many came from the cloud.
fn normals(
    cloud: &PointCloud,
    nbrs: &[Vec<usize>],
    source: NormalSource,
) -> (Vec<[f64; 3]>, usize) {
    let pts = cloud.positions();
    let given = match source {
        NormalSource::FromCloud => cloud.normals(),
        NormalSource::Estimate => None,
    };
    let out: Vec<([f64; 3], bool)> = (0..pts.len())
        .into_par_iter()
        .map(|i| {
            if let Some(g) = given {
                let nrm = normalize(g[i]);
                if norm(nrm) > 0.0 {
                    return (nrm, true);
                }
            }
            let it = std::iter::once(pts[i]).chain(nbrs[i].iter().map(|&j| pts[j]));
            (pca_normal(it), false)
        })
        .collect();
    let used = out.iter().filter(|x| x.1).count();
    (out.into_iter().map(|x| x.0).collect(), used)
}

/// The triangle soup the Laplacian is built on (see [`TriangleUnion`]; copies repeated,
/// the operator being divided by 3 except for [`TriangleUnion::ConsensusOnly`]). Indices
/// refer to the cloud's points; orientation is arbitrary.
pub fn point_cloud_triangles(
    cloud: &PointCloud,
    params: &PointCloudParams,
) -> Result<Vec<[usize; 3]>, RobustError> {
    params.validate()?;
    let nbrs = nearest_neighbors(cloud.positions(), params.neighbors);
    let (nrm, _) = normals(cloud, &nbrs, params.normals);
    let tris = union_of_stars(cloud.positions(), &nbrs, &nrm);
    Ok(match params.union {
        TriangleUnion::ConsensusOnly => consensus(cloud.positions(), &nbrs, count_triangles(&tris)),
        TriangleUnion::Multiplicity | TriangleUnion::Interleaved => tris,
        TriangleUnion::Consensus => {
            patched_union(cloud.positions(), &nbrs, count_triangles(&tris), &mut 0)
        }
    })
}

fn union_of_stars(pts: &[[f64; 3]], nbrs: &[Vec<usize>], nrm: &[[f64; 3]]) -> Vec<[usize; 3]> {
    (0..pts.len())
        .into_par_iter()
        .fold(Vec::new, |mut acc, i| {
            local_star(i, pts[i], nrm[i], &nbrs[i], pts, &mut acc);
            acc
        })
        .collect::<Vec<Vec<[usize; 3]>>>()
        .concat()
}

/// Distinct triangles (sorted vertex triples, ascending) with the number of times they
/// occur.
fn count_triangles(tris: &[[usize; 3]]) -> Vec<([usize; 3], usize)> {
    let mut sorted: Vec<[usize; 3]> = tris.iter().map(|t| sorted_triangle(*t)).collect();
    sorted.par_sort_unstable();
    let mut out = Vec::with_capacity(sorted.len() / 3 + 1);
    let mut k = 0;
    while k < sorted.len() {
        let mut e = k + 1;
        while e < sorted.len() && sorted[e] == sorted[k] {
            e += 1;
        }
        out.push((sorted[k], e - k));
        k = e;
    }
    out
}

/// The number of points of `cand` strictly inside the smallest ball through the corners of
/// `t` (centred on the triangle's circumcentre); `usize::MAX` for a degenerate triangle.
fn points_in_circumball(pts: &[[f64; 3]], t: &[usize; 3], cand: &[usize]) -> usize {
    let a = pts[t[0]];
    let u = sub(pts[t[1]], a);
    let v = sub(pts[t[2]], a);
    let w = cross(u, v);
    let ww = dot(w, w);
    let scale_ = dot(u, u).max(dot(v, v));
    if ww.is_nan() || ww <= 1e-24 * scale_ * scale_ {
        return usize::MAX;
    }
    let c = add(
        a,
        scale(
            add(scale(cross(v, w), dot(u, u)), scale(cross(w, u), dot(v, v))),
            0.5 / ww,
        ),
    );
    let r2 = dot(sub(a, c), sub(a, c)) * (1.0 - 1e-9);
    cand.iter()
        .filter(|&&j| j != t[0] && j != t[1] && j != t[2])
        .filter(|&&j| dot(sub(pts[j], c), sub(pts[j], c)) < r2)
        .count()
}

/// The consensus triangle set (see the module docs): the triangles found by all three of
/// their corners first; then the others, those whose circumball holds the fewest
/// neighbouring points first (an empty circumball is the 3D Delaunay criterion, the same
/// seen from every corner, so it settles the splittings the tangent planes disagree on),
/// then by count, then by shape; each triangle is kept while none of its three edges
/// already has two kept triangles.
fn consensus(
    pts: &[[f64; 3]],
    nbrs: &[Vec<usize>],
    counted: Vec<([usize; 3], usize)>,
) -> Vec<[usize; 3]> {
    // Cosine of the largest angle: larger = better shaped.
    let quality = |t: &[usize; 3]| -> f64 {
        let mut worst = 1.0f64;
        for k in 0..3 {
            let a = sub(pts[t[(k + 1) % 3]], pts[t[k]]);
            let b = sub(pts[t[(k + 2) % 3]], pts[t[k]]);
            let d = norm(a) * norm(b);
            let c = if d > 0.0 { dot(a, b) / d } else { -1.0 };
            worst = worst.min(c);
        }
        worst
    };
    let mut keyed: Vec<(bool, usize, usize, f64, [usize; 3])> = counted
        .into_par_iter()
        .map_init(Vec::new, |cand: &mut Vec<usize>, (t, c)| {
            if c >= 3 {
                return (false, 0, c, 0.0, t);
            }
            cand.clear();
            for &v in &t {
                cand.extend_from_slice(&nbrs[v]);
            }
            cand.sort_unstable();
            cand.dedup();
            (true, points_in_circumball(pts, &t, cand), c, quality(&t), t)
        })
        .collect();
    keyed.par_sort_unstable_by(|a, b| {
        a.0.cmp(&b.0)
            .then(a.1.cmp(&b.1))
            .then(b.2.cmp(&a.2))
            .then(b.3.total_cmp(&a.3))
            .then(a.4.cmp(&b.4))
    });
    let mut edge_use: HashMap<(usize, usize), u8> = HashMap::with_capacity(keyed.len() * 2);
    let mut vertex_used = vec![false; pts.len()];
    let edges_of = |t: &[usize; 3]| [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])];
    let mut out = Vec::with_capacity(keyed.len());
    let add = |t: [usize; 3],
               edge_use: &mut HashMap<(usize, usize), u8>,
               vertex_used: &mut [bool],
               out: &mut Vec<[usize; 3]>| {
        for e in edges_of(&t) {
            *edge_use.entry(e).or_insert(0) += 1;
        }
        for v in t {
            vertex_used[v] = true;
        }
        out.push(t);
    };
    // 1. Agreed triangles, while no edge gets a third.
    let split = keyed.partition_point(|k| !k.0);
    for &(.., t) in &keyed[..split] {
        if edges_of(&t)
            .iter()
            .all(|e| edge_use.get(e).is_none_or(|&u| u < 2))
        {
            add(t, &mut edge_use, &mut vertex_used, &mut out);
        }
    }
    // 2. Disputed triangles fill the gaps: each must attach to an edge that has one
    // triangle so far (a triangle with three unused edges would float over a region
    // already covered) and none of its edges may get a third; repeated while it helps.
    // A region no agreed triangle reached is seeded by its first triangle whose corners
    // are all still unused.
    let mut pending: Vec<[usize; 3]> = keyed[split..].iter().map(|k| k.4).collect();
    loop {
        loop {
            let before = pending.len();
            pending.retain(|&t| {
                let uses = edges_of(&t).map(|e| edge_use.get(&e).copied().unwrap_or(0));
                if uses.iter().any(|&u| u >= 2) {
                    return false;
                }
                if uses.contains(&1) {
                    add(t, &mut edge_use, &mut vertex_used, &mut out);
                    return false;
                }
                true
            });
            if pending.len() == before || pending.is_empty() {
                break;
            }
        }
        let Some(k) = pending
            .iter()
            .position(|t| t.iter().all(|&v| !vertex_used[v]))
        else {
            break;
        };
        let t = pending.remove(k);
        add(t, &mut edge_use, &mut vertex_used, &mut out);
    }
    // 3. Fill the small holes left (where no local triangulation had the right
    // triangles): simple loops of at most `MAX_HOLE` edges with one triangle each,
    // ear-clipped, kept only when every new triangle lies across its loop edge from the
    // triangle already there (so the boundary of an open patch is never capped).
    fill_small_holes(pts, &mut out, &mut edge_use);
    out
}

/// The consensus set, three copies of each, plus the local triangles it left out that lie
/// where it has holes: no edge interior to the consensus surface (two triangles) and a
/// corner on its boundary or outside it; those with their multiplicity. To be divided by 3.
fn patched_union(
    pts: &[[f64; 3]],
    nbrs: &[Vec<usize>],
    counted: Vec<([usize; 3], usize)>,
    consensus_len: &mut usize,
) -> Vec<[usize; 3]> {
    let chosen = consensus(pts, nbrs, counted.clone());
    *consensus_len = chosen.len();
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    let mut edge_use: HashMap<(usize, usize), u8> = HashMap::with_capacity(2 * chosen.len());
    let mut state = vec![0u8; pts.len()]; // 0 unused, 1 interior, 2 on the boundary
    for t in &chosen {
        for k in 0..3 {
            *edge_use.entry(key(t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for t in &chosen {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let on_boundary = edge_use.get(&key(a, b)) == Some(&1);
            for v in [a, b] {
                state[v] = state[v].max(if on_boundary { 2 } else { 1 });
            }
        }
    }
    let mut set: Vec<[usize; 3]> = chosen.iter().map(|t| sorted_triangle(*t)).collect();
    set.sort_unstable();
    let mut out: Vec<[usize; 3]> = Vec::with_capacity(3 * chosen.len());
    for t in &chosen {
        out.extend([*t; 3]);
    }
    for (t, c) in counted {
        if set.binary_search(&t).is_ok() {
            continue;
        }
        let interior_edge = [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])]
            .iter()
            .any(|&(a, b)| edge_use.get(&key(a, b)).is_some_and(|&u| u >= 2));
        if !interior_edge && t.iter().any(|&v| state[v] != 1) {
            for _ in 0..c {
                out.push(t);
            }
        }
    }
    out
}

/// Largest boundary loop (in edges) that [`consensus`] fills.
const MAX_HOLE: usize = 8;

fn fill_small_holes(
    pts: &[[f64; 3]],
    out: &mut Vec<[usize; 3]>,
    edge_use: &mut HashMap<(usize, usize), u8>,
) {
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    // Boundary edges with the third corner of their one triangle.
    let mut open: HashMap<usize, Vec<(usize, usize)>> = HashMap::new();
    for t in out.iter() {
        for k in 0..3 {
            let (a, b, x) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            if edge_use.get(&key(a, b)) == Some(&1) {
                open.entry(a).or_default().push((b, x));
                open.entry(b).or_default().push((a, x));
            }
        }
    }
    let mut starts: Vec<usize> = open.keys().copied().collect();
    starts.sort_unstable();
    let mut done: std::collections::HashSet<usize> = std::collections::HashSet::new();
    let mut fill = Vec::new();
    for s0 in starts {
        if done.contains(&s0) {
            continue;
        }
        // Walk the loop through vertices of boundary degree 2.
        let mut lp = vec![s0];
        let mut prev = usize::MAX;
        let mut cur = s0;
        let simple = loop {
            let Some(nb) = open.get(&cur) else {
                break false;
            };
            if nb.len() != 2 || lp.len() > MAX_HOLE {
                break false;
            }
            let nxt = if nb[0].0 != prev { nb[0].0 } else { nb[1].0 };
            if nxt == s0 {
                break true;
            }
            if lp.contains(&nxt) {
                break false;
            }
            prev = cur;
            cur = nxt;
            lp.push(cur);
        };
        done.extend(lp.iter().copied());
        if !simple || lp.len() < 3 {
            continue;
        }
        fill.clear();
        if !crate::io::triangulate_polygon(pts, &lp, &mut fill) {
            continue;
        }
        // Every loop edge must get its new triangle on the other side of the old one.
        let across = (0..lp.len()).all(|i| {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            let Some(t) = fill.iter().find(|t| t.contains(&a) && t.contains(&b)) else {
                return false;
            };
            let c = t.iter().copied().find(|&v| v != a && v != b).unwrap_or(a);
            let Some(&(_, x)) = open[&a].iter().find(|&&(y, _)| y == b) else {
                return false;
            };
            let e = sub(pts[b], pts[a]);
            dot(cross(e, sub(pts[c], pts[a])), cross(e, sub(pts[x], pts[a]))) < 0.0
        });
        let fits = fill.iter().all(|t| {
            [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])]
                .iter()
                .all(|&(a, b)| edge_use.get(&key(a, b)).is_none_or(|&u| u < 2))
        });
        if across && fits {
            for t in &fill {
                let mut t = *t;
                t.sort_unstable();
                for e in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                    *edge_use.entry(e).or_insert(0) += 1;
                }
                out.push(t);
            }
        }
    }
}

/// The point-cloud Laplacian (S, B) of `cloud` (see the module docs). Errors only for
/// parameters out of range.
pub fn point_cloud_laplacian(
    cloud: &PointCloud,
    params: &PointCloudParams,
) -> Result<PointCloudLaplacian, RobustError> {
    params.validate()?;
    let pts = cloud.positions();
    let n = pts.len();
    let nbrs = nearest_neighbors(pts, params.neighbors);
    let (nrm, given_used) = normals(cloud, &nbrs, params.normals);
    let tris = union_of_stars(pts, &nbrs, &nrm);
    let mut stats = PointCloudStats {
        neighbors: params.neighbors.min(n.saturating_sub(1)),
        local_triangles: tris.len(),
        given_normals_used: given_used,
        ..Default::default()
    };
    let counted = count_triangles(&tris);
    stats.distinct_triangles = counted.len();
    stats.agreed_triangles = counted.iter().filter(|c| c.1 >= 3).count();
    let mut consensus_len = usize::MAX;
    let (mut soup, mut factor, gluing) = match params.union {
        TriangleUnion::ConsensusOnly => (consensus(pts, &nbrs, counted), 1.0, Gluing::Angular),
        TriangleUnion::Multiplicity => (tris, 1.0 / 3.0, Gluing::Angular),
        TriangleUnion::Interleaved => (tris, 1.0 / 3.0, Gluing::InterleaveCopies),
        TriangleUnion::Consensus => (
            patched_union(pts, &nbrs, counted, &mut consensus_len),
            1.0 / 3.0,
            Gluing::InterleaveCopies,
        ),
    };
    if params.union == TriangleUnion::Consensus && soup.len() == 3 * consensus_len {
        // Nothing was added in holes: three copies of one consistent set give the same
        // operator as the set once.
        soup = soup.into_iter().step_by(3).collect();
        factor = 1.0;
    }
    stats.triangles = soup.len();
    let r = robust_from_soup(Soup {
        positions: pts,
        triangles: &soup,
        params: &params.robust(),
        factor,
        gluing,
    });
    stats.robust = r.stats;
    let tris = soup;
    let mut stiffness = r.stiffness;
    let mut mass_diag = r.mass.diag();
    let mut used = vec![false; n];
    for t in &tris {
        for &v in t {
            used[v] = true;
        }
    }
    stats.isolated_points = (0..n).filter(|&i| !used[i]).collect();
    let mut seen = std::collections::HashSet::with_capacity(tris.len());
    let distinct: Vec<[usize; 3]> = tris
        .iter()
        .map(|t| {
            let mut t = *t;
            t.sort_unstable();
            t
        })
        .filter(|t| seen.insert(*t))
        .collect();
    if !stats.isolated_points.is_empty() {
        let mut extra: Vec<(usize, usize, f64)> = Vec::new();
        for &i in &stats.isolated_points {
            if let Some(&j) = nbrs[i].first() {
                extra.push((i.min(j), i.max(j), 1.0));
            }
            let r = nbrs[i]
                .iter()
                .map(|&j| norm(sub(pts[j], pts[i])))
                .fold(0.0f64, f64::max);
            mass_diag[i] = std::f64::consts::PI * r * r / (nbrs[i].len() + 1) as f64;
        }
        let attach = assemble_laplacian(n, &extra);
        stiffness = stiffness.add_scaled(1.0, &attach, 1.0);
    }
    Ok(PointCloudLaplacian {
        stiffness,
        mass: SparseMatrix::diagonal(&mass_diag),
        stats,
        triangles: distinct,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_finds_the_least_variance_direction() {
        // Points spread in a tilted plane: the normal is the plane's.
        let nrm = normalize([1.0, 2.0, 3.0]);
        let u = perpendicular(nrm);
        let w = cross(nrm, u);
        let pts: Vec<[f64; 3]> = (0..40)
            .map(|k| {
                let (s, t) = ((k as f64 * 0.37).sin(), (k as f64 * 0.91).cos() * 2.0);
                add(
                    add(scale(u, s), scale(w, t)),
                    scale(nrm, 1e-3 * (k % 3) as f64),
                )
            })
            .collect();
        let e = pca_normal(pts.iter().copied());
        assert!(dot(e, nrm).abs() > 1.0 - 1e-5, "{e:?}");
        // Diagonal input, smallest in the middle.
        let e = smallest_eigenvector([[3.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]]);
        assert_eq!(e.map(f64::abs), [0.0, 1.0, 0.0]);
    }

    #[test]
    fn neighbours_exclude_the_point_and_are_sorted() {
        let pts: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 0.0, 0.0]).collect();
        let nb = nearest_neighbors(&pts, 3);
        assert_eq!(nb[0], vec![1, 2, 3]);
        assert_eq!(nb[5], vec![4, 6, 3]);
        let all = nearest_neighbors(&pts[..3], 30);
        assert_eq!(all[1], vec![0, 2]);
    }

    #[test]
    fn planar_grid_star_is_a_fan_around_the_centre() {
        // A jittered grid in the plane z = 0: interior stars are closed fans.
        let pts = crate::test_support::jittered_grid(7, 0.01, |_, _| 0.0);
        let nb = nearest_neighbors(&pts, 12);
        let c = 3 * 7 + 3;
        let mut out = Vec::new();
        local_star(c, pts[c], [0.0, 0.0, 1.0], &nb[c], &pts, &mut out);
        assert!(out.len() >= 4 && out.len() <= 8, "{}", out.len());
        // The star's angles sum to 2 pi.
        let mut sum = 0.0;
        for t in &out {
            assert_eq!(t[0], c);
            let (a, b) = (sub(pts[t[1]], pts[c]), sub(pts[t[2]], pts[c]));
            sum += (dot(a, b) / (norm(a) * norm(b))).acos();
        }
        assert!((sum - 2.0 * std::f64::consts::PI).abs() < 1e-9, "{sum}");
    }
}
