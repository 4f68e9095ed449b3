//! The orientation operator of a function `f` (Ren, Poulenard, Wonka and Ovsjanikov 2018,
//! pyFM's convention): `O_f g = <n x grad f, grad g>` at each vertex, the per-triangle
//! value (both gradients constant on a triangle, `n` its unit normal) spread a third to
//! each corner and divided by the vertex area `a_i` (the row sums of the mass matrix):
//!
//! `(O_f g)_i = 1 / a_i sum_{t ∋ i} 1/3 sum_{v ∈ t} g_v <n_t x grad_t f, J_{t,v}>`
//!
//! with `J_{t,v} = n_t x e_v / 2` (`e_v` the edge opposite `v`, counter-clockwise), so
//! that `grad_t g = sum_v g_v J_{t,v} / |t|`. In the basis: `Phi^T M O_f Phi` (`k x k`).
//! Triangles of zero area carry nothing.

use rayon::prelude::*;

use crate::linalg::dense_ops::gram;
use crate::linalg::sym_spmm;
use crate::mesh::{Mesh, cross, dot, norm, scale, sub};
use crate::spectral::BasisView;

/// A triangle's unit normal and `J_{t,v}` for its three corners.
pub(crate) type Frame = ([f64; 3], [[f64; 3]; 3]);

/// Per-triangle frames (`None` for a triangle of zero area).
pub(crate) fn triangle_frames(mesh: &Mesh) -> Vec<Option<Frame>> {
    mesh.triangles()
        .iter()
        .enumerate()
        .map(|(t, _)| {
            let [p0, p1, p2] = mesh.corners(t);
            let nn = cross(sub(p1, p0), sub(p2, p0));
            let len = norm(nn);
            if !(len.is_finite() && len > 0.0) {
                return None;
            }
            let n = scale(nn, 1.0 / len);
            // Edge opposite each corner, counter-clockwise.
            let e = [sub(p2, p1), sub(p0, p2), sub(p1, p0)];
            let j = e.map(|ev| scale(cross(n, ev), 0.5));
            Some((n, j))
        })
        .collect()
}

/// `Phi^T M O_f Phi` (`k x k`, column-major) for the function `f` (`n` values), with
/// `frames` from [`triangle_frames`] and `areas` the vertex areas (row sums of `M`).
/// `O_f Phi` column by column on both cores (each column's sums in the triangles' order).
pub(crate) fn reduced_operator(
    mesh: &Mesh,
    basis: BasisView<'_>,
    frames: &[Option<Frame>],
    areas: &[f64],
    f: &[f64],
) -> Vec<f64> {
    let n = basis.n;
    let k = basis.k();
    // Per triangle of positive area, the weight of each corner's value.
    let coefs: Vec<([usize; 3], [f64; 3])> = mesh
        .triangles()
        .iter()
        .zip(frames)
        .filter_map(|(tri, frame)| {
            let (nrm, j) = frame.as_ref()?;
            // |t| grad_t f = sum_v f_v J_v, rotated by the normal.
            let mut gf = [0.0; 3];
            for c in 0..3 {
                let fv = f[tri[c]];
                for d in 0..3 {
                    gf[d] += fv * j[c][d];
                }
            }
            let rot = cross(*nrm, gf);
            // |t| <n x grad f, grad g> = sum_v g_v <n x grad f, J_v>: with `rot` = |t| n x
            // grad f, one more 1/|t|; a third to each corner.
            let area2 = norm(cross(
                sub(mesh.positions()[tri[1]], mesh.positions()[tri[0]]),
                sub(mesh.positions()[tri[2]], mesh.positions()[tri[0]]),
            ));
            let inv_area = 2.0 / area2;
            Some((
                *tri,
                [
                    dot(rot, j[0]) * inv_area / 3.0,
                    dot(rot, j[1]) * inv_area / 3.0,
                    dot(rot, j[2]) * inv_area / 3.0,
                ],
            ))
        })
        .collect();
    let mut op_phi = vec![0.0; n * k];
    if n > 0 {
        op_phi
            .par_chunks_mut(n)
            .zip(basis.vectors.par_chunks(n))
            .for_each(|(out, x)| {
                for (tri, coef) in &coefs {
                    let sq = coef[0] * x[tri[0]] + coef[1] * x[tri[1]] + coef[2] * x[tri[2]];
                    for &v in tri {
                        out[v] += (1.0 / areas[v]) * sq;
                    }
                }
            });
    }
    let m_op = sym_spmm(basis.mass, &op_phi, k);
    gram(basis.vectors, &m_op, n, k, k)
}
