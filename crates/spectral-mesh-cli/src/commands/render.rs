//! `spectral-mesh render MESH --field values.txt -o out.png`.

use std::path::PathBuf;

use anyhow::Result;

use spectral_mesh::Laplacian;
use spectral_mesh::analysis::{Analysis, AnalysisInput, AnalysisOptions};
use spectral_mesh_render::figure::{Figure, POINT_RADIUS_FACTOR};

use crate::engine::CloudArgs;
use crate::figure::FigureArgs;
use crate::input::read_field;
use crate::output::check_writable;

/// Arguments of `render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (drawn as discs) or built-in shape (default: the
    /// 3-torus).
    pub mesh: Option<String>,
    /// Per-vertex values, one per line (the format every experiment writes). Without
    /// it the surface is coloured by height (z).
    #[arg(long)]
    pub field: Option<PathBuf>,
    /// Output file; its extension picks the format unless --format is given.
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// Output format: png, wrl, ply or txt.
    #[arg(long)]
    pub format: Option<String>,
    /// Vertices to mark as sources (yellow stars, as the web page draws them).
    #[arg(long = "mark")]
    pub marks: Vec<usize>,
    /// Overwrite the output if it exists.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
    #[command(flatten)]
    pub cloud: CloudArgs,
}

/// Draws the field.
pub fn run(args: Args) -> Result<()> {
    // A point cloud's picture is drawn on its triangle union (level sets, critical
    // points, the disc size), which depends on the Laplacian's parameters.
    let input = args.cloud.load(args.mesh.as_deref(), false)?;
    let label = input.label();
    let n = input.n();
    // A point cloud is drawn from its analysis (the triangle union carries the level sets
    // and critical points; the points are discs).
    let an = match &input.shape {
        AnalysisInput::Points { .. } => Some(Analysis::from_input(
            input.shape.clone(),
            AnalysisOptions {
                laplacian: Laplacian::Robust,
                ..AnalysisOptions::default()
            },
        )?),
        AnalysisInput::Mesh(_) => None,
    };
    let mesh = match &an {
        Some(an) => an.mesh(),
        None => input.mesh("render")?,
    };
    let field = match &args.field {
        Some(p) => read_field(p, n)?,
        None => mesh.positions().iter().map(|p| p[2]).collect(),
    };
    for &m in &args.marks {
        if m >= n {
            anyhow::bail!("--mark {m}: the input has only {n} vertices");
        }
    }
    let out = match &args.format {
        Some(f) => args.out.with_extension(f),
        None => args.out.clone(),
    };
    check_writable(&out, args.force)?;
    let mut fig = Figure::new(mesh, &field, args.marks.clone(), args.figure.options())?;
    fig.point_radius = an
        .as_ref()
        .and_then(|a| a.point_spacing())
        .map(|h| POINT_RADIUS_FACTOR * h);
    fig.write(&out)?;
    println!("{label} -> {}", out.display());
    Ok(())
}
