//! One module per subcommand: an `Args` struct (clap) and a `run` function.

pub mod batch;
pub mod convert;
pub mod distance;
pub mod eigs;
pub mod embed;
pub mod experiment;
pub mod geodesic;
pub mod heat;
pub mod info;
pub mod match_pairs;
pub mod matching;
pub mod operators;
pub mod perturb;
pub mod render;
pub mod run;
pub mod segment;
pub mod serve;
pub mod shapes;
pub mod signature;
pub mod study;
