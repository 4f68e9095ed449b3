//! Shape correspondence on the spectral basis: functional maps, ZoomOut, point-to-point
//! maps and their evaluation (formulas, shapes, signs and scales in `docs/MATH.md`,
//! "Correspondence").
//!
//! Conventions (pyFM's): a **functional map** `C` (`k2 x k1`) carries the coefficients of a
//! function on shape 1 (in the first `k1` eigenvectors of shape 1) to those of a function
//! on shape 2; a **point-to-point map** `p2p_21` goes the other way: for each vertex of
//! shape 2, a vertex of shape 1, and its functional map is the pull-back
//! `C = Phi_2^T M_2 Phi_1[p2p_21, :]`.
//!
//! - [`descriptors`](mod@descriptors): WKS/HKS (and landmarks' kernels) chosen as pyFM chooses them,
//!   normalized in `L2(M)` and projected on a basis;
//! - [`energy`]: the functional-map energy (descriptor preservation, Laplacian
//!   commutativity, descriptor commutativity, orientation) and its exact minimizer: every
//!   term is quadratic in `C`, so one dense symmetric solve in `vec(C)`;
//! - [`pointwise`]: nearest neighbours in the spectral embedding (k-d tree), both ways,
//!   the functional map of a point map, function transfer;
//! - [`zoomout`](mod@zoomout): ZoomOut refinement from `k` to `k_final` in steps, of `p2p_21`, of
//!   `p2p_12` or both ([`ZoomoutDirection`]);
//! - [`evaluate`]: mean geodesic error normalized by `sqrt(area)` and the cumulative curve;
//! - [`match_shapes`]: the whole pipeline (descriptors, map, ZoomOut, point map).

pub mod descriptors;
pub mod energy;
pub mod evaluate;
pub mod orientation;
pub mod pointwise;
pub mod zoomout;

pub use descriptors::{DescriptorKind, DescriptorParams, Descriptors, descriptors, project};
pub use energy::{FmapProblem, FmapWeights, MatchShape};
pub use evaluate::{GeodesicErrors, cumulative_curve, default_thresholds, geodesic_errors};
pub use pointwise::{fmap_to_p2p, fmap_to_p2p_12, p2p_to_fmap, transfer, transfer_spectral};
pub use zoomout::{Refined, Zoomed, ZoomoutDirection, zoomout};

use crate::mesh::Mesh;
use crate::spectral::BasisView;

/// Default size of the bases of the first functional map (`k1 = k2`).
pub const DEFAULT_K: usize = 30;
/// Default size the ZoomOut refinement ends at (`0`: no refinement).
pub const DEFAULT_ZOOMOUT_K: usize = 100;
/// Default ZoomOut step (added to both sizes at each iteration).
pub const DEFAULT_ZOOMOUT_STEP: usize = 1;
/// Default ZoomOut direction: the forward map `p2p_21` only (pyFM's).
pub const DEFAULT_ZOOMOUT_DIRECTION: ZoomoutDirection = ZoomoutDirection::Forward;
/// Largest number of unknowns `k1 k2` of the exact solve (its dense Hessian holds
/// `(k1 k2)^2` values: 134 MB at this limit, `k1 = k2 = 64`).
pub const MAX_FMAP_UNKNOWNS: usize = 4096;

