//! Spectral quantities: the generalized eigenbasis and everything computed from it.

pub mod distances;
pub mod eigenbasis;
pub mod embedding;
pub mod filters;
pub mod heat;
pub mod signatures;
pub mod store;

pub use eigenbasis::{BasisView, EigenSolver, Eigenbasis};
