//! `spectral-mesh`: harmonic maps, heat diffusion and spectral distances on triangle
//! meshes, from the command line. See `spectral-mesh --help`.

mod basis;
mod commands;
mod figure;
mod input;
mod output;
mod progress;

use clap::{Parser, Subcommand};

/// Harmonic maps, heat diffusion and filtered spectral distances on triangle meshes.
///
/// MESH arguments take a file (OFF, OBJ, PLY, STL) or a built-in shape such as
/// `3torus` or `sphere:res=4` (`spectral-mesh shapes` lists them). With no mesh, the
/// paper's default shape, the 3-torus, is used.
#[derive(Debug, Parser)]
#[command(name = "spectral-mesh", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the built-in shapes and their parameters.
    Shapes(commands::shapes::Args),
    /// Counts, topology and problems of a mesh.
    Info(commands::info::Args),
    /// Convert a mesh between OFF, OBJ, PLY and STL.
    Convert(commands::convert::Args),
    /// Export the stiffness S and the mass matrices (Matrix Market) with the mesh.
    Operators(commands::operators::Args),
    /// Draw a per-vertex field: PNG picture, VRML scene, coloured PLY.
    Render(commands::render::Args),
    /// Run one of the paper's experiments with its defaults and outputs.
    #[command(subcommand)]
    Experiment(commands::experiment::Experiment),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Shapes(a) => commands::shapes::run(a),
        Command::Info(a) => commands::info::run(a),
        Command::Convert(a) => commands::convert::run(a),
        Command::Operators(a) => commands::operators::run(a),
        Command::Render(a) => commands::render::run(a),
        Command::Experiment(e) => commands::experiment::run(e),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
