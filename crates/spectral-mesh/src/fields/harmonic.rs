//! harmonic (to be written).
