//! Sparse Cholesky factorization (faer, supernodal; nested dissection or AMD ordering) with the symbolic
//! analysis kept so that a matrix with the same pattern refactors cheaply.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;

use super::supernodal::Supernodes;
use super::{SparseMatrix, ordering};

/// Errors from the factorization.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CholeskyError {
    /// The matrix is not square.
    #[error("the matrix is not square ({0} x {1})")]
    NotSquare(usize, usize),
    /// The matrix is not (numerically) positive definite.
    #[error("the matrix is not positive definite: {0}")]
    NotPositiveDefinite(String),
    /// faer could not allocate or analyse the matrix.
    #[error("sparse factorization failed: {0}")]
    Internal(String),
    /// An `L D L^T` factorization met a zero (or non-finite) pivot.
    #[error("zero pivot in the L D L^T factorization: {0}")]
    ZeroPivot(String),
}

/// A sparse `L L^T` factorization of a symmetric positive definite matrix.
///
/// The analysis (ordering, supernodal structure) and the numeric factorization are
/// faer's. The triangular solves are our own (`supernodal.rs`).
///
/// Parallelism is explicit and coarse: the factorization runs on one thread (faer's
/// parallel factorization took twice as long on 104k vertices and 2 cores); a large
/// factor's solve runs on two threads, one per half of the elimination tree; a small
/// factor's multi-right-hand-side solves split their columns over the rayon pool, each
/// part solved sequentially. This avoids fine-grained spin barriers, which are very slow
/// on a loaded machine.
#[derive(Debug, Clone)]
pub struct SparseCholesky {
    n: usize,
    symbolic: Arc<SymbolicCholesky<usize>>,
    layout: Option<Arc<Supernodes>>,
    values: Vec<f64>,
    /// `None` for `L L^T`; for `L D L^T` (an indefinite matrix, see
    /// [`CholeskyAnalysis::factor_indefinite`]) the signs of its pivots.
    pivots: Option<Inertia>,
    /// Fingerprint of the pattern that was analysed (see [`pattern_fingerprint`]), so that
    /// [`SparseCholesky::refactor`] knows when the analysis still applies without keeping
    /// a copy of the pattern (26 MB at 411k vertices).
    pattern: [u64; 2],
}

/// Two independent 64-bit hashes (SipHash with two salts) of the size and the pattern of
/// `a`: 128 bits, so that two different patterns share a fingerprint with probability
/// about 2^-128.
fn pattern_fingerprint(a: &SparseMatrix) -> [u64; 2] {
    use std::hash::{Hash, Hasher};
    [0u8, 1].map(|salt| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        salt.hash(&mut h);
        a.nrows().hash(&mut h);
        a.col_ptr().hash(&mut h);
        a.row_idx().hash(&mut h);
        h.finish()
    })
}

fn view(a: &SparseMatrix) -> Result<SparseColMatRef<'_, usize, f64>, CholeskyError> {
    let sym =
        SymbolicSparseColMatRef::new_checked(a.nrows(), a.ncols(), a.col_ptr(), None, a.row_idx());
    Ok(SparseColMatRef::new(sym, a.values()))
}

/// The numeric factor values of `a` on the analysis `symbolic`, by one of faer's numeric
/// factorizations (`llt` or `ldlt`: the name of its scratch query and of its factorization,
/// sequential, lower triangle, no regularization), its failure mapped by `$error`.
macro_rules! factor_values {
    ($symbolic:expr, $a:expr, $scratch:ident, $factorize:ident, $error:expr) => {{
        let m = view($a)?;
        let mut values = vec![0.0; $symbolic.len_val()];
        let par = Par::Seq;
        let mut mem = MemBuffer::try_new($symbolic.$scratch::<f64>(par, Default::default()))
            .map_err(|e| CholeskyError::Internal(format!("{e:?}")))?;
        $symbolic
            .$factorize::<f64>(
                &mut values,
                m,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| $error(format!("{e:?}")))?;
        values
    }};
}

fn numeric(
    symbolic: &SymbolicCholesky<usize>,
    a: &SparseMatrix,
) -> Result<Vec<f64>, CholeskyError> {
    let values = factor_values!(
        symbolic,
        a,
        factorize_numeric_llt_scratch,
        factorize_numeric_llt,
        CholeskyError::NotPositiveDefinite
    );
    if values.iter().any(|v| !v.is_finite()) {
        return Err(CholeskyError::NotPositiveDefinite(
            "non-finite factor".to_string(),
        ));
    }
    Ok(values)
}

