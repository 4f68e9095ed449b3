//! level_sets (to be written).
