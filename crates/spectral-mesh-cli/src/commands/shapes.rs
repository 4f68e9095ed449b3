//! `spectral-mesh shapes`: list the built-in shapes.

use anyhow::Result;
use spectral_mesh::shapes::shape_names;

/// Arguments of `shapes`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Prints the shapes.
pub fn run(args: Args) -> Result<()> {
    let shapes = shape_names();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&shapes)?);
        return Ok(());
    }
    for s in shapes {
        println!("{:<22} {}", s.name, s.description);
        for p in &s.params {
            println!("{:<22}   {}={} : {}", "", p.name, p.default, p.meaning);
        }
    }
    Ok(())
}
