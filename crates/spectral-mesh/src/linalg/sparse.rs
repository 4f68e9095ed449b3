//! A compressed-sparse-column matrix of `f64`, the crate's one sparse type.
//!
//! Storage is the same as SciPy's `csc_matrix` and faer's `SparseColMat`: column pointers,
//! row indices sorted within each column, no duplicates, explicit zeros allowed.

use rayon::prelude::*;

/// A sparse `nrows x ncols` matrix in compressed-sparse-column form.
#[derive(Debug, Clone, PartialEq)]
pub struct SparseMatrix {
    nrows: usize,
    ncols: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

impl SparseMatrix {
    /// Builds a matrix from `(row, col, value)` triplets, summing duplicates.
    ///
    /// Duplicates are summed in the order they are given, so two entries fed the same
    /// sequence of contributions are bit-identical (this is how the operators stay
    /// symmetric to the last bit).
    ///
    /// # Panics
    /// If a triplet is out of range (a programming error, never user data).
    pub fn from_triplets(nrows: usize, ncols: usize, triplets: &[(usize, usize, f64)]) -> Self {
        let mut count = vec![0usize; ncols + 1];
        for &(r, c, _) in triplets {
            assert!(r < nrows && c < ncols, "triplet ({r}, {c}) out of range");
            count[c + 1] += 1;
        }
        for c in 0..ncols {
            count[c + 1] += count[c];
        }
        // Counting sort by column keeps input order within a column (stable); each column's
        // (row, value) pairs are contiguous, sorted by row (stably: input order among equal
        // rows, so duplicates are summed in input order).
        let mut fill = count.clone();
        let mut pairs = vec![(0usize, 0f64); triplets.len()];
        for &(r, c, v) in triplets {
            pairs[fill[c]] = (r, v);
            fill[c] += 1;
        }
        drop(fill);
        let mut col_ptr = Vec::with_capacity(ncols + 1);
        let mut row_idx = Vec::with_capacity(triplets.len());
        let mut values = Vec::with_capacity(triplets.len());
        col_ptr.push(0);
        for c in 0..ncols {
            let col = &mut pairs[count[c]..count[c + 1]];
            col.sort_by_key(|p| p.0);
            let mut k = 0;
            while k < col.len() {
                let r = col[k].0;
                let mut s = 0.0;
                while k < col.len() && col[k].0 == r {
                    s += col[k].1;
                    k += 1;
                }
                row_idx.push(r);
                values.push(s);
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// The `n x n` identity.
    pub fn identity(n: usize) -> Self {
        Self::diagonal(&vec![1.0; n])
    }

    /// A diagonal matrix.
    pub fn diagonal(d: &[f64]) -> Self {
        let n = d.len();
        Self {
            nrows: n,
            ncols: n,
            col_ptr: (0..=n).collect(),
            row_idx: (0..n).collect(),
            values: d.to_vec(),
        }
    }

    /// Builds from raw CSC arrays (checked).
    pub fn from_csc(
        nrows: usize,
        ncols: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        values: Vec<f64>,
    ) -> Option<Self> {
        if col_ptr.len() != ncols + 1
            || col_ptr[0] != 0
            || *col_ptr.last()? != row_idx.len()
            || row_idx.len() != values.len()
        {
            return None;
        }
        for c in 0..ncols {
            if col_ptr[c] > col_ptr[c + 1] {
                return None;
            }
            let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            if rows.iter().any(|&r| r >= nrows) || rows.windows(2).any(|w| w[0] >= w[1]) {
                return None;
            }
        }
        Some(Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Column pointers (`ncols + 1`).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row indices, sorted within each column.
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// Stored values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Rows and values of column `c`.
    pub fn col(&self, c: usize) -> (&[usize], &[f64]) {
        let r = self.col_ptr[c]..self.col_ptr[c + 1];
        (&self.row_idx[r.clone()], &self.values[r])
    }

    /// Entry `(r, c)` (zero when not stored).
    pub fn get(&self, r: usize, c: usize) -> f64 {
        let (rows, vals) = self.col(c);
        match rows.binary_search(&r) {
            Ok(k) => vals[k],
            Err(_) => 0.0,
        }
    }

    /// The diagonal (`min(nrows, ncols)` entries).
    pub fn diag(&self) -> Vec<f64> {
        (0..self.nrows.min(self.ncols))
            .map(|i| self.get(i, i))
            .collect()
    }

    /// True when the matrix stores only diagonal entries.
    pub fn is_diagonal(&self) -> bool {
        (0..self.ncols).all(|c| self.col(c).0.iter().all(|&r| r == c))
    }

    /// Largest absolute stored value.
    pub fn max_abs(&self) -> f64 {
        self.values.iter().fold(0.0, |m, v| m.max(v.abs()))
    }

    /// `y = A x` (serial, by columns). For a symmetric matrix
    /// [`SparseMatrix::transpose_mul_vec`] gives the same product in parallel.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(x.len(), self.ncols);
        let mut y = vec![0.0; self.nrows];
        for (c, &xc) in x.iter().enumerate() {
            if xc != 0.0 {
                let (rows, vals) = self.col(c);
                for (&r, &v) in rows.iter().zip(vals) {
                    y[r] += v * xc;
                }
            }
        }
        y
    }

    /// `y = A^T x`, parallel over the columns of A.
    pub fn transpose_mul_vec(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(x.len(), self.nrows);
        (0..self.ncols)
            .into_par_iter()
            .map(|c| {
                let (rows, vals) = self.col(c);
                rows.iter().zip(vals).map(|(&r, &v)| v * x[r]).sum()
            })
            .collect()
    }

    /// The transpose.
    pub fn transpose(&self) -> Self {
        let mut t = Vec::with_capacity(self.nnz());
        for c in 0..self.ncols {
            let (rows, vals) = self.col(c);
            for (&r, &v) in rows.iter().zip(vals) {
                t.push((c, r, v));
            }
        }
        Self::from_triplets(self.ncols, self.nrows, &t)
    }

    /// `alpha * self + beta * other` (same shape).
    pub fn add_scaled(&self, alpha: f64, other: &Self, beta: f64) -> Self {
        assert_eq!((self.nrows, self.ncols), (other.nrows, other.ncols));
        let mut t = Vec::with_capacity(self.nnz() + other.nnz());
        for c in 0..self.ncols {
            let (rows, vals) = self.col(c);
            t.extend(rows.iter().zip(vals).map(|(&r, &v)| (r, c, alpha * v)));
            let (rows, vals) = other.col(c);
            t.extend(rows.iter().zip(vals).map(|(&r, &v)| (r, c, beta * v)));
        }
        Self::from_triplets(self.nrows, self.ncols, &t)
    }

    /// Largest `|A(i,j) - A(j,i)|` (zero for a bit-symmetric matrix).
    pub fn asymmetry(&self) -> f64 {
        let mut m: f64 = 0.0;
        for c in 0..self.ncols {
            let (rows, vals) = self.col(c);
            for (&r, &v) in rows.iter().zip(vals) {
                m = m.max((v - self.get(c, r)).abs());
            }
        }
        m
    }

    /// Row sums (`A 1`).
    pub fn row_sums(&self) -> Vec<f64> {
        self.mul_vec(&vec![1.0; self.ncols])
    }

    /// The submatrix with the given rows and columns (each list ascending, no repeats).
    pub fn submatrix(&self, rows: &[usize], cols: &[usize]) -> Self {
        let mut rmap = vec![usize::MAX; self.nrows];
        for (k, &r) in rows.iter().enumerate() {
            rmap[r] = k;
        }
        let mut t = Vec::new();
        for (kc, &c) in cols.iter().enumerate() {
            let (rr, vv) = self.col(c);
            for (&r, &v) in rr.iter().zip(vv) {
                if rmap[r] != usize::MAX {
                    t.push((rmap[r], kc, v));
                }
            }
        }
        Self::from_triplets(rows.len(), cols.len(), &t)
    }

    /// Dense copy as rows, `d[r][c]` (for tests and tiny problems).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.ncols]; self.nrows];
        for c in 0..self.ncols {
            let (rows, vals) = self.col(c);
            for (&r, &v) in rows.iter().zip(vals) {
                d[r][c] = v;
            }
        }
        d
    }

    /// Writes the matrix in Matrix Market coordinate format (general, 1-based, full
    /// precision: values round-trip bit for bit through `f64` parsing).
    pub fn write_matrix_market(&self, w: &mut impl std::io::Write) -> std::io::Result<()> {
        writeln!(w, "%%MatrixMarket matrix coordinate real general")?;
        writeln!(w, "% written by spectral-mesh")?;
        writeln!(w, "{} {} {}", self.nrows, self.ncols, self.nnz())?;
        for c in 0..self.ncols {
            let (rows, vals) = self.col(c);
            for (&r, &v) in rows.iter().zip(vals) {
                writeln!(w, "{} {} {:e}", r + 1, c + 1, v)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triplets_sum_duplicates_and_sort() {
        let a = SparseMatrix::from_triplets(
            3,
            3,
            &[(2, 0, 1.0), (0, 0, 2.0), (2, 0, 3.0), (1, 2, -1.0)],
        );
        assert_eq!(a.nnz(), 3);
        assert_eq!(a.get(2, 0), 4.0);
        assert_eq!(a.get(0, 0), 2.0);
        assert_eq!(a.get(1, 2), -1.0);
        assert_eq!(a.get(1, 1), 0.0);
        assert_eq!(a.mul_vec(&[1.0, 2.0, 3.0]), vec![2.0, -3.0, 4.0]);
        assert_eq!(a.transpose_mul_vec(&[1.0, 2.0, 3.0]), vec![14.0, 0.0, -2.0]);
        assert_eq!(a.transpose().get(0, 2), 4.0);
    }

    #[test]
    fn submatrix_picks_entries() {
        let a = SparseMatrix::from_triplets(3, 3, &[(0, 0, 1.0), (2, 2, 5.0), (0, 2, 7.0)]);
        let s = a.submatrix(&[0, 2], &[2]);
        assert_eq!(s.to_dense(), vec![vec![7.0], vec![5.0]]);
    }
}
