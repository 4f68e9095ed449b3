//! heat (to be written).
