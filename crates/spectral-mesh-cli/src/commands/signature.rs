//! `spectral-mesh signature MESH --kind hks --times auto:16 -o hks.txt -o hks.png`: point
//! signatures (HKS, WKS, ADF, generalized spectral function).

use std::path::PathBuf;

use anyhow::{Result, bail};
use spectral_mesh::spectral::Eigenbasis;
use spectral_mesh::spectral::distances::spectral_function;
use spectral_mesh::spectral::filters::Filter;
use spectral_mesh::spectral::signatures::{
    auto_diffusion, hks, hks_auto_times, wks, wks_auto_energies,
};

use super::distance::FILTER_HELP;
use super::eigs::{BasisArgs, FIGURE_EXTS, check_outputs, extension, normalized};
use crate::figure::{Figure, FigureArgs};
use crate::input;
use crate::output::{field_text, write_atomic};

/// Which signature.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// Heat kernel signature sum_k exp(-lambda_k t) x_k(p)^2 (all pairs, pyFM's convention).
    Hks,
    /// Wave kernel signature at log-eigenvalue energies.
    Wks,
    /// Auto-diffusion function G(p,p) with w = exp(-t s) (zero eigenvalues skipped).
    Adf,
    /// Generalized spectral function G(p,p) = sum_k w(lambda_k) x_k(p)^2 of --filter.
    SpectralFunction,
}

/// Arguments of `signature`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// The signature.
    #[arg(long, value_enum, default_value = "hks")]
    pub kind: Kind,
    /// One time (HKS, ADF), for the shape scaled to unit area unless --no-normalize.
    #[arg(long, conflicts_with = "times")]
    pub t: Option<f64>,
    /// Several times (HKS, ADF): `auto:N` (pyFM's geometric spacing from the spectrum)
    /// or a comma-separated list. Default for HKS and ADF: t = 0.1.
    #[arg(long)]
    pub times: Option<String>,
    /// WKS energies (log-eigenvalues): `auto:N` (default auto:16) or a comma-separated
    /// list (then --sigma is needed).
    #[arg(long)]
    pub energies: Option<String>,
    /// WKS bandwidth for an explicit --energies list.
    #[arg(long)]
    pub sigma: Option<f64>,
    /// Divide HKS by the heat trace and WKS by its normalization sum.
    #[arg(long)]
    pub scaled: bool,
    /// The filter of the spectral function (default biharmonic).
    #[arg(long, default_value = "biharmonic", long_help = FILTER_HELP)]
    pub filter: String,
    /// Which column (time or energy, 0-based) is drawn in .png, .wrl and .ply outputs;
    /// .txt outputs hold every column.
    #[arg(long, default_value_t = 0)]
    pub column: usize,
    #[command(flatten)]
    pub basis: BasisArgs,
    /// Use the basis as given instead of the shape scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
    /// Output file(s): .png, .wrl, .ply or .txt by extension (repeatable).
    #[arg(long, short = 'o', required = true)]
    pub out: Vec<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
}

/// A list of parameters: `auto:N` or `a,b,c`.
enum ParamList {
    Auto(usize),
    Values(Vec<f64>),
}

fn parse_list(option: &str, text: &str) -> Result<ParamList> {
    let t = text.trim();
    if let Some(n) = t.strip_prefix("auto:").or_else(|| t.strip_prefix("auto=")) {
        let n: usize = n.trim().parse().map_err(|_| {
            anyhow::anyhow!("{option} {text}: '{n}' is not a count (expected auto:N)")
        })?;
        if n == 0 {
            bail!("{option} {text}: at least one value is needed");
        }
        return Ok(ParamList::Auto(n));
    }
    let mut v = Vec::new();
    for tok in t.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let x: f64 = tok.parse().map_err(|_| {
            anyhow::anyhow!("{option} {text}: '{tok}' is not a number (expected auto:N or a list)")
        })?;
        if !x.is_finite() {
            bail!("{option} {text}: '{tok}' is not finite");
        }
        v.push(x);
    }
    if v.is_empty() {
        bail!("{option} {text}: expected auto:N or a comma-separated list");
    }
    Ok(ParamList::Values(v))
}

fn check_times(times: &[f64]) -> Result<()> {
    if let Some(t) = times.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
        bail!("time {t}: times must be positive");
    }
    Ok(())
}

/// The columns of a signature and their labels.
pub struct Columns {
    /// Parameter name (`t`, `e`, `filter`).
    pub name: &'static str,
    /// One label per column.
    pub labels: Vec<String>,
    /// One `n`-vector per column.
    pub values: Vec<Vec<f64>>,
}

fn times_of(args: &Args, basis: &Eigenbasis) -> Result<Vec<f64>> {
    let times = match (&args.t, &args.times) {
        (Some(t), _) => vec![*t],
        (None, Some(spec)) => match parse_list("--times", spec)? {
            ParamList::Auto(n) => hks_auto_times(basis, n)?,
            ParamList::Values(v) => v,
        },
        (None, None) => vec![0.1],
    };
    check_times(&times)?;
    Ok(times)
}