/// The symbolic analysis of a sparsity pattern (AMD ordering, supernodal structure), kept
/// to factor several matrices of that pattern: the eigensolver's retries of `S - sigma B`
/// with larger shifts all have the pattern of `S + B`.
#[derive(Debug, Clone)]
pub(crate) struct CholeskyAnalysis {
    n: usize,
    symbolic: Arc<SymbolicCholesky<usize>>,
    layout: Option<Arc<Supernodes>>,
    pattern: [u64; 2],
}

impl CholeskyAnalysis {
    /// Analyses the pattern of `a` (its lower triangle).
    pub(crate) fn new(a: &SparseMatrix) -> Result<Self, CholeskyError> {
        if a.nrows() != a.ncols() {
            return Err(CholeskyError::NotSquare(a.nrows(), a.ncols()));
        }
        let m = view(a)?;
        let n = a.nrows();
        // Nested dissection on large patterns, AMD on small ones (see `ordering.rs`).
        let order = (n >= ordering::MIN_ROWS).then(|| {
            let fwd = ordering::nested_dissection(a);
            let mut inv = vec![0; n];
            for (p, &v) in fwd.iter().enumerate() {
                inv[v] = p;
            }
            (fwd, inv)
        });
        let ord = match &order {
            Some((fwd, inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, n)),
            None => SymmetricOrdering::Amd,
        };
        let symbolic = factorize_symbolic_cholesky(
            m.symbolic(),
            Side::Lower,
            ord,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| CholeskyError::Internal(format!("{e:?}")))?;
        let layout = Supernodes::from_symbolic(&symbolic).map(Arc::new);
        Ok(Self {
            n: a.nrows(),
            symbolic: Arc::new(symbolic),
            layout,
            pattern: pattern_fingerprint(a),
        })
    }

    /// Factors `a` with this analysis (a fresh analysis when `a` has another pattern). The
    /// factor is the same, bit for bit, as [`SparseCholesky::new`] of `a`.
    pub(crate) fn factor(&self, a: &SparseMatrix) -> Result<SparseCholesky, CholeskyError> {
        if a.nrows() != self.n || a.ncols() != self.n || pattern_fingerprint(a) != self.pattern {
            return SparseCholesky::new(a);
        }
        self.factor_same_pattern(a)
    }

    fn factor_same_pattern(&self, a: &SparseMatrix) -> Result<SparseCholesky, CholeskyError> {
        let values = numeric(&self.symbolic, a)?;
        Ok(SparseCholesky {
            n: self.n,
            symbolic: self.symbolic.clone(),
            layout: self.layout.clone(),
            values,
            pivots: None,
            pattern: self.pattern,
        })
    }

    /// Factors the symmetric, possibly indefinite `a` (of the analysed pattern) as
    /// `L D L^T` without pivoting, as [`inertia`] does; the factor solves like an `L L^T`
    /// one and knows the signs of its pivots ([`SparseCholesky::inertia`]). A zero or
    /// non-finite pivot is [`CholeskyError::ZeroPivot`]; a matrix of another pattern is
    /// [`CholeskyError::Internal`].
    pub(crate) fn factor_indefinite(
        &self,
        a: &SparseMatrix,
    ) -> Result<SparseCholesky, CholeskyError> {
        if a.nrows() != self.n || a.ncols() != self.n || pattern_fingerprint(a) != self.pattern {
            return Err(CholeskyError::Internal(
                "the matrix does not have the analysed pattern".to_string(),
            ));
        }
        let (values, signs) = ldlt_values(&self.symbolic, a)?;
        Ok(SparseCholesky {
            n: self.n,
            symbolic: self.symbolic.clone(),
            layout: self.layout.clone(),
            values,
            pivots: Some(signs),
            pattern: self.pattern,
        })
    }
}

impl SparseCholesky {
    /// Analyses and factors `a` (only its lower triangle is read).
    pub fn new(a: &SparseMatrix) -> Result<Self, CholeskyError> {
        CholeskyAnalysis::new(a)?.factor_same_pattern(a)
    }

    /// Number of values of the factor `L` (its memory is 8 bytes each, plus the
    /// analysis).
    pub fn factor_len(&self) -> usize {
        self.values.len()
    }

