//! Spectral quantities: the generalized eigenbasis and everything computed from it.

pub mod eigenbasis;

pub use eigenbasis::Eigenbasis;
