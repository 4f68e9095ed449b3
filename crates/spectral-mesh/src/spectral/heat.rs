//! The heat kernel on a truncated eigenbasis (Sect. 4 of the paper; `docs/MATH.md`, "Heat
//! kernel"), a dense non-truncated reference, a time-stepping reference, and the analytic
//! kernel of the round sphere.
//!
//! With `S X = B X Lambda`, `X^T B X = I` (S positive semi-definite) and
//! `D_t = diag(exp(-lambda_j t))`:
//!
//! - [`Kernel::Wfem`]: `K_t = X D_t X^T B` (the paper's wFEM kernel),
//! - [`Kernel::VoronoiCot`]: `K*_t = X D_t X^T D`, `D` = lumped mass = row sums of B,
//! - [`Kernel::Standard`]: `K~_t = X D_t X^T`.
//!
//! `K_t f` is the solution at time t of `B F' + S F = 0`, `F(0) = f` (exactly so for the full
//! spectrum and the wFEM kernel). Nothing here forms an `n x n` matrix: a column `K_t e_i` or
//! a diffusion `K_t f` costs O(nk).
//!
//! # Scale normalisation
//!
//! A shape scaled by `alpha` has eigenvalues divided by `alpha^2`, so a time `t` means
//! different things on different scales. With [`ScaleNormalization::UnitArea`] every time is
//! interpreted for the shape uniformly scaled to total mass 1, without re-meshing: with
//! `A = 1^T B 1` (the total area for the fem, voronoi-cot and mixed masses; `n` for the
//! identity mass of `cot`), the normalised basis ([`normalize_basis`]) has
//!
//! - eigenvalues `lambda' = lambda * A`,
//! - eigenvectors `x' = x * sqrt(A)` (so that `x'^T B' x' = 1`),
//! - mass `B' = B / A`.
//!
//! Consequences for values (we return the values **of the normalised shape**):
//! - `Wfem` and `VoronoiCot`: `K'_t e_i = K_{A t} e_i`: the columns are unchanged apart from
//!   the time rescaling (the factors `A` and `1/A` cancel): as functions they are
//!   dimensionless weights (`1^T B K_t e_i = a(i)`-like masses sum to the mass at `i`);
//! - `Standard`: `K~'_t = A * K~_{A t}` (a density per unit area of the normalised shape).
//!
//! [`ScaleNormalization::None`] (the default of the free functions) uses the basis as given.

use rayon::prelude::*;

use super::{BasisView, Eigenbasis};
use crate::linalg::{CholeskyError, SparseCholesky};
use crate::operators::Operators;

/// Errors of the heat kernel functions.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum HeatError {
    /// A vertex index is out of range.
    #[error("vertex {vertex} is out of range: the mesh has {n} vertices")]
    VertexOutOfRange {
        /// The index given.
        vertex: usize,
        /// Number of vertices.
        n: usize,
    },
    /// A signal has the wrong length.
    #[error("the signal has {got} values but the mesh has {n} vertices")]
    LengthMismatch {
        /// Length given.
        got: usize,
        /// Number of vertices.
        n: usize,
    },
    /// The time is negative or not finite.
    #[error("the diffusion time must be finite and >= 0, got {0}")]
    InvalidTime(f64),
    /// The tolerance is not positive.
    #[error("the tolerance must be finite and > 0, got {0}")]
    InvalidTolerance(f64),
    /// The dense eigen-decomposition failed.
    #[error("dense eigen-decomposition failed: {0}")]
    Eigen(String),
    /// A factorization failed.
    #[error("factorization failed: {0}")]
    Cholesky(#[from] CholeskyError),
    /// The time stepping did not reach the tolerance.
    #[error(
        "time stepping did not reach tolerance {tol} (estimated error {estimate} with {steps} base steps)"
    )]
    NotConverged {
        /// Requested tolerance.
        tol: f64,
        /// Last error estimate.
        estimate: f64,
        /// Last base step count.
        steps: usize,
    },
}

