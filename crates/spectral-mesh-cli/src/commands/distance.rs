//! `spectral-mesh distance MESH --source V --distance FILTER -o out.png`: filtered
//! spectral distances from a vertex, and optionally the all-pairs matrix as `.npy`.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use spectral_mesh::spectral::distances::{
    ALL_PAIRS_LIMIT, all_pairs, distances_from, wfem_diffusion_distances_from,
};
use spectral_mesh::spectral::filters::Filter;

use super::eigs::{
    BasisArgs, FIGURE_EXTS, check_outputs, check_vertex, default_vertex, extension, normalized,
};
use crate::figure::{Figure, FigureArgs};
use crate::input;
use crate::output::{check_writable, write_atomic};

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
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Source vertex (default: the vertex of largest x, ties to the lowest index).
    #[arg(long)]
    pub source: Option<usize>,
    /// The filter (see below); also wfem-diffusion:t=0.5 for the paper's eq. 15.
    #[arg(long, default_value = "biharmonic", long_help = FILTER_HELP)]
    pub distance: String,
    #[command(flatten)]
    pub basis: BasisArgs,
    /// Use the basis as given instead of the shape scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
    /// Also write every pairwise distance as an n x n NumPy .npy matrix (small meshes).
    #[arg(long, value_name = "OUT.npy")]
    pub all_pairs: Option<PathBuf>,
    /// Output file(s) of the distances from the source: .png, .wrl, .ply or .txt.
    #[arg(long, short = 'o')]
    pub out: Vec<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
}

/// What `--distance` denotes.
enum Kind {
    Filter(Filter),
    WfemDiffusion(f64),
}

fn parse_kind(text: &str) -> Result<Kind> {
    if let Some(rest) = text.trim().strip_prefix("wfem-diffusion") {
        let t = rest.trim_start_matches(':').trim();
        let t = t.strip_prefix("t=").unwrap_or(t).trim();
        if t.is_empty() {
            return Ok(Kind::WfemDiffusion(0.5));
        }
        let v: f64 = t
            .parse()
            .map_err(|_| anyhow::anyhow!("--distance {text}: bad time '{t}'"))?;
        if !(v.is_finite() && v >= 0.0) {
            bail!("--distance {text}: the time must be finite and >= 0");
        }
        return Ok(Kind::WfemDiffusion(v));
    }
    text.parse::<Filter>()
        .map(Kind::Filter)
        .map_err(|e| anyhow::anyhow!("--distance {text}: {e}"))
}

/// A little-endian float64 NumPy `.npy` file of the given shape (C order).
pub fn npy_bytes(shape: &[usize], data: &[f64]) -> Vec<u8> {
    let dims = match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {dims}, }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + 8 * data.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

fn check_npy(p: &Path, force: bool) -> Result<()> {
    if extension(p).as_deref() != Some("npy") {
        bail!("{}: --all-pairs writes a .npy file", p.display());
    }
    check_writable(p, force)
}

/// Computes the distances and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = input::load(args.mesh.as_deref())?;
    let mesh = &input.mesh;
    let n = mesh.n_vertices();
    let kind = parse_kind(&args.distance)?;
    if args.out.is_empty() && args.all_pairs.is_none() {
        bail!("nothing to write: give -o FILE and/or --all-pairs OUT.npy");
    }
    check_outputs(&args.out, &FIGURE_EXTS, args.force)?;
    if let Some(p) = &args.all_pairs {
        check_npy(p, args.force)?;
        if matches!(kind, Kind::WfemDiffusion(_)) {
            bail!("--all-pairs: only for filters of the form w(lambda), not wfem-diffusion");
        }
        if n > ALL_PAIRS_LIMIT {
            bail!(
                "--all-pairs: the mesh has {n} vertices; the n x n matrix is limited to {ALL_PAIRS_LIMIT}"
            );
        }
    }
    let source = args.source.unwrap_or_else(|| default_vertex(mesh));
    check_vertex(source, mesh, "--source")?;
    let tb = args.basis.compute(mesh, None)?;
    let basis = normalized(&tb.basis, args.no_normalize);
    let d = match &kind {
        Kind::Filter(f) => distances_from(&basis, source, f),
        Kind::WfemDiffusion(t) => wfem_diffusion_distances_from(&basis, source, *t),
    }
    .map_err(|e| anyhow::anyhow!("--distance {}: {e}", args.distance))?;
    let (far, dmax) = d.iter().enumerate().fold(
        (source, 0.0f64),
        |b, (i, &v)| if v > b.1 { (i, v) } else { b },
    );
    println!(
        "{}: n = {n}; {} distance from vertex {source}, k = {} ({}){}, eigenpairs in {:.2} s",
        input.label(),
        args.distance,
        tb.basis.k(),
        tb.basis.laplacian,
        if args.no_normalize {
            ""
        } else {
            ", unit-area shape"
        },
        tb.seconds
    );
    println!("max distance {dmax} at vertex {far}");
    let fig = Figure::new(mesh, &d, vec![source], &args.figure)?;
    for o in &args.out {
        fig.write_by_extension(o, &args.figure)?;
        println!("-> {}", o.display());
    }
    if let (Some(p), Kind::Filter(f)) = (&args.all_pairs, &kind) {
        let m = all_pairs(&basis, f)?;
        write_atomic(p, &npy_bytes(&[n, n], &m))?;
        println!("all pairs ({n} x {n}) -> {}", p.display());
    }
    Ok(())
}
