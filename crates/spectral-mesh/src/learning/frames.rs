//! Vertex normals and tangent frames (DiffusionNet's conventions; `docs/MATH.md`,
//! "Learning operators").

use rayon::prelude::*;

use crate::mesh::{Mesh, add, cross, dot, norm, normalize, scale, sub};
use crate::operators::point_cloud::smallest_eigenvector;

/// The normal used where none can be found (a vertex no non-degenerate triangle uses,
/// normals that cancel, a point with no neighbour).
const FALLBACK_NORMAL: [f64; 3] = [0.0, 0.0, 1.0];

/// Unit vertex normals of a mesh: the normalized sum of the **unit** normals of the
/// triangles around the vertex (every triangle counts the same, whatever its area, as in
/// DiffusionNet). Zero-area triangles count for nothing; where the sum vanishes the
/// area-weighted normal is tried, then `(0, 0, 1)`.
pub fn mesh_vertex_normals(mesh: &Mesh) -> Vec<[f64; 3]> {
    let unit = mesh.triangle_normals();
    let mut sum = vec![[0.0; 3]; mesh.n_vertices()];
    for (tri, nt) in mesh.triangles().iter().zip(&unit) {
        for &v in tri {
            sum[v] = add(sum[v], *nt);
        }
    }
    let mut area_weighted: Option<Vec<[f64; 3]>> = None;
    sum.iter()
        .enumerate()
        .map(|(i, &s)| {
            let l = norm(s);
            if l > 1e-12 && l.is_finite() {
                return scale(s, 1.0 / l);
            }
            let aw = area_weighted.get_or_insert_with(|| mesh.vertex_normals())[i];
            if norm(aw) > 0.0 { aw } else { FALLBACK_NORMAL }
        })
        .collect()
}

/// Unit normals of a point cloud: at each point, the direction of least spread of the
/// vectors to its neighbours, `p_j - p_i` (the eigenvector of the smallest eigenvalue of
/// `sum_j (p_j - p_i)(p_j - p_i)^T`: second moments about the point itself, not about the
/// neighbourhood's centroid, as DiffusionNet's SVD of those vectors). The sign is whatever
/// the eigensolver gives (no consistent orientation, as in DiffusionNet). A point with no
/// neighbour, or whose neighbours coincide with it, gets `(0, 0, 1)`.
pub fn cloud_normals(positions: &[[f64; 3]], neighbors: &[Vec<usize>]) -> Vec<[f64; 3]> {
    positions
        .par_iter()
        .zip(neighbors)
        .map(|(&p, nb)| {
            let mut a = [[0.0f64; 3]; 3];
            for &j in nb {
                let d = sub(positions[j], p);
                for r in 0..3 {
                    for s in 0..3 {
                        a[r][s] += d[r] * d[s];
                    }
                }
            }
            let v = normalize(smallest_eigenvector(a));
            if norm(v) > 0.0 { v } else { FALLBACK_NORMAL }
        })
        .collect()
}

/// The frame `[X, Y, N]` of every unit normal `N`: `X` is the x axis `(1, 0, 0)` projected
/// on the tangent plane and normalized, or the y axis when `|N . x| >= 0.9`; `Y = N x X`.
pub fn tangent_frames(normals: &[[f64; 3]]) -> Vec<[[f64; 3]; 3]> {
    normals
        .iter()
        .map(|&nrm| {
            let cand = if dot(nrm, [1.0, 0.0, 0.0]).abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let x = normalize(sub(cand, scale(nrm, dot(cand, nrm))));
            let y = cross(nrm, x);
            [x, y, nrm]
        })
        .collect()
}