/// Which discretization of the heat kernel (see the module documentation). Typed (and
/// serialized) as `wfem`, `voronoi-cot` or `standard`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Kernel {
    /// `K_t = X D_t X^T B` (the paper's wFEM kernel; conserves the B-mass). Default.
    #[default]
    Wfem,
    /// `K*_t = X D_t X^T D`, `D` = lumped mass (row sums of B).
    VoronoiCot,
    /// `K~_t = X D_t X^T` (no mass; LaPy's and pyFM's kernel).
    Standard,
}

impl Kernel {
    /// Every kernel, in a stable order.
    pub const ALL: [Kernel; 3] = [Kernel::Wfem, Kernel::VoronoiCot, Kernel::Standard];

    /// The name typed.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Wfem => "wfem",
            Kernel::VoronoiCot => "voronoi-cot",
            Kernel::Standard => "standard",
        }
    }
}

impl std::str::FromStr for Kernel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Kernel::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
            .ok_or_else(|| format!("unknown kernel '{s}': expected wfem, voronoi-cot or standard"))
    }
}

/// Scale normalisation of times (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ScaleNormalization {
    /// Use the basis as given.
    None,
    /// Interpret times for the shape scaled to total mass (area) 1 (default of
    /// [`HeatSolver`]).
    #[default]
    UnitArea,
}

/// Total mass `A = 1^T B 1` of a basis (the area for area-based masses).
pub fn total_mass(basis: &Eigenbasis) -> f64 {
    basis.mass.values().iter().sum()
}

/// The basis of the shape scaled to unit total mass: `lambda * A`, `x * sqrt(A)`, `B / A`
/// (a copy; [`ScaleNormalization::None`] returns a plain copy).
pub fn normalize_basis(basis: &Eigenbasis, norm: ScaleNormalization) -> Eigenbasis {
    let mut b = basis.clone();
    if norm == ScaleNormalization::UnitArea {
        let a = total_mass(basis);
        if a > 0.0 && a.is_finite() {
            let r = a.sqrt();
            b.values.iter_mut().for_each(|v| *v *= a);
            b.vectors.iter_mut().for_each(|v| *v *= r);
            b.mass = b.mass.add_scaled(1.0 / a, &basis.mass, 0.0);
        }
    }
    b
}

/// Rows per parallel task of the column kernels ([`combine_columns`] and the distances').
pub(crate) const ROW_BLOCK: usize = 4096;

/// Whether a kernel over `n x k` values is worth spreading over the threads.
pub(crate) fn parallel_worth(n: usize, k: usize) -> bool {
    n * k > 200_000
}

/// `y = X c` for the column-major `n x k` matrix `x`, parallel over blocks of rows.
///
/// Columns with `c_j = 0` are skipped; the others are added in order (see
/// [`accumulate_columns`]).
pub(crate) fn combine_columns(x: &[f64], n: usize, c: &[f64]) -> Vec<f64> {
    let used: Vec<(usize, f64)> = c
        .iter()
        .copied()
        .enumerate()
        .filter(|&(_, cj)| cj != 0.0)
        .collect();
    accumulate_columns(x, n, c.len(), &used, |t, xi, cj| t + cj * xi)
}

/// `y(p) = add(... add(add(0, x_j1(p), a_j1), x_j2(p), a_j2) ..., x_jm(p), a_jm)` for
/// every row `p` of the column-major `n x k` matrix `x`, over the columns `used = [(j,
/// a_j)]` in order: the one kernel of [`combine_columns`] and the distances. Parallel over
/// blocks of rows (when `n x k` is worth it); the columns are taken four at a time with
/// each row's sum in a register, the same additions in the same order as one column at a
/// time, so the same bits, in a third of the time (one pass over the block of `y` per four
/// columns instead of per column).
pub(crate) fn accumulate_columns<A: Copy + Sync>(
    x: &[f64],
    n: usize,
    k: usize,
    used: &[(usize, A)],
    add: impl Fn(f64, f64, A) -> f64 + Sync,
) -> Vec<f64> {
    let mut y = vec![0.0; n];
    let work = |(b, chunk): (usize, &mut [f64])| {
        let start = b * ROW_BLOCK;
        let len = chunk.len();
        let col = |j: usize| &x[j * n + start..j * n + start + len];
        let mut groups = used.chunks_exact(4);
        for g in &mut groups {
            let (a0, a1, a2, a3) = (g[0].1, g[1].1, g[2].1, g[3].1);
            let rows = chunk
                .iter_mut()
                .zip(col(g[0].0))
                .zip(col(g[1].0))
                .zip(col(g[2].0))
                .zip(col(g[3].0));
            for ((((yi, &x0), &x1), &x2), &x3) in rows {
                *yi = add(add(add(add(*yi, x0, a0), x1, a1), x2, a2), x3, a3);
            }
        }
        for &(j, aj) in groups.remainder() {
            for (yi, &xi) in chunk.iter_mut().zip(col(j)) {
                *yi = add(*yi, xi, aj);
            }
        }
    };
    if parallel_worth(n, k) {
        y.par_chunks_mut(ROW_BLOCK).enumerate().for_each(work);
    } else {
        y.chunks_mut(ROW_BLOCK).enumerate().for_each(work);
    }
    y
}

