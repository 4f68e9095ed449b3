//! One module per subcommand: an `Args` struct (clap) and a `run` function.

pub mod convert;
pub mod info;
pub mod operators;
pub mod shapes;
