//! `spectral-mesh signature MESH --kind hks --times auto:16 -o hks.txt -o hks.png`: point
//! signatures (HKS, WKS, ADF, generalized spectral function).

use std::path::PathBuf;

use anyhow::{Result, bail};
use spectral_mesh::analysis::FieldRequest;
use spectral_mesh::analysis::request::{DEFAULT_SIGNATURE_T, DEFAULT_WKS_SIGMA};
use spectral_mesh::experiments::paper::FieldStats;
use spectral_mesh::spectral::BasisView;
use spectral_mesh::spectral::distances::spectral_function;
use spectral_mesh::spectral::filters::Filter;
use spectral_mesh::spectral::signatures::{
    auto_diffusion, hks, hks_auto_times, wks, wks_auto_energies,
};

use super::distance::FILTER_HELP;
use crate::engine::{self, FieldBasisArgs};
use crate::field_output::FieldOutputArgs;
use crate::output::{extension, write};

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

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Hks => "hks",
            Kind::Wks => "wks",
            Kind::Adf => "adf",
            Kind::SpectralFunction => "spectralfunction",
        }
    }
}

/// Arguments of `signature`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
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
    /// list.
    #[arg(long)]
    pub energies: Option<String>,
    /// WKS bandwidth (default: from auto:N, or 0.5 for a list).
    #[arg(long)]
    pub sigma: Option<f64>,
    /// Divide HKS by the heat trace and WKS by its normalization sum.
    #[arg(long)]
    pub scaled: bool,
    /// The filter of the spectral function (default biharmonic).
    #[arg(long, default_value_t = Filter::default().to_string(), long_help = FILTER_HELP)]
    pub filter: String,
    /// Which column (time or energy, 0-based) is drawn in .png, .wrl and .ply outputs;
    /// .txt outputs hold every column.
    #[arg(long, default_value_t = 0)]
    pub column: usize,
    #[command(flatten)]
    pub spectral: FieldBasisArgs,
    /// Output file(s): .png, .wrl, .ply or .txt by extension (repeatable).
    #[arg(long, short = 'o', required = true)]
    pub out: Vec<PathBuf>,
    #[command(flatten)]
    pub output: FieldOutputArgs,
}

/// A list of parameters: `auto:N` or `a,b,c`.
enum ParamList {
    Auto(usize),
    Values(Vec<f64>),
}

