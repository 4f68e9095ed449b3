//! critical_points (to be written).
