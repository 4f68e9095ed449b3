//! distances (to be written).
