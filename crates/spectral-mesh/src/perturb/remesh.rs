//! Re-triangulations of the same piecewise-linear surface: random resampling, local
//! refinement and tiny triangles. Every new vertex is a convex combination of the corners
//! of one original triangle, so it lies on the original surface (to rounding), and the
//! map is [`SurfaceMap::Barycentric`].
//!
//! The refinement step is conforming longest-edge bisection in Rivara's LEPP form: to
//! refine a triangle, follow the longest-edge propagation path (the neighbour across the
//! longest edge, if that edge is not also the neighbour's longest edge, is refined
//! first), then split the shared longest edge at its midpoint together with every
//! triangle on it. Each split adds exactly one vertex, keeps the mesh conforming
//! (no hanging vertices), keeps manifoldness, closedness and orientation, and bounds the
//! smallest angle from below (LEPP bisection does not degrade angles indefinitely).
//! Ties between equally long edges are broken by vertex index so the result is
//! deterministic.

use std::collections::HashMap;

use super::rng::Rng;
use super::{PerturbError, Perturbed, SurfaceMap, ball_radius, unreferenced_count};
use crate::mesh::{Mesh, add, dot, norm, scale as vscale, sub};

/// Barycentric weight given to the near corner(s) by [`tiny_triangles`]: the inserted
/// vertex is at distance of order `TINY_EPS` (relative to the triangle) from a corner or
/// an edge, so the new triangles have areas of order `TINY_EPS` times the original.
pub const TINY_EPS: f64 = 1e-3;

/// Largest number of refinement levels [`refine_locally`] accepts.
pub const MAX_REFINE_LEVELS: usize = 16;

/// Working state: the current triangulation with, for each vertex, the original triangle
/// it lies on and, for each triangle, the original triangle it lies in.
struct Remesher<'a> {
    orig: &'a Mesh,
    positions: Vec<[f64; 3]>,
    /// Original triangle containing each vertex.
    vert_orig: Vec<usize>,
    /// Barycentric coordinates of each vertex in `vert_orig`.
    vert_bary: Vec<[f64; 3]>,
    tris: Vec<[usize; 3]>,
    tri_orig: Vec<usize>,
    edge_tris: HashMap<[usize; 2], Vec<usize>>,
    /// Triangles modified or created since the caller last drained this list.
    touched: Vec<usize>,
}

fn key(a: usize, b: usize) -> [usize; 2] {
    if a < b { [a, b] } else { [b, a] }
}

impl<'a> Remesher<'a> {
    fn new(orig: &'a Mesh) -> Result<Self, PerturbError> {
        let unref = unreferenced_count(orig);
        if unref > 0 {
            return Err(PerturbError::UnreferencedVertices(unref));
        }
        let n = orig.n_vertices();
        let mut vert_orig = vec![usize::MAX; n];
        let mut vert_bary = vec![[0.0; 3]; n];
        let mut edge_tris: HashMap<[usize; 2], Vec<usize>> = HashMap::new();
        for (t, tri) in orig.triangles().iter().enumerate() {
            for k in 0..3 {
                if vert_orig[tri[k]] == usize::MAX {
                    vert_orig[tri[k]] = t;
                    let mut b = [0.0; 3];
                    b[k] = 1.0;
                    vert_bary[tri[k]] = b;
                }
                edge_tris
                    .entry(key(tri[k], tri[(k + 1) % 3]))
                    .or_default()
                    .push(t);
            }
        }
        Ok(Self {
            orig,
            positions: orig.positions().to_vec(),
            vert_orig,
            vert_bary,
            tris: orig.triangles().to_vec(),
            tri_orig: (0..orig.n_triangles()).collect(),
            edge_tris,
            touched: Vec::new(),
        })
    }

    /// Barycentric coordinates of vertex `v` in original triangle `t`, which must contain
    /// it (true for every vertex of a current triangle lying in `t`).
    fn bary_in(&self, v: usize, t: usize) -> [f64; 3] {
        let home = self.vert_orig[v];
        if home == t {
            return self.vert_bary[v];
        }
        // Express v through original vertex indices, then read off t's corners.
        let ht = self.orig.triangles()[home];
        let hb = self.vert_bary[v];
        let tt = self.orig.triangles()[t];
        let mut b = [0.0; 3];
        for k in 0..3 {
            if hb[k] != 0.0
                && let Some(j) = tt.iter().position(|&x| x == ht[k])
            {
                b[j] += hb[k];
            }
        }
        b
    }

