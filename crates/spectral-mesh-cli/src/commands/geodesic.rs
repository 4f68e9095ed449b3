//! `spectral-mesh geodesic MESH --source V [--source V ...] -o d.png`: geodesic distance
//! from a set of vertices (or points inside triangles) by the heat method
//! ([`spectral_mesh::geodesic`]).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use spectral_mesh::Laplacian;
use spectral_mesh::experiments::paper::FieldStats;
use spectral_mesh::geodesic::{Convention, GeodesicParams, GeodesicSolver, Source};
use spectral_mesh::spectral::store::npy_f64;
use spectral_mesh_render::figure::{Figure, field_text};

use crate::engine::{LAPLACIAN_HELP, LAPLACIAN_LONG_HELP, resolve_laplacian};
use crate::figure::FigureArgs;
use crate::input;
use crate::output::{check_outputs, extension, write};

/// Outputs of `geodesic`.
const EXTS: [&str; 6] = ["png", "wrl", "vrml", "ply", "txt", "npy"];

/// Arguments of `geodesic`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Source vertex (repeatable: the distance to the nearest source). Default: the vertex
    /// of largest x when no --face-point is given either.
    #[arg(long)]
    pub source: Vec<usize>,
    /// Source point inside a triangle, written F,B0,B1,B2 (triangle index and barycentric
    /// coordinates of its three vertices; repeatable).
    #[arg(long, value_name = "F,B0,B1,B2")]
    pub face_point: Vec<String>,
    /// Discretization (S, B) of the heat and Poisson solves.
    #[arg(long, help = LAPLACIAN_HELP, long_help = LAPLACIAN_LONG_HELP)]
    pub laplacian: Option<Laplacian>,
    /// m in the time step t = m h^2 (h the mean edge length; potpourri3d's t_coef).
    #[arg(long, default_value_t = GeodesicParams::default().time_factor)]
    pub time_factor: f64,
    /// crane: on a mesh with boundary, the average of the Neumann and Dirichlet heat
    /// solutions, exact Poisson solve (the default); potpourri3d: geometry-central's
    /// solver (Neumann heat, Poisson matrix shifted by 1e-6 I), for comparisons.
    #[arg(long, default_value_t = GeodesicParams::default().convention)]
    pub convention: Convention,
    /// Distances from each --source on its own instead of from the set, solved as blocks
    /// of right-hand sides: one row per source in .npy (sources x n) and .txt (one line
    /// per source, values separated by spaces).
    #[arg(long)]
    pub each: bool,
    /// Repair the mesh first (see `info --repair`).
    #[arg(long)]
    pub repair: bool,
    /// Output file(s): .png, .wrl, .ply, .txt or .npy by extension (repeatable).
    #[arg(long, short = 'o', required = true)]
    pub out: Vec<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
}

/// Parses `F,B0,B1,B2`.
fn parse_face_point(text: &str) -> Result<Source> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 4 {
        bail!(
            "--face-point {text}: expected F,B0,B1,B2 (a triangle and three barycentric coordinates)"
        );
    }
    let face: usize = parts[0].parse().map_err(|_| {
        anyhow::anyhow!(
            "--face-point {text}: '{}' is not a triangle index",
            parts[0]
        )
    })?;
    let mut bary = [0.0; 3];
    for (b, s) in bary.iter_mut().zip(&parts[1..]) {
        *b = s
            .parse()
            .map_err(|_| anyhow::anyhow!("--face-point {text}: '{s}' is not a number"))?;
    }
    Ok(Source::FacePoint { face, bary })
}

