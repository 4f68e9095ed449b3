//! The known null space of the pencil, deflated exactly: one indicator per connected
//! component (see [`ComponentNullSpace`]).
//!
//! A mesh with `c` connected components has `c` zero eigenvalues, one indicator vector
//! per component. With more components than the Krylov basis holds (a CAD mesh with 122
//! parts and `k = 20`) the zero cluster is larger than the basis and the iteration cannot
//! converge. Since that null space is known exactly, it is returned directly and the
//! iteration runs in its B-orthogonal complement, asked for the `k - c` pairs after it.
//!
//! The operator `Op = (S - sigma B)^-1 B` maps an indicator `z` to `z / -sigma` and is
//! self-adjoint in the B inner product, so the B-orthogonal complement of the indicators
//! is invariant: in exact arithmetic a Krylov space started there stays there. Rounding
//! brings indicator components back, amplified by `Op` (their `theta = 1 / -sigma` is the
//! largest), so every new block is projected, `W -= Z (Z^T B W)`, before its
//! orthonormalization (and again when it lost most of its norm to the basis). The
//! indicators have disjoint supports, so a projection costs two passes over the block
//! whatever the number of components.

use rayon::prelude::*;

use super::kernels::{norm1, sym_spmm};
use super::shift_invert::check_sizes;
use super::types::SparseEigenError;
use crate::linalg::SparseMatrix;

/// Marks a vertex outside every null component.
const NONE: u32 = u32::MAX;

/// The null space of `S` spanned by component indicators: the connected components of
/// the graph of the nonzero entries of `S` and `B` (so it works for any pencil, mesh or
/// point cloud) whose indicator `1_C` passes the solver's convergence test as a pair
/// `(0, 1_C)`: `||S 1_C||_2 / (||S||_1 ||1_C||_2) <= tol` (the row sums of `S` vanish on
/// `C`). A component that touches a Dirichlet vertex (removed from the pencil) loses that
/// property and has no zero mode.
///
/// Convention: null component `i` is numbered in the order of its smallest vertex index,
/// and its eigenvector is the B-normalized indicator `z_i = 1_C / sqrt(1_C^T B 1_C)`:
/// positive on the component, zero elsewhere, `Z^T B Z = I` (the supports are disjoint and
/// `B` has no entry between components).
#[derive(Debug, Clone)]
pub struct ComponentNullSpace {
    n: usize,
    /// The value `1 / sqrt(1_C^T B 1_C)` of each indicator on its component.
    zc: Vec<f64>,
    /// `B z` per vertex, `z` the sum of the indicators (supported on the null
    /// components; `(B z_i)_v` for `v` in component `i`).
    bz: Vec<f64>,
    /// Vertices of null component `i`: `verts[start[i]..start[i + 1]]`, ascending.
    start: Vec<usize>,
    verts: Vec<usize>,
    /// `||S z_i||_2 / (||S||_1 ||z_i||_2)` per null component.
    residuals: Vec<f64>,
    /// Connected components of the graph, null or not.
    components: usize,
}

/// The label of each vertex's connected component in the graph of the nonzero entries of
/// `S` and `B` (both `n x n`, symmetric patterns), components numbered in the order of
/// their smallest vertex; and the number of components.
fn component_labels(s: &SparseMatrix, b: &SparseMatrix) -> (Vec<u32>, usize) {
    let n = s.ncols();
    let mut label = vec![NONE; n];
    let mut components = 0u32;
    let mut stack = Vec::new();
    for root in 0..n {
        if label[root] != NONE {
            continue;
        }
        label[root] = components;
        stack.push(root);
        while let Some(v) = stack.pop() {
            for m in [s, b] {
                let (rows, vals) = m.col(v);
                for (&r, &x) in rows.iter().zip(vals) {
                    if x != 0.0 && label[r] == NONE {
                        label[r] = components;
                        stack.push(r);
                    }
                }
            }
        }
        components += 1;
    }
    (label, components as usize)
}