/// Errors of the correspondence functions, each saying what to change.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CorrespondenceError {
    /// A parameter is out of its range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// A basis has fewer pairs than asked for.
    #[error("shape {shape}'s basis has {have} eigenpairs, {need} are needed")]
    BasisTooSmall {
        /// 1 or 2.
        shape: usize,
        /// Pairs in the basis.
        have: usize,
        /// Pairs needed.
        need: usize,
    },
    /// Arrays whose sizes do not agree.
    #[error("size mismatch: {0}")]
    SizeMismatch(String),
    /// The descriptors could not be computed.
    #[error("descriptors: {0}")]
    Descriptors(String),
    /// The linear system of the functional map is singular.
    #[error(
        "the functional-map system is singular (give a positive Laplacian-commutativity weight or more descriptors)"
    )]
    Singular,
    /// The geodesic solver failed.
    #[error("geodesics: {0}")]
    Geodesic(String),
    /// A point-map or landmark file that cannot be read.
    #[error("{file}, line {line}: {message}")]
    Parse {
        /// The file's name.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

fn parse_vertex(
    word: &str,
    n: usize,
    file: &str,
    line: usize,
    what: &str,
) -> Result<usize, CorrespondenceError> {
    let err = |message: String| CorrespondenceError::Parse {
        file: file.to_string(),
        line,
        message,
    };
    let v: usize = word.parse().map_err(|_| {
        err(format!(
            "'{word}' is not a vertex index (a whole number >= 0)"
        ))
    })?;
    if v >= n {
        return Err(err(format!(
            "vertex {v} does not exist: the {what} has {n} vertices"
        )));
    }
    Ok(v)
}

/// The lines of `text` that hold data (blank lines and `#` comments skipped), with
/// their 1-based numbers.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, Vec<&str>)> {
    text.lines().enumerate().filter_map(|(i, l)| {
        let l = l.split('#').next().unwrap_or("").trim();
        (!l.is_empty()).then(|| (i + 1, l.split_whitespace().collect()))
    })
}

/// Reads a point map: one vertex of the second shape (`< n_to`) per line, for each of the
/// `n_from` vertices of the first, 0-based (blank lines and `#` comments skipped).
pub fn parse_point_map(
    text: &str,
    file: &str,
    n_from: usize,
    n_to: usize,
) -> Result<Vec<usize>, CorrespondenceError> {
    let mut map = Vec::with_capacity(n_from);
    let mut last = 0;
    for (line, words) in data_lines(text) {
        last = line;
        if words.len() != 1 {
            return Err(CorrespondenceError::Parse {
                file: file.to_string(),
                line,
                message: format!("expected one vertex index, found {} values", words.len()),
            });
        }
        map.push(parse_vertex(words[0], n_to, file, line, "mapped-to shape")?);
    }
    if map.len() != n_from {
        return Err(CorrespondenceError::Parse {
            file: file.to_string(),
            line: last,
            message: format!(
                "{} entries, one per vertex of the mapped shape ({n_from}) expected",
                map.len()
            ),
        });
    }
    Ok(map)
}

/// The text of a point map as [`parse_point_map`] reads it: one 0-based vertex per line.
pub fn point_map_text(map: &[usize]) -> String {
    let mut s = String::with_capacity(map.len() * 7);
    for v in map {
        s.push_str(&v.to_string());
        s.push('\n');
    }
    s
}

/// Reads landmarks: lines `A B`, a vertex of the first shape (`< n_a`) and its
/// counterpart on the second (`< n_b`), 0-based.
pub fn parse_landmarks(
    text: &str,
    file: &str,
    n_a: usize,
    n_b: usize,
) -> Result<Vec<(usize, usize)>, CorrespondenceError> {
    data_lines(text)
        .map(|(line, words)| {
            if words.len() != 2 {
                return Err(CorrespondenceError::Parse {
                    file: file.to_string(),
                    line,
                    message: format!("expected two vertex indices, found {} values", words.len()),
                });
            }
            Ok((
                parse_vertex(words[0], n_a, file, line, "first shape")?,
                parse_vertex(words[1], n_b, file, line, "second shape")?,
            ))
        })
        .collect()
}

/// A functional map `C` (`k2 x k1`, column-major: `c[j * k2 + i] = C[i, j]`) from the
/// first `k1` eigenvectors of shape 1 to the first `k2` of shape 2.
#[derive(Debug, Clone, PartialEq)]
pub struct FunctionalMap {
    /// Size of the basis of shape 1 (columns).
    pub k1: usize,
    /// Size of the basis of shape 2 (rows).
    pub k2: usize,
    /// The entries, column-major.
    pub c: Vec<f64>,
}

