//! The cotangent stiffness matrix S (positive semi-definite) and the uniform graph
//! Laplacian.
//!
//! `S(i,j) = -(cot a_ij + cot b_ij) / 2` on an edge, `S(i,i) = -sum_j S(i,j)`; a boundary
//! edge has one opposite angle. This is libigl's `-cotmatrix`. `S 1 = 0` and S is
//! symmetric to the last bit.

use crate::linalg::SparseMatrix;
use crate::mesh::{Mesh, dot, sub};

/// Twice the area of a triangle with edge lengths `l`, by Kahan's numerically stable
/// form of Heron's formula (negative rounding inside the root is clamped to zero).
pub fn double_area_from_lengths(l: [f64; 3]) -> f64 {
    let mut s = l;
    s.sort_by(|a, b| b.total_cmp(a));
    let [a, b, c] = s;
    let arg = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
    0.5 * arg.max(0.0).sqrt()
}

/// Half the cotangent of each corner of a triangle, `[c_0, c_1, c_2]` where `c_k` is
/// `cot(angle at corner k) / 2`, the weight of the opposite edge. Computed from the
/// squared edge lengths and Kahan's Heron area, the same route as libigl's
/// `cotmatrix_entries`, so that the two agree to rounding.
///
/// Returns `None` for a triangle whose area is at rounding level of its squared edge
/// lengths: it has no well-defined angles and contributes nothing (reported by
/// `mesh::validate`).
pub fn half_cotangents(p: [[f64; 3]; 3]) -> Option<[f64; 3]> {
    let l2 = [
        dot(sub(p[1], p[2]), sub(p[1], p[2])),
        dot(sub(p[2], p[0]), sub(p[2], p[0])),
        dot(sub(p[0], p[1]), sub(p[0], p[1])),
    ];
    let dbl = double_area_from_lengths([l2[0].sqrt(), l2[1].sqrt(), l2[2].sqrt()]);
    let scale = l2[0] + l2[1] + l2[2];
    if !dbl.is_finite() || dbl <= f64::EPSILON * scale {
        return None;
    }
    Some(std::array::from_fn(|k| {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        (l2[i] + l2[j] - l2[k]) / dbl / 4.0
    }))
}

/// Assembles a symmetric matrix from per-edge off-diagonal weights `w_ij` so that
/// `A(i,j) = -w_ij` and `A(i,i) = sum_j w_ij`, bit-symmetric.
pub(crate) fn assemble_laplacian(n: usize, edge_weights: &[(usize, usize, f64)]) -> SparseMatrix {
    let mut t = Vec::with_capacity(2 * edge_weights.len() + n);
    for &(i, j, w) in edge_weights {
        t.push((i, j, -w));
        t.push((j, i, -w));
    }
    for i in 0..n {
        t.push((i, i, 0.0));
    }
    let off = SparseMatrix::from_triplets(n, n, &t);
    drop(t);
    // Diagonal = minus the sum of the off-diagonal entries of its column (= row), summed
    // in row order, and set in its place among them (every column holds its diagonal).
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(off.nnz());
    let mut values = Vec::with_capacity(off.nnz());
    col_ptr.push(0);
    for c in 0..n {
        let (rows, vals) = off.col(c);
        let s = rows
            .iter()
            .zip(vals)
            .filter(|(r, _)| **r != c)
            .fold(0.0, |s, (_, &v)| s - v);
        for (&r, &v) in rows.iter().zip(vals) {
            row_idx.push(r);
            values.push(if r == c { s } else { v });
        }
        col_ptr.push(row_idx.len());
    }
    SparseMatrix::from_csc(n, n, col_ptr, row_idx, values)
        .expect("the columns of a matrix from triplets are sorted and in range")
}

/// The cotangent stiffness matrix S, `n x n`, positive semi-definite.
///
/// Zero-area triangles contribute nothing. Runs in O(m).
pub fn cotan_stiffness(mesh: &Mesh) -> SparseMatrix {
    let mut w = Vec::with_capacity(3 * mesh.n_triangles());
    for (t, tri) in mesh.triangles().iter().enumerate() {
        if let Some(c) = half_cotangents(mesh.corners(t)) {
            for k in 0..3 {
                let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                w.push((a.min(b), a.max(b), c[k]));
            }
        }
    }
    assemble_laplacian(mesh.n_vertices(), &w)
}

/// The uniform (graph) Laplacian: `-1` per edge, the degree on the diagonal.
pub fn uniform_laplacian(mesh: &Mesh) -> SparseMatrix {
    let mut e = crate::mesh::sorted_edges(mesh.triangles());
    e.dedup();
    let w: Vec<(usize, usize, f64)> = e.into_iter().map(|(i, j)| (i, j, 1.0)).collect();
    assemble_laplacian(mesh.n_vertices(), &w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_tetrahedron_has_cot60_weights() {
        let s3 = 3f64.sqrt();
        let m = Mesh::new(
            vec![
                [1.0, 1.0, 1.0],
                [1.0, -1.0, -1.0],
                [-1.0, 1.0, -1.0],
                [-1.0, -1.0, 1.0],
            ],
            vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
        )
        .unwrap();
        let s = cotan_stiffness(&m);
        // Each edge has two opposite 60 degree angles: S(i,j) = -(2 / sqrt 3) / 2.
        for i in 0..4 {
            for j in 0..4 {
                let want = if i == j { 3.0 / s3 } else { -1.0 / s3 };
                assert!((s.get(i, j) - want).abs() < 1e-15, "({i},{j})");
            }
        }
        let u = uniform_laplacian(&m);
        assert_eq!(u.get(0, 0), 3.0);
        assert_eq!(u.get(0, 1), -1.0);
    }

    #[test]
    fn boundary_edge_has_one_angle_and_degenerate_triangle_contributes_nothing() {
        // Right isosceles triangle: the hypotenuse sees the right angle (cot 0), each leg
        // sees a 45 degree angle (cot 1).
        let m = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let s = cotan_stiffness(&m);
        assert!((s.get(0, 1) + 0.5).abs() < 1e-15);
        assert!((s.get(0, 2) + 0.5).abs() < 1e-15);
        assert!(s.get(1, 2).abs() < 1e-15);
        let flat = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert_eq!(cotan_stiffness(&flat).max_abs(), 0.0);
    }
}