/// Computes the requested signature on a (normalised) basis.
pub fn compute(args: &Args, basis: &Eigenbasis) -> Result<Columns> {
    let labels = |v: &[f64]| v.iter().map(|x| format!("{x}")).collect::<Vec<_>>();
    Ok(match args.kind {
        Kind::Hks => {
            let times = times_of(args, basis)?;
            Columns {
                name: "t",
                labels: labels(&times),
                values: hks(basis, &times, args.scaled),
            }
        }
        Kind::Adf => {
            let times = times_of(args, basis)?;
            let values = times
                .iter()
                .map(|&t| auto_diffusion(basis, t))
                .collect::<Result<Vec<_>, _>>()?;
            Columns {
                name: "t",
                labels: labels(&times),
                values,
            }
        }
        Kind::Wks => {
            let (energies, sigma) =
                match parse_list("--energies", args.energies.as_deref().unwrap_or("auto:16"))? {
                    ParamList::Auto(n) => {
                        let (e, s) = wks_auto_energies(basis, n)?;
                        (e, args.sigma.unwrap_or(s))
                    }
                    ParamList::Values(v) => match args.sigma {
                        Some(s) => (v, s),
                        None => bail!("--energies with a list needs --sigma (the WKS bandwidth)"),
                    },
                };
            Columns {
                name: "e",
                labels: labels(&energies),
                values: wks(basis, &energies, sigma, args.scaled)?,
            }
        }
        Kind::SpectralFunction => {
            let f: Filter = args
                .filter
                .parse()
                .map_err(|e| anyhow::anyhow!("--filter {}: {e}", args.filter))?;
            let g = spectral_function(basis, &f)
                .map_err(|e| anyhow::anyhow!("--filter {}: {e}", args.filter))?;
            Columns {
                name: "filter",
                labels: vec![args.filter.clone()],
                values: vec![g],
            }
        }
    })
}

/// Several columns as text: a `#` header naming the columns, then one row per vertex.
pub fn columns_text(kind: &str, cols: &Columns) -> String {
    let n = cols.values.first().map_or(0, Vec::len);
    let mut s = format!(
        "# {kind}, one column per {}: {}\n",
        cols.name,
        cols.labels.join(" ")
    );
    for i in 0..n {
        let row: Vec<String> = cols.values.iter().map(|c| format!("{:?}", c[i])).collect();
        s.push_str(&row.join(" "));
        s.push('\n');
    }
    s
}

/// Computes the signature and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = input::load(args.mesh.as_deref())?;
    let mesh = &input.mesh;
    check_outputs(&args.out, &FIGURE_EXTS, args.force)?;
    if args.t.is_some() && !matches!(args.kind, Kind::Hks | Kind::Adf) {
        bail!("--t is for --kind hks or adf");
    }
    if args.energies.is_some() && args.kind != Kind::Wks {
        bail!("--energies is for --kind wks");
    }
    // Check the filter before the eigenpairs.
    if args.kind == Kind::SpectralFunction {
        args.filter
            .parse::<Filter>()
            .map_err(|e| anyhow::anyhow!("--filter {}: {e}", args.filter))?;
    }
    let tb = args.basis.compute(mesh, None)?;
    let basis = normalized(&tb.basis, args.no_normalize);
    let cols = compute(&args, &basis)?;
    if args.column >= cols.values.len() {
        bail!(
            "--column {}: the signature has {} column(s)",
            args.column,
            cols.values.len()
        );
    }
    let kind = format!("{:?}", args.kind).to_ascii_lowercase();
    println!(
        "{}: n = {}; {kind} with {} column(s) ({} = {}), k = {} ({}){}, eigenpairs in {:.2} s",
        input.label(),
        mesh.n_vertices(),
        cols.values.len(),
        cols.name,
        cols.labels.join(", "),
        tb.basis.k(),
        tb.basis.laplacian,
        if args.no_normalize {
            ""
        } else {
            ", unit-area shape"
        },
        tb.seconds
    );
    let field = &cols.values[args.column];
    let (lo, hi) = field
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    println!(
        "column {} ({} = {}): min {lo}, max {hi}",
        args.column, cols.name, cols.labels[args.column]
    );
    let fig = Figure::new(mesh, field, Vec::new(), &args.figure)?;
    for o in &args.out {
        if extension(o).as_deref() == Some("txt") && cols.values.len() > 1 {
            write_atomic(o, columns_text(&kind, &cols).as_bytes())?;
        } else if extension(o).as_deref() == Some("txt") {
            write_atomic(o, field_text(field).as_bytes())?;
        } else {
            fig.write_by_extension(o, &args.figure)?;
        }
        println!("-> {}", o.display());
    }
    Ok(())
}
