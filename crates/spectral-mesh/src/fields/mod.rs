//! Per-vertex fields: harmonic maps, critical points, level sets, segmentation.

pub mod critical_points;
pub mod harmonic;
pub mod level_sets;
pub mod persistence;
pub mod segmentation;