    /// Adds a vertex at barycentric `b` of original triangle `t`.
    fn push_vertex(&mut self, t: usize, b: [f64; 3]) -> usize {
        let [p, q, r] = self.orig.corners(t);
        let pos = add(add(vscale(p, b[0]), vscale(q, b[1])), vscale(r, b[2]));
        self.positions.push(pos);
        self.vert_orig.push(t);
        self.vert_bary.push(b);
        self.positions.len() - 1
    }

    fn edge_len2(&self, e: [usize; 2]) -> f64 {
        let d = sub(self.positions[e[0]], self.positions[e[1]]);
        dot(d, d)
    }

    /// The longest edge of triangle `t`, ties broken by the sorted vertex pair.
    fn longest_edge(&self, t: usize) -> [usize; 2] {
        let tri = self.tris[t];
        let mut best = key(tri[0], tri[1]);
        let mut best_len = self.edge_len2(best);
        for k in 1..3 {
            let e = key(tri[k], tri[(k + 1) % 3]);
            let l = self.edge_len2(e);
            if l > best_len || (l == best_len && e > best) {
                best = e;
                best_len = l;
            }
        }
        best
    }

    fn replace_in_edge(&mut self, e: [usize; 2], from: usize, to: usize) {
        if let Some(list) = self.edge_tris.get_mut(&e) {
            for x in list.iter_mut() {
                if *x == from {
                    *x = to;
                }
            }
        }
    }

    fn add_to_edge(&mut self, e: [usize; 2], t: usize) {
        self.edge_tris.entry(e).or_default().push(t);
    }

    /// Splits edge `e` at its midpoint, and every triangle on it into two.
    fn split_edge(&mut self, e: [usize; 2]) {
        let Some(on) = self.edge_tris.remove(&e) else {
            return;
        };
        let Some(&t0) = on.first() else {
            return;
        };
        let ot = self.tri_orig[t0];
        let bu = self.bary_in(e[0], ot);
        let bv = self.bary_in(e[1], ot);
        let bm = [
            0.5 * (bu[0] + bv[0]),
            0.5 * (bu[1] + bv[1]),
            0.5 * (bu[2] + bv[2]),
        ];
        let m = self.push_vertex(ot, bm);
        for t in on {
            let tri = self.tris[t];
            let Some(k) = (0..3).find(|&k| key(tri[k], tri[(k + 1) % 3]) == e) else {
                continue;
            };
            let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let t2 = self.tris.len();
            self.tris[t] = [a, m, c];
            self.tris.push([m, b, c]);
            self.touched.push(t);
            self.touched.push(t2);
            self.tri_orig.push(self.tri_orig[t]);
            self.replace_in_edge(key(b, c), t, t2);
            self.add_to_edge(key(a, m), t);
            self.add_to_edge(key(m, b), t2);
            self.add_to_edge(key(m, c), t);
            self.add_to_edge(key(m, c), t2);
        }
    }

    /// LEPP refinement of triangle `t`, stopping early once the mesh has `budget`
    /// vertices. Returns the number of vertices added.
    fn refine(&mut self, t: usize, budget: usize) -> usize {
        let start = self.positions.len();
        let mut stack = vec![t];
        while let Some(&top) = stack.last() {
            if self.positions.len() >= budget {
                break;
            }
            let e = self.longest_edge(top);
            let next = self.edge_tris.get(&e).and_then(|list| {
                list.iter()
                    .copied()
                    .find(|&n| n != top && self.longest_edge(n) != e)
            });
            match next {
                // The path is strictly increasing in edge length, so it cannot be
                // longer than the number of edges; the bound is a safeguard only.
                Some(n) if stack.len() <= self.tris.len() => stack.push(n),
                _ => {
                    self.split_edge(e);
                    stack.pop();
                }
            }
        }
        self.positions.len() - start
    }

    /// Inserts a vertex inside current triangle `t` at local barycentric `l` (relative to
    /// the current corners) and splits `t` into three.
    fn insert_in_triangle(&mut self, t: usize, l: [f64; 3]) {
        let tri = self.tris[t];
        let ot = self.tri_orig[t];
        let mut b = [0.0; 3];
        for (k, &v) in tri.iter().enumerate() {
            let bv = self.bary_in(v, ot);
            for j in 0..3 {
                b[j] += l[k] * bv[j];
            }
        }
        let m = self.push_vertex(ot, b);
        let [a, bb, c] = tri;
        let t2 = self.tris.len();
        let t3 = t2 + 1;
        self.tris[t] = [a, bb, m];
        self.tris.push([bb, c, m]);
        self.tris.push([c, a, m]);
        self.touched.extend([t, t2, t3]);
        self.tri_orig.push(ot);
        self.tri_orig.push(ot);
        self.replace_in_edge(key(bb, c), t, t2);
        self.replace_in_edge(key(c, a), t, t3);
        self.add_to_edge(key(a, m), t);
        self.add_to_edge(key(a, m), t3);
        self.add_to_edge(key(bb, m), t);
        self.add_to_edge(key(bb, m), t2);
        self.add_to_edge(key(c, m), t2);
        self.add_to_edge(key(c, m), t3);
    }

