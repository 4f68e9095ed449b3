//! Discrete Laplace-Beltrami operators as the symmetric pair (S, B).
//!
//! S is the stiffness matrix, **positive semi-definite** (the paper's L is -S); B is a
//! mass matrix. The generalized eigenproblem `S x = lambda B x` then has eigenvalues
//! `>= 0`, one zero per connected component.

pub mod discretization;
pub mod mass;
pub mod stiffness;

pub use discretization::{Laplacian, Operators};
pub use mass::{MassKind, mass_matrix};
pub use stiffness::{cotan_stiffness, uniform_laplacian};
