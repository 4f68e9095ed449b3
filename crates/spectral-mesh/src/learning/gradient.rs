//! Gradient operators in the tangent frames: a least-squares fit per vertex over its
//! neighbours (`docs/MATH.md`, "Learning operators").

use rayon::prelude::*;

use crate::linalg::SparseMatrix;
use crate::mesh::plane_coordinates;

/// The 2 x 2 symmetric matrix `[[a, b], [b, c]]`'s inverse, or its pseudo-inverse when it
/// is singular to working precision (`det <= 1e-12 trace^2`: neighbours all on one line
/// through the vertex, or none), so that a degenerate neighbourhood gives the gradient's
/// component along its line (or zero) instead of infinities.
fn inverse_2x2(a: f64, b: f64, c: f64) -> [[f64; 2]; 2] {
    let tr = a + c;
    let det = a * c - b * b;
    if det > 1e-12 * tr * tr && det.is_finite() {
        return [[c / det, -b / det], [-b / det, a / det]];
    }
    let half = 0.5 * (a - c);
    let l1 = 0.5 * tr + (half * half + b * b).sqrt();
    if !(l1 > 0.0 && l1.is_finite()) {
        return [[0.0; 2]; 2];
    }
    let v = if b != 0.0 {
        [l1 - c, b]
    } else if a >= c {
        [1.0, 0.0]
    } else {
        [0.0, 1.0]
    };
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    let v = [v[0] / l, v[1] / l];
    [
        [v[0] * v[0] / l1, v[0] * v[1] / l1],
        [v[1] * v[0] / l1, v[1] * v[1] / l1],
    ]
}

/// `(grad_x, grad_y)`, each `n x n`: for a function `f` on the vertices, `(grad_x f)_i` and
/// `(grad_y f)_i` are the components, along `X_i` and `Y_i` of `frames[i]`, of the vector
/// `g` that minimizes `sum_j (e_ij . g - (f_j - f_i))^2 + reg |g|^2` over the neighbours `j`
/// of `i` (`j != i`), `e_ij` being `p_j - p_i` in the frame's tangent coordinates:
/// `g = (E^T E + reg I)^-1 E^T (f_J - f_i)`. With `reg = 0` the fit is exact on linear
/// functions of a flat neighbourhood (two independent directions at least). Each row sums
/// to zero (constants have no gradient).
pub fn gradient_matrices(
    positions: &[[f64; 3]],
    frames: &[[[f64; 3]; 3]],
    neighbors: &[Vec<usize>],
    reg: f64,
) -> (SparseMatrix, SparseMatrix) {
    let n = positions.len();
    let rows: Vec<Vec<(usize, usize, f64, f64)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let [x, y, _] = frames[i];
            let nb: Vec<usize> = neighbors[i].iter().copied().filter(|&j| j != i).collect();
            let e = plane_coordinates(positions, &nb, positions[i], [x, y]);
            let (mut a, mut b, mut c) = (reg, 0.0, reg);
            for v in &e {
                a += v[0] * v[0];
                b += v[0] * v[1];
                c += v[1] * v[1];
            }
            let inv = inverse_2x2(a, b, c);
            let mut out = Vec::with_capacity(nb.len() + 1);
            let (mut sx, mut sy) = (0.0, 0.0);
            for (&j, v) in nb.iter().zip(&e) {
                let wx = inv[0][0] * v[0] + inv[0][1] * v[1];
                let wy = inv[1][0] * v[0] + inv[1][1] * v[1];
                sx += wx;
                sy += wy;
                out.push((i, j, wx, wy));
            }
            out.push((i, i, -sx, -sy));
            out
        })
        .collect();
    let total: usize = rows.iter().map(Vec::len).sum();
    let mut tx = Vec::with_capacity(total);
    let mut ty = Vec::with_capacity(total);
    for (i, j, wx, wy) in rows.into_iter().flatten() {
        tx.push((i, j, wx));
        ty.push((i, j, wy));
    }
    (
        SparseMatrix::from_triplets(n, n, &tx),
        SparseMatrix::from_triplets(n, n, &ty),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_pseudo_inverse_of_2x2() {
        let inv = inverse_2x2(2.0, 1.0, 3.0);
        // [[2,1],[1,3]]^-1 = [[3,-1],[-1,2]] / 5
        let want = [[0.6, -0.2], [-0.2, 0.4]];
        for r in 0..2 {
            for c in 0..2 {
                assert!((inv[r][c] - want[r][c]).abs() < 1e-15);
            }
        }
        // Rank one: [[1,1],[1,1]] = 2 v v^T with v = (1,1)/sqrt2; pinv = v v^T / 2.
        let p = inverse_2x2(1.0, 1.0, 1.0);
        for row in p {
            for x in row {
                assert!((x - 0.25).abs() < 1e-15, "{p:?}");
            }
        }
        assert_eq!(inverse_2x2(0.0, 0.0, 0.0), [[0.0; 2]; 2]);
        assert_eq!(inverse_2x2(0.0, 0.0, 4.0), [[0.0, 0.0], [0.0, 0.25]]);
    }
}