    fn area(&self, t: usize) -> f64 {
        let [a, b, c] = self.tris[t];
        let (pa, pb, pc) = (self.positions[a], self.positions[b], self.positions[c]);
        0.5 * norm(crate::mesh::cross(sub(pb, pa), sub(pc, pa)))
    }

    fn finish(self, description: String) -> Result<Perturbed, PerturbError> {
        let map = self
            .vert_orig
            .iter()
            .zip(&self.vert_bary)
            .map(|(&t, &b)| (t, b))
            .collect();
        Ok(Perturbed {
            mesh: Mesh::new(self.positions, self.tris)?,
            map: SurfaceMap::Barycentric(map),
            description,
        })
    }
}

/// How [`resample_with`] picks the triangles it refines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ResampleMode {
    /// With probability proportional to the current area: the refinement spreads over
    /// the surface and the density stays comparable to the input's (a different
    /// triangulation at a similar sampling).
    #[default]
    AreaWeighted,
    /// Uniformly by triangle index: refined regions hold more triangles and get picked
    /// more often, so the sampling becomes strongly irregular (the paper's irregularly
    /// sampled inputs).
    Irregular,
}

impl ResampleMode {
    /// The name used in specs (`area`, `irregular`).
    pub fn name(self) -> &'static str {
        match self {
            ResampleMode::AreaWeighted => "area",
            ResampleMode::Irregular => "irregular",
        }
    }
}

/// A Fenwick (binary indexed) tree of non-negative weights, for sampling an index with
/// probability proportional to its weight while weights change and indices are added.
struct Fenwick {
    tree: Vec<f64>,
    weight: Vec<f64>,
}

impl Fenwick {
    fn new(weights: &[f64], capacity: usize) -> Self {
        let cap = capacity.max(weights.len()).max(1);
        let mut f = Self {
            tree: vec![0.0; cap + 1],
            weight: vec![0.0; cap],
        };
        for (i, &w) in weights.iter().enumerate() {
            f.set(i, w);
        }
        f
    }

    fn set(&mut self, i: usize, w: f64) {
        if i >= self.weight.len() {
            // Grow by rebuilding with double the capacity.
            let old = std::mem::take(&mut self.weight);
            *self = Self::new(&old, 2 * (i + 1));
        }
        let delta = w - self.weight[i];
        self.weight[i] = w;
        let mut k = i + 1;
        while k < self.tree.len() {
            self.tree[k] += delta;
            k += k & k.wrapping_neg();
        }
    }

    fn total(&self) -> f64 {
        let mut s = 0.0;
        let mut k = self.weight.len();
        while k > 0 {
            s += self.tree[k];
            k -= k & k.wrapping_neg();
        }
        s
    }

    /// The index whose cumulative weight interval contains `u` in `[0, total)`.
    fn find(&self, mut u: f64) -> usize {
        let n = self.tree.len() - 1;
        let mut pos = 0;
        let mut step = n.next_power_of_two();
        while step > 0 {
            let next = pos + step;
            if next <= n && self.tree[next] <= u {
                u -= self.tree[next];
                pos = next;
            }
            step >>= 1;
        }
        pos.min(self.weight.len() - 1)
    }
}

/// [`resample_with`] in the default [`ResampleMode::AreaWeighted`] mode.
pub fn resample(mesh: &Mesh, target_vertices: usize, seed: u64) -> Result<Perturbed, PerturbError> {
    resample_with(mesh, target_vertices, seed, ResampleMode::AreaWeighted)
}

