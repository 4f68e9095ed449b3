//! `spectral-mesh info MESH|SHAPE [--repair] [--json]`.

use anyhow::Result;
use spectral_mesh::mesh::validate::report;

use crate::input;

/// Arguments of `info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
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

/// Prints counts, topology and problems.
pub fn run(args: Args) -> Result<()> {
    let input = input::load_repaired(args.mesh.as_deref(), args.repair)?;
    let r = report(&input.mesh);
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
