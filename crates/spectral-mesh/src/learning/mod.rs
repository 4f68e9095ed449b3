//! The per-shape operators that learning pipelines on surfaces precompute, as
//! DiffusionNet's `get_operators` does: tangent frames, the lumped mass vector, the weak
//! Laplacian, its smallest eigenpairs and the gradient operators in the tangent frames,
//! for a triangle mesh or a point cloud, with a disk cache keyed by the shape's content
//! hash ([`load_or_compute`]).
//!
//! Every formula, and each place where these operators differ from DiffusionNet's, is in
//! the repository's `docs/MATH.md` ("Learning operators"). In short:
//! - mesh: the cotangent stiffness with the barycentric lumped mass
//!   ([`Laplacian::VoronoiCot`], DiffusionNet's `cotan_laplacian` + `vertex_areas`), the
//!   mass raised by [`MASS_EPS`] times its mean; point cloud: the library's point-cloud
//!   Laplacian ([`Operators::from_points`]);
//! - the `k_eig` smallest pairs of `S x = lambda M x` from the library's eigensolver
//!   ([`EigenSolver`]), `X^T M X = I` for the returned mass `M`;
//! - frames `[X, Y, N]` per vertex ([`frames`]); gradients by a regularized least-squares
//!   fit over the Laplacian's neighbours (meshes) or the `k` nearest points (clouds)
//!   ([`gradient`]).

use std::sync::Arc;

use crate::cancel::CancelToken;
use crate::linalg::{EigenProgress, SparseMatrix};
use crate::mesh::{Mesh, PointCloud, norm, scale};
use crate::operators::point_cloud::{DEFAULT_NEIGHBORS, nearest_neighbors};
use crate::operators::{Laplacian, Operators, PointCloudParams, RobustError};
use crate::spectral::eigenbasis::{EigenError, EigenParams, EigenSolver};
use crate::spectral::store::{BasisDtype, StoreError};

mod cache;
pub mod frames;
pub mod gradient;
#[cfg(test)]
mod tests;

pub use cache::{
    CACHE_FORMAT_VERSION, CacheMeta, cache_file_name, cache_key, load_operators, load_or_compute,
    save_operators,
};
pub use frames::{cloud_normals, mesh_vertex_normals, tangent_frames};
pub use gradient::gradient_matrices;

/// Default number of eigenpairs, DiffusionNet's `k_eig = 128`.
pub const DEFAULT_K_EIG: usize = 128;
/// Default Tikhonov term added to the 2 x 2 normal matrix of every vertex's gradient fit,
/// DiffusionNet's `eps_reg = 1e-5` (absolute: in squared length units).
pub const DEFAULT_GRAD_REGULARIZATION: f64 = 1e-5;
/// A mesh's mass vector is raised by `MASS_EPS` times its mean (DiffusionNet's `eps`), so
/// that a vertex no triangle uses still has a positive mass.
pub const MASS_EPS: f64 = 1e-8;
/// Default discretization for meshes: the cotangent stiffness with the barycentric lumped
/// mass, what DiffusionNet computes (`cotan_laplacian`, `vertex_areas`).
pub const DEFAULT_LAPLACIAN: Laplacian = Laplacian::VoronoiCot;

/// What [`compute_operators`] is asked.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LearningParams {
    /// Number of eigenpairs (`0`: none; at most the number of vertices). Default
    /// [`DEFAULT_K_EIG`].
    pub k_eig: usize,
    /// The discretization of a mesh; it must have a lumped (diagonal) mass. Default
    /// [`DEFAULT_LAPLACIAN`]. Point clouds always use the point-cloud Laplacian.
    pub laplacian: Laplacian,
    /// The regularization of the gradient fit, `>= 0` (`0`: the exact least-squares fit,
    /// exact on linear functions). Default [`DEFAULT_GRAD_REGULARIZATION`].
    pub grad_regularization: f64,
    /// Point clouds: the nearest neighbours of each point used for its normal, its
    /// gradient fit and the point-cloud Laplacian (`>= 2`). Default 30.
    pub neighbors: usize,
    /// Target relative residual of every eigenpair (the library's default, `1e-10`).
    pub tolerance: f64,
}

impl Default for LearningParams {
    fn default() -> Self {
        Self {
            k_eig: DEFAULT_K_EIG,
            laplacian: DEFAULT_LAPLACIAN,
            grad_regularization: DEFAULT_GRAD_REGULARIZATION,
            neighbors: DEFAULT_NEIGHBORS,
            tolerance: EigenParams::default().tolerance,
        }
    }
}