/// A different triangulation of the same surface with exactly `target_vertices`
/// vertices (at least the current count): random triangles (picked as `mode` says) are
/// refined by conforming longest-edge bisection (LEPP) until the count is reached. New
/// vertices are edge midpoints, exactly on the original surface; the original vertices
/// are kept. Coarsening is not offered (it cannot keep every vertex on the surface).
/// Deterministic in `seed`.
pub fn resample_with(
    mesh: &Mesh,
    target_vertices: usize,
    seed: u64,
    mode: ResampleMode,
) -> Result<Perturbed, PerturbError> {
    let n = mesh.n_vertices();
    if target_vertices < n {
        return Err(PerturbError::InvalidParameter {
            name: "target vertex count",
            value: target_vertices.to_string(),
            reason: format!(
                "must be at least the current count {n} (only refinement keeps the surface)"
            ),
        });
    }
    let mut r = Remesher::new(mesh)?;
    let mut rng = Rng::new(seed);
    match mode {
        ResampleMode::Irregular => {
            while r.positions.len() < target_vertices {
                let t = rng.below(r.tris.len());
                r.refine(t, target_vertices);
                r.touched.clear();
            }
        }
        ResampleMode::AreaWeighted => {
            let areas: Vec<f64> = (0..r.tris.len()).map(|t| r.area(t)).collect();
            let cap = areas.len() + 3 * (target_vertices - n);
            let mut fw = Fenwick::new(&areas, cap);
            while r.positions.len() < target_vertices {
                let total = fw.total();
                let t = if total > 0.0 && total.is_finite() {
                    fw.find(rng.uniform() * total).min(r.tris.len() - 1)
                } else {
                    rng.below(r.tris.len())
                };
                r.refine(t, target_vertices);
                for t in std::mem::take(&mut r.touched) {
                    let a = r.area(t);
                    fw.set(t, a);
                }
            }
        }
    }
    r.finish(format!(
        "resampled by random conforming longest-edge bisection ({} picking): {n} -> {target_vertices} vertices, seed {seed}",
        mode.name()
    ))
}

/// Closest distance from point `p` to the triangle with corners `a, b, c` (the distance
/// to [`closest_point_barycentric`]'s point).
pub fn point_triangle_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    closest_point_barycentric(p, a, b, c).1.sqrt()
}

