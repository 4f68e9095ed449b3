//! The paper's executable experiments as plain functions with parameter structs whose
//! `Default` is the paper's default.

pub mod file;
pub mod harmonic;
pub mod paper;
pub mod study;
pub mod truncation;
