//! The k smallest generalized eigenpairs of (S, B): `S X = B X Lambda`, `X^T B X = I`.

use crate::linalg::{SparseMatrix, dense_generalized_eigen};
use crate::operators::{Laplacian, Operators};

/// Errors of the eigenbasis computation.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum EigenError {
    /// More pairs were asked for than the mesh has vertices.
    #[error("asked for k = {k} eigenpairs but the mesh has only n = {n} vertices")]
    TooMany {
        /// Requested pairs.
        k: usize,
        /// Vertices.
        n: usize,
    },
    /// k = 0.
    #[error("k must be at least 1")]
    Zero,
    /// A numerical failure, with what failed.
    #[error("eigensolver failed: {0}")]
    Numerical(String),
}

/// A generalized eigenbasis: `k` pairs, eigenvalues ascending, eigenvectors B-orthonormal
/// with a deterministic sign (see [`Eigenbasis::fix_signs`]).
#[derive(Debug, Clone)]
pub struct Eigenbasis {
    /// The discretization it was computed for.
    pub laplacian: Laplacian,
    /// Number of vertices `n`.
    pub n: usize,
    /// Eigenvalues, `k` entries, ascending.
    pub values: Vec<f64>,
    /// Eigenvectors, `n x k`, column-major (`vectors[j * n + i]` is `x_j(p_i)`).
    pub vectors: Vec<f64>,
    /// The mass matrix B the vectors are orthonormal in.
    pub mass: SparseMatrix,
    /// Relative residuals `||S x - lambda B x|| / (||S||_1 ||x||_B)` per pair (empty
    /// when not computed).
    pub residuals: Vec<f64>,
}

impl Eigenbasis {
    /// Number of pairs `k`.
    pub fn k(&self) -> usize {
        self.values.len()
    }

    /// Eigenvector `j` (`n` entries).
    pub fn vector(&self, j: usize) -> &[f64] {
        &self.vectors[j * self.n..(j + 1) * self.n]
    }

    /// The documented sign convention: each eigenvector is flipped so that its entry of
    /// largest magnitude is positive (ties: the lowest vertex index wins).
    pub fn fix_signs(&mut self) {
        let n = self.n;
        for col in self.vectors.chunks_mut(n) {
            let mut best = 0;
            for i in 1..n {
                if col[i].abs() > col[best].abs() {
                    best = i;
                }
            }
            if col[best] < 0.0 {
                col.iter_mut().for_each(|v| *v = -*v);
            }
        }
    }

    /// All pairs of (S, B) by the dense path (O(n^3), small meshes only), truncated to
    /// the first `k`.
    pub fn dense(ops: &Operators, k: usize) -> Result<Self, EigenError> {
        let n = ops.n();
        if k == 0 {
            return Err(EigenError::Zero);
        }
        if k > n {
            return Err(EigenError::TooMany { k, n });
        }
        let (values, vectors) = dense_generalized_eigen(&ops.stiffness, &ops.mass)
            .map_err(|e| EigenError::Numerical(e.to_string()))?;
        let mut b = Self {
            laplacian: ops.laplacian,
            n,
            values: values[..k].to_vec(),
            vectors: vectors[..n * k].to_vec(),
            mass: ops.mass.clone(),
            residuals: Vec::new(),
        };
        b.fix_signs();
        b.residuals = b.compute_residuals(&ops.stiffness);
        Ok(b)
    }

    /// Relative residual of every pair against the stiffness `s`:
    /// `||S x - lambda B x||_2 / (||S||_1 * ||x||_B)`.
    pub fn compute_residuals(&self, s: &SparseMatrix) -> Vec<f64> {
        let snorm = (0..s.ncols())
            .map(|c| s.col(c).1.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        (0..self.k())
            .map(|j| {
                let x = self.vector(j);
                let sx = s.mul_vec(x);
                let bx = self.mass.mul_vec(x);
                let r: f64 = sx
                    .iter()
                    .zip(&bx)
                    .map(|(a, b)| (a - self.values[j] * b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let xb: f64 = x.iter().zip(&bx).map(|(a, b)| a * b).sum::<f64>().sqrt();
                r / (snorm * xb.max(f64::MIN_POSITIVE))
            })
            .collect()
    }
}
