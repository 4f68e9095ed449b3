//! The user's choice of discretization: which stiffness and which mass.

use std::fmt;
use std::str::FromStr;

use super::mass::{MassKind, mass_matrix};
use super::point_cloud::{PointCloudParams, point_cloud_laplacian};
use super::robust::{Gluing, RobustError, RobustParams, robust_from_soup};
use super::stiffness::{cotan_stiffness, uniform_laplacian};
use crate::linalg::SparseMatrix;
use crate::mesh::{Mesh, PointCloud};

/// A discretization of the Laplace-Beltrami operator as a pair (S, B).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Laplacian {
    /// Cotangent stiffness with `B = I` (the paper's "cot weights").
    Cot,
    /// Cotangent stiffness with barycentric lumped mass (the paper's "Voronoi-cot").
    VoronoiCot,
    /// Cotangent stiffness with the consistent linear FEM mass (the paper's default).
    #[default]
    Fem,
    /// Cotangent stiffness with Meyer et al.'s mixed Voronoi mass.
    MixedVoronoi,
    /// The uniform graph Laplacian with `B = I` (not geometric: a baseline).
    Uniform,
    /// The robust Laplacian of Sharp and Crane 2020 ([`super::robust`]): tufted cover,
    /// mollification, intrinsic Delaunay cotangent stiffness with its lumped mass. Works on
    /// any triangle soup (non-manifold, degenerate, duplicate triangles). On a manifold mesh
    /// that is intrinsically Delaunay it equals [`Laplacian::VoronoiCot`] up to
    /// mollification. The same as `robust_laplacian.mesh_laplacian` (default parameters).
    Robust,
}

impl Laplacian {
    /// Every discretization, in a stable order.
    pub const ALL: [Laplacian; 6] = [
        Laplacian::Cot,
        Laplacian::VoronoiCot,
        Laplacian::Fem,
        Laplacian::MixedVoronoi,
        Laplacian::Uniform,
        Laplacian::Robust,
    ];

    /// The name users type (`cot`, `voronoi-cot`, `fem`, `mixed-voronoi`, `uniform`,
    /// `robust`).
    pub fn name(self) -> &'static str {
        match self {
            Laplacian::Cot => "cot",
            Laplacian::VoronoiCot => "voronoi-cot",
            Laplacian::Fem => "fem",
            Laplacian::MixedVoronoi => "mixed-voronoi",
            Laplacian::Uniform => "uniform",
            Laplacian::Robust => "robust",
        }
    }

    /// The mass matrix this discretization uses.
    ///
    /// For [`Laplacian::Robust`] this is [`MassKind::Barycentric`] in kind only: the lumping
    /// is done on the intrinsic Delaunay triangulation of the tufted cover, not on the
    /// input triangles, so `mass_matrix(mesh, MassKind::Barycentric)` is not its mass (use
    /// [`Operators::new`]).
    pub fn mass_kind(self) -> MassKind {
        match self {
            Laplacian::Cot | Laplacian::Uniform => MassKind::Identity,
            Laplacian::VoronoiCot | Laplacian::Robust => MassKind::Barycentric,
            Laplacian::Fem => MassKind::Fem,
            Laplacian::MixedVoronoi => MassKind::MixedVoronoi,
        }
    }

    /// True when the stiffness is a cotangent one (on the input triangles, or for
    /// [`Laplacian::Robust`] on the intrinsic Delaunay triangulation of the tufted cover).
    pub fn is_cotangent(self) -> bool {
        !matches!(self, Laplacian::Uniform)
    }

    /// True when the discretization is defined on any triangle soup (non-manifold edges
    /// and vertices, degenerate and duplicate triangles) with a positive semi-definite
    /// stiffness whose off-diagonal entries are `<= 0`: only [`Laplacian::Robust`].
    pub fn is_robust(self) -> bool {
        matches!(self, Laplacian::Robust)
    }
}

