//! Built-in procedural shapes with a resolution parameter.