/// The connected components of the graph of the nonzero entries of `S` and `B` (both
/// `n x n`): the vertices of each, ascending, components in the order of their smallest
/// vertex. The pencil is block diagonal over them: each can be solved on its own.
pub fn connected_components(
    s: &SparseMatrix,
    b: &SparseMatrix,
) -> Result<Vec<Vec<usize>>, SparseEigenError> {
    check_sizes(s, b)?;
    let (label, nc) = component_labels(s, b);
    let mut parts = vec![Vec::new(); nc];
    for (v, &c) in label.iter().enumerate() {
        parts[c as usize].push(v);
    }
    Ok(parts)
}

impl ComponentNullSpace {
    /// The indicator null space of `(S, B)` (both `n x n`) at relative tolerance `tol`
    /// (see the type's documentation). Linear time in the number of nonzeros. Fails when
    /// a null component has no mass (`1_C^T B 1_C <= 0`, an unreferenced vertex under a
    /// mass that gives it none).
    pub fn find(s: &SparseMatrix, b: &SparseMatrix, tol: f64) -> Result<Self, SparseEigenError> {
        let n = check_sizes(s, b)?;
        let (label, nc) = component_labels(s, b);
        // Mass 1_C^T B 1_C and size of each component.
        let ones = vec![1.0; n];
        let b1 = sym_spmm(b, &ones, 1);
        let mut mass = vec![0.0; nc];
        let mut size = vec![0usize; nc];
        for v in 0..n {
            let c = label[v] as usize;
            mass[c] += b1[v];
            size[c] += 1;
        }
        // Every component's normalized indicator (1 where it has no mass, for the test),
        // all in one vector, and their product with S: the components do not touch, so
        // S z is S z_C on each C, computed as `relative_residuals` computes it.
        let zval: Vec<f64> = mass
            .iter()
            .map(|&m| {
                if m > 0.0 && m.is_finite() {
                    1.0 / m.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        let z_all: Vec<f64> = label.iter().map(|&c| zval[c as usize]).collect();
        let sz = sym_spmm(s, &z_all, 1);
        // The relative residual of (0, z_C): ||S z_C||_2 / (||S||_1 ||z_C||_2), the terms
        // summed in vertex order as `relative_residuals` does (so both give the same
        // number).
        let mut r2 = vec![0.0; nc];
        let mut x2 = vec![0.0; nc];
        for v in 0..n {
            let c = label[v] as usize;
            r2[c] += sz[v].powi(2);
            x2[c] += z_all[v] * z_all[v];
        }
        let sn = norm1(s);
        let mut start_of = vec![0usize; nc];
        let mut null_of = vec![NONE; nc];
        let mut residuals = Vec::new();
        let mut start = vec![0usize];
        for c in 0..nc {
            let den = sn * x2[c].sqrt();
            let r = if den > 0.0 {
                r2[c].sqrt() / den
            } else {
                r2[c].sqrt()
            };
            // Not null (NaN included).
            if r.is_nan() || r > tol {
                continue;
            }
            if !(mass[c] > 0.0 && mass[c].is_finite()) {
                let vertex = label.iter().position(|&l| l as usize == c).unwrap_or(0);
                return Err(SparseEigenError::ZeroMass { vertex });
            }
            null_of[c] = residuals.len() as u32;
            start_of[c] = start[start.len() - 1];
            residuals.push(r);
            start.push(start[start.len() - 1] + size[c]);
        }
        let count = residuals.len();
        let mut zc = vec![0.0; count];
        let mut z = vec![0.0; n];
        let mut verts = vec![0usize; start[count]];
        for v in 0..n {
            let c = label[v] as usize;
            let i = null_of[c];
            if i != NONE {
                zc[i as usize] = zval[c];
                z[v] = z_all[v];
                verts[start_of[c]] = v;
                start_of[c] += 1;
            }
        }
        let bz = if count > 0 {
            sym_spmm(b, &z, 1)
        } else {
            vec![0.0; n]
        };
        Ok(Self {
            n,
            zc,
            bz,
            start,
            verts,
            residuals,
            components: nc,
        })
    }

    /// A null space with no indicator (nothing deflated), for `n x n` problems.
    pub fn none(n: usize) -> Self {
        Self {
            n,
            zc: Vec::new(),
            bz: Vec::new(),
            start: vec![0],
            verts: Vec::new(),
            residuals: Vec::new(),
            components: 0,
        }
    }

    /// Number `c` of indicators (null components).
    pub fn count(&self) -> usize {
        self.residuals.len()
    }

    /// Connected components of the graph, including those that are not null (0 for
    /// [`ComponentNullSpace::none`]).
    pub fn components(&self) -> usize {
        self.components
    }

    /// The vertices of null component `i` (ascending; the first is its smallest).
    pub fn vertices(&self, i: usize) -> &[usize] {
        &self.verts[self.start[i]..self.start[i + 1]]
    }

    /// The relative residual `||S z_i||_2 / (||S||_1 ||z_i||_2)` of indicator `i`.
    pub fn residual(&self, i: usize) -> f64 {
        self.residuals[i]
    }

    /// Writes indicator `i` into `out` (`n` entries, assumed zero outside component `i`).
    pub fn write_indicator(&self, i: usize, out: &mut [f64]) {
        for &v in self.vertices(i) {
            out[v] = self.zc[i];
        }
    }

    /// Indicator `i` as an `n`-vector.
    pub fn indicator(&self, i: usize) -> Vec<f64> {
        let mut x = vec![0.0; self.n];
        self.write_indicator(i, &mut x);
        x
    }

    /// `W -= Z (Z^T B W)` for the `cols` column-major columns of `w` (`n` rows each): the
    /// B-orthogonal projection onto the complement of the indicators. Each column is
    /// summed in a fixed order (results do not depend on the thread count). A component
    /// whose vertices are consecutive (the usual case: one component, or parts stored one
    /// after the other) is a contiguous dot product and update.
    pub(super) fn project(&self, w: &mut [f64], cols: usize) {
        let (n, c) = (self.n, self.count());
        if c == 0 || n == 0 || cols == 0 {
            return;
        }
        w[..n * cols]
            .par_chunks_mut(n)
            .for_each(|col| self.project_column(col));
    }

    fn project_column(&self, x: &mut [f64]) {
        for i in 0..self.count() {
            let vs = self.vertices(i);
            let (first, len) = (vs[0], vs.len());
            // The indicator is constant on its component.
            let zc = self.zc[i];
            if vs[len - 1] - first + 1 == len {
                let r = first..first + len;
                let coef = dot(&self.bz[r.clone()], &x[r.clone()]);
                for xv in &mut x[r] {
                    *xv -= zc * coef;
                }
            } else {
                let coef: f64 = vs.iter().map(|&v| self.bz[v] * x[v]).sum();
                for &v in vs {
                    x[v] -= zc * coef;
                }
            }
        }
    }
}

/// Dense vectors deflated besides the indicators (see
/// [`super::SparseEigenOptions::deflate_vectors`]): `X` (`n x p`, B-orthonormal) and
/// `B X`, so that `W -= X ((B X)^T W)` projects a block onto their B-orthogonal
/// complement with two matrix products (rows split in a fixed order).
#[derive(Debug, Clone)]
pub(super) struct DenseDeflation {
    n: usize,
    p: usize,
    x: std::sync::Arc<Vec<f64>>,
    bx: Vec<f64>,
}

impl DenseDeflation {
    /// `x` (`n x p` column-major) and `B x`; an error when its length is not a multiple of
    /// `n`.
    pub(super) fn new(
        b: &SparseMatrix,
        x: std::sync::Arc<Vec<f64>>,
    ) -> Result<Self, SparseEigenError> {
        let n = b.ncols();
        if n == 0 || !x.len().is_multiple_of(n) {
            return Err(SparseEigenError::Invalid(format!(
                "deflated vectors: {} values is not a multiple of n = {n}",
                x.len()
            )));
        }
        let p = x.len() / n;
        let bx = sym_spmm(b, &x, p);
        Ok(Self { n, p, x, bx })
    }

    /// Number `p` of vectors.
    pub(super) fn count(&self) -> usize {
        self.p
    }

    /// `W -= X ((B X)^T W)` for the `cols` columns of `w`.
    pub(super) fn project(&self, w: &mut [f64], cols: usize) {
        if self.p == 0 || cols == 0 {
            return;
        }
        let c = super::dense::gram(&self.bx, w, self.n, self.p, cols);
        super::dense::sub_product(w, &self.x, c.as_ref(), self.n);
    }
}

/// `a . b` in a fixed order with four partial sums (vectorizes).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ac, ar) = a.as_chunks::<4>();
    let (bc, br) = b.as_chunks::<4>();
    for (p, q) in ac.iter().zip(bc) {
        for l in 0..4 {
            acc[l] += p[l] * q[l];
        }
    }
    let rest: f64 = ar.iter().zip(br).map(|(p, q)| p * q).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two path graphs and an isolated vertex, `B` diagonal: three components; the
    /// indicators are B-orthonormal, numbered by smallest vertex, and the projection
    /// leaves a B-orthogonal remainder.
    #[test]
    fn indicators_of_components() {
        // Vertices 0, 2, 4 form one path, 1, 3 another, 5 is alone.
        let n = 6;
        let mut t = Vec::new();
        for (a, c) in [(0, 2), (2, 4), (1, 3)] {
            t.push((a, a, 1.0));
            t.push((c, c, 1.0));
            t.push((a, c, -1.0));
            t.push((c, a, -1.0));
        }
        let s = SparseMatrix::from_triplets(n, n, &t);
        let b = SparseMatrix::from_triplets(
            n,
            n,
            &(0..n).map(|i| (i, i, 1.0 + i as f64)).collect::<Vec<_>>(),
        );
        let ns = ComponentNullSpace::find(&s, &b, 1e-10).unwrap();
        assert_eq!(ns.count(), 3);
        assert_eq!(ns.components(), 3);
        assert_eq!(ns.vertices(0), &[0, 2, 4]);
        assert_eq!(ns.vertices(1), &[1, 3]);
        assert_eq!(ns.vertices(2), &[5]);
        assert_eq!(
            connected_components(&s, &b).unwrap(),
            vec![vec![0, 2, 4], vec![1, 3], vec![5]]
        );
        let z0 = ns.indicator(0);
        let m0 = 1.0 + 3.0 + 5.0;
        assert_eq!(z0[2], 1.0 / f64::sqrt(m0));
        assert_eq!(z0[1], 0.0);
        assert!((0..3).all(|i| ns.residual(i) == 0.0));
        // The residuals are those `relative_residuals` gives for the indicators.
        for i in 0..3 {
            let r = crate::linalg::relative_residuals(&s, &b, &[0.0], &ns.indicator(i));
            assert_eq!(r[0], ns.residual(i));
        }
        // Project a vector: the remainder is B-orthogonal to every indicator.
        let mut w: Vec<f64> = (0..2 * n).map(|i| (i as f64 * 0.7).sin() + 0.3).collect();
        ns.project(&mut w, 2);
        for col in w.chunks(n) {
            for i in 0..3 {
                let zi = ns.indicator(i);
                let dot: f64 = (0..n).map(|v| zi[v] * (1.0 + v as f64) * col[v]).sum();
                assert!(dot.abs() < 1e-14, "{dot}");
            }
        }
        // S not annihilating a component's indicator (a "Dirichlet" row): not null.
        let mut t2 = t.clone();
        t2.push((1, 1, 0.5));
        let s2 = SparseMatrix::from_triplets(n, n, &t2);
        let ns2 = ComponentNullSpace::find(&s2, &b, 1e-10).unwrap();
        assert_eq!(ns2.count(), 2);
        assert_eq!(ns2.components(), 3);
        assert_eq!(ns2.vertices(1), &[5]);
        // A null component without mass is an error naming its first vertex.
        let b0 =
            SparseMatrix::from_triplets(n, n, &(0..5).map(|i| (i, i, 1.0)).collect::<Vec<_>>());
        assert_eq!(
            ComponentNullSpace::find(&s, &b0, 1e-10).unwrap_err(),
            SparseEigenError::ZeroMass { vertex: 5 }
        );
    }
}
