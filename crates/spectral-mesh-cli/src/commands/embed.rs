//! `spectral-mesh embed MESH --filter F --dims 3 -o embedded.off`: the spectral embedding
//! `p -> (sqrt(w(lambda_k)) x_k(p))_k`, as a mesh with the same triangles and as coordinates.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use spectral_mesh::io::{MeshFormat, WriteOptions, write_mesh};
use spectral_mesh::spectral::embedding::{embedding_mesh, spectral_embedding};
use spectral_mesh::spectral::filters::Filter;

use super::distance::FILTER_HELP;
use crate::engine::{self, FieldBasisArgs};
use crate::output::{check_outputs, check_writable, write};

/// Arguments of `embed`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// The filter whose distance the embedding realizes (see below).
    #[arg(long, default_value_t = Filter::default().to_string(), long_help = FILTER_HELP)]
    pub filter: String,
    /// Number of coordinates (pairs with non-zero weight, in basis order) written by
    /// --coords. The mesh output always has the first three (0 where the basis has fewer
    /// pairs of non-zero weight).
    #[arg(long, default_value_t = spectral_mesh::defaults::EMBED_DIMS)]
    pub dims: usize,
    #[command(flatten)]
    pub spectral: FieldBasisArgs,
    /// The embedded mesh: .off, .obj, .ply or .stl (repeatable).
    #[arg(long, short = 'o')]
    pub out: Vec<PathBuf>,
    /// Write the coordinates: one row per vertex, --dims columns.
    #[arg(long)]
    pub coords: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
}

/// Computes the embedding and writes it.
pub fn run(args: Args) -> Result<()> {
    let input = args.spectral.basis.load(args.mesh.as_deref())?;
    let filter: Filter = args
        .filter
        .parse()
        .map_err(|e| anyhow::anyhow!("--filter {}: {e}", args.filter))?;
    if args.dims == 0 {
        bail!("--dims 0: at least one coordinate is needed");
    }
    if args.out.is_empty() && args.coords.is_none() {
        bail!("nothing to write: give -o MESH and/or --coords FILE");
    }
    check_outputs(&args.out, &["off", "obj", "ply", "stl"], args.force)?;
    if let Some(c) = &args.coords {
        check_writable(c, args.force)?;
    }
    args.spectral.basis.check_k(input.n())?;
    let label = input.label();
    let k = args.spectral.basis.k;
    let an = args.spectral.analysis(input.shape)?;
    let engine::Solved { basis, seconds, .. } =
        engine::basis(&an, k, args.spectral.basis.cache.as_deref())?;
    let view = basis.view(k);
    let mesh = an.mesh();
    let coords = spectral_embedding(view, &filter, args.dims)
        .map_err(|e| anyhow::anyhow!("--filter {}: {e}", args.filter))?;
    let got = coords.first().map_or(0, Vec::len);
    println!(
        "{label}: n = {}, m = {}; {} embedding with {got} coordinate(s){}, k = {k} ({}){}, eigenpairs in {seconds:.2} s",
        mesh.n_vertices(),
        mesh.n_triangles(),
        args.filter,
        if got < args.dims {
            format!(
                " (asked for {}: the basis has only {got} pairs of non-zero weight)",
                args.dims
            )
        } else {
            String::new()
        },
        an.options().laplacian,
        args.spectral.scale_note(),
    );
    if !args.out.is_empty() {
        let embedded = embedding_mesh(mesh, view, &filter)
            .context("the embedded positions do not form a mesh")?;
        let (lo, hi) = embedded.bounding_box();
        println!(
            "embedded mesh: bounding box {:?} .. {:?}, area {}",
            lo,
            hi,
            embedded.area()
        );
        for o in &args.out {
            let format = MeshFormat::from_path(o)
                .with_context(|| format!("{}: unknown mesh format", o.display()))?;
            write_mesh(
                o,
                &embedded,
                &WriteOptions {
                    format: Some(format),
                    ..Default::default()
                },
            )?;
            println!("-> {}", o.display());
        }
    }
    if let Some(c) = &args.coords {
        let mut s = String::with_capacity(coords.len() * got * 24);
        for row in &coords {
            let r: Vec<String> = row.iter().map(|v| format!("{v:?}")).collect();
            s.push_str(&r.join(" "));
            s.push('\n');
        }
        write(c, s.as_bytes())?;
        println!("coordinates ({} x {got}) -> {}", coords.len(), c.display());
    }
    Ok(())
}
