//! The functional-map energy and its exact minimizer (pyFM's `FunctionalMapping.fit`
//! energy, terms and scalings; `docs/MATH.md`, "Correspondence"):
//!
//! `E(C) = w_d/2 ||C A - B||^2 + w_l/2 sum_ij C_ij^2 D_ij
//!        + w_c/2 sum_d ||C X_d - Y_d C||^2 + w_o'/2 sum_d ||C P_d - Q_d C||^2`
//!
//! - `A = Phi_1^T M_1 F_1` (`k1 x p`), `B = Phi_2^T M_2 F_2` (`k2 x p`): the projected
//!   descriptors;
//! - `D_ij = (lambda1_j - lambda2_i)^2 / sum_ij (lambda1_j - lambda2_i)^2`: Laplacian
//!   commutativity, normalized to sum 1;
//! - `X_d = Phi_1^T M_1 diag(f_1d) Phi_1`, `Y_d` likewise: descriptor commutativity;
//! - `P_d`, `Q_d`: the orientation operators of the descriptors
//!   ([`super::orientation`]); with `orientation_reversing`, `Q_d` is negated. The weight
//!   is rescaled as pyFM 1.3 does: `w_o' = w_o E_rest(I) / ((w_d + w_l + w_c) E_orient(I))`
//!   at `C = I_{k2 x k1}`;
//! - with `fix_constant` (pyFM always does), the first column is held at
//!   `C[:, 0] = (s sqrt(area_2 / area_1), 0, ...)`, `s` the sign of the product of the
//!   first entries of the first eigenvectors (constant functions map to constants).
//!
//! Every term is quadratic in `C`: with `c = vec(C)` (column-major) the energy is
//! `c^T H c / 2 - r^T c + const`, and the minimizer solves `H c = r` (on the free
//! columns). `H = w_d (A A^T ⊗ I) + diag(w_l D) + sum w (X X^T ⊗ I - X ⊗ Y - X^T ⊗ Y^T
//! + I ⊗ Y^T Y)`, `r = w_d vec(B A^T)`.

use super::descriptors::{Descriptors, project};
use super::orientation::{reduced_operator, triangle_frames};
use super::{CorrespondenceError, FunctionalMap, MAX_FMAP_UNKNOWNS};
use crate::linalg::dense_ops::{gram, product, solve_symmetric};
use crate::linalg::sym_spmm;
use crate::mesh::Mesh;
use crate::spectral::BasisView;

/// Default weight of descriptor preservation (pyFM's quickstart: 1).
pub const DEFAULT_W_DESCRIPTORS: f64 = 1.0;
/// Default weight of Laplacian commutativity (pyFM's quickstart: 1e-2).
pub const DEFAULT_W_LAPLACIAN: f64 = 1e-2;
/// Default weight of descriptor commutativity (pyFM's quickstart: 1e-1).
pub const DEFAULT_W_COMMUTATIVITY: f64 = 1e-1;
/// Default weight of the orientation term, relative to the rest of the energy at the
/// identity (pyFM's default 0; on here so that mirror-symmetric shapes do not come out
/// mirrored: the descriptors cannot tell the sign of the antisymmetric eigenfunctions, only
/// this term can, and at 0.1 it was too weak on the tests' mirror-symmetric pair).
pub const DEFAULT_W_ORIENTATION: f64 = 1.0;

/// Weights of the energy. `Default`: 1, 1e-2, 1e-1, 1, preserving, constant fixed.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct FmapWeights {
    /// Descriptor preservation `w_d`.
    pub descriptors: f64,
    /// Laplacian commutativity `w_l`.
    pub laplacian: f64,
    /// Descriptor commutativity `w_c`.
    pub commutativity: f64,
    /// Orientation `w_o` (before the rescaling).
    pub orientation: f64,
    /// Orientation-reversing term instead of the preserving one.
    pub orientation_reversing: bool,
    /// Hold the first column at the map of constants (pyFM: always).
    pub fix_constant: bool,
}

impl Default for FmapWeights {
    fn default() -> Self {
        Self {
            descriptors: DEFAULT_W_DESCRIPTORS,
            laplacian: DEFAULT_W_LAPLACIAN,
            commutativity: DEFAULT_W_COMMUTATIVITY,
            orientation: DEFAULT_W_ORIENTATION,
            orientation_reversing: false,
            fix_constant: true,
        }
    }
}