impl LearningParams {
    /// Checks the parameters (not `k_eig` against the shape: see [`compute_operators`]).
    pub fn validate(&self) -> Result<(), LearningError> {
        if !(self.grad_regularization.is_finite() && self.grad_regularization >= 0.0) {
            return Err(LearningError::Parameter(format!(
                "grad_regularization = {}: must be a finite number >= 0",
                self.grad_regularization
            )));
        }
        if self.neighbors < 2 {
            return Err(LearningError::Parameter(format!(
                "neighbors = {}: must be at least 2",
                self.neighbors
            )));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(LearningError::Parameter(format!(
                "tolerance = {}: must be a finite number > 0",
                self.tolerance
            )));
        }
        if self.laplacian.mass_kind() == crate::operators::MassKind::Fem {
            return Err(LearningError::Parameter(format!(
                "laplacian '{}' has a full (consistent) mass matrix; the learning operators \
                 need a lumped one: voronoi-cot (DiffusionNet's), mixed-voronoi, robust, cot \
                 or uniform",
                self.laplacian
            )));
        }
        Ok(())
    }
}

/// The shape the operators are computed for.
#[derive(Debug, Clone, Copy)]
pub enum LearningShape<'a> {
    /// A triangle mesh.
    Mesh(&'a Mesh),
    /// A point cloud (its own normals are not used; pass normals to
    /// [`compute_operators`] to use them).
    Cloud(&'a PointCloud),
}

impl LearningShape<'_> {
    /// Number of vertices (points).
    pub fn n(&self) -> usize {
        match self {
            LearningShape::Mesh(m) => m.n_vertices(),
            LearningShape::Cloud(c) => c.n_points(),
        }
    }

    /// The positions.
    pub fn positions(&self) -> &[[f64; 3]] {
        match self {
            LearningShape::Mesh(m) => m.positions(),
            LearningShape::Cloud(c) => c.positions(),
        }
    }

    /// The library's content hash of the shape ([`Mesh::content_hash`],
    /// [`PointCloud::content_hash`]: equal for the same positions without triangles).
    pub fn content_hash(&self) -> String {
        match self {
            LearningShape::Mesh(m) => m.content_hash(),
            LearningShape::Cloud(c) => c.content_hash(),
        }
    }

    /// True for a point cloud.
    pub fn is_cloud(&self) -> bool {
        matches!(self, LearningShape::Cloud(_))
    }
}

/// The operators of one shape, in DiffusionNet's order. Computed in double precision;
/// [`LearningOperators::rounded`] gives the single-precision values.
#[derive(Debug, Clone, PartialEq)]
pub struct LearningOperators {
    /// Per vertex the rows `[X, Y, N]`: two unit tangent vectors and the unit normal, a
    /// right-handed orthonormal frame (`Y = N x X`).
    pub frames: Vec<[[f64; 3]; 3]>,
    /// The lumped mass of every vertex (the diagonal of `M`).
    pub mass: Vec<f64>,
    /// The weak Laplacian `S` (`n x n`, symmetric positive semi-definite: the stiffness,
    /// `-cotmatrix` in libigl's terms).
    pub laplacian: SparseMatrix,
    /// The `k` smallest eigenvalues of `S x = lambda M x`, ascending.
    pub evals: Vec<f64>,
    /// The eigenvectors, `n x k` column-major, `X^T M X = I`, each with its entry of
    /// largest magnitude positive.
    pub evecs: Vec<f64>,
    /// `n x n`: row `i` gives the X component (in frame `i`) of the gradient at vertex `i`.
    pub grad_x: SparseMatrix,
    /// `n x n`: the Y components.
    pub grad_y: SparseMatrix,
}

impl LearningOperators {
    /// Number of vertices.
    pub fn n(&self) -> usize {
        self.mass.len()
    }

    /// Number of eigenpairs.
    pub fn k(&self) -> usize {
        self.evals.len()
    }

    /// Every value rounded once to `dtype` (to nearest, ties to even; the identity for
    /// float64), the sparsity patterns unchanged: what a float32 request returns.
    pub fn rounded(&self, dtype: BasisDtype) -> Self {
        let r = |v: &[f64]| v.iter().map(|&x| dtype.round(x)).collect::<Vec<f64>>();
        let rm = |m: &SparseMatrix| {
            SparseMatrix::from_csc(
                m.nrows(),
                m.ncols(),
                m.col_ptr().to_vec(),
                m.row_idx().to_vec(),
                r(m.values()),
            )
            .unwrap_or_else(|| m.clone())
        };
        Self {
            frames: self
                .frames
                .iter()
                .map(|f| f.map(|row| row.map(|x| dtype.round(x))))
                .collect(),
            mass: r(&self.mass),
            laplacian: rm(&self.laplacian),
            evals: r(&self.evals),
            evecs: r(&self.evecs),
            grad_x: rm(&self.grad_x),
            grad_y: rm(&self.grad_y),
        }
    }
}