/// The closest point of triangle `(a, b, c)` to `p` as barycentric coordinates (in the
/// order a, b, c), with the squared distance. Degenerate triangles fall back to the closest
/// of their edges.
pub fn closest_point_barycentric(
    p: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
) -> ([f64; 3], f64) {
    let at = |w: [f64; 3]| -> ([f64; 3], f64) {
        let q = [
            w[0] * a[0] + w[1] * b[0] + w[2] * c[0],
            w[0] * a[1] + w[1] * b[1] + w[2] * c[1],
            w[0] * a[2] + w[1] * b[2] + w[2] * c[2],
        ];
        let d = sub(p, q);
        (w, dot(d, d))
    };
    // Closest point on segment (u, v): parameter s in [0, 1].
    let seg = |u: [f64; 3], v: [f64; 3]| -> f64 {
        let e = sub(v, u);
        let l2 = dot(e, e);
        if l2 > 0.0 {
            (dot(sub(p, u), e) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    // Solve the 2x2 normal equations for the projection onto the plane.
    let (d00, d01, d11) = (dot(ab, ab), dot(ab, ac), dot(ac, ac));
    let (d20, d21) = (dot(ap, ab), dot(ap, ac));
    let den = d00 * d11 - d01 * d01;
    if den > 1e-300 * (d00 * d11).max(f64::MIN_POSITIVE) {
        let v = (d11 * d20 - d01 * d21) / den;
        let w = (d00 * d21 - d01 * d20) / den;
        let u = 1.0 - v - w;
        if u >= 0.0 && v >= 0.0 && w >= 0.0 {
            return at([u, v, w]);
        }
    }
    // Outside (or degenerate): the closest point is on an edge.
    let s_ab = seg(a, b);
    let s_bc = seg(b, c);
    let s_ca = seg(c, a);
    let cands = [
        at([1.0 - s_ab, s_ab, 0.0]),
        at([0.0, 1.0 - s_bc, s_bc]),
        at([s_ca, 0.0, 1.0 - s_ca]),
    ];
    cands
        .into_iter()
        .fold(cands[0], |best, c| if c.1 < best.1 { c } else { best })
}

/// Local refinement inside the ball of `radius` about `center`: `levels` rounds, each
/// refining (conforming LEPP bisection, see the module notes) every triangle that meets
/// the ball at the start of the round once. Each round roughly doubles the density inside
/// the ball; the propagation path may add a few vertices just outside it. New vertices
/// are on the original surface. At most [`MAX_REFINE_LEVELS`] levels.
pub fn refine_locally(
    mesh: &Mesh,
    center: [f64; 3],
    radius: f64,
    levels: usize,
) -> Result<Perturbed, PerturbError> {
    let radius = ball_radius("refinement radius", center, radius)?;
    if levels > MAX_REFINE_LEVELS {
        return Err(PerturbError::InvalidParameter {
            name: "refinement levels",
            value: levels.to_string(),
            reason: format!("must be at most {MAX_REFINE_LEVELS}"),
        });
    }
    let n0 = mesh.n_vertices();
    let mut r = Remesher::new(mesh)?;
    for _ in 0..levels {
        let selected: Vec<usize> = (0..r.tris.len())
            .filter(|&t| {
                let [a, b, c] = r.tris[t];
                point_triangle_distance(center, r.positions[a], r.positions[b], r.positions[c])
                    <= radius
            })
            .collect();
        for t in selected {
            r.refine(t, usize::MAX);
        }
    }
    let n1 = r.positions.len();
    r.finish(format!(
        "local longest-edge refinement, {levels} level(s) in the ball of radius {radius} about ({}, {}, {}): {n0} -> {n1} vertices",
        center[0], center[1], center[2]
    ))
}

/// Splits `count` distinct random triangles into three by inserting a vertex very close
/// to one of their corners (weights `1 - 2 eps, eps, eps`) or to one of their edges
/// (weights `eps, (1 - eps)/2, (1 - eps)/2`), with `eps =` [`TINY_EPS`], chosen at random
/// half of the time each. This creates tiny and skinny, but not zero-area, triangles.
/// The new vertices are inside original triangles. Deterministic in `seed`.
pub fn tiny_triangles(mesh: &Mesh, count: usize, seed: u64) -> Result<Perturbed, PerturbError> {
    let m = mesh.n_triangles();
    if count > m {
        return Err(PerturbError::InvalidParameter {
            name: "tiny triangle count",
            value: count.to_string(),
            reason: format!("must be at most the number of triangles ({m})"),
        });
    }
    let mut r = Remesher::new(mesh)?;
    let mut rng = Rng::new(seed);
    let mut order: Vec<usize> = (0..m).collect();
    rng.shuffle(&mut order);
    let e = TINY_EPS;
    for &t in &order[..count] {
        let k = rng.below(3);
        let near_corner = rng.below(2) == 0;
        let mut l = if near_corner {
            [e; 3]
        } else {
            [0.5 * (1.0 - e); 3]
        };
        l[k] = if near_corner { 1.0 - 2.0 * e } else { e };
        r.insert_in_triangle(t, l);
    }
    r.finish(format!(
        "tiny triangles: {count} triangles split by a vertex at relative distance {e} from a corner or an edge, seed {seed}"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_inside_on_edge_and_at_corner() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let (w, d2) = closest_point_barycentric([0.25, 0.25, 2.0], a, b, c);
        assert!((w[0] - 0.5).abs() < 1e-12 && (w[1] - 0.25).abs() < 1e-12);
        assert!((d2 - 4.0).abs() < 1e-12);
        let (w, d2) = closest_point_barycentric([0.5, -1.0, 0.0], a, b, c);
        assert!((w[0] - 0.5).abs() < 1e-12 && (w[1] - 0.5).abs() < 1e-12 && w[2] == 0.0);
        assert!((d2 - 1.0).abs() < 1e-12);
        let (w, d2) = closest_point_barycentric([2.0, 2.0, 0.0], a, b, c);
        assert!((w[1] - 0.5).abs() < 1e-12 && (w[2] - 0.5).abs() < 1e-12);
        assert!((d2 - 4.5).abs() < 1e-12);
        let (w, _) = closest_point_barycentric([-1.0, -1.0, 0.0], a, b, c);
        assert_eq!(w, [1.0, 0.0, 0.0]);
        // The distance is the one to that point: above the inside, off an edge, off a corner.
        assert!((point_triangle_distance([0.25, 0.25, 2.0], a, b, c) - 2.0).abs() < 1e-12);
        assert!((point_triangle_distance([0.5, -1.0, 0.0], a, b, c) - 1.0).abs() < 1e-12);
        assert!((point_triangle_distance([-3.0, -4.0, 0.0], a, b, c) - 5.0).abs() < 1e-12);
        // A degenerate (collinear) triangle: the distance to its segment.
        let d = point_triangle_distance([0.5, 1.0, 0.0], a, b, [0.5, 0.0, 0.0]);
        assert!((d - 1.0).abs() < 1e-12);
    }
}
