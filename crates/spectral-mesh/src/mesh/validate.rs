//! Mesh checks and repairs.