/// Errors of the learning operators.
#[derive(Debug, thiserror::Error)]
pub enum LearningError {
    /// A parameter is out of range.
    #[error("{0}")]
    Parameter(String),
    /// More eigenpairs than vertices.
    #[error("k_eig = {k} but the shape has only {n} vertices")]
    TooMany {
        /// Requested pairs.
        k: usize,
        /// Vertices.
        n: usize,
    },
    /// The given normals do not fit the shape.
    #[error("{0}")]
    Normals(String),
    /// The point-cloud or robust Laplacian failed.
    #[error(transparent)]
    Laplacian(#[from] RobustError),
    /// The eigensolver failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// Reading or writing the cache failed.
    #[error(transparent)]
    Store(#[from] StoreError),
}

/// Unit normals from the caller: one per vertex, each finite and non-zero (normalized
/// here).
fn given_normals(normals: &[[f64; 3]], n: usize) -> Result<Vec<[f64; 3]>, LearningError> {
    if normals.len() != n {
        return Err(LearningError::Normals(format!(
            "normals has {} rows but the shape has {n} vertices",
            normals.len()
        )));
    }
    normals
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let l = norm(v);
            if l.is_finite() && l > 0.0 {
                Ok(scale(v, 1.0 / l))
            } else {
                Err(LearningError::Normals(format!(
                    "normals[{i}] = {v:?} is zero or not finite"
                )))
            }
        })
        .collect()
}

/// The off-diagonal sparsity pattern of a symmetric matrix, per vertex (ascending): the
/// neighbours a mesh's gradient is fitted over, the edges of its Laplacian.
fn pattern_neighbors(s: &SparseMatrix) -> Vec<Vec<usize>> {
    (0..s.ncols())
        .map(|c| s.col(c).0.iter().copied().filter(|&r| r != c).collect())
        .collect()
}

/// The operators of `shape` (see the module documentation and `docs/MATH.md`). `normals`
/// (one per vertex, normalized here) replace the estimated ones in the frames. Progress of
/// the eigensolver goes to `progress`; `cancel` stops it.
pub fn compute_operators(
    shape: LearningShape<'_>,
    normals: Option<&[[f64; 3]]>,
    params: &LearningParams,
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<LearningOperators, LearningError> {
    params.validate()?;
    let n = shape.n();
    if params.k_eig > n {
        return Err(LearningError::TooMany { k: params.k_eig, n });
    }
    let given = normals.map(|v| given_normals(v, n)).transpose()?;
    let positions = shape.positions();
    let (ops, mass, neighbors, normals) = match shape {
        LearningShape::Mesh(mesh) => {
            let ops = if params.laplacian == Laplacian::Robust {
                Operators::robust(mesh, &Default::default())?
            } else {
                Operators::new(mesh, params.laplacian)
            };
            let mut mass = ops.mass.diag();
            let mean = mass.iter().sum::<f64>() / n.max(1) as f64;
            mass.iter_mut().for_each(|m| *m += MASS_EPS * mean);
            let neighbors = pattern_neighbors(&ops.stiffness);
            let normals = given.unwrap_or_else(|| mesh_vertex_normals(mesh));
            (ops, mass, neighbors, normals)
        }
        LearningShape::Cloud(cloud) => {
            let pc = PointCloudParams {
                neighbors: params.neighbors,
                ..PointCloudParams::default()
            };
            let plain = cloud.clone().without_normals();
            let ops = Operators::from_points(&plain, &pc)?;
            let mass = ops.mass.diag();
            let neighbors = nearest_neighbors(positions, params.neighbors);
            let normals = given.unwrap_or_else(|| cloud_normals(positions, &neighbors));
            (ops, mass, neighbors, normals)
        }
    };
    let frames = tangent_frames(&normals);
    let (grad_x, grad_y) =
        gradient_matrices(positions, &frames, &neighbors, params.grad_regularization);
    let ops = Operators {
        laplacian: ops.laplacian,
        stiffness: ops.stiffness,
        mass: SparseMatrix::diagonal(&mass),
    };
    let (evals, evecs, ops) = if params.k_eig == 0 {
        (Vec::new(), Vec::new(), Arc::new(ops))
    } else {
        let eigen = EigenParams {
            k: params.k_eig,
            tolerance: params.tolerance,
            ..EigenParams::default()
        };
        let mut solver = EigenSolver::new(Arc::new(ops), eigen);
        let basis = solver.solve(params.k_eig, progress, cancel)?;
        let ops = solver.operators().clone();
        drop(solver);
        let basis = Arc::try_unwrap(basis).unwrap_or_else(|b| (*b).clone());
        (basis.values, basis.vectors, ops)
    };
    let laplacian = match Arc::try_unwrap(ops) {
        Ok(o) => o.stiffness,
        Err(o) => o.stiffness.clone(),
    };
    Ok(LearningOperators {
        frames,
        mass,
        laplacian,
        evals,
        evecs,
        grad_x,
        grad_y,
    })
}
