//! `spectral-mesh`: harmonic maps, heat diffusion and spectral distances on triangle
//! meshes, from the command line. See `spectral-mesh --help`.

mod commands;
#[cfg(test)]
mod defaults_test;
mod engine;
mod field_output;
mod figure;
mod input;
mod output;
mod progress;

use clap::{Parser, Subcommand};

/// mimalloc keeps freed pages for reuse: the eigensolver and the web server allocate and
/// free many large temporaries, which with the system allocator cost fresh, zeroed pages
/// (page faults) every time.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Harmonic maps, heat diffusion and filtered spectral distances on triangle meshes.
///
/// MESH arguments take a file (OFF, OBJ, PLY, STL) or a built-in shape such as
/// `3torus` or `sphere:res=4` (`spectral-mesh shapes` lists them). With no mesh, the
/// paper's default shape, the 3-torus, is used. Point clouds (.xyz, .pts, .txt, .csv, PLY
/// without faces) go wherever a mesh does, with their point-cloud Laplacian
/// (`--laplacian robust`).
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
    /// Compute an eigenbasis, check it and save it (.npz), its eigenvalues and a plot.
    Eigs(commands::eigs::Args),
    /// Heat kernel: the basis function K_t e_V or the diffusion of a signal.
    Heat(commands::heat::Args),
    /// Filtered spectral distances from a vertex (and all pairs for small meshes).
    Distance(commands::distance::Args),
    /// Geodesic distance from vertices or face points by the heat method.
    Geodesic(commands::geodesic::Args),
    /// Point signatures: HKS, WKS, auto-diffusion, generalized spectral function.
    Signature(commands::signature::Args),
    /// Segment into patches: basins of the maxima of a signature.
    Segment(commands::segment::Args),
    /// Spectral embedding as a mesh with the same triangles, and its coordinates.
    Embed(commands::embed::Args),
    /// Match two shapes: functional map, ZoomOut, point map (one target vertex per
    /// source vertex).
    Match(commands::matching::Args),
    /// Match pairs of a collection (all, consecutive or listed): a map per pair and
    /// pairs.csv.
    MatchPairs(commands::match_pairs::Args),
    /// Perturb a mesh (noise, scaling, resampling, holes, ...) and map it to the original.
    Perturb(commands::perturb::Args),
    /// Run one of the paper's experiments with its defaults and outputs.
    #[command(subcommand)]
    Experiment(commands::experiment::Experiment),
    /// Replay an experiment file written by --save-experiment (or by hand).
    Run(commands::run::Args),
    /// Truncation (Fig. 12) and robustness studies.
    #[command(subcommand)]
    Study(commands::study::Study),
    /// The interactive web app on http://127.0.0.1:8000 (pick a shape, click, move sliders).
    Serve(commands::serve::Args),
    /// Eigenbases and descriptors of a whole collection of shapes, resumable, in parallel.
    Batch(commands::batch::Args),
}

fn main() -> std::process::ExitCode {
    // `spectral-mesh shapes | head` closes stdout early: end quietly as a pipe
    // reader expects (status 141, as after SIGPIPE) instead of panicking.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("Broken pipe") {
            std::process::exit(141);
        }
        default_hook(info);
    }));
    let cli = Cli::parse();
    if !matches!(cli.command, Command::Serve(_) | Command::Batch(_)) {
        main_thread_in_pool();
    }
    let result = match cli.command {
        Command::Shapes(a) => commands::shapes::run(a),
        Command::Info(a) => commands::info::run(a),
        Command::Convert(a) => commands::convert::run(a),
        Command::Operators(a) => commands::operators::run(a),
        Command::Render(a) => commands::render::run(a),
        Command::Eigs(a) => commands::eigs::run(a),
        Command::Heat(a) => commands::heat::run(a),
        Command::Distance(a) => commands::distance::run(a),
        Command::Geodesic(a) => commands::geodesic::run(a),
        Command::Signature(a) => commands::signature::run(a),
        Command::Segment(a) => commands::segment::run(a),
        Command::Embed(a) => commands::embed::run(a),
        Command::Match(a) => commands::matching::run(a),
        Command::MatchPairs(a) => commands::match_pairs::run(a),
        Command::Perturb(a) => commands::perturb::run(a),
        Command::Experiment(e) => commands::experiment::run(e),
        Command::Run(a) => commands::run::run(a),
        Command::Study(s) => commands::study::run(s),
        Command::Serve(a) => commands::serve::run(a),
        Command::Batch(a) => commands::batch::run(a),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Makes the main thread one of the global rayon pool's threads (with the pool's usual
/// size: all cores, or `RAYON_NUM_THREADS`), so that the library's parallel steps, which
/// a one-shot command starts from the main thread, are joined on a pool thread instead of
/// being handed over to the pool and waited for. Measured on `eigs` at k = 50 (26k
/// vertices, 2 cores): about 5,000 futex and yield calls become about 700, and the
/// command takes about 15% less time. Not for `serve` and `batch`, whose main thread
/// blocks on connections and jobs and would hold a pool thread idle. Should the pool
/// exist already (it cannot here), the usual pool is used.
fn main_thread_in_pool() {
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global();
}