/// `X^T g` (`k` entries) for the column-major `n x k` matrix `x`.
pub(crate) fn project(x: &[f64], n: usize, g: &[f64]) -> Vec<f64> {
    let k = x.len() / n.max(1);
    let dotc = |j: usize| -> f64 {
        x[j * n..(j + 1) * n]
            .iter()
            .zip(g)
            .map(|(a, b)| a * b)
            .sum()
    };
    if parallel_worth(n, k) {
        (0..k).into_par_iter().map(dotc).collect()
    } else {
        (0..k).map(dotc).collect()
    }
}

fn check_time(t: f64) -> Result<(), HeatError> {
    if t.is_finite() && t >= 0.0 {
        Ok(())
    } else {
        Err(HeatError::InvalidTime(t))
    }
}

/// The row `i` of `X^T M` for the kernel's right factor `M` (B, D or I): `k` entries.
fn anchor_coefficients(basis: BasisView<'_>, anchor: usize, kind: Kernel) -> Vec<f64> {
    let n = basis.n;
    let k = basis.k();
    match kind {
        Kernel::Standard => (0..k).map(|j| basis.vectors[j * n + anchor]).collect(),
        Kernel::VoronoiCot => {
            let (_, vals) = basis.mass.col(anchor);
            let d: f64 = vals.iter().sum();
            (0..k).map(|j| d * basis.vectors[j * n + anchor]).collect()
        }
        Kernel::Wfem => {
            // Row `anchor` of B X = column `anchor` of B (B symmetric) against X.
            let (rows, vals) = basis.mass.col(anchor);
            (0..k)
                .map(|j| {
                    rows.iter()
                        .zip(vals)
                        .map(|(&r, &v)| v * basis.vectors[j * n + r])
                        .sum()
                })
                .collect()
        }
    }
}

/// The basis function `K_t e_anchor` (`n` values) of the truncated kernel of `kind`, in
/// O(nk). Times are those of the basis as given (no scale normalisation; see
/// [`HeatSolver`] for that).
pub fn basis_function<'a>(
    basis: impl Into<BasisView<'a>>,
    anchor: usize,
    t: f64,
    kind: Kernel,
) -> Result<Vec<f64>, HeatError> {
    let basis: BasisView<'a> = basis.into();
    if anchor >= basis.n {
        return Err(HeatError::VertexOutOfRange {
            vertex: anchor,
            n: basis.n,
        });
    }
    check_time(t)?;
    let mut c = anchor_coefficients(basis, anchor, kind);
    for (cj, l) in c.iter_mut().zip(basis.values) {
        *cj *= (-l * t).exp();
    }
    Ok(combine_columns(basis.vectors, basis.n, &c))
}