impl FunctionalMap {
    /// The `k2 x k1` matrix with ones on its diagonal.
    pub fn identity(k1: usize, k2: usize) -> Self {
        let mut c = vec![0.0; k1 * k2];
        for j in 0..k1.min(k2) {
            c[j * k2 + j] = 1.0;
        }
        Self { k1, k2, c }
    }

    /// Entry `C[i, j]` (row `i < k2`, column `j < k1`).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.c[j * self.k2 + i]
    }

    /// The transpose (`k1 x k2`), a map from shape 2 to shape 1 (the inverse of `C` when
    /// `C` is orthogonal, as for an isometry).
    pub fn transpose(&self) -> Self {
        let mut c = vec![0.0; self.k1 * self.k2];
        for j in 0..self.k1 {
            for i in 0..self.k2 {
                c[i * self.k1 + j] = self.c[j * self.k2 + i];
            }
        }
        Self {
            k1: self.k2,
            k2: self.k1,
            c,
        }
    }

    /// The entries row by row (`k2` rows of `k1`), the order of a C-ordered `.npy`.
    pub fn row_major(&self) -> Vec<f64> {
        self.transpose().c
    }
}

/// A copy of `mesh` with its vertices renumbered by a seeded shuffle, and the true point
/// map from the copy to `mesh` (`p2p_21` with the copy as shape 2 and `mesh` as shape 1):
/// vertex `i` of the copy is vertex `map[i]` of `mesh`. The simplest pair with a known
/// correspondence (the tests' and the benchmarks').
pub fn shuffled_copy(mesh: &Mesh, seed: u64) -> Result<(Mesh, Vec<usize>), crate::mesh::MeshError> {
    let n = mesh.n_vertices();
    let mut map: Vec<usize> = (0..n).collect();
    crate::perturb::rng::Rng::new(seed).shuffle(&mut map);
    let mut inverse = vec![0; n];
    for (i, &p) in map.iter().enumerate() {
        inverse[p] = i;
    }
    let positions = map.iter().map(|&p| mesh.positions()[p]).collect();
    let triangles = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|v| inverse[v]))
        .collect();
    Ok((Mesh::new(positions, triangles)?, map))
}

/// The first `k` pairs of `basis` (checked: `BasisTooSmall` names `shape`).
pub(crate) fn truncate<'a>(
    basis: BasisView<'a>,
    k: usize,
    shape: usize,
) -> Result<BasisView<'a>, CorrespondenceError> {
    if basis.k() < k {
        return Err(CorrespondenceError::BasisTooSmall {
            shape,
            have: basis.k(),
            need: k,
        });
    }
    Ok(BasisView {
        values: &basis.values[..k],
        vectors: &basis.vectors[..k * basis.n],
        ..basis
    })
}

/// Parameters of the whole pipeline [`match_shapes`]. `Default`: `k = 30`, ZoomOut to
/// 100 in steps of 1 in the forward direction, the default descriptors and weights.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct MatchParams {
    /// Size of both bases of the first functional map.
    pub k: usize,
    /// Size ZoomOut ends at; `0` or `<= k`: no refinement.
    pub zoomout_k: usize,
    /// ZoomOut step.
    pub zoomout_step: usize,
    /// Which point maps ZoomOut refines: `p2p_21` (forward), `p2p_12` (reverse) or both.
    pub zoomout_direction: ZoomoutDirection,
    /// Descriptors.
    pub descriptors: DescriptorParams,
    /// Weights of the energy.
    pub weights: FmapWeights,
}

impl Default for MatchParams {
    fn default() -> Self {
        Self {
            k: DEFAULT_K,
            zoomout_k: DEFAULT_ZOOMOUT_K,
            zoomout_step: DEFAULT_ZOOMOUT_STEP,
            zoomout_direction: DEFAULT_ZOOMOUT_DIRECTION,
            descriptors: DescriptorParams::default(),
            weights: FmapWeights::default(),
        }
    }
}

