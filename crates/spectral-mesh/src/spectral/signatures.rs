//! signatures (to be written).
