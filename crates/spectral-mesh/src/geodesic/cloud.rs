//! The gradient and divergence of the heat method on a point cloud: a least-squares
//! gradient in each point's tangent plane, and the divergence as its adjoint with the
//! mass (see `docs/MATH.md`, "Geodesic distance on point clouds").

use rayon::prelude::*;

use crate::linalg::SparseMatrix;
use crate::mesh::{PointCloud, cross, norm, normalize, plane_coordinates};
use crate::operators::point_cloud::{NormalSource, nearest_neighbors, pca_normal};

/// Neighbours of the least-squares gradient of each point by default.
pub const DEFAULT_GRADIENT_NEIGHBORS: usize = 12;

/// The tangent-plane gradient of a cloud: at point `i`,
/// `g_i = sum_j c_ij (u_j - u_i)` over its gradient neighbours `j` (coefficients in the
/// tangent basis of `i`), and the point's mass `b_i`.
#[derive(Debug, Clone, Default)]
pub(super) struct TangentGradient {
    /// `start[i]..start[i + 1]` indexes the neighbours of point `i`.
    start: Vec<usize>,
    nbr: Vec<usize>,
    coef: Vec<[f64; 2]>,
    mass: Vec<f64>,
}

impl TangentGradient {
    /// Tangent planes (the cloud's normals with [`NormalSource::FromCloud`] where given,
    /// otherwise the PCA of the point and its `pca_neighbors` nearest neighbours about
    /// their centroid, as the point-cloud Laplacian does) and the least-squares
    /// coefficients of the `k` nearest neighbours; `mass` is the lumped mass of each point.
    pub fn new(
        cloud: &PointCloud,
        k: usize,
        pca_neighbors: usize,
        normals: NormalSource,
        mass: Vec<f64>,
    ) -> Self {
        let pts = cloud.positions();
        let n = pts.len();
        let nb_pca = nearest_neighbors(pts, pca_neighbors.max(k));
        let given = match normals {
            NormalSource::FromCloud => cloud.normals(),
            NormalSource::Estimate => None,
        };
        let rows: Vec<(Vec<usize>, Vec<[f64; 2]>)> = (0..n)
            .into_par_iter()
            .map(|i| {
                let p = pts[i];
                let mut nrm = given.map_or([0.0; 3], |g| normalize(g[i]));
                if norm(nrm) == 0.0 {
                    let it = std::iter::once(p)
                        .chain(nb_pca[i].iter().take(pca_neighbors).map(|&j| pts[j]));
                    nrm = pca_normal(it);
                }
                let e1 = normalize(perpendicular(nrm));
                let e2 = cross(nrm, e1);
                let nb: Vec<usize> = nb_pca[i].iter().take(k).copied().collect();
                let x = plane_coordinates(pts, &nb, p, [e1, e2]);
                (nb.clone(), least_squares(&x))
            })
            .collect();
        let mut start = Vec::with_capacity(n + 1);
        start.push(0);
        let mut nbr = Vec::with_capacity(n * k);
        let mut coef = Vec::with_capacity(n * k);
        for (nb, c) in rows {
            nbr.extend(nb);
            coef.extend(c);
            start.push(nbr.len());
        }
        Self {
            start,
            nbr,
            coef,
            mass,
        }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        8 * (self.start.len() + self.nbr.len() + self.mass.len()) + 16 * self.coef.len()
    }

    /// The Dirichlet energy of the gradient, `G^T B G` (`n x n`, symmetric positive
    /// semi-definite, `G^T B G 1 = 0`): entry `(r, c)` is the sum over the points `i`
    /// whose stencil (the point and its gradient neighbours) holds both `r` and `c` of
    /// `b_i a_ir . a_ic`, with `a_ij = c_ij` for a neighbour and `a_ii = -sum_j c_ij`.
    /// Summed in the order of `i` in every entry, so it is symmetric to the last bit.
    pub fn energy(&self) -> SparseMatrix {
        let n = self.mass.len();
        // Where each point appears: (stencil owner i, position in its stencil).
        let mut appear: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        for i in 0..n {
            let len = self.start[i + 1] - self.start[i];
            for p in 0..=len {
                appear[self.stencil_point(i, p)].push((i, p));
            }
        }
        let cols: Vec<(Vec<usize>, Vec<f64>)> = appear
            .par_iter()
            .map(|app| {
                let mut e: Vec<(usize, f64)> = Vec::new();
                for &(i, p) in app {
                    let ap = self.stencil_coef(i, p);
                    let len = self.start[i + 1] - self.start[i];
                    for q in 0..=len {
                        let aq = self.stencil_coef(i, q);
                        e.push((
                            self.stencil_point(i, q),
                            self.mass[i] * (ap[0] * aq[0] + ap[1] * aq[1]),
                        ));
                    }
                }
                // Stable: the order of i among equal rows is kept.
                e.sort_by_key(|x| x.0);
                let mut rows = Vec::with_capacity(e.len());
                let mut vals: Vec<f64> = Vec::with_capacity(e.len());
                for (r, v) in e {
                    if rows.last() == Some(&r) {
                        if let Some(x) = vals.last_mut() {
                            *x += v;
                        }
                    } else {
                        rows.push(r);
                        vals.push(v);
                    }
                }
                (rows, vals)
            })
            .collect();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for (r, v) in cols {
            row_idx.extend(r);
            values.extend(v);
            col_ptr.push(row_idx.len());
        }
        SparseMatrix::from_csc(n, n, col_ptr, row_idx, values).unwrap_or_else(|| {
            // Unreachable: every column is sorted and in range.
            SparseMatrix::from_triplets(n, n, &[])
        })
    }