impl FmapWeights {
    /// Checks that every weight is finite and `>= 0`.
    pub fn validate(&self) -> Result<(), CorrespondenceError> {
        for (name, w) in [
            ("descriptor", self.descriptors),
            ("Laplacian", self.laplacian),
            ("commutativity", self.commutativity),
            ("orientation", self.orientation),
        ] {
            if !(w.is_finite() && w >= 0.0) {
                return Err(CorrespondenceError::InvalidParameter(format!(
                    "the {name} weight must be finite and >= 0, got {w}"
                )));
            }
        }
        Ok(())
    }
}

/// One shape of the problem: its mesh (for the orientation term), its basis (the first
/// `k` pairs are used) and its descriptors.
#[derive(Debug, Clone, Copy)]
pub struct MatchShape<'a> {
    /// The mesh.
    pub mesh: &'a Mesh,
    /// The basis (`k` pairs).
    pub basis: BasisView<'a>,
    /// The descriptors (`n x p`).
    pub descriptors: &'a Descriptors,
}

/// One number per term of the energy: the value of each term at some `C` (weighted;
/// [`FmapProblem::terms`]), or the weight of each ([`FmapProblem::weights`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergyTerms {
    /// `w_d/2 ||C A - B||^2`.
    pub descriptors: f64,
    /// `w_l/2 sum C_ij^2 D_ij`.
    pub laplacian: f64,
    /// `w_c/2 sum ||C X - Y C||^2`.
    pub commutativity: f64,
    /// `w_o'/2 sum ||C P - Q C||^2`.
    pub orientation: f64,
}

impl EnergyTerms {
    /// The sum.
    pub fn total(&self) -> f64 {
        self.descriptors + self.laplacian + self.commutativity + self.orientation
    }
}

/// The assembled problem (see the module docs).
#[derive(Debug, Clone)]
pub struct FmapProblem {
    /// Basis size of shape 1.
    pub k1: usize,
    /// Basis size of shape 2.
    pub k2: usize,
    /// Number of descriptors.
    pub p: usize,
    /// `A`, `k1 x p`.
    pub a: Vec<f64>,
    /// `B`, `k2 x p`.
    pub b: Vec<f64>,
    /// `D`, `k2 x k1`, sums to 1.
    pub ev_sqdiff: Vec<f64>,
    /// `(X_d, Y_d)` (empty when `w_c = 0`).
    pub commutativity_ops: Vec<(Vec<f64>, Vec<f64>)>,
    /// `(P_d, Q_d)` (empty when `w_o = 0`).
    pub orientation_ops: Vec<(Vec<f64>, Vec<f64>)>,
    /// The weight of each term: `w_d`, `w_l`, `w_c` and `w_o'`, the rescaled orientation
    /// weight.
    pub weights: EnergyTerms,
    /// The held first column (`k2`), with `fix_constant`.
    pub first_column: Option<Vec<f64>>,
}

/// `Phi^T M diag(f) Phi` (`k x k`).
fn multiplication_operator(basis: BasisView<'_>, f: &[f64]) -> Vec<f64> {
    let n = basis.n;
    let k = basis.k();
    let mut fx = basis.vectors[..n * k].to_vec();
    for col in fx.chunks_mut(n) {
        col.iter_mut().zip(f).for_each(|(x, fi)| *x *= fi);
    }
    let mfx = sym_spmm(basis.mass, &fx, k);
    gram(basis.vectors, &mfx, n, k, k)
}

/// `sum_d ||C X_d - Y_d C||_F^2 / 2` over the operator pairs `ops` (the descriptor
/// commutativity or orientation term, unweighted).
fn operators_energy(c: &[f64], ops: &[(Vec<f64>, Vec<f64>)], k1: usize, k2: usize) -> f64 {
    ops.iter()
        .map(|(x, y)| commutator_energy(c, x, y, k1, k2))
        .sum()
}

/// `0.5 ||C X - Y C||^2` for `C` (`k2 x k1`), `X` (`k1 x k1`), `Y` (`k2 x k2`).
fn commutator_energy(c: &[f64], x: &[f64], y: &[f64], k1: usize, k2: usize) -> f64 {
    let cx = product(c, x, k2, k1, k1);
    let yc = product(y, c, k2, k2, k1);
    0.5 * cx
        .iter()
        .zip(&yc)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
}