    /// Number of row indices of the supernodal layout (0 for a simplicial factor).
    pub(crate) fn row_indices(&self) -> usize {
        self.layout.as_ref().map_or(0, |l| l.row_indices())
    }

    /// The share of a one-thread solve's time that a solve is predicted to take with the
    /// elimination tree split over two threads (1 when it is not split).
    pub(crate) fn split_share(&self) -> f64 {
        self.layout.as_ref().map_or(1.0, |l| l.split_share())
    }

    /// Refactors a matrix with the same sparsity pattern, reusing the symbolic analysis
    /// (falls back to a fresh analysis when the pattern differs). The result is the same,
    /// bit for bit, as [`SparseCholesky::new`] of `a`; on error the factor is left as it
    /// was.
    pub fn refactor(&mut self, a: &SparseMatrix) -> Result<(), CholeskyError> {
        if a.nrows() != a.ncols() || pattern_fingerprint(a) != self.pattern {
            *self = Self::new(a)?;
            return Ok(());
        }
        self.values = numeric(&self.symbolic, a)?;
        self.pivots = None;
        Ok(())
    }

    /// The signs of the pivots of an `L D L^T` factor (of an indefinite matrix, made for
    /// an interior shift of the eigensolver); `None` for an `L L^T` one (positive
    /// definite).
    pub fn inertia(&self) -> Option<Inertia> {
        self.pivots
    }

    /// Dimension `n`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Solves `A x = b` in place for one right-hand side.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.solve_seq(b, 1);
    }

    fn solve_seq(&self, b: &mut [f64], k: usize) {
        if k == 0 || self.n == 0 {
            return;
        }
        // Every column goes through the same arithmetic whatever the group width, so a
        // column solved alone and in a block give bitwise equal results.
        if let Some(layout) = &self.layout {
            let ldlt = self.pivots.is_some();
            layout.solve_many(&self.values, &mut b[..self.n * k], self.n, ldlt);
            return;
        }
        let rhs = MatMut::from_column_major_slice_mut(b, self.n, k);
        let par = Par::Seq;
        let req = self.symbolic.solve_in_place_scratch::<f64>(k, par);
        let mut mem = MemBuffer::new(req);
        let stack = MemStack::new(&mut mem);
        if self.pivots.is_some() {
            LdltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                par,
                stack,
            );
        } else {
            LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                par,
                stack,
            );
        }
    }

    /// Solves `A X = B` in place for `k` right-hand sides stored column-major
    /// (`b.len() == n * k`). The columns are split into groups solved in parallel.
    pub fn solve_many_in_place(&self, b: &mut [f64], k: usize) {
        assert_eq!(b.len(), self.n * k);
        if k == 0 || self.n == 0 {
            return;
        }
        let threads = rayon::current_num_threads().max(1);
        if threads == 1 || k == 1 {
            self.solve_seq(b, k);
            return;
        }
        // A factor whose solves run on two threads already (split over its elimination
        // tree) is solved in one group: at 104k vertices and k = 128 one group of 8
        // columns took 0.9 of the time of two groups of 4, and it reads the factor once.
        // Otherwise groups of at least 4 columns (multi-RHS solves are cheaper per column),
        // at most one group per thread.
        if self.layout.as_ref().is_some_and(|l| l.is_split()) {
            self.solve_seq(b, k);
            return;
        }
        let groups = threads.min(k.div_ceil(4)).max(1);
        let per = k.div_ceil(groups);
        b.par_chunks_mut(self.n * per).for_each(|chunk| {
            let c = chunk.len() / self.n;
            self.solve_seq(chunk, c);
        });
    }

    /// Returns `A^-1 b`.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        self.solve_in_place(&mut x);
        x
    }

    /// The inertia of a symmetric (possibly indefinite) matrix `a` of this factor's
    /// sparsity pattern (a fresh analysis when the pattern differs): see [`inertia`]. The
    /// eigensolver's certificate factors `S - sigma B`, whose pattern is that of the
    /// factored `S - sigma_0 B`, so the analysis (ordering, supernodes) is reused.
    pub fn inertia_of(&self, a: &SparseMatrix) -> Result<Inertia, CholeskyError> {
        if a.nrows() != a.ncols() || a.nrows() != self.n || pattern_fingerprint(a) != self.pattern {
            return inertia(a);
        }
        ldlt_inertia(&self.symbolic, a)
    }
}