/// The diffusion `K_t f` (`n` values) of the signal `f` by the truncated kernel of `kind`,
/// in O(nk + nnz(B)).
pub fn diffuse<'a>(
    basis: impl Into<BasisView<'a>>,
    f: &[f64],
    t: f64,
    kind: Kernel,
) -> Result<Vec<f64>, HeatError> {
    let basis: BasisView<'a> = basis.into();
    if f.len() != basis.n {
        return Err(HeatError::LengthMismatch {
            got: f.len(),
            n: basis.n,
        });
    }
    check_time(t)?;
    let g = match kind {
        Kernel::Wfem => basis.mass.mul_vec(f),
        Kernel::VoronoiCot => basis
            .mass
            .row_sums()
            .iter()
            .zip(f)
            .map(|(d, v)| d * v)
            .collect(),
        Kernel::Standard => f.to_vec(),
    };
    let mut c = project(basis.vectors, basis.n, &g);
    for (cj, l) in c.iter_mut().zip(basis.values) {
        *cj *= (-l * t).exp();
    }
    Ok(combine_columns(basis.vectors, basis.n, &c))
}

/// A heat-kernel solver: holds a (normalised) basis and the precomputed rows of `X^T M`
/// (`M` = B, D or I), and answers many `(t, anchor)` queries in O(nk) each.
#[derive(Debug, Clone)]
pub struct HeatSolver {
    basis: Eigenbasis,
    kind: Kernel,
    normalization: ScaleNormalization,
    area: f64,
    /// `M X`, row-major `n x k` (row i = coefficients of anchor i before `D_t`).
    mx_rows: Vec<f64>,
    /// Lumped masses (row sums of the normalised B).
    lumped: Vec<f64>,
}

impl HeatSolver {
    /// Builds the solver for `basis`, kernel `kind`, and scale normalisation `norm`.
    pub fn new(basis: &Eigenbasis, kind: Kernel, norm: ScaleNormalization) -> Self {
        let area = total_mass(basis);
        let b = normalize_basis(basis, norm);
        let (n, k) = (b.n, b.k());
        let mut mx_rows = vec![0.0; n * k];
        mx_rows
            .par_chunks_mut(k.max(1))
            .enumerate()
            .for_each(|(i, row)| {
                row.copy_from_slice(&anchor_coefficients(b.view(k), i, kind));
            });
        let lumped = b.mass.row_sums();
        Self {
            basis: b,
            kind,
            normalization: norm,
            area,
            mx_rows,
            lumped,
        }
    }

    /// The basis used (normalised when the normalisation is on).
    pub fn basis(&self) -> &Eigenbasis {
        &self.basis
    }

    /// The kernel kind.
    pub fn kind(&self) -> Kernel {
        self.kind
    }

    /// The scale normalisation in force.
    pub fn normalization(&self) -> ScaleNormalization {
        self.normalization
    }

    /// Total mass `1^T B 1` of the *input* basis (the factor `A` of the normalisation).
    pub fn input_total_mass(&self) -> f64 {
        self.area
    }

    /// Lumped masses of the (normalised) basis, `n` entries.
    pub fn lumped_mass(&self) -> &[f64] {
        &self.lumped
    }

    /// `K_t e_anchor` (`n` values), O(nk).
    pub fn basis_function(&self, anchor: usize, t: f64) -> Result<Vec<f64>, HeatError> {
        let (n, k) = (self.basis.n, self.basis.k());
        if anchor >= n {
            return Err(HeatError::VertexOutOfRange { vertex: anchor, n });
        }
        check_time(t)?;
        let c: Vec<f64> = self.mx_rows[anchor * k..(anchor + 1) * k]
            .iter()
            .zip(&self.basis.values)
            .map(|(c, l)| c * (-l * t).exp())
            .collect();
        Ok(combine_columns(&self.basis.vectors, n, &c))
    }

    /// `K_t f` (`n` values), O(nk + nnz(B)).
    pub fn diffuse(&self, f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
        diffuse(&self.basis, f, t, self.kind)
    }

    /// Several basis functions at once (parallel over anchors), each `n` values.
    pub fn basis_functions(&self, anchors: &[usize], t: f64) -> Result<Vec<Vec<f64>>, HeatError> {
        anchors
            .par_iter()
            .map(|&a| self.basis_function(a, t))
            .collect()
    }
}

