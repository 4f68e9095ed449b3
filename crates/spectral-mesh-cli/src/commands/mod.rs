//! One module per subcommand: an `Args` struct (clap) and a `run` function.

pub mod convert;
pub mod experiment;
pub mod info;
pub mod operators;
pub mod render;
pub mod shapes;