/// The inertia of a symmetric matrix: how many eigenvalues are negative and positive
/// (Sylvester's law of inertia: those of `D` in any `A = L D L^T` with `L` invertible).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Inertia {
    /// Negative eigenvalues (negative pivots of `D`).
    pub negative: usize,
    /// Positive eigenvalues (positive pivots of `D`).
    pub positive: usize,
}

/// The inertia of the symmetric matrix `a` (its lower triangle is read) from a sparse
/// `L D L^T` factorization without pivoting (AMD ordering, supernodal): by Sylvester's law
/// of inertia the signs of the pivots `D` are those of the eigenvalues of `a`. A zero (or
/// non-finite) pivot is an error ([`CholeskyError::ZeroPivot`]): a caller counting
/// eigenvalues below a shift moves the shift.
///
/// Without pivoting the factorization exists whenever every leading principal minor (in
/// the elimination order) is nonzero, which holds for `S - sigma B` at a shift `sigma`
/// that is not an eigenvalue of the pencil unless by an exact cancellation. It is the
/// factorization spectrum slicing uses (as SLEPc's with Cholesky or MUMPS without
/// pivoting); the certificate's shifts lie just above `lambda_k` with `k` much smaller
/// than `n`, where `S - sigma B` is definite but for a few directions.
pub fn inertia(a: &SparseMatrix) -> Result<Inertia, CholeskyError> {
    let analysis = CholeskyAnalysis::new(a)?;
    ldlt_inertia(&analysis.symbolic, a)
}

fn ldlt_inertia(
    symbolic: &SymbolicCholesky<usize>,
    a: &SparseMatrix,
) -> Result<Inertia, CholeskyError> {
    ldlt_values(symbolic, a).map(|(_, signs)| signs)
}

