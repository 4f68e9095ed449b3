//! `spectral-mesh operators MESH|POINTS --out DIR`: export S and the mass matrices.

use std::path::{Path, PathBuf};

use anyhow::Result;
use spectral_mesh::SparseMatrix;
use spectral_mesh::io::{Input, MeshFormat, WriteOptions, read_input, write_mesh};
use spectral_mesh::operators::{
    MassKind, RobustParams, cotan_stiffness, mass_matrix, point_cloud_laplacian, robust_laplacian,
    uniform_laplacian,
};

use crate::engine::CloudArgs;
use crate::input;
use crate::output::{prepare_outputs, write};

/// Arguments of `operators`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt, or a PLY without faces) or built-in
    /// shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Output folder.
    #[arg(long, short = 'o', default_value = "operators")]
    pub out: PathBuf,
    /// Repair the mesh first (see `info --repair`).
    #[arg(long)]
    pub repair: bool,
    /// Also write the robust Laplacian (tufted cover, mollification, intrinsic Delaunay;
    /// Sharp and Crane 2020): S_robust.mtx and B_robust.mtx. Always on for point clouds.
    #[arg(long)]
    pub robust: bool,
    // The point-cloud Laplacian's parameters; --mollify-factor also sets the robust
    // Laplacian's of a mesh (with --robust).
    #[command(flatten)]
    pub cloud: CloudArgs,
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
/// `B_barycentric.mtx` (the paper's Voronoi-cot) and `B_mixed_voronoi.mtx`; with
/// `--robust` also `S_robust.mtx` and `B_robust.mtx`. A point cloud gives `S_robust.mtx`
/// and `B_robust.mtx` only.
pub fn run(args: Args) -> Result<()> {
    if let Some(spec) = args.mesh.as_deref()
        && Path::new(spec).is_file()
        && let Input::Points(p) = read_input(Path::new(spec))?
    {
        return run_points(&args, spec, p);
    }
    let mut input = input::load_repaired(args.mesh.as_deref(), args.repair)?;
    // On a mesh, only --mollify-factor applies (to the robust Laplacian, with --robust).
    CloudArgs {
        mollify_factor: args.cloud.mollify_factor.filter(|_| !args.robust),
        ..args.cloud.clone()
    }
    .apply(&mut input)?;
    let mesh = input.mesh("operators")?;
    let mut names = vec![
        "mesh.off",
        "S.mtx",
        "S_uniform.mtx",
        "B_fem.mtx",
        "B_barycentric.mtx",
        "B_mixed_voronoi.mtx",
    ];
    if args.robust {
        names.extend(["S_robust.mtx", "B_robust.mtx"]);
    }
    let robust = if args.robust {
        Some(robust_laplacian(
            mesh,
            &RobustParams {
                mollify_factor: args
                    .cloud
                    .mollify_factor
                    .unwrap_or(RobustParams::default().mollify_factor),
                ..Default::default()
            },
        )?)
    } else {
        None
    };
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
        paths[3..6]
            .iter()
            .zip([MassKind::Fem, MassKind::Barycentric, MassKind::MixedVoronoi])
    {
        write(p, &mtx(&mass_matrix(mesh, kind))?)?;
    }
    if let Some(r) = &robust {
        write(&paths[6], &mtx(&r.stiffness)?)?;
        write(&paths[7], &mtx(&r.mass)?)?;
    }
    println!(
        "{}: n = {}, m = {}; wrote {} files to {}",
        input.label(),
        mesh.n_vertices(),
        mesh.n_triangles(),
        names.len(),
        args.out.display()
    );
    if let Some(r) = &robust {
        let s = &r.stats;
        println!(
            "robust: {} intrinsic flips, mollified by {:.3e} ({} non-manifold edges, {} boundary edges)",
            s.flips, s.mollify_epsilon, s.non_manifold_edges, s.boundary_edges
        );
    }
    Ok(())
}

fn run_points(args: &Args, spec: &str, p: spectral_mesh::io::LoadedPoints) -> Result<()> {
    let params = args.cloud.params()?;
    let r = point_cloud_laplacian(&p.cloud, &params)?;
    let names = ["S_robust.mtx", "B_robust.mtx"];
    let paths = prepare_outputs(&args.out, &names, args.force)?;
    write(&paths[0], &mtx(&r.stiffness)?)?;
    write(&paths[1], &mtx(&r.mass)?)?;
    println!(
        "{spec}: point cloud, n = {}; {} neighbours, {} local triangles ({} distinct, {} found by all three corners), {} isolated points; wrote {} files to {}",
        p.cloud.n_points(),
        r.stats.neighbors,
        r.stats.local_triangles,
        r.stats.distinct_triangles,
        r.stats.agreed_triangles,
        r.stats.isolated_points.len(),
        names.len(),
        args.out.display()
    );
    for w in &p.warnings {
        println!("note: {w}");
    }
    Ok(())
}