impl fmt::Display for Laplacian {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Laplacian {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let k = s.trim().to_ascii_lowercase().replace('_', "-");
        Laplacian::ALL
            .into_iter()
            .find(|l| l.name() == k)
            .or(match k.as_str() {
                "voronoi" | "barycentric" | "lumped" => Some(Laplacian::VoronoiCot),
                "linear-fem" | "wfem" => Some(Laplacian::Fem),
                "mixed" | "meyer" => Some(Laplacian::MixedVoronoi),
                "graph" | "combinatorial" => Some(Laplacian::Uniform),
                "tufted" | "intrinsic-delaunay" | "nonmanifold" => Some(Laplacian::Robust),
                _ => None,
            })
            .ok_or_else(|| {
                format!(
                    "unknown Laplacian '{s}': expected one of cot, voronoi-cot, fem, mixed-voronoi, uniform, robust"
                )
            })
    }
}

/// The operator pair of one mesh under one discretization.
#[derive(Debug, Clone)]
pub struct Operators {
    /// Which discretization.
    pub laplacian: Laplacian,
    /// Stiffness S, `n x n`, positive semi-definite.
    pub stiffness: SparseMatrix,
    /// Mass B, `n x n`, symmetric positive (semi-)definite.
    pub mass: SparseMatrix,
}

impl Operators {
    /// Assembles (S, B) for `mesh`. [`Laplacian::Robust`] uses the default
    /// [`RobustParams`] (see [`Operators::robust`] for others).
    pub fn new(mesh: &Mesh, laplacian: Laplacian) -> Self {
        if laplacian == Laplacian::Robust {
            let r = robust_from_soup(
                mesh.positions(),
                mesh.triangles(),
                &RobustParams::default(),
                1.0,
                Gluing::Angular,
            );
            return Self {
                laplacian,
                stiffness: r.stiffness,
                mass: r.mass,
            };
        }
        let stiffness = if laplacian.is_cotangent() {
            cotan_stiffness(mesh)
        } else {
            uniform_laplacian(mesh)
        };
        let mass = mass_matrix(mesh, laplacian.mass_kind());
        Self {
            laplacian,
            stiffness,
            mass,
        }
    }

    /// The robust pair (S, B) of `mesh` with the given parameters
    /// ([`super::robust::robust_laplacian`]); `laplacian` is [`Laplacian::Robust`].
    pub fn robust(mesh: &Mesh, params: &RobustParams) -> Result<Self, RobustError> {
        params.validate()?;
        let r = robust_from_soup(
            mesh.positions(),
            mesh.triangles(),
            params,
            1.0,
            Gluing::Angular,
        );
        Ok(Self {
            laplacian: Laplacian::Robust,
            stiffness: r.stiffness,
            mass: r.mass,
        })
    }

    /// The point-cloud Laplacian (S, B) of `cloud`
    /// ([`super::point_cloud::point_cloud_laplacian`]), `n x n` for `n` points;
    /// `laplacian` is [`Laplacian::Robust`] (the same pipeline after the local
    /// triangulations).
    pub fn from_points(cloud: &PointCloud, params: &PointCloudParams) -> Result<Self, RobustError> {
        let r = point_cloud_laplacian(cloud, params)?;
        Ok(Self {
            laplacian: Laplacian::Robust,
            stiffness: r.stiffness,
            mass: r.mass,
        })
    }

    /// Number of vertices.
    pub fn n(&self) -> usize {
        self.stiffness.nrows()
    }

    /// The total mass `A = 1^T B 1` as assembled; with `normalize` the mass becomes
    /// `B / A` (unit total mass: the shape scaled to unit area for the area-based masses)
    /// unless `A` is zero or not finite. Returns `A`.
    pub fn normalize_mass(&mut self, normalize: bool) -> f64 {
        let total: f64 = self.mass.values().iter().sum();
        if normalize && total > 0.0 && total.is_finite() {
            self.mass = self.mass.add_scaled(1.0 / total, &self.mass, 0.0);
        }
        total
    }
}
