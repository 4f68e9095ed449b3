//! `spectral-mesh heat MESH --anchor V --t T -o out.png`: the heat-kernel basis function
//! `K_t e_V`, or the diffusion `K_t f` of a signal.

use std::path::PathBuf;

use anyhow::{Result, bail};
use spectral_mesh::spectral::heat::{HeatSolver, KernelKind};

use super::eigs::{BasisArgs, FIGURE_EXTS, check_outputs, check_vertex, default_vertex};
use crate::figure::{Figure, FigureArgs, read_field};
use crate::input;

/// Which heat kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Kernel {
    /// `K_t = X D_t X^T B` (the paper's wFEM kernel; conserves the B-mass).
    Wfem,
    /// `K*_t = X D_t X^T D`, D the lumped mass.
    VoronoiCot,
    /// `K~_t = X D_t X^T` (no mass).
    Standard,
}

impl Kernel {
    /// The name typed on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Wfem => "wfem",
            Kernel::VoronoiCot => "voronoi-cot",
            Kernel::Standard => "standard",
        }
    }
}

impl From<Kernel> for KernelKind {
    fn from(k: Kernel) -> Self {
        match k {
            Kernel::Wfem => KernelKind::Wfem,
            Kernel::VoronoiCot => KernelKind::VoronoiCot,
            Kernel::Standard => KernelKind::Standard,
        }
    }
}

/// Arguments of `heat`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Anchor vertex of the basis function K_t e_V (default: the vertex of largest x).
    #[arg(long)]
    pub anchor: Option<usize>,
    /// Diffusion time (for the shape scaled to unit area unless --no-normalize).
    #[arg(long, default_value_t = 0.5)]
    pub t: f64,
    #[command(flatten)]
    pub basis: BasisArgs,
    /// Diffuse this per-vertex signal (one value per line) instead of e_V.
    #[arg(long, conflicts_with_all = ["indicator", "anchor"])]
    pub signal: Option<PathBuf>,
    /// Diffuse the indicator of the ball of radius R (mesh units, Euclidean) around
    /// vertex V, written V,R.
    #[arg(long, value_name = "V,R", conflicts_with = "anchor")]
    pub indicator: Option<String>,
    /// Heat kernel discretization.
    #[arg(long, value_enum, default_value = "wfem")]
    pub kernel: Kernel,
    /// Use times for the shape as given instead of scaled to unit area.
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
    let input = input::load(args.mesh.as_deref())?;
    let mesh = &input.mesh;
    let n = mesh.n_vertices();
    if !(args.t.is_finite() && args.t >= 0.0) {
        bail!("--t {}: the time must be a finite number >= 0", args.t);
    }
    // What is diffused: None = e_anchor.
    let (signal, marks, what): (Option<Vec<f64>>, Vec<usize>, String) =
        match (&args.signal, &args.indicator) {
            (Some(p), _) => (
                Some(read_field(p, n)?),
                Vec::new(),
                format!("signal {}", p.display()),
            ),
            (None, Some(spec)) => {
                let (v, r) = parse_indicator(spec)?;
                check_vertex(v, mesh, "--indicator")?;
                let c = mesh.positions()[v];
                let f: Vec<f64> = mesh
                    .positions()
                    .iter()
                    .map(|p| {
                        let d2: f64 = (0..3).map(|i| (p[i] - c[i]).powi(2)).sum();
                        if d2 <= r * r { 1.0 } else { 0.0 }
                    })
                    .collect();
                let count = f.iter().filter(|x| **x > 0.0).count();
                (
                    Some(f),
                    vec![v],
                    format!(
                        "indicator of the ball of radius {r} around vertex {v} ({count} vertices)"
                    ),
                )
            }
            (None, None) => {
                let a = args.anchor.unwrap_or_else(|| default_vertex(mesh));
                check_vertex(a, mesh, "--anchor")?;
                (None, vec![a], format!("basis function K_t e_{a}"))
            }
        };
    check_outputs(&args.out, &FIGURE_EXTS, args.force)?;
    let tb = args.basis.compute(mesh, None)?;
    let solver = HeatSolver::new(
        &tb.basis,
        args.kernel.into(),
        super::eigs::normalization(args.no_normalize),
    );
    let bmass = |f: &[f64]| -> f64 { solver.basis().mass.mul_vec(f).iter().sum() };
    let (f, mass_in) = match &signal {
        Some(s) => (solver.diffuse(s, args.t)?, bmass(s)),
        None => {
            let a = marks[0];
            let mut e = vec![0.0; n];
            e[a] = 1.0;
            (solver.basis_function(a, args.t)?, bmass(&e))
        }
    };
    let mass_out = bmass(&f);
    let (imax, fmax) =
        f.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |b, (i, &v)| if v > b.1 { (i, v) } else { b },
        );
    let fmin = f.iter().copied().fold(f64::INFINITY, f64::min);
    println!(
        "{}: n = {}; {what}, t = {}{}, kernel {}, k = {} ({}), eigenpairs in {:.2} s",
        input.label(),
        n,
        args.t,
        if args.no_normalize {
            ""
        } else {
            " (unit-area shape)"
        },
        args.kernel.name(),
        tb.basis.k(),
        tb.basis.laplacian,
        tb.seconds
    );
    if let Some(&a) = marks.first() {
        println!("value at vertex {a}: {}", f[a]);
    }
    println!("min {fmin}, max {fmax} at vertex {imax}");
    println!(
        "B-mass (1^T B f{}): input {mass_in}, output {mass_out}, relative change {:.2e}",
        if args.no_normalize {
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
    let fig = Figure::new(mesh, &f, marks, &args.figure)?;
    for o in &args.out {
        fig.write_by_extension(o, &args.figure)?;
        println!("-> {}", o.display());
    }
    Ok(())
}