/// The non-truncated wFEM basis function `K_t e_anchor` through the full dense
/// eigen-decomposition of (S, B) (O(n^3); small meshes only).
pub fn reference_basis_function_dense(
    ops: &Operators,
    anchor: usize,
    t: f64,
) -> Result<Vec<f64>, HeatError> {
    let n = ops.n();
    if anchor >= n {
        return Err(HeatError::VertexOutOfRange { vertex: anchor, n });
    }
    let basis = Eigenbasis::dense(ops, n).map_err(|e| HeatError::Eigen(e.to_string()))?;
    basis_function(&basis, anchor, t, Kernel::Wfem)
}

/// The result of [`reference_heat_time_stepping`].
#[derive(Debug, Clone)]
pub struct TimeSteppingSolution {
    /// `F(t)`, `n` values.
    pub values: Vec<f64>,
    /// Estimated error `max |F_N - F_2N| / max |F_2N|` of the returned solution's coarser
    /// companion (the returned one is more accurate than this).
    pub estimated_error: f64,
    /// The base step count `N` of the returned solution.
    pub base_steps: usize,
}

/// Number of extrapolation stages of [`reference_heat_time_stepping`].
const EXTRAPOLATION_STAGES: usize = 6;

/// Solves `B F' + S F = 0`, `F(0) = f`, up to time `t` without any eigenvector: the
/// extrapolated implicit Euler method.
///
/// Stage `j = 1..=6` takes `j N` implicit Euler steps `(B + h S) F_{m+1} = B F_m`,
/// `h = t / (j N)`, each with one sparse Cholesky factorization; the six results are
/// combined by Aitken-Neville extrapolation in `h` (implicit Euler's error expands in powers
/// of h), giving order 6. `N` starts at 8 and doubles until two successive extrapolated
/// results differ by less than `tol` (relative to their max norm); the finer one is
/// returned. Implicit Euler is L-stable, so rough data such as `e_i` do not oscillate.
/// Fails with [`HeatError::NotConverged`] if `N` would exceed 8192.
pub fn reference_heat_time_stepping(
    ops: &Operators,
    f: &[f64],
    t: f64,
    tol: f64,
) -> Result<TimeSteppingSolution, HeatError> {
    let n = ops.n();
    if f.len() != n {
        return Err(HeatError::LengthMismatch { got: f.len(), n });
    }
    check_time(t)?;
    if !(tol.is_finite() && tol > 0.0) {
        return Err(HeatError::InvalidTolerance(tol));
    }
    if t == 0.0 {
        return Ok(TimeSteppingSolution {
            values: f.to_vec(),
            estimated_error: 0.0,
            base_steps: 0,
        });
    }
    let extrapolated = |base: usize| -> Result<Vec<f64>, HeatError> {
        let mut table: Vec<Vec<Vec<f64>>> = Vec::with_capacity(EXTRAPOLATION_STAGES);
        let mut counts: Vec<f64> = Vec::with_capacity(EXTRAPOLATION_STAGES);
        for j in 1..=EXTRAPOLATION_STAGES {
            let steps = j * base;
            let h = t / steps as f64;
            let a = ops.mass.add_scaled(1.0, &ops.stiffness, h);
            let chol = SparseCholesky::new(&a)?;
            let mut y = f.to_vec();
            for _ in 0..steps {
                let mut r = ops.mass.mul_vec(&y);
                chol.solve_in_place(&mut r);
                y = r;
            }
            // Aitken-Neville: T_{j,m} = T_{j,m-1} + (T_{j,m-1} - T_{j-1,m-1}) / (n_j/n_{j-m+1} - 1).
            counts.push(steps as f64);
            let mut cur = y;
            let jj = table.len();
            let mut new_row = vec![cur.clone()];
            for m in 1..=jj {
                let prev = &table[jj - 1][m - 1];
                let ratio = counts[jj] / counts[jj - m] - 1.0;
                cur = cur
                    .iter()
                    .zip(prev)
                    .map(|(c, p)| c + (c - p) / ratio)
                    .collect();
                new_row.push(cur.clone());
            }
            table.push(new_row);
        }
        Ok(table
            .pop()
            .and_then(|mut r| r.pop())
            .unwrap_or_else(|| f.to_vec()))
    };
    let maxn = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut base = 8;
    let mut prev = extrapolated(base)?;
    let mut estimate = f64::INFINITY;
    while base < 8192 {
        base *= 2;
        let next = extrapolated(base)?;
        let diff = next
            .iter()
            .zip(&prev)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        estimate = diff / maxn(&next).max(f64::MIN_POSITIVE);
        if estimate < tol {
            return Ok(TimeSteppingSolution {
                values: next,
                estimated_error: estimate,
                base_steps: base,
            });
        }
        prev = next;
    }
    Err(HeatError::NotConverged {
        tol,
        estimate,
        steps: base,
    })
}