/// The values of the `L D L^T` factor of `a` (no pivoting) and the signs of its pivots.
fn ldlt_values(
    symbolic: &SymbolicCholesky<usize>,
    a: &SparseMatrix,
) -> Result<(Vec<f64>, Inertia), CholeskyError> {
    let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
        return Err(CholeskyError::Internal(
            "the analysis is not supernodal".to_string(),
        ));
    };
    let values = factor_values!(
        symbolic,
        a,
        factorize_numeric_ldlt_scratch,
        factorize_numeric_ldlt,
        CholeskyError::ZeroPivot
    );
    let (mut negative, mut positive) = (0usize, 0usize);
    let begin = sn.supernode_begin();
    let end = sn.supernode_end();
    let val_ptr = sn.col_ptr_for_val();
    let nnz = sn.nnz_per_super();
    for s in 0..sn.n_supernodes() {
        let ncols = end[s] - begin[s];
        let nrows = ncols + nnz[s];
        let block = &values[val_ptr[s]..val_ptr[s + 1]];
        for j in 0..ncols {
            let d = block[j * nrows + j];
            if !d.is_finite() || d == 0.0 {
                return Err(CholeskyError::ZeroPivot(format!(
                    "pivot {d:e} at column {} of {}",
                    begin[s] + j,
                    a.ncols()
                )));
            }
            if d < 0.0 {
                negative += 1;
            } else {
                positive += 1;
            }
        }
    }
    if values.iter().any(|v| !v.is_finite()) {
        return Err(CholeskyError::ZeroPivot("non-finite factor".to_string()));
    }
    Ok((values, Inertia { negative, positive }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triplets of the `n x n` tridiagonal matrix with `diagonal` on the diagonal and
    /// -1 beside it.
    fn tridiagonal(n: usize, diagonal: f64) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, diagonal));
            if i + 1 < n {
                t.push((i, i + 1, -1.0));
                t.push((i + 1, i, -1.0));
            }
        }
        t
    }

    /// The largest difference between the entries of `x` and `y`.
    fn max_difference(x: &[f64], y: &[f64]) -> f64 {
        x.iter()
            .zip(y)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn solves_a_small_spd_system() {
        // 1D Laplacian + identity: tridiagonal SPD.
        let n = 50;
        let a = SparseMatrix::from_triplets(n, n, &tridiagonal(n, 3.0));
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let b = a.mul_vec(&x_true);
        let c = SparseCholesky::new(&a).unwrap();
        let x = c.solve(&b);
        for i in 0..n {
            assert!((x[i] - x_true[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn block_solves_match_for_every_width() {
        // A 2D grid Laplacian plus a diagonal: supernodes of several sizes after AMD.
        let side = 23;
        let n = side * side;
        let varied: Vec<f64> = (0..n).map(|p| (p % 7) as f64 * 0.01).collect();
        let a = ordering::tests::grid_matrix(side, 4.1).add_scaled(
            1.0,
            &SparseMatrix::diagonal(&varied),
            1.0,
        );
        let c = SparseCholesky::new(&a).unwrap();
        assert!(c.layout.is_some(), "the factor should be supernodal");
        // 15 columns: one block of 8, 4, 2 and 1.
        let k = 15;
        let x_true: Vec<f64> = (0..n * k)
            .map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0)
            .collect();
        let mut b = Vec::with_capacity(n * k);
        for j in 0..k {
            b.extend(a.mul_vec(&x_true[j * n..(j + 1) * n]));
        }
        c.solve_many_in_place(&mut b, k);
        let err = max_difference(&b, &x_true);
        assert!(err < 1e-12, "max error {err}");
        // Column by column gives the same bits as the block.
        for j in 0..k {
            let mut one = a.mul_vec(&x_true[j * n..(j + 1) * n]);
            c.solve_in_place(&mut one);
            assert_eq!(&one[..], &b[j * n..(j + 1) * n]);
        }
    }

    #[test]
    fn a_tree_split_solve_equals_the_one_thread_solve_on_any_pool() {
        // Grids above the split threshold: 12k rows (AMD) and 55k rows (nested dissection,
        // postordered). The split must be found, agree with the unsplit solve to
        // rounding, and give the same bits whatever the number of threads.
        for m in [110, 235] {
            let a = ordering::tests::grid_matrix(m, 4.5);
            let n = a.nrows();
            let c = SparseCholesky::new(&a).unwrap();
            let split = c.layout.as_ref().unwrap();
            assert!(split.is_split(), "{m} x {m}: no split");
            let share = c.split_share();
            assert!(share > 0.5 && share < 0.8, "{m} x {m}: share {share}");
            let plain = Supernodes::build(&c.symbolic, false).unwrap();
            assert!(!plain.is_split());
            let mut rand = crate::test_support::lcg53(m as u64);
            let k = 5;
            let b: Vec<f64> = (0..n * k).map(|_| rand() - 0.5).collect();
            let mut x = b.clone();
            split.solve_many(&c.values, &mut x, n, false);
            let mut y = b.clone();
            plain.solve_many(&c.values, &mut y, n, false);
            let scale = y.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            let diff = x
                .iter()
                .zip(&y)
                .fold(0.0f64, |d, (p, q)| d.max((p - q).abs()));
            assert!(diff <= 1e-13 * scale, "{m} x {m}: split differs by {diff}");
            for q in 0..k {
                let r = a.mul_vec(&x[q * n..(q + 1) * n]);
                let err = r
                    .iter()
                    .zip(&b[q * n..(q + 1) * n])
                    .fold(0.0f64, |d, (p, q)| d.max((p - q).abs()));
                assert!(err < 1e-12, "{m} x {m}: residual {err}");
            }
            let one = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap();
            let mut z = b.clone();
            one.install(|| split.solve_many(&c.values, &mut z, n, false));
            assert!(x.iter().zip(&z).all(|(p, q)| p.to_bits() == q.to_bits()));
        }
    }

    /// An indefinite grid matrix factored as `L D L^T` (the interior shifts of the
    /// eigensolver): the pivots' signs are the eigenvalues' (known in closed form), and the
    /// solve, split over the tree or not, solves the system.
    #[test]
    fn an_indefinite_factor_solves_and_counts_its_negative_pivots() {
        for m in [20, 110] {
            // Eigenvalues d - 2 cos(i pi / (m + 1)) - 2 cos(j pi / (m + 1)): both signs.
            let d = 1.5137;
            let a = ordering::tests::grid_matrix(m, d);
            let n = a.nrows();
            let h = std::f64::consts::PI / (m + 1) as f64;
            let mut negative = 0;
            for i in 1..=m {
                for j in 1..=m {
                    if d - 2.0 * (i as f64 * h).cos() - 2.0 * (j as f64 * h).cos() < 0.0 {
                        negative += 1;
                    }
                }
            }
            assert!(negative > n / 10 && negative < n - n / 10);
            let c = CholeskyAnalysis::new(&a)
                .unwrap()
                .factor_indefinite(&a)
                .unwrap();
            let signs = c.inertia().unwrap();
            assert_eq!(signs.negative, negative, "{m} x {m}");
            assert_eq!(signs.positive, n - negative);
            assert_eq!(c.layout.as_ref().unwrap().is_split(), m == 110);
            let mut rand = crate::test_support::lcg53(7 + m as u64);
            let k = 5;
            let x_true: Vec<f64> = (0..n * k).map(|_| rand() - 0.5).collect();
            let mut b = Vec::with_capacity(n * k);
            for q in 0..k {
                b.extend(a.mul_vec(&x_true[q * n..(q + 1) * n]));
            }
            c.solve_many_in_place(&mut b, k);
            let err = max_difference(&b, &x_true);
            assert!(err < 1e-9, "{m} x {m}: error {err:e}");
            // An `L L^T` factor of the same matrix does not exist.
            assert!(SparseCholesky::new(&a).is_err());
        }
    }

    #[test]
    fn a_large_pattern_is_dissected_and_solved_exactly() {
        // A 260 x 260 grid Laplacian plus the identity: above `ordering::MIN_ROWS`, so the
        // analysis uses nested dissection; the solve and the inertia must not notice.
        let m = 260;
        let n = m * m;
        assert!(n >= ordering::MIN_ROWS);
        let a = ordering::tests::grid_matrix(m, 4.5);
        let x_true: Vec<f64> = (0..n).map(|i| (0.001 * i as f64).sin()).collect();
        let b = a.mul_vec(&x_true);
        let c = SparseCholesky::new(&a).unwrap();
        let x = c.solve(&b);
        let err = max_difference(&x, &x_true);
        assert!(err < 1e-10, "max error {err}");
        // Shifted by `shift` the matrix keeps its pattern and has negative eigenvalues
        // (the grid Laplacian's lie in (0, 8); a shift with no round value, so that no
        // pivot of the unpivoted LDL^T is exactly zero).
        let shift = 3.487_123;
        let shifted = a.add_scaled(1.0, &SparseMatrix::identity(n), -shift);
        let inertia = c.inertia_of(&shifted).unwrap();
        // Its eigenvalues are 4.5 - shift - 2 cos(pi i / (m + 1)) - 2 cos(pi j / (m + 1)).
        let c = |i: usize| (std::f64::consts::PI * i as f64 / (m + 1) as f64).cos();
        let expected = (1..=m)
            .flat_map(|i| (1..=m).map(move |j| (i, j)))
            .filter(|&(i, j)| 4.5 - shift - 2.0 * c(i) - 2.0 * c(j) < 0.0)
            .count();
        assert_eq!(inertia.negative, expected);
        assert_eq!(inertia.negative + inertia.positive, n);
    }

    #[test]
    fn refactor_reuses_the_analysis_only_for_the_same_pattern() {
        let n = 40;
        let tri = |d: f64, with_far: bool| {
            let mut t = tridiagonal(n, d);
            if with_far {
                t.push((0, n - 1, -0.5));
                t.push((n - 1, 0, -0.5));
            }
            SparseMatrix::from_triplets(n, n, &t)
        };
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
        let a = tri(3.0, false);
        let mut c = SparseCholesky::new(&a).unwrap();
        let same = c.pattern;
        // Same pattern, new values: the analysis is kept.
        let a2 = tri(5.0, false);
        c.refactor(&a2).unwrap();
        assert_eq!(c.pattern, same);
        let x = c.solve(&a2.mul_vec(&x_true));
        assert!(max_difference(&x, &x_true) < 1e-12);
        // A new entry: a fresh analysis, and still the right solution.
        let a3 = tri(3.0, true);
        c.refactor(&a3).unwrap();
        assert_ne!(c.pattern, same);
        let x = c.solve(&a3.mul_vec(&x_true));
        assert!(max_difference(&x, &x_true) < 1e-12);
    }

    #[test]
    fn indefinite_matrix_is_refused() {
        let a = SparseMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, -1.0)]);
        assert!(matches!(
            SparseCholesky::new(&a),
            Err(CholeskyError::NotPositiveDefinite(_))
        ));
    }
}