    /// Point `p` of the stencil of `i`: its neighbours in order, then `i` itself.
    fn stencil_point(&self, i: usize, p: usize) -> usize {
        let q = self.start[i] + p;
        if q < self.start[i + 1] {
            self.nbr[q]
        } else {
            i
        }
    }

    /// The gradient coefficient of stencil point `p` of `i` (`-sum_j c_ij` for `i`).
    fn stencil_coef(&self, i: usize, p: usize) -> [f64; 2] {
        let q = self.start[i] + p;
        if q < self.start[i + 1] {
            self.coef[q]
        } else {
            let mut s = [0.0; 2];
            for c in &self.coef[self.start[i]..self.start[i + 1]] {
                s[0] -= c[0];
                s[1] -= c[1];
            }
            s
        }
    }

    /// The gradient neighbours of point `i`.
    pub fn neighbors(&self, i: usize) -> &[usize] {
        &self.nbr[self.start[i]..self.start[i + 1]]
    }

    /// The gradient of `u` at point `i` in its tangent basis.
    fn gradient_at(&self, u: &[f64], i: usize) -> [f64; 2] {
        let ui = u[i];
        let mut g = [0.0; 2];
        for q in self.start[i]..self.start[i + 1] {
            let d = u[self.nbr[q]] - ui;
            g[0] += self.coef[q][0] * d;
            g[1] += self.coef[q][1] * d;
        }
        g
    }

    /// Writes into `div` (zeroed first) the integrated divergence of
    /// `X = grad u / |grad u|` (zero where `grad u = 0`): `div = -G^T B X`, so that
    /// `div grad` is minus the positive semi-definite `G^T B G`, as `div grad = -S` on
    /// meshes.
    pub fn normalized_divergence(&self, u: &[f64], div: &mut [f64]) {
        div.fill(0.0);
        for i in 0..self.start.len() - 1 {
            let g = self.gradient_at(u, i);
            let len = (g[0] * g[0] + g[1] * g[1]).sqrt();
            if !(len > 0.0 && len.is_finite()) {
                continue;
            }
            let x = [g[0] / len * self.mass[i], g[1] / len * self.mass[i]];
            let mut sum = 0.0;
            for q in self.start[i]..self.start[i + 1] {
                let c = self.coef[q];
                let v = c[0] * x[0] + c[1] * x[1];
                div[self.nbr[q]] -= v;
                sum += v;
            }
            div[i] += sum;
        }
    }
}

/// Coefficients `c_j` of the least-squares gradient `g = sum_j c_j (u_j - u_i)` from the
/// tangent offsets `x_j`: `c_j = (sum_l x_l x_l^T)^-1 x_j`. All zero when the offsets do
/// not span the plane (fewer than two independent directions).
fn least_squares(x: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for v in x {
        a += v[0] * v[0];
        b += v[0] * v[1];
        c += v[1] * v[1];
    }
    let det = a * c - b * b;
    let tr = a + c;
    if !(det > 1e-12 * tr * tr && det.is_finite()) {
        return vec![[0.0; 2]; x.len()];
    }
    x.iter()
        .map(|v| [(c * v[0] - b * v[1]) / det, (a * v[1] - b * v[0]) / det])
        .collect()
}

/// A unit vector perpendicular to the unit vector `d`.
fn perpendicular(d: [f64; 3]) -> [f64; 3] {
    let a = if d[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    normalize(cross(d, a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{dot, sub};

    #[test]
    fn gradient_of_a_linear_function_is_exact_and_divergence_is_its_adjoint() {
        // A jittered planar grid in z = 0.3 x (tilted plane): u = a . p is linear.
        let pts = crate::test_support::jittered_grid(9, 0.013, |x, _| 0.3 * x);
        let n = pts.len();
        let cloud = PointCloud::new(pts.clone(), None).unwrap();
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * (i % 3) as f64).collect();
        let g = TangentGradient::new(&cloud, 8, 12, NormalSource::Estimate, mass.clone());
        let a = [0.7, -0.4, 0.2];
        let u: Vec<f64> = pts.iter().map(|p| dot(*p, a)).collect();
        // The tangential part of a has length |a - (a.n) n| at every point.
        let nrm = normalize([-0.3, 0.0, 1.0]);
        let an = dot(a, nrm);
        let tang = norm(sub(a, crate::mesh::scale(nrm, an)));
        for i in 0..n {
            let gi = g.gradient_at(&u, i);
            let len = (gi[0] * gi[0] + gi[1] * gi[1]).sqrt();
            assert!((len - tang).abs() < 1e-9, "{i}: {len} vs {tang}");
        }
        // <div X, w> = -<X, B grad w> for any w (adjoint), with X the unit gradient of u.
        let w: Vec<f64> = (0..n).map(|i| ((i * 7 % 13) as f64).sin()).collect();
        let mut div = vec![0.0; n];
        g.normalized_divergence(&u, &mut div);
        let lhs: f64 = div.iter().zip(&w).map(|(a, b)| a * b).sum();
        let mut rhs = 0.0;
        for i in 0..n {
            let gu = g.gradient_at(&u, i);
            let l = (gu[0] * gu[0] + gu[1] * gu[1]).sqrt();
            let gw = g.gradient_at(&w, i);
            rhs -= mass[i] * (gu[0] * gw[0] + gu[1] * gw[1]) / l;
        }
        assert!((lhs - rhs).abs() < 1e-9 * rhs.abs().max(1.0), "{lhs} {rhs}");
        // Constants have no gradient: the divergence sums to 0.
        let s: f64 = div.iter().sum();
        assert!(s.abs() < 1e-9, "{s}");
    }
}