/// The analytic heat kernel of the round sphere of radius `radius` between two points at
/// angle `theta`:
/// `sum_{l=0}^{l_max} exp(-l(l+1) t / R^2) (2l+1) / (4 pi R^2) P_l(cos theta)`
/// (Legendre polynomials by their three-term recurrence).
pub fn sphere_heat_kernel(theta: f64, t: f64, radius: f64, l_max: usize) -> f64 {
    let x = theta.cos();
    let r2 = radius * radius;
    let c = 1.0 / (4.0 * std::f64::consts::PI * r2);
    let (mut p_prev, mut p) = (1.0, x);
    let mut sum = c; // l = 0
    for l in 1..=l_max {
        let lf = l as f64;
        if l > 1 {
            let next = ((2.0 * lf - 1.0) * x * p - (lf - 1.0) * p_prev) / lf;
            p_prev = p;
            p = next;
        }
        sum += (-lf * (lf + 1.0) * t / r2).exp() * (2.0 * lf + 1.0) * c * p;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The four-column kernel gives the bits of one column at a time (zero coefficients
    /// skipped), for sizes around the block and group sizes, serial and parallel.
    #[test]
    fn combine_columns_is_one_column_at_a_time() {
        let mut rnd = crate::test_support::lcg53(7);
        let mut next = || rnd() - 0.3;
        for (n, k) in [(5, 3), (100, 9), (ROW_BLOCK + 17, 13), (3 * ROW_BLOCK, 70)] {
            let x: Vec<f64> = (0..n * k).map(|_| next()).collect();
            let mut c: Vec<f64> = (0..k).map(|_| next() * 1e3).collect();
            c[k / 2] = 0.0;
            c[0] = -0.0;
            let mut naive = vec![0.0; n];
            for (j, &cj) in c.iter().enumerate() {
                if cj != 0.0 {
                    for i in 0..n {
                        naive[i] += cj * x[j * n + i];
                    }
                }
            }
            let got = combine_columns(&x, n, &c);
            assert!(
                got.iter()
                    .zip(&naive)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "n {n} k {k}"
            );
        }
    }

    #[test]
    fn sphere_kernel_integrates_to_one_and_matches_small_l() {
        // Integral over the unit sphere: 2 pi int_0^pi k(theta) sin(theta) dtheta = 1.
        let t = 0.05;
        let m = 4000;
        let h = std::f64::consts::PI / m as f64;
        let mut s = 0.0;
        for i in 0..m {
            let th = (i as f64 + 0.5) * h;
            s += sphere_heat_kernel(th, t, 1.0, 200) * th.sin() * h;
        }
        s *= 2.0 * std::f64::consts::PI;
        assert!((s - 1.0).abs() < 1e-6, "{s}");
        // l_max = 2 by hand: P_2 = (3x^2-1)/2.
        let (th, t) = (0.7f64, 0.3f64);
        let x = th.cos();
        let c = 1.0 / (4.0 * std::f64::consts::PI);
        let want = c
            * (1.0
                + 3.0 * (-2.0 * t).exp() * x
                + 5.0 * (-6.0 * t).exp() * (3.0 * x * x - 1.0) / 2.0);
        assert!((sphere_heat_kernel(th, t, 1.0, 2) - want).abs() < 1e-15);
        // Radius scaling: k_R(theta, t) = k_1(theta, t / R^2) / R^2.
        let a = sphere_heat_kernel(0.4, 0.8, 2.0, 60);
        let b = sphere_heat_kernel(0.4, 0.2, 1.0, 60) / 4.0;
        assert!((a - b).abs() < 1e-14 * b.abs().max(1.0));
    }
}