impl ParamList {
    fn len(&self) -> usize {
        match self {
            ParamList::Auto(n) => *n,
            ParamList::Values(v) => v.len(),
        }
    }
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

/// What the columns are made of, as parsed (before the spectrum is known).
enum Plan {
    /// HKS or ADF at these times.
    Times(ParamList),
    /// WKS at these energies.
    Energies(ParamList),
    /// The spectral function of a filter.
    Filter(Filter),
}

/// The columns of a signature: the parameter's name and one label, one request per
/// column.
struct Columns {
    name: &'static str,
    labels: Vec<String>,
    requests: Vec<FieldRequest>,
    /// WKS bandwidth (all columns).
    sigma: f64,
    /// Times or energies (HKS, ADF, WKS).
    params: Vec<f64>,
}

fn plan(args: &Args) -> Result<Plan> {
    Ok(match args.kind {
        Kind::Hks | Kind::Adf => Plan::Times(match (&args.t, &args.times) {
            (Some(t), _) => ParamList::Values(vec![*t]),
            (None, Some(spec)) => parse_list("--times", spec)?,
            (None, None) => ParamList::Values(vec![DEFAULT_SIGNATURE_T]),
        }),
        Kind::Wks => Plan::Energies(parse_list(
            "--energies",
            args.energies.as_deref().unwrap_or("auto:16"),
        )?),
        Kind::SpectralFunction => Plan::Filter(
            args.filter
                .parse()
                .map_err(|e| anyhow::anyhow!("--filter {}: {e}", args.filter))?,
        ),
    })
}

/// The columns' parameters, from the spectrum where `auto:N` asks for it.
fn columns(args: &Args, plan: Plan, basis: BasisView<'_>) -> Result<Columns> {
    let k = basis.k();
    let labels = |v: &[f64]| v.iter().map(|x| format!("{x}")).collect::<Vec<_>>();
    Ok(match plan {
        Plan::Times(list) => {
            let times = match list {
                ParamList::Auto(n) => hks_auto_times(basis, n)?,
                ParamList::Values(v) => v,
            };
            let requests = times
                .iter()
                .map(|&t| match args.kind {
                    Kind::Adf => FieldRequest::Adf { t, k },
                    _ => FieldRequest::Hks {
                        t,
                        scaled: args.scaled,
                        k,
                    },
                })
                .collect();
            Columns {
                name: "t",
                labels: labels(&times),
                requests,
                sigma: 0.0,
                params: times,
            }
        }
        Plan::Energies(list) => {
            let (energies, sigma) = match list {
                ParamList::Auto(n) => {
                    let (e, s) = wks_auto_energies(basis, n)?;
                    (e, args.sigma.unwrap_or(s))
                }
                ParamList::Values(v) => (v, args.sigma.unwrap_or(DEFAULT_WKS_SIGMA)),
            };
            let requests = energies
                .iter()
                .map(|&energy| FieldRequest::Wks {
                    energy,
                    sigma,
                    scaled: args.scaled,
                    k,
                })
                .collect();
            Columns {
                name: "e",
                labels: labels(&energies),
                requests,
                sigma,
                params: energies,
            }
        }
        Plan::Filter(filter) => Columns {
            name: "filter",
            labels: vec![args.filter.clone()],
            requests: vec![FieldRequest::SpectralFunction { filter, k }],
            sigma: 0.0,
            params: Vec::new(),
        },
    })
}

/// Every column, computed by the library's signature functions on the basis.
fn all_columns(args: &Args, cols: &Columns, basis: BasisView<'_>) -> Result<Vec<Vec<f64>>> {
    Ok(match args.kind {
        Kind::Hks => hks(basis, &cols.params, args.scaled),
        Kind::Adf => cols
            .params
            .iter()
            .map(|&t| auto_diffusion(basis, t))
            .collect::<Result<Vec<_>, _>>()?,
        Kind::Wks => wks(basis, &cols.params, cols.sigma, args.scaled)?,
        Kind::SpectralFunction => match &cols.requests[0] {
            FieldRequest::SpectralFunction { filter, .. } => {
                vec![spectral_function(basis, filter)?]
            }
            _ => Vec::new(),
        },
    })
}

/// Several columns as text: a `#` header naming the columns, then one row per vertex.
fn columns_text(kind: &str, name: &str, labels: &[String], values: &[Vec<f64>]) -> String {
    let n = values.first().map_or(0, Vec::len);
    let mut s = format!("# {kind}, one column per {name}: {}\n", labels.join(" "));
    for i in 0..n {
        let row: Vec<String> = values.iter().map(|c| format!("{:?}", c[i])).collect();
        s.push_str(&row.join(" "));
        s.push('\n');
    }
    s
}

/// Computes the signature and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = args.spectral.basis.load(args.mesh.as_deref())?;
    args.output.check(&args.out)?;
    if args.t.is_some() && !matches!(args.kind, Kind::Hks | Kind::Adf) {
        bail!("--t is for --kind hks or adf");
    }
    if args.energies.is_some() && args.kind != Kind::Wks {
        bail!("--energies is for --kind wks");
    }
    // Check the parameters before the eigenpairs.
    let plan = plan(&args)?;
    let count = match &plan {
        Plan::Times(l) | Plan::Energies(l) => l.len(),
        Plan::Filter(_) => 1,
    };
    if args.column >= count {
        bail!(
            "--column {}: the signature has {count} column(s)",
            args.column
        );
    }
    args.spectral
        .basis
        .warn_unrecorded(args.output.save_experiment.as_ref());
    let info = input.info;
    let k = args.spectral.basis.k;
    let an = args.spectral.analysis(input.shape)?;
    let engine::Solved { basis, seconds, .. } =
        engine::basis(&an, k, args.spectral.basis.cache.as_deref())?;
    let cols = columns(&args, plan, basis.view(k))?;
    for r in &cols.requests {
        r.validate().map_err(|e| anyhow::anyhow!("--{e}"))?;
    }
    let kind = args.kind.name();
    println!(
        "{}: n = {}; {kind} with {} column(s) ({} = {}), k = {k} ({}){}, eigenpairs in {seconds:.2} s",
        info.label(),
        an.n(),
        cols.requests.len(),
        cols.name,
        cols.labels.join(", "),
        an.options().laplacian,
        args.spectral.scale_note(),
    );
    // The drawn column is the analysis' field of its request.
    let field = an
        .field(&cols.requests[args.column])
        .map_err(|e| match args.kind {
            Kind::SpectralFunction => anyhow::anyhow!("--filter {}: {e}", args.filter),
            _ => e.into(),
        })?;
    let stats = FieldStats::of(&field.values);
    println!(
        "column {} ({} = {}): min {}, max {}",
        args.column, cols.name, cols.labels[args.column], stats.min, stats.max
    );
    let (many, single): (Vec<PathBuf>, Vec<PathBuf>) = args
        .out
        .iter()
        .cloned()
        .partition(|o| cols.requests.len() > 1 && extension(o).as_deref() == Some("txt"));
    if !many.is_empty() {
        let values = all_columns(&args, &cols, basis.view(k))?;
        let text = columns_text(kind, cols.name, &cols.labels, &values);
        for o in &many {
            write(o, text.as_bytes())?;
            println!("-> {}", o.display());
        }
    }
    args.output.write_field(&an, &field, &single)?;
    args.output
        .save_experiment(&info, &an, &field, args.spectral.basis.repair)?;
    Ok(())
}
