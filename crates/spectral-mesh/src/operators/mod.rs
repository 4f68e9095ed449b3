//! Discrete Laplace-Beltrami operators as the symmetric pair (S, B).
//!
//! S is the stiffness matrix, **positive semi-definite** (the paper's L is -S); B is a
//! mass matrix. The generalized eigenproblem `S x = lambda B x` then has eigenvalues
//! `>= 0`, one zero per connected component.
//!
//! - [`stiffness`], [`mass`]: the cotangent stiffness, the uniform graph Laplacian and the
//!   mass matrices on the input triangles.
//! - [`robust`]: the robust Laplacian of Sharp and Crane (tufted cover, mollification,
//!   intrinsic Delaunay) for any triangle soup.
//! - [`point_cloud`]: the point-cloud Laplacian of the same paper (local triangulations of
//!   k-nearest neighbourhoods, then the robust pipeline).
//! - [`discretization`]: the user's choice of (S, B).

pub mod discretization;
pub mod mass;
pub mod point_cloud;
pub mod robust;
pub mod stiffness;

pub use discretization::{Laplacian, Operators};
pub use mass::{MassKind, mass_matrix};
pub use point_cloud::{
    NormalSource, PointCloudLaplacian, PointCloudParams, TriangleUnion, point_cloud_laplacian,
    point_cloud_triangles,
};
pub use robust::{RobustError, RobustLaplacian, RobustParams, RobustStats, robust_laplacian};
pub use stiffness::{cotan_stiffness, uniform_laplacian};
