//! `spectral-mesh distance MESH --source V --distance FILTER -o out.png`: filtered
//! spectral distances from a vertex, and optionally the all-pairs matrix as `.npy`.

use std::path::PathBuf;

use anyhow::{Result, bail};
use spectral_mesh::analysis::{DistanceSpec, FieldRequest};
use spectral_mesh::experiments::paper::FieldStats;
use spectral_mesh::spectral::distances::{ALL_PAIRS_LIMIT, all_pairs};
use spectral_mesh::spectral::store::npy_f64;

use crate::engine::{self, FieldBasisArgs, check_vertex};
use crate::field_output::FieldOutputArgs;
use crate::output::{check_writable, extension, write};

/// The syntax of `--distance` / `--filter`, shown in `--help`.
pub const FILTER_HELP: &str = "The filter, stored as its weight w = 1/phi; \
d(p,q)^2 = sum over non-zero eigenvalues of w(lambda) (x(p) - x(q))^2.
  diffusion:t=0.5        w = exp(-t s) (also heat:t=...)
  commute                w = 1/s
  biharmonic             w = 1/s^2 (default)
  mix:a=0.5,t=0.5        w = (1-a) exp(-t s) + a/s^2
  poly:p=2               w = s^-p
  band:1,4,5             suppress eigenpairs 1, 4, 5 (0-based): w = |prod (s - lambda_i)|
  custom-w:EXPR;name=v   EXPR is the weight w(s), e.g. custom-w:exp(-s*t)/s;t=0.1
  custom-phi:EXPR;name=v EXPR is the filter map phi(s); w = 1/phi
  wfem-diffusion:t=0.5   (distance only) the paper's eq. 15, all pairs incl. lambda = 0
Expressions: numbers, s, pi, named parameters, + - * / ^, parentheses, exp log sqrt abs \
sin cos tanh, pow min max. Every non-zero eigenvalue must get a positive finite weight, \
or the filter is refused.";

/// Arguments of `distance`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Source vertex (default: the vertex of largest x, ties to the lowest index).
    #[arg(long)]
    pub source: Option<usize>,
    /// The filter (see below); also wfem-diffusion:t=0.5 for the paper's eq. 15.
    #[arg(long, default_value_t = DistanceSpec::default().to_string(), long_help = FILTER_HELP)]
    pub distance: String,
    #[command(flatten)]
    pub spectral: FieldBasisArgs,
    /// Also write every pairwise distance as an n x n NumPy .npy matrix (small meshes).
    #[arg(long, value_name = "OUT.npy")]
    pub all_pairs: Option<PathBuf>,
    /// Output file(s) of the distances from the source: .png, .wrl, .ply or .txt.
    #[arg(long, short = 'o')]
    pub out: Vec<PathBuf>,
    #[command(flatten)]
    pub output: FieldOutputArgs,
}

/// Computes the distances and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = args.spectral.basis.load(args.mesh.as_deref())?;
    let n = input.n();
    let spec: DistanceSpec = args
        .distance
        .parse()
        .map_err(|e| anyhow::anyhow!("--distance {}: {e}", args.distance))?;
    if args.out.is_empty() && args.all_pairs.is_none() {
        bail!("nothing to write: give -o FILE and/or --all-pairs OUT.npy");
    }
    args.output.check(&args.out)?;
    let filter = match (&args.all_pairs, &spec) {
        (None, _) => None,
        (Some(p), spec) => {
            if extension(p).as_deref() != Some("npy") {
                bail!("{}: --all-pairs writes a .npy file", p.display());
            }
            check_writable(p, args.output.force)?;
            let DistanceSpec::Filter(f) = spec else {
                bail!("--all-pairs: only for filters of the form w(lambda), not wfem-diffusion");
            };
            if n > ALL_PAIRS_LIMIT {
                bail!(
                    "--all-pairs: the mesh has {n} vertices; the n x n matrix is limited to {ALL_PAIRS_LIMIT}"
                );
            }
            Some(f.clone())
        }
    };
    if let Some(s) = args.source {
        check_vertex(s, n, "--source")?;
    }
    args.spectral
        .basis
        .warn_unrecorded(args.output.save_experiment.as_ref());
    let request = FieldRequest::Distance {
        source: args.source,
        distance: spec,
        k: args.spectral.basis.k,
    };
    let info = input.info;
    let an = args.spectral.analysis(input.shape)?;
    let (field, seconds) = engine::field(&an, &request, args.spectral.basis.cache.as_deref())
        .map_err(|e| anyhow::anyhow!("--distance {}: {e:#}", args.distance))?;
    let source = field.marks[0];
    let stats = FieldStats::of(&field.values);
    println!(
        "{}: n = {n}; {} distance from vertex {source}, k = {} ({}){}, eigenpairs in {seconds:.2} s",
        info.label(),
        args.distance,
        args.spectral.basis.k,
        an.options().laplacian,
        args.spectral.scale_note(),
    );
    println!("max distance {} at vertex {}", stats.max, stats.argmax);
    args.output.write_field(&an, &field, &args.out)?;
    if let (Some(p), Some(f)) = (&args.all_pairs, &filter) {
        let basis = engine::basis(&an, args.spectral.basis.k, None)?.basis;
        let m = all_pairs(basis.view(args.spectral.basis.k), f)?;
        write(p, &npy_f64(&m, &[n as u64, n as u64], false)?)?;
        println!("all pairs ({n} x {n}) -> {}", p.display());
    }
    args.output
        .save_experiment(&info, &an, &field, args.spectral.basis.repair)?;
    Ok(())
}
