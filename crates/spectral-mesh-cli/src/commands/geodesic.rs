//! `spectral-mesh geodesic MESH --source V [--source V ...] -o d.png`: geodesic distance
//! from a set of vertices (or points inside triangles) by the heat method
//! ([`spectral_mesh::geodesic`]); on a point cloud (a point file) from a set of points,
//! with the point-cloud Laplacian and a gradient in each point's tangent plane.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use spectral_mesh::Laplacian;
use spectral_mesh::analysis::AnalysisInput;
use spectral_mesh::experiments::paper::FieldStats;
use spectral_mesh::geodesic::{
    BLOCK, CloudGeodesicParams, Convention, GeodesicParams, GeodesicSolver, Source,
};
use spectral_mesh::spectral::store::{npy_f64, write_npy_f64};
use spectral_mesh_render::figure::{Figure, field_text};

use crate::engine::{CloudArgs, LAPLACIAN_HELP, LAPLACIAN_LONG_HELP, resolve_laplacian};
use crate::figure::FigureArgs;
use crate::output::{check_outputs, extension, write};

/// Outputs of `geodesic`.
const EXTS: [&str; 6] = ["png", "wrl", "vrml", "ply", "txt", "npy"];

/// Arguments of `geodesic`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, PLY without faces) or built-in
    /// shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Source vertex, or point of a point cloud (repeatable: the distance to the nearest
    /// source). Default: the vertex of largest x when no --face-point is given either.
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
    // Help (with the library's default) in `gradient_help`.
    #[arg(long, value_name = "K", help = gradient_help())]
    pub gradient_neighbors: Option<usize>,
    #[command(flatten)]
    pub cloud: CloudArgs,
    #[command(flatten)]
    pub figure: FigureArgs,
}

/// The help of --gradient-neighbors, with the library's default.
fn gradient_help() -> String {
    format!(
        "Point clouds: nearest neighbours of the least-squares gradient in each point's tangent plane [default: {}]",
        CloudGeodesicParams::default().gradient_neighbors
    )
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
    let input = args.cloud.load(args.mesh.as_deref(), args.repair)?;
    let laplacian = resolve_laplacian(args.laplacian, &input.shape)?;
    let params = GeodesicParams {
        time_factor: args.time_factor,
        convention: args.convention,
        ..GeodesicParams::default()
    };
    let clock = Instant::now();
    let (solver, cloud_mesh) = match &input.shape {
        AnalysisInput::Points { cloud, params: lp } => {
            let d = CloudGeodesicParams::default();
            let cp = CloudGeodesicParams {
                laplacian: *lp,
                gradient_neighbors: args.gradient_neighbors.unwrap_or(d.gradient_neighbors),
                ..d
            };
            let solver = GeodesicSolver::from_point_cloud(cloud, &cp, &params)?;
            let drawn = args
                .out
                .iter()
                .any(|o| !matches!(extension(o).as_deref(), Some("txt" | "npy")));
            let mesh = if drawn {
                Some(solver.point_cloud_mesh().ok_or_else(|| {
                    anyhow::anyhow!(
                        "{}: the point cloud's Laplacian has no triangle to draw the distance on: write .txt or .npy",
                        input.label()
                    )
                })?)
            } else {
                None
            };
            (solver, mesh)
        }
        AnalysisInput::Mesh(mesh) => {
            if args.gradient_neighbors.is_some() {
                bail!(
                    "--gradient-neighbors applies only to point clouds, and {} is a mesh",
                    input.label()
                );
            }
            (GeodesicSolver::new(mesh, laplacian, &params)?, None)
        }
    };
    let setup = clock.elapsed().as_secs_f64();
    let mut sources: Vec<Source> = args.source.iter().map(|&v| Source::Vertex(v)).collect();
    for fp in &args.face_point {
        sources.push(parse_face_point(fp)?);
    }
    if args.each {
        return write_each(&args, &solver, setup);
    }
    let mesh: &spectral_mesh::Mesh = match (&input.shape, &cloud_mesh) {
        (AnalysisInput::Mesh(m), _) => m,
        (_, Some(m)) => m,
        (AnalysisInput::Points { cloud, .. }, None) => {
            // Only .txt and .npy outputs: no picture, the default source from the points.
            if sources.is_empty() {
                sources.push(Source::Vertex(largest_x(cloud.positions())));
            }
            return write_values(&args, &input.label(), &solver, &sources, setup, None);
        }
    };
    if sources.is_empty() {
        sources.push(Source::Vertex(mesh.vertex_of_largest_x()));
    }
    write_values(&args, &input.label(), &solver, &sources, setup, Some(mesh))
}

/// The index of the point of largest x (the first of equals).
fn largest_x(points: &[[f64; 3]]) -> usize {
    let mut best = 0;
    for (i, p) in points.iter().enumerate() {
        if p[0] > points[best][0] {
            best = i;
        }
    }
    best
}

/// Solves for one source set and writes the outputs (pictures on `mesh`).
fn write_values(
    args: &Args,
    label: &str,
    solver: &GeodesicSolver,
    sources: &[Source],
    setup: f64,
    mesh: Option<&spectral_mesh::Mesh>,
) -> Result<()> {
    let laplacian = solver.laplacian();
    let clock = Instant::now();
    let d = solver.distance(sources)?;
    let solve = clock.elapsed().as_secs_f64();
    let unreachable = d.iter().filter(|x| x.is_infinite()).count();
    let finite: Vec<f64> = d.iter().copied().filter(|x| x.is_finite()).collect();
    let stats = FieldStats::of(&finite);
    println!(
        "{label}: n = {}; heat-method distance from {} source(s), {}, {} convention, t = {:.6e} (m = {}, h = {:.6e}){}; set-up {setup:.3} s, solve {solve:.3} s",
        solver.n(),
        sources.len(),
        if solver.is_point_cloud() {
            format!(
                "point-cloud Laplacian and tangent-plane gradient ({} neighbours)",
                args.gradient_neighbors
                    .unwrap_or(CloudGeodesicParams::default().gradient_neighbors)
            )
        } else {
            laplacian.to_string()
        },
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
                mesh.map_or(0, |m| m.triangles()[face][k])
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
                let Some(mesh) = mesh else {
                    bail!(
                        "{}: a point cloud's distance is written as .txt or .npy",
                        o.display()
                    );
                };
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
    // Block by block into one matrix (the rows are not held twice).
    let clock = Instant::now();
    let n = solver.n();
    let k = args.source.len();
    let mut flat = Vec::with_capacity(k * n);
    for chunk in args.source.chunks(BLOCK) {
        for r in solver.distances_from_vertices(chunk)? {
            flat.extend_from_slice(&r);
        }
    }
    let solve = clock.elapsed().as_secs_f64();
    println!(
        "n = {n}; heat-method distances from {k} sources each, {}; set-up {setup:.3} s, solves {solve:.3} s ({:.4} s per source)",
        solver.laplacian(),
        solve / k as f64
    );
    for o in &args.out {
        if extension(o).as_deref() == Some("npy") {
            spectral_mesh::io::write_atomic_with(o, |f| {
                write_npy_f64(f, &flat, &[k as u64, n as u64], false)
            })?;
        } else {
            let mut text = String::new();
            for r in flat.chunks(n.max(1)) {
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
