//! The result: [`Eigenbasis`] (owned pairs, their sign rule and checks) and [`BasisView`]
//! (a borrowed prefix of it).

use crate::linalg::{SparseMatrix, b_orthogonality_error, relative_residuals};
use crate::operators::Laplacian;

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
    /// Relative residuals `||S x - lambda B x||_2 / ((||S||_1 + |lambda| ||B||_1) ||x||_2)`
    /// per pair (empty when not computed; on the free block for Dirichlet problems).
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
    /// largest magnitude is positive (ties: the lowest vertex index wins). The component
    /// indicators of the zero eigenvalues (see [`super::compute_eigenbasis`]) are positive and
    /// stay as they are.
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

    /// Relative residual of every pair against the stiffness `s` (positive
    /// semi-definite) and this basis' mass:
    /// `||S x - lambda B x||_2 / ((||S||_1 + |lambda| ||B||_1) ||x||_2)`, a normwise backward
    /// error that does not change when the mesh is scaled.
    pub fn compute_residuals(&self, s: &SparseMatrix) -> Vec<f64> {
        relative_residuals(s, &self.mass, &self.values, &self.vectors)
    }

    /// `max |X^T B X - I|` over the stored vectors (zero for an exactly B-orthonormal basis).
    pub fn orthogonality_error(&self) -> f64 {
        b_orthogonality_error(&self.mass, &self.vectors, self.k())
    }
}

/// A borrowed view of the first `k` pairs of an [`Eigenbasis`]: what every spectral
/// quantity (heat kernel, distances, signatures, embeddings) is computed from. A basis of
/// `K` pairs serves any `k <= K` without copying its `n x K` vectors.
#[derive(Debug, Clone, Copy)]
pub struct BasisView<'a> {
    /// The discretization the basis was computed for.
    pub laplacian: Laplacian,
    /// Number of vertices `n`.
    pub n: usize,
    /// The first `k` eigenvalues, ascending.
    pub values: &'a [f64],
    /// The first `k` eigenvectors, `n x k` column-major (`vectors[j * n + i]` = `x_j(p_i)`).
    pub vectors: &'a [f64],
    /// The mass matrix B the vectors are orthonormal in (`n x n`).
    pub mass: &'a SparseMatrix,
}

impl<'a> BasisView<'a> {
    /// Number of pairs `k` in the view.
    pub fn k(&self) -> usize {
        self.values.len()
    }

    /// Eigenvector `j` (`n` entries).
    pub fn vector(&self, j: usize) -> &'a [f64] {
        &self.vectors[j * self.n..(j + 1) * self.n]
    }
}

impl<'a> From<&'a Eigenbasis> for BasisView<'a> {
    fn from(b: &'a Eigenbasis) -> Self {
        b.view(b.k())
    }
}

impl Eigenbasis {
    /// The view of the first `min(k, self.k())` pairs.
    pub fn view(&self, k: usize) -> BasisView<'_> {
        let k = k.min(self.k());
        BasisView {
            laplacian: self.laplacian,
            n: self.n,
            values: &self.values[..k],
            vectors: &self.vectors[..k * self.n],
            mass: &self.mass,
        }
    }
}