impl FmapProblem {
    /// Assembles the problem between `shape1` and `shape2` (bases of `k1`, `k2` pairs,
    /// the same number of descriptors on both).
    pub fn new(
        shape1: MatchShape<'_>,
        shape2: MatchShape<'_>,
        weights: &FmapWeights,
    ) -> Result<Self, CorrespondenceError> {
        weights.validate()?;
        let (k1, k2) = (shape1.basis.k(), shape2.basis.k());
        let p = shape1.descriptors.p;
        if shape2.descriptors.p != p {
            return Err(CorrespondenceError::SizeMismatch(format!(
                "{} descriptors on shape 1, {} on shape 2",
                p, shape2.descriptors.p
            )));
        }
        for (s, sh) in [(1, &shape1), (2, &shape2)] {
            if sh.descriptors.n != sh.basis.n || sh.mesh.n_vertices() != sh.basis.n {
                return Err(CorrespondenceError::SizeMismatch(format!(
                    "shape {s}: mesh of {} vertices, basis of {}, descriptors of {}",
                    sh.mesh.n_vertices(),
                    sh.basis.n,
                    sh.descriptors.n
                )));
            }
            if sh.basis.k() == 0 {
                return Err(CorrespondenceError::BasisTooSmall {
                    shape: s,
                    have: 0,
                    need: 1,
                });
            }
        }
        if k1 * k2 > MAX_FMAP_UNKNOWNS {
            return Err(CorrespondenceError::InvalidParameter(format!(
                "k1 k2 = {} unknowns, more than the dense solve's limit {MAX_FMAP_UNKNOWNS}",
                k1 * k2
            )));
        }
        let a = project(shape1.basis, &shape1.descriptors.values, p)?;
        let b = project(shape2.basis, &shape2.descriptors.values, p)?;
        let mut ev_sqdiff = vec![0.0; k1 * k2];
        for j in 0..k1 {
            for i in 0..k2 {
                ev_sqdiff[j * k2 + i] = (shape1.basis.values[j] - shape2.basis.values[i]).powi(2);
            }
        }
        let total: f64 = ev_sqdiff.iter().sum();
        if total > 0.0 {
            ev_sqdiff.iter_mut().for_each(|v| *v /= total);
        }
        let commutativity_ops = if weights.commutativity > 0.0 {
            (0..p)
                .map(|d| {
                    (
                        multiplication_operator(shape1.basis, shape1.descriptors.column(d)),
                        multiplication_operator(shape2.basis, shape2.descriptors.column(d)),
                    )
                })
                .collect()
        } else {
            Vec::new()
        };
        let orientation_ops = if weights.orientation > 0.0 {
            let f1 = triangle_frames(shape1.mesh);
            let f2 = triangle_frames(shape2.mesh);
            let a1 = shape1.basis.mass.row_sums();
            let a2 = shape2.basis.mass.row_sums();
            if a1.iter().chain(&a2).any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(CorrespondenceError::InvalidParameter(
                    "the orientation term needs every vertex in a triangle of positive area".into(),
                ));
            }
            let sign = if weights.orientation_reversing {
                -1.0
            } else {
                1.0
            };
            (0..p)
                .map(|d| {
                    let x = reduced_operator(
                        shape1.mesh,
                        shape1.basis,
                        &f1,
                        &a1,
                        shape1.descriptors.column(d),
                    );
                    let mut y = reduced_operator(
                        shape2.mesh,
                        shape2.basis,
                        &f2,
                        &a2,
                        shape2.descriptors.column(d),
                    );
                    y.iter_mut().for_each(|v| *v *= sign);
                    (x, y)
                })
                .collect()
        } else {
            Vec::new()
        };
        let first_column = weights.fix_constant.then(|| {
            let area1: f64 = shape1.basis.mass.values().iter().sum();
            let area2: f64 = shape2.basis.mass.values().iter().sum();
            let s = (shape1.basis.vectors[0] * shape2.basis.vectors[0]).signum();
            let mut col = vec![0.0; k2];
            col[0] = s * (area2 / area1).sqrt();
            col
        });
        let mut problem = Self {
            k1,
            k2,
            p,
            a,
            b,
            ev_sqdiff,
            commutativity_ops,
            orientation_ops,
            weights: EnergyTerms {
                descriptors: weights.descriptors,
                laplacian: weights.laplacian,
                commutativity: weights.commutativity,
                orientation: 0.0,
            },
            first_column,
        };
        if weights.orientation > 0.0 {
            let eye = FunctionalMap::identity(k1, k2);
            let rest = problem.terms(&eye).total();
            let orient = operators_energy(&eye.c, &problem.orientation_ops, k1, k2);
            // pyFM 1.3's scaling: the rest of the energy at I with its weights summing
            // to 1, over the unweighted orientation energy at I.
            let others = weights.descriptors + weights.laplacian + weights.commutativity;
            let others = if others > 0.0 { others } else { 1.0 };
            problem.weights.orientation = if orient > 0.0 {
                weights.orientation * rest / (others * orient)
            } else {
                0.0
            };
        }
        Ok(problem)
    }

    /// The value of each term at `c`.
    pub fn terms(&self, c: &FunctionalMap) -> EnergyTerms {
        let (k1, k2, p) = (self.k1, self.k2, self.p);
        let mut t = EnergyTerms::default();
        if self.weights.descriptors > 0.0 {
            let ca = product(&c.c, &self.a, k2, k1, p);
            t.descriptors = self.weights.descriptors
                * 0.5
                * ca.iter()
                    .zip(&self.b)
                    .map(|(x, y)| (x - y).powi(2))
                    .sum::<f64>();
        }
        if self.weights.laplacian > 0.0 {
            t.laplacian = self.weights.laplacian
                * 0.5
                * c.c
                    .iter()
                    .zip(&self.ev_sqdiff)
                    .map(|(x, d)| x * x * d)
                    .sum::<f64>();
        }
        if self.weights.commutativity > 0.0 {
            t.commutativity = self.weights.commutativity
                * operators_energy(&c.c, &self.commutativity_ops, k1, k2);
        }
        if self.weights.orientation > 0.0 {
            t.orientation =
                self.weights.orientation * operators_energy(&c.c, &self.orientation_ops, k1, k2);
        }
        t
    }

    /// `E(c)`.
    pub fn energy(&self, c: &FunctionalMap) -> f64 {
        self.terms(c).total()
    }

    /// The weighted operator pairs of both commutator terms.
    fn weighted_ops(&self) -> impl Iterator<Item = (f64, &(Vec<f64>, Vec<f64>))> {
        let wc = self.weights.commutativity;
        let wo = self.weights.orientation;
        self.commutativity_ops
            .iter()
            .map(move |op| (wc, op))
            .chain(self.orientation_ops.iter().map(move |op| (wo, op)))
            .filter(|(w, _)| *w > 0.0)
    }

    /// The Hessian `H` (`k1 k2` square, column-major) and the right-hand side `r`.
    pub fn normal_equations(&self) -> (Vec<f64>, Vec<f64>) {
        let (k1, k2, p) = (self.k1, self.k2, self.p);
        let nn = k1 * k2;
        let mut h = vec![0.0; nn * nn];
        // -sum w X ⊗ Y: entry ((j,i),(l,m)) = X[j,l] Y[i,m], index (j,i) = j k2 + i.
        for (w, (x, y)) in self.weighted_ops() {
            for l in 0..k1 {
                for m in 0..k2 {
                    let col = &mut h[(l * k2 + m) * nn..(l * k2 + m + 1) * nn];
                    let ym = &y[m * k2..(m + 1) * k2];
                    for j in 0..k1 {
                        let xjl = w * x[l * k1 + j];
                        if xjl != 0.0 {
                            let dst = &mut col[j * k2..(j + 1) * k2];
                            // Y[i, m] for i in 0..k2 is row m of Y^T: Y is column-major,
                            // so Y[i, m] = y[m * k2 + i].
                            dst.iter_mut().zip(ym).for_each(|(d, yim)| *d -= xjl * yim);
                        }
                    }
                }
            }
        }
        // Add the transpose (the X^T ⊗ Y^T part).
        for r in 0..nn {
            for c in r + 1..nn {
                let v = h[c * nn + r] + h[r * nn + c];
                h[c * nn + r] = v;
                h[r * nn + c] = v;
            }
            h[r * nn + r] *= 2.0;
        }
        // S1 = w_d A A^T + sum w X X^T (k1 x k1); S2 = sum w Y^T Y (k2 x k2).
        let mut s1 = vec![0.0; k1 * k1];
        let mut s2 = vec![0.0; k2 * k2];
        if self.weights.descriptors > 0.0 {
            // A A^T = (A^T)^T (A^T): gram of the p x k1 transpose.
            let at = transpose(&self.a, k1, p);
            let aat = gram(&at, &at, p, k1, k1);
            s1.iter_mut()
                .zip(&aat)
                .for_each(|(s, v)| *s += self.weights.descriptors * v);
        }
        for (w, (x, y)) in self.weighted_ops() {
            let xt = transpose(x, k1, k1);
            let xxt = gram(&xt, &xt, k1, k1, k1);
            let yty = gram(y, y, k2, k2, k2);
            s1.iter_mut().zip(&xxt).for_each(|(s, v)| *s += w * v);
            s2.iter_mut().zip(&yty).for_each(|(s, v)| *s += w * v);
        }
        for l in 0..k1 {
            for j in 0..k1 {
                let v = s1[l * k1 + j];
                if v != 0.0 {
                    for i in 0..k2 {
                        h[(l * k2 + i) * nn + j * k2 + i] += v;
                    }
                }
            }
        }
        for j in 0..k1 {
            for m in 0..k2 {
                for i in 0..k2 {
                    h[(j * k2 + m) * nn + j * k2 + i] += s2[m * k2 + i];
                }
            }
        }
        if self.weights.laplacian > 0.0 {
            for (q, d) in self.ev_sqdiff.iter().enumerate() {
                h[q * nn + q] += self.weights.laplacian * d;
            }
        }
        let mut r = vec![0.0; nn];
        if self.weights.descriptors > 0.0 {
            // B A^T (k2 x k1) = B (k2 x p) times A^T (p x k1).
            let at = transpose(&self.a, k1, p);
            let bat = product(&self.b, &at, k2, p, k1);
            r.iter_mut()
                .zip(&bat)
                .for_each(|(ri, v)| *ri = self.weights.descriptors * v);
        }
        (h, r)
    }

    /// The gradient of `E` at `c` (`k2 x k1`, column-major); the first column is zero
    /// with `fix_constant`.
    pub fn gradient(&self, c: &FunctionalMap) -> Vec<f64> {
        let (h, r) = self.normal_equations();
        let nn = self.k1 * self.k2;
        let mut g: Vec<f64> = (0..nn)
            .map(|row| (0..nn).map(|col| h[col * nn + row] * c.c[col]).sum::<f64>() - r[row])
            .collect();
        if self.first_column.is_some() {
            g[..self.k2].iter_mut().for_each(|v| *v = 0.0);
        }
        g
    }

    /// The exact minimizer of `E` (with the first column held under `fix_constant`).
    pub fn solve(&self) -> Result<FunctionalMap, CorrespondenceError> {
        let (k1, k2) = (self.k1, self.k2);
        let nn = k1 * k2;
        let (h, mut r) = self.normal_equations();
        let Some(first) = &self.first_column else {
            solve_symmetric(&h, nn, &mut r).ok_or(CorrespondenceError::Singular)?;
            return Ok(FunctionalMap { k1, k2, c: r });
        };
        let m = nn - k2;
        let mut hff = vec![0.0; m * m];
        for c in 0..m {
            hff[c * m..(c + 1) * m].copy_from_slice(&h[(c + k2) * nn + k2..(c + k2 + 1) * nn]);
        }
        let mut rf: Vec<f64> = (0..m)
            .map(|q| {
                let row = q + k2;
                r[row]
                    - first
                        .iter()
                        .enumerate()
                        .map(|(c, v)| h[c * nn + row] * v)
                        .sum::<f64>()
            })
            .collect();
        solve_symmetric(&hff, m, &mut rf).ok_or(CorrespondenceError::Singular)?;
        let mut c = first.clone();
        c.extend(rf);
        r.clear();
        Ok(FunctionalMap { k1, k2, c })
    }
}

/// The transpose of a `rows x cols` column-major matrix.
fn transpose(a: &[f64], rows: usize, cols: usize) -> Vec<f64> {
    let mut t = vec![0.0; rows * cols];
    for j in 0..cols {
        for i in 0..rows {
            t[i * cols + j] = a[j * rows + i];
        }
    }
    t
}
