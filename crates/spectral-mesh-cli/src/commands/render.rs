//! `spectral-mesh render MESH --field values.txt -o out.png`.

use std::path::PathBuf;

use anyhow::Result;

use spectral_mesh_render::figure::Figure;

use crate::figure::FigureArgs;
use crate::input::{self, read_field};
use crate::output::check_writable;

/// Arguments of `render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
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
    /// Vertices to mark as sources (yellow).
    #[arg(long = "mark")]
    pub marks: Vec<usize>,
    /// Overwrite the output if it exists.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
}

/// Draws the field.
pub fn run(args: Args) -> Result<()> {
    let input = input::load(args.mesh.as_deref())?;
    let mesh = &input.mesh;
    let n = mesh.n_vertices();
    let field = match &args.field {
        Some(p) => read_field(p, n)?,
        None => mesh.positions().iter().map(|p| p[2]).collect(),
    };
    for &m in &args.marks {
        if m >= n {
            anyhow::bail!("--mark {m}: the mesh has only {n} vertices");
        }
    }
    let out = match &args.format {
        Some(f) => args.out.with_extension(f),
        None => args.out.clone(),
    };
    check_writable(&out, args.force)?;
    let fig = Figure::new(mesh, &field, args.marks.clone(), args.figure.options())?;
    fig.write(&out)?;
    println!("{} -> {}", input.label(), out.display());
    Ok(())
}
