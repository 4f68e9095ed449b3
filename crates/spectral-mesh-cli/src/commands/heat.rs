//! `spectral-mesh heat MESH --anchor V --t T -o out.png`: the heat-kernel basis function
//! `K_t e_V`, or the diffusion `K_t f` of a signal.

use std::path::PathBuf;

use anyhow::{Result, bail};
use spectral_mesh::analysis::request::DEFAULT_HEAT_T;
use spectral_mesh::analysis::{FieldRequest, Kernel, Signal};
use spectral_mesh::experiments::paper::FieldStats;

use crate::engine::{self, FieldBasisArgs, check_vertex};
use crate::field_output::FieldOutputArgs;
use crate::input::read_field;

/// The kernels, as typed.
fn kernel_parser() -> impl clap::builder::TypedValueParser<Value = Kernel> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(Kernel::ALL.map(Kernel::name))
        .try_map(|s| s.parse::<Kernel>())
}

/// Arguments of `heat`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Anchor vertex of the basis function K_t e_V (default: the vertex of largest x).
    #[arg(long)]
    pub anchor: Option<usize>,
    /// Diffusion time (for the shape scaled to unit area unless --no-normalize).
    #[arg(long, default_value_t = DEFAULT_HEAT_T)]
    pub t: f64,
    #[command(flatten)]
    pub spectral: FieldBasisArgs,
    /// Diffuse this per-vertex signal (one value per line) instead of e_V.
    #[arg(long, conflicts_with_all = ["indicator", "anchor"])]
    pub signal: Option<PathBuf>,
    /// Diffuse the indicator of the ball of radius R (mesh units, Euclidean) around
    /// vertex V, written V,R.
    #[arg(long, value_name = "V,R", conflicts_with = "anchor")]
    pub indicator: Option<String>,
    /// Heat kernel discretization: wfem (X D_t X^T B, the paper's), voronoi-cot
    /// (X D_t X^T D, D the lumped mass) or standard (X D_t X^T).
    #[arg(long, default_value = Kernel::default().name(), value_parser = kernel_parser())]
    pub kernel: Kernel,
    /// Output file(s): .png, .wrl, .ply or .txt by extension (repeatable).
    #[arg(long, short = 'o', required = true)]
    pub out: Vec<PathBuf>,
    #[command(flatten)]
    pub output: FieldOutputArgs,
}

fn parse_indicator(text: &str) -> Result<(usize, f64)> {
    let (v, r) = text
        .split_once(',')
        .ok_or_else(|| anyhow::anyhow!("--indicator {text}: expected V,R (vertex,radius)"))?;
    let v: usize = v
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--indicator {text}: '{v}' is not a vertex index"))?;
    let r: f64 = r
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--indicator {text}: '{r}' is not a radius"))?;
    if !(r.is_finite() && r >= 0.0) {
        bail!("--indicator {text}: the radius must be a finite number >= 0");
    }
    Ok((v, r))
}

/// Computes the basis function or the diffusion and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = args.spectral.basis.load(args.mesh.as_deref())?;
    let n = input.n();
    // What is diffused: None = e_anchor.
    let (signal, what) = match (&args.signal, &args.indicator) {
        (Some(p), _) => (
            Some(Signal::Values(read_field(p, n)?)),
            format!("signal {}", p.display()),
        ),
        (None, Some(spec)) => {
            let (v, r) = parse_indicator(spec)?;
            check_vertex(v, n, "--indicator")?;
            (
                Some(Signal::Ball {
                    vertex: v,
                    radius: r,
                }),
                format!("indicator of the ball of radius {r} around vertex {v}"),
            )
        }
        (None, None) => {
            if let Some(a) = args.anchor {
                check_vertex(a, n, "--anchor")?;
            }
            (None, String::new())
        }
    };
    let (t, kernel, k) = (args.t, args.kernel, args.spectral.basis.k);
    let request = match &signal {
        Some(s) => FieldRequest::Diffusion {
            signal: s.clone(),
            t,
            kernel,
            k,
        },
        None => FieldRequest::Heat {
            anchor: args.anchor,
            t,
            kernel,
            k,
        },
    };
    request.validate().map_err(|e| anyhow::anyhow!("--{e}"))?;
    args.output.check(&args.out)?;
    args.spectral
        .basis
        .warn_unrecorded(args.output.save_experiment.as_ref());
    let info = input.info;
    let an = args.spectral.analysis(input.shape)?;
    let (field, seconds) = engine::field(&an, &request, args.spectral.basis.cache.as_deref())?;
    let f = &field.values;
    // The B-mass of what was diffused, and of the result.
    let start = match &signal {
        Some(s) => an.signal(s)?,
        None => an.signal(&Signal::Impulse(field.marks[0]))?,
    };
    let (mass_in, mass_out) = (an.mass_of(&start), an.mass_of(f));
    let what = match signal {
        Some(_) => what,
        None => format!("basis function K_t e_{}", field.marks[0]),
    };
    let stats = FieldStats::of(f);
    println!(
        "{}: n = {n}; {what}, t = {t}{}, kernel {}, k = {k} ({}), eigenpairs in {seconds:.2} s",
        info.label(),
        if args.spectral.no_normalize {
            ""
        } else {
            " (unit-area shape)"
        },
        kernel.name(),
        an.options().laplacian,
    );
    if let Some(&a) = field.marks.first() {
        println!("value at vertex {a}: {}", f[a]);
    }
    println!(
        "min {}, max {} at vertex {}",
        stats.min, stats.max, stats.argmax
    );
    println!(
        "B-mass (1^T B f{}): input {mass_in}, output {mass_out}, relative change {:.2e}",
        if args.spectral.no_normalize {
            ""
        } else {
            ", B of the unit-area shape"
        },
        if mass_in != 0.0 {
            (mass_out - mass_in).abs() / mass_in.abs()
        } else {
            (mass_out - mass_in).abs()
        }
    );
    args.output.write_field(&an, &field, &args.out)?;
    args.output
        .save_experiment(&info, &an, &field, args.spectral.basis.repair)?;
    Ok(())
}
