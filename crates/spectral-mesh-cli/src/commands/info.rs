//! `spectral-mesh info MESH|SHAPE [--repair] [--json]`.

use std::path::Path;

use anyhow::Result;
use spectral_mesh::Mesh;
use spectral_mesh::io::{Input, LoadedPoints, read_input};
use spectral_mesh::mesh::validate::{MeshReport, report};
use spectral_mesh::operators::cotan_stiffness;

use crate::input;

/// Arguments of `info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Repair the mesh (unreferenced vertices, duplicate and zero-area faces,
    /// non-manifold vertices, orientation) and report the result.
    #[arg(long)]
    pub repair: bool,
    /// Print the full report as JSON.
    #[arg(long)]
    pub json: bool,
}

fn list<T: std::fmt::Debug>(v: &[T]) -> String {
    const SHOW: usize = 8;
    let head: Vec<String> = v.iter().take(SHOW).map(|x| format!("{x:?}")).collect();
    if v.len() > SHOW {
        format!("{}, ... ({} in all)", head.join(", "), v.len())
    } else {
        head.join(", ")
    }
}

/// Which discretizations suit the mesh, and why: the cotangent ones assume a manifold mesh
/// without degenerate triangles and are best with non-negative weights; `robust` takes
/// anything.
fn advice(mesh: &Mesh, r: &MeshReport) -> (Vec<&'static str>, String) {
    let mut why = Vec::new();
    if !r.non_manifold_edges.is_empty() {
        why.push(format!("{} non-manifold edges", r.non_manifold_edges.len()));
    }
    if !r.non_manifold_vertices.is_empty() {
        why.push(format!(
            "{} non-manifold vertices",
            r.non_manifold_vertices.len()
        ));
    }
    if !r.degenerate_faces.is_empty() {
        why.push(format!("{} degenerate faces", r.degenerate_faces.len()));
    }
    if !r.duplicate_faces.is_empty() {
        why.push(format!("{} duplicate faces", r.duplicate_faces.len()));
    }
    if !why.is_empty() {
        return (
            vec!["robust"],
            format!("{}: use --laplacian robust", why.join(", ")),
        );
    }
    let s = cotan_stiffness(mesh);
    let negative = (0..s.ncols())
        .map(|c| {
            let (rows, vals) = s.col(c);
            rows.iter()
                .zip(vals)
                .filter(|(r, v)| **r > c && **v > 0.0)
                .count()
        })
        .sum::<usize>();
    if negative > 0 {
        (
            vec!["robust", "fem", "voronoi-cot", "mixed-voronoi", "cot"],
            format!(
                "manifold; {negative} edges have negative cotangent weights \
                 (--laplacian robust flips them: intrinsic Delaunay)"
            ),
        )
    } else {
        (
            vec!["fem", "voronoi-cot", "mixed-voronoi", "cot", "robust"],
            "manifold, every cotangent weight >= 0: all apply (robust = voronoi-cot here, up to mollification)".to_string(),
        )
    }
}

fn run_points(spec: &str, p: &LoadedPoints, json: bool) -> Result<()> {
    let c = &p.cloud;
    let (lo, hi) = c.bounding_box();
    if json {
        let v = serde_json::json!({
            "source": spec,
            "kind": "point cloud",
            "format": p.format.to_string(),
            "points": c.n_points(),
            "normals": c.n_normals(),
            "bbox_min": lo,
            "bbox_max": hi,
            "suitable_laplacians": ["robust"],
            "notes": p.warnings,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("point cloud        {spec} ({})", p.format);
    println!("points             {}", c.n_points());
    println!("normals            {}", c.n_normals());
    println!(
        "bounding box       [{:.6e}, {:.6e}, {:.6e}] .. [{:.6e}, {:.6e}, {:.6e}]",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    println!("laplacian          robust (point-cloud Laplacian: `operators` writes it)");
    for n in &p.warnings {
        println!("note: {n}");
    }
    Ok(())
}

/// Prints counts, topology and problems.
pub fn run(args: Args) -> Result<()> {
    if let Some(spec) = args.mesh.as_deref()
        && Path::new(spec).is_file()
        && let Input::Points(p) = read_input(Path::new(spec))?
    {
        return run_points(spec, &p, args.json);
    }
    let input = input::load_repaired(args.mesh.as_deref(), args.repair)?;
    let mesh = input.mesh("info")?;
    let r = report(mesh);
    let (suitable, why) = advice(mesh, &r);
    if args.json {
        let mut v = serde_json::to_value(&r)?;
        if let Some(o) = v.as_object_mut() {
            o.insert("source".into(), input.label().into());
            o.insert(
                "polygons_triangulated".into(),
                input.info.polygons_triangulated.into(),
            );
            o.insert("notes".into(), input.info.notes.clone().into());
            o.insert("problems".into(), r.problems().into());
            o.insert("suitable_laplacians".into(), suitable.clone().into());
            o.insert("laplacian_advice".into(), why.clone().into());
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("mesh               {}", input.label());
    println!("vertices           {}", r.vertices);
    println!("edges              {}", r.edges);
    println!("faces              {}", r.faces);
    if input.info.polygons_triangulated > 0 {
        println!(
            "triangulated       {} polygons were split into triangles",
            input.info.polygons_triangulated
        );
    }
    println!("components         {}", r.components);
    println!(
        "boundary           {} loops, {} edges",
        r.boundary_loops, r.boundary_edges
    );
    println!("euler char.        {}", r.euler_characteristic);
    for (i, c) in r.component_details.iter().enumerate() {
        let genus = match c.genus {
            Some(g) => format!("genus {g}"),
            None => "genus undefined (non-manifold or non-orientable)".into(),
        };
        println!(
            "  component {i:<4}   V {} E {} F {}, chi {}, {} boundary loops, {}{}",
            c.vertices,
            c.edges,
            c.faces,
            c.euler_characteristic,
            c.boundary_loops,
            genus,
            if c.closed { ", closed" } else { "" }
        );
    }
    println!("area               {:.10e}", r.area);
    println!(
        "bounding box       [{:.6e}, {:.6e}, {:.6e}] .. [{:.6e}, {:.6e}, {:.6e}]",
        r.bbox_min[0], r.bbox_min[1], r.bbox_min[2], r.bbox_max[0], r.bbox_max[1], r.bbox_max[2]
    );
    println!("smallest angle     {:.4} degrees", r.smallest_angle_degrees);
    println!("degenerate faces   {}", r.degenerate_faces.len());
    println!("duplicate faces    {}", r.duplicate_faces.len());
    println!("unreferenced vert. {}", r.unreferenced_vertices.len());
    println!(
        "non-manifold       {} edges, {} vertices",
        r.non_manifold_edges.len(),
        r.non_manifold_vertices.len()
    );
    println!("mis-oriented edges {}", r.inconsistently_oriented_edges);
    println!("orientable         {}", r.orientable);
    println!("laplacian          {} ({why})", suitable.join(", "));
    let problems = r.problems();
    if problems.is_empty() {
        println!("problems           none");
    } else {
        println!("problems           {}", problems.join("; "));
        if !r.degenerate_faces.is_empty() {
            println!("  degenerate faces: {}", list(&r.degenerate_faces));
        }
        if !r.non_manifold_vertices.is_empty() {
            println!(
                "  non-manifold vertices: {}",
                list(&r.non_manifold_vertices)
            );
        }
        if !args.repair {
            println!("(run with --repair to fix what can be fixed)");
        }
    }
    for n in &input.info.notes {
        println!("note: {n}");
    }
    Ok(())
}
