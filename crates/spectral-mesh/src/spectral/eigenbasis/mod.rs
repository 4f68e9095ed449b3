//! The k smallest generalized eigenpairs of (S, B): `S X = B X Lambda`, `X^T B X = I`.
//!
//! # Layout
//!
//! Each file depends only on the ones above it in this list (no cycle):
//!
//! - `params.rs`: [`EigenParams`], [`EigenMethod`], the dense-path limits and
//!   [`EigenError`];
//! - `basis.rs`: the result, [`Eigenbasis`] (sign rule, residuals, checks) and
//!   [`BasisView`];
//! - `pencil.rs`: the pencil a solve works on (whole, or the free block under Dirichlet
//!   conditions), the dense-or-sparse choice, the kept factorizations;
//! - `solve.rs`: [`compute_eigenbasis`] and the driver shared with the solver;
//! - `components.rs`: several connected components, solved one by one and merged;
//! - `solver.rs`: [`EigenSolver`], factor once and answer many `k`;
//! - `certify.rs`: [`certify_eigenbasis`], the inertia certificate that no eigenvalue was
//!   skipped, and the completion of a basis that skipped some.
//!
//! The numerical work (dense and sparse generalized eigensolvers, factorizations) lives in
//! [`crate::linalg`].

mod basis;
mod certify;
mod components;
mod params;
mod pencil;
mod solve;
mod solver;

pub use crate::linalg::EigenProgress;
pub use basis::{BasisView, Eigenbasis};
pub use certify::{CertifyReport, certify_eigenbasis};
pub use params::{
    DENSE_MAX_N, DENSE_MAX_N_LARGE_K, EigenError, EigenMethod, EigenParams, takes_dense_path,
};
pub use solve::compute_eigenbasis;
pub use solver::EigenSolver;

#[cfg(test)]
pub(crate) mod test_meshes;

#[cfg(test)]
mod tests;