impl MatchParams {
    /// Eigenpairs each basis must hold: `max(k, zoomout_k)`.
    pub fn basis_size(&self) -> usize {
        self.k.max(self.zoomout_k)
    }

    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), CorrespondenceError> {
        if self.k < 2 {
            return Err(CorrespondenceError::InvalidParameter(format!(
                "the basis size k must be >= 2, got {}",
                self.k
            )));
        }
        if self.k * self.k > MAX_FMAP_UNKNOWNS {
            return Err(CorrespondenceError::InvalidParameter(format!(
                "k = {} gives {} unknowns, more than the dense solve's limit {MAX_FMAP_UNKNOWNS} (k <= 64); refine with ZoomOut instead",
                self.k,
                self.k * self.k
            )));
        }
        if self.zoomout_k > self.k && self.zoomout_step == 0 {
            return Err(CorrespondenceError::InvalidParameter(
                "the ZoomOut step must be >= 1".into(),
            ));
        }
        self.descriptors.validate()?;
        self.weights.validate()
    }
}

/// What [`match_shapes`] returns.
#[derive(Debug, Clone)]
pub struct MatchResult {
    /// The functional map of the energy (`k x k`).
    pub initial: FunctionalMap,
    /// The refined functional map (`zoomout_k x zoomout_k`; the initial one without
    /// ZoomOut or when only the reverse direction is refined).
    pub refined: FunctionalMap,
    /// For each vertex of shape 2, a vertex of shape 1 (from `refined`).
    pub p2p_21: Vec<usize>,
    /// The reverse direction, when [`MatchParams::zoomout_direction`] asks for it: `C_12`
    /// refined from `initial^T` (`zoomout_k x zoomout_k`, functions on shape 2 to shape 1)
    /// and `p2p_12`, for each vertex of shape 1 a vertex of shape 2.
    pub reverse: Option<Refined>,
    /// The energy of `initial`.
    pub energy: f64,
}

/// The whole pipeline: descriptors on both shapes, the functional map of the energy
/// (exact), ZoomOut refinement, the point map from shape 2 to shape 1 (refined unless
/// only the reverse direction is asked for) and, when asked for, the reverse one. Both bases must
/// hold [`MatchParams::basis_size`] pairs; `landmarks` are pairs (vertex of shape 1,
/// vertex of shape 2) whose kernels are added to the descriptors.
pub fn match_shapes(
    mesh1: &Mesh,
    basis1: BasisView<'_>,
    mesh2: &Mesh,
    basis2: BasisView<'_>,
    landmarks: &[(usize, usize)],
    params: &MatchParams,
) -> Result<MatchResult, CorrespondenceError> {
    params.validate()?;
    let need = params.basis_size();
    truncate(basis1, need, 1)?;
    truncate(basis2, need, 2)?;
    let (l1, l2): (Vec<usize>, Vec<usize>) = landmarks.iter().copied().unzip();
    let b1 = truncate(basis1, params.k, 1)?;
    let b2 = truncate(basis2, params.k, 2)?;
    let d1 = descriptors(b1, &params.descriptors, &l1)?;
    let d2 = descriptors(b2, &params.descriptors, &l2)?;
    let problem = FmapProblem::new(
        MatchShape {
            mesh: mesh1,
            basis: b1,
            descriptors: &d1,
        },
        MatchShape {
            mesh: mesh2,
            basis: b2,
            descriptors: &d2,
        },
        &params.weights,
    )?;
    let initial = problem.solve()?;
    let energy = problem.energy(&initial);
    // Without refinement (`zoomout_k <= k`) these are the point maps of `initial`.
    let zoomed = zoomout(
        &initial,
        basis1,
        basis2,
        params.zoomout_k,
        params.zoomout_step,
        params.zoomout_direction,
    )?;
    let Refined {
        fmap: refined,
        p2p: p2p_21,
    } = match zoomed.forward {
        Some(f) => f,
        None => Refined {
            p2p: fmap_to_p2p(&initial, basis1, basis2, false)?,
            fmap: initial.clone(),
        },
    };
    Ok(MatchResult {
        initial,
        refined,
        p2p_21,
        reverse: zoomed.reverse,
        energy,
    })
}
