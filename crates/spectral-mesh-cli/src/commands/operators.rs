//! `spectral-mesh operators MESH --out DIR`: export S and the mass matrices.

use std::path::PathBuf;

use anyhow::Result;
use spectral_mesh::SparseMatrix;
use spectral_mesh::io::{MeshFormat, WriteOptions, write_mesh};
use spectral_mesh::operators::{MassKind, cotan_stiffness, mass_matrix, uniform_laplacian};

use crate::input;
use crate::output::{prepare_outputs, write};

/// Arguments of `operators`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Output folder.
    #[arg(long, short = 'o', default_value = "operators")]
    pub out: PathBuf,
    /// Repair the mesh first (see `info --repair`).
    #[arg(long)]
    pub repair: bool,
    /// Overwrite existing files.
    #[arg(long, short = 'f')]
    pub force: bool,
}

fn mtx(a: &SparseMatrix) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    a.write_matrix_market(&mut buf)?;
    Ok(buf)
}

/// Writes `mesh.off` (the triangulated mesh the matrices belong to), `S.mtx`
/// (cotangent stiffness, positive semi-definite), `S_uniform.mtx`, `B_fem.mtx`,
/// `B_barycentric.mtx` (the paper's Voronoi-cot) and `B_mixed_voronoi.mtx`.
pub fn run(args: Args) -> Result<()> {
    let input = input::load_repaired(args.mesh.as_deref(), args.repair)?;
    let mesh = &input.mesh;
    let names = [
        "mesh.off",
        "S.mtx",
        "S_uniform.mtx",
        "B_fem.mtx",
        "B_barycentric.mtx",
        "B_mixed_voronoi.mtx",
    ];
    let paths = prepare_outputs(&args.out, &names, args.force)?;
    write_mesh(
        &paths[0],
        mesh,
        &WriteOptions {
            format: Some(MeshFormat::Off),
            ..Default::default()
        },
    )?;
    write(&paths[1], &mtx(&cotan_stiffness(mesh))?)?;
    write(&paths[2], &mtx(&uniform_laplacian(mesh))?)?;
    for (p, kind) in
        paths[3..]
            .iter()
            .zip([MassKind::Fem, MassKind::Barycentric, MassKind::MixedVoronoi])
    {
        write(p, &mtx(&mass_matrix(mesh, kind))?)?;
    }
    println!(
        "{}: n = {}, m = {}; wrote {} files to {}",
        input.label(),
        mesh.n_vertices(),
        mesh.n_triangles(),
        names.len(),
        args.out.display()
    );
    Ok(())
}
