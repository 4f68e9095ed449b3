//! `spectral-mesh convert IN OUT`.

use std::path::PathBuf;

use anyhow::Result;
use spectral_mesh::io::{MeshFormat, WriteOptions, write_mesh};

use crate::input;
use crate::output::check_writable;

/// Arguments of `convert`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input mesh file or built-in shape.
    pub input: String,
    /// Output file; the format follows its extension (.off, .obj, .ply, .stl).
    pub output: PathBuf,
    /// Output format, overriding the extension.
    #[arg(long)]
    pub format: Option<MeshFormat>,
    /// Write binary where the format has it (PLY).
    #[arg(long)]
    pub binary: bool,
    /// Repair the mesh first.
    #[arg(long)]
    pub repair: bool,
    /// Overwrite the output if it exists.
    #[arg(long, short = 'f')]
    pub force: bool,
}

/// Reads, optionally repairs, writes.
pub fn run(args: Args) -> Result<()> {
    let input = input::load_repaired(Some(&args.input), args.repair)?;
    check_writable(&args.output, args.force)?;
    write_mesh(
        &args.output,
        input.mesh("convert")?,
        &WriteOptions {
            format: args.format,
            binary: args.binary,
            ..Default::default()
        },
    )?;
    println!(
        "{} -> {}: {} vertices, {} triangles{}",
        input.label(),
        args.output.display(),
        input.n(),
        input.mesh("convert")?.n_triangles(),
        if input.info.polygons_triangulated > 0 {
            format!(
                " ({} polygons triangulated)",
                input.info.polygons_triangulated
            )
        } else {
            String::new()
        }
    );
    for n in &input.info.notes {
        println!("note: {n}");
    }
    Ok(())
}