/// Computes the distances and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    check_outputs(&args.out, &EXTS, args.force)?;
    let input = input::load_repaired(args.mesh.as_deref(), args.repair)?;
    let laplacian = resolve_laplacian(args.laplacian, &input.shape)?;
    let mesh = input.mesh("geodesic")?;
    let mut sources: Vec<Source> = args.source.iter().map(|&v| Source::Vertex(v)).collect();
    for fp in &args.face_point {
        sources.push(parse_face_point(fp)?);
    }
    if sources.is_empty() {
        sources.push(Source::Vertex(mesh.vertex_of_largest_x()));
    }
    let params = GeodesicParams {
        time_factor: args.time_factor,
        convention: args.convention,
        ..GeodesicParams::default()
    };
    let clock = Instant::now();
    let solver = GeodesicSolver::new(mesh, laplacian, &params)?;
    let setup = clock.elapsed().as_secs_f64();
    if args.each {
        return write_each(&args, &solver, setup);
    }
    let clock = Instant::now();
    let d = solver.distance(&sources)?;
    let solve = clock.elapsed().as_secs_f64();
    let unreachable = d.iter().filter(|x| x.is_infinite()).count();
    let finite: Vec<f64> = d.iter().copied().filter(|x| x.is_finite()).collect();
    let stats = FieldStats::of(&finite);
    println!(
        "{}: n = {}; heat-method distance from {} source(s), {laplacian}, {} convention, t = {:.6e} (m = {}, h = {:.6e}){}; set-up {setup:.3} s, solve {solve:.3} s",
        input.label(),
        mesh.n_vertices(),
        sources.len(),
        args.convention.name(),
        solver.time(),
        args.time_factor,
        solver.mean_edge_length(),
        if solver.averages_boundary() {
            ", boundary: average of Neumann and Dirichlet heat"
        } else {
            ""
        },
    );
    println!("max distance {}", stats.max);
    if unreachable > 0 {
        eprintln!(
            "warning: {unreachable} vertices are on components without a source (or in no triangle): their distance is infinite (written as inf)"
        );
    }
    let marks: Vec<usize> = sources
        .iter()
        .map(|s| match *s {
            Source::Vertex(v) => v,
            Source::FacePoint { face, bary } => {
                let k = (0..3)
                    .max_by(|&a, &b| bary[a].total_cmp(&bary[b]))
                    .unwrap_or(0);
                mesh.triangles()[face][k]
            }
        })
        .collect();
    let options = args.figure.options();
    let mut fig = None;
    for o in &args.out {
        match extension(o).as_deref() {
            Some("txt") => write(o, field_text(&d).as_bytes())?,
            Some("npy") => write(o, &npy_f64(&d, &[d.len() as u64], false)?)?,
            _ => {
                if fig.is_none() {
                    fig = Some(Figure::new(mesh, &d, marks.clone(), options)?);
                }
                if let Some(f) = &fig {
                    f.write(o)?;
                }
            }
        }
        println!("-> {}", o.display());
    }
    Ok(())
}

/// `--each`: one row of distances per source vertex.
fn write_each(args: &Args, solver: &GeodesicSolver, setup: f64) -> Result<()> {
    if !args.face_point.is_empty() || args.source.is_empty() {
        bail!("--each takes --source vertices only (at least one), not --face-point");
    }
    for o in &args.out {
        if !matches!(extension(o).as_deref(), Some("npy" | "txt")) {
            bail!("{}: --each writes a matrix: use .npy or .txt", o.display());
        }
    }
    let clock = Instant::now();
    let rows = solver.distances_from_vertices(&args.source)?;
    let solve = clock.elapsed().as_secs_f64();
    let n = solver.n();
    println!(
        "n = {n}; heat-method distances from {} sources each, {}; set-up {setup:.3} s, solves {solve:.3} s ({:.4} s per source)",
        rows.len(),
        solver.laplacian(),
        solve / rows.len() as f64
    );
    for o in &args.out {
        if extension(o).as_deref() == Some("npy") {
            let flat = rows.concat();
            write(o, &npy_f64(&flat, &[rows.len() as u64, n as u64], false)?)?;
        } else {
            let mut text = String::new();
            for r in &rows {
                let line: Vec<String> = r.iter().map(|x| format!("{x}")).collect();
                text.push_str(&line.join(" "));
                text.push('\n');
            }
            write(o, text.as_bytes())?;
        }
        println!("-> {}", o.display());
    }
    Ok(())
}
