//! Mass matrices B (symmetric positive definite on vertices that some triangle uses).
//!
//! - [`MassKind::Fem`]: the linear FEM (consistent) mass, `|t|/12` per triangle off the
//!   diagonal and `|t|/6` on it (libigl `MASSMATRIX_TYPE_FULL`).
//! - [`MassKind::Barycentric`]: the paper's "Voronoi-cot", diagonal `a(i) = sum |t| / 3`,
//!   the row sums of the FEM mass (libigl `BARYCENTRIC`).
//! - [`MassKind::MixedVoronoi`]: Meyer et al. 2003 mixed Voronoi areas (libigl `VORONOI`).
//! - [`MassKind::Identity`]: `B = I` (the paper's "cot").

use crate::linalg::SparseMatrix;
use crate::mesh::{Mesh, dot, sub};

/// Which mass matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassKind {
    /// Consistent linear FEM mass (full, not diagonal).
    Fem,
    /// Barycentric lumping, `area / 3` per corner (the paper's Voronoi-cot).
    Barycentric,
    /// Mixed Voronoi areas of Meyer et al. (circumcentric, barycentric-like on obtuse).
    MixedVoronoi,
    /// The identity.
    Identity,
}

/// Assembles the mass matrix of the given kind, `n x n`.
pub fn mass_matrix(mesh: &Mesh, kind: MassKind) -> SparseMatrix {
    let n = mesh.n_vertices();
    let areas = mesh.triangle_areas();
    match kind {
        MassKind::Identity => SparseMatrix::identity(n),
        MassKind::Barycentric => SparseMatrix::diagonal(&lumped_areas(mesh, &areas)),
        MassKind::Fem => {
            let mut t = Vec::with_capacity(9 * mesh.n_triangles());
            for (tri, &a) in mesh.triangles().iter().zip(&areas) {
                for k in 0..3 {
                    let (i, j) = (tri[k], tri[(k + 1) % 3]);
                    t.push((i, i, a / 6.0));
                    let (lo, hi) = (i.min(j), i.max(j));
                    t.push((lo, hi, a / 12.0));
                    t.push((hi, lo, a / 12.0));
                }
            }
            SparseMatrix::from_triplets(n, n, &t)
        }
        MassKind::MixedVoronoi => {
            let mut d = vec![0.0; n];
            for (t, (tri, &a)) in mesh.triangles().iter().zip(&areas).enumerate() {
                let q = mixed_voronoi_corner_areas(mesh.corners(t), a);
                for k in 0..3 {
                    d[tri[k]] += q[k];
                }
            }
            SparseMatrix::diagonal(&d)
        }
    }
}

/// Barycentric vertex areas `a(i) = sum of |t| at i / 3` (`n` entries).
pub fn lumped_areas(mesh: &Mesh, areas: &[f64]) -> Vec<f64> {
    let mut d = vec![0.0; mesh.n_vertices()];
    for (tri, &a) in mesh.triangles().iter().zip(areas) {
        for &v in tri {
            d[v] += a / 3.0;
        }
    }
    d
}

/// Meyer et al.'s mixed area of each corner of one triangle of area `area`.
///
/// Non-obtuse: the circumcentric (Voronoi) split `(|e_ij|^2 cot k + |e_ik|^2 cot j) / 8`;
/// obtuse at corner c: `area / 2` to c and `area / 4` to each other corner.
pub fn mixed_voronoi_corner_areas(p: [[f64; 3]; 3], area: f64) -> [f64; 3] {
    // Squared edge lengths opposite each corner.
    let l2 = [
        dot(sub(p[1], p[2]), sub(p[1], p[2])),
        dot(sub(p[2], p[0]), sub(p[2], p[0])),
        dot(sub(p[0], p[1]), sub(p[0], p[1])),
    ];
    // Corner c is obtuse when its opposite squared edge exceeds the sum of the others,
    // i.e. cos(angle_c) < 0.
    for c in 0..3 {
        let (a, b) = ((c + 1) % 3, (c + 2) % 3);
        if l2[c] > l2[a] + l2[b] {
            let mut q = [area / 4.0; 3];
            q[c] = area / 2.0;
            return q;
        }
    }
    if area <= 0.0 {
        return [0.0; 3];
    }
    // cot of corner c = (l_a^2 + l_b^2 - l_c^2) / (4 area).
    let cot: [f64; 3] = std::array::from_fn(|c| {
        let (a, b) = ((c + 1) % 3, (c + 2) % 3);
        (l2[a] + l2[b] - l2[c]) / (4.0 * area)
    });
    std::array::from_fn(|c| {
        let (a, b) = ((c + 1) % 3, (c + 2) % 3);
        // Edge (c,a) is opposite b; edge (c,b) is opposite a.
        (l2[b] * cot[b] + l2[a] * cot[a]) / 8.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mixed_voronoi_matches_meyer_on_acute_and_obtuse_triangles() {
        // Equilateral: each corner gets a third.
        let s3 = 3f64.sqrt();
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, s3 / 2.0, 0.0]];
        let a = s3 / 4.0;
        for q in mixed_voronoi_corner_areas(p, a) {
            assert!((q - a / 3.0).abs() < 1e-15);
        }
        // Obtuse at corner 2.
        let p = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.1, 0.0]];
        let q = mixed_voronoi_corner_areas(p, 0.1);
        assert_eq!(q, [0.025, 0.025, 0.05]);
    }

    #[test]
    fn fem_mass_rows_sum_to_barycentric_and_total_area() {
        // A non-planar quad: vertex 3 = (1, 1) lifted to z = 0.3, split along 0-3.
        let m = crate::test_support::grid(2, |i, j| [i as f64, j as f64, 0.3 * (i * j) as f64]);
        let fem = mass_matrix(&m, MassKind::Fem);
        let bary = mass_matrix(&m, MassKind::Barycentric);
        let rs = fem.row_sums();
        for (i, r) in rs.iter().enumerate() {
            assert!((r - bary.get(i, i)).abs() < 1e-15);
        }
        let total: f64 = fem.values().iter().sum();
        assert!((total - m.area()).abs() < 1e-14);
        assert_eq!(fem.get(1, 2), 0.0);
        assert!(fem.get(0, 3) > fem.get(0, 1));
    }
}
