//! `spectral-mesh perturb MESH --apply noise:0.1 [--apply ...] -o out.off [--map map.txt]`:
//! chained perturbations, with the map of every new vertex back to the original surface.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use spectral_mesh::Mesh;
use spectral_mesh::experiments::study::closest_point_barycentric;
use spectral_mesh::io::{MeshFormat, WriteOptions, write_mesh_to};
use spectral_mesh::mesh::topology::VertexTriangles;
use spectral_mesh::perturb::{SurfaceMap, apply, parse_perturbation};

use crate::input;
use crate::output::check_outputs;
use crate::output::{check_writable, write};

/// Help of `--apply`.
const APPLY_HELP: &str = "A perturbation, applied in the order given (repeatable):
  noise:MAG[,seed=S]                  normal noise, sigma = MAG x mean edge length
  scale:ALPHA                         uniform scaling about the centroid
  localscale:x,y,z,R,ALPHA | localscale:v=I,R,ALPHA
  rotate:axis=x|y|z|a/b/c,angle=DEG[,t=dx/dy/dz] | rotate:DEG
  translate:dx,dy,dz
  resample:FACTOR[,seed=S]            FACTOR x as many vertices on the same surface
  refine:x,y,z,R,LEVELS | refine:v=I,R,LEVELS
  hole:x,y,z,R | hole:v=I,R
  tiny:COUNT[,seed=S]                 tiny triangles
  missing:COUNT[,seed=S]              missing triangles
  bend:DEG[,axis=x|y|z]               near-isometric bend
Vertex centres (v=I) refer to the mesh the step is applied to.";

/// Arguments of `perturb`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// A perturbation (see below); repeat to chain them.
    #[arg(long = "apply", required = true, long_help = APPLY_HELP)]
    pub apply: Vec<String>,
    /// The perturbed mesh: .off, .obj, .ply or .stl (repeatable).
    #[arg(long, short = 'o', required = true)]
    pub out: Vec<PathBuf>,
    /// Write, for each new vertex, its original triangle and barycentric coordinates.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
}

/// A point of the original surface as a combination of original vertices.
type Combo = Vec<(usize, f64)>;

fn add_scaled(acc: &mut Combo, c: &Combo, s: f64) {
    for &(v, w) in c {
        match acc.iter_mut().find(|(u, _)| *u == v) {
            Some(e) => e.1 += s * w,
            None => acc.push((v, s * w)),
        }
    }
}

/// Composes the correspondence so far (`prev`: one combination per vertex of the mesh the
/// step was applied to, `before`) with one step's map.
fn compose(prev: &[Combo], map: &SurfaceMap, before: &Mesh, n_after: usize) -> Result<Vec<Combo>> {
    match map {
        SurfaceMap::Identity => {
            if n_after != prev.len() {
                bail!("identity map between meshes of different sizes");
            }
            Ok(prev.to_vec())
        }
        SurfaceMap::Vertices(v) => v
            .iter()
            .map(|&i| {
                prev.get(i)
                    .cloned()
                    .with_context(|| format!("map names vertex {i}, which does not exist"))
            })
            .collect(),
        SurfaceMap::Barycentric(b) => b
            .iter()
            .map(|&(t, w)| {
                let tri = before
                    .triangles()
                    .get(t)
                    .with_context(|| format!("map names triangle {t}, which does not exist"))?;
                let mut acc = Combo::new();
                for c in 0..3 {
                    add_scaled(&mut acc, &prev[tri[c]], w[c]);
                }
                acc.retain(|(_, w)| *w != 0.0);
                Ok(acc)
            })
            .collect(),
    }
}

/// One line of the map: original triangle and barycentric coordinates; `None` for a
/// point on no triangle (an unreferenced original vertex). The flag says whether the
/// triangle had to be chosen by the closest point (the combination spans several
/// original triangles).
fn to_triangle(
    combo: &Combo,
    original: &Mesh,
    vt: &VertexTriangles,
) -> (Option<(usize, [f64; 3])>, bool) {
    let tris = original.triangles();
    let Some(&(first, _)) = combo.first() else {
        return (None, false);
    };
    // Exact: a triangle holding every vertex of the combination.
    for &t in vt.of(first) {
        let tri = tris[t];
        if combo.iter().all(|(v, _)| tri.contains(v)) {
            let mut b = [0.0; 3];
            for &(v, w) in combo {
                if let Some(c) = tri.iter().position(|u| *u == v) {
                    b[c] += w;
                }
            }
            return (Some((t, b)), false);
        }
    }
    // Approximate: the closest point among the triangles around the combination.
    let pos = original.positions();
    let p: [f64; 3] = std::array::from_fn(|i| combo.iter().map(|&(v, w)| w * pos[v][i]).sum());
    let mut best: Option<(usize, [f64; 3], f64)> = None;
    for &(v, _) in combo {
        for &t in vt.of(v) {
            let [a, b, c] = original.corners(t);
            let (w, d2) = closest_point_barycentric(p, a, b, c);
            if best.as_ref().is_none_or(|x| d2 < x.2) {
                best = Some((t, w, d2));
            }
        }
    }
    (best.map(|(t, w, _)| (t, w)), true)
}

/// Applies the chain and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = input::load(args.mesh.as_deref())?;
    let original = input.mesh("perturb")?;
    let specs = args
        .apply
        .iter()
        .map(|s| parse_perturbation(s).map_err(|e| anyhow::anyhow!("--apply {s}: {e}")))
        .collect::<Result<Vec<_>>>()?;
    check_outputs(&args.out, &["off", "obj", "ply", "stl"], args.force)?;
    if let Some(m) = &args.map {
        check_writable(m, args.force)?;
        if args.out.contains(m) {
            bail!("{}: named both as the mesh and the map", m.display());
        }
    }
    println!(
        "{}: n = {}, m = {}",
        input.label(),
        original.n_vertices(),
        original.n_triangles()
    );
    let mut mesh = original.clone();
    let mut combos: Vec<Combo> = (0..mesh.n_vertices()).map(|v| vec![(v, 1.0)]).collect();
    for (text, spec) in args.apply.iter().zip(&specs) {
        let p = apply(&mesh, spec).map_err(|e| anyhow::anyhow!("--apply {text}: {e}"))?;
        combos = compose(&combos, &p.map, &mesh, p.mesh.n_vertices())
            .with_context(|| format!("--apply {text}: composing the surface map"))?;
        println!(
            "{}: n = {}, m = {}",
            p.description,
            p.mesh.n_vertices(),
            p.mesh.n_triangles()
        );
        mesh = p.mesh;
    }
    // Displacement when every vertex still corresponds to one original vertex.
    if combos
        .iter()
        .all(|c| c.len() == 1 && (c[0].1 - 1.0).abs() < 1e-12)
    {
        let (op, np) = (original.positions(), mesh.positions());
        let disp: Vec<f64> = combos
            .iter()
            .zip(np)
            .map(|(c, q)| spectral_mesh::mesh::norm(spectral_mesh::mesh::sub(*q, op[c[0].0])))
            .collect();
        let max = disp.iter().copied().fold(0.0, f64::max);
        let mean = disp.iter().sum::<f64>() / disp.len().max(1) as f64;
        println!(
            "vertex displacement: mean {mean:.4e}, max {max:.4e} (mean edge length of the input {:.4e})",
            original.mean_edge_length()
        );
    }
    for o in &args.out {
        let format = MeshFormat::from_path(o)
            .with_context(|| format!("{}: unknown mesh format", o.display()))?;
        let mut buf = Vec::new();
        write_mesh_to(
            &mut buf,
            format,
            &mesh,
            &WriteOptions {
                format: Some(format),
                ..Default::default()
            },
        )
        .with_context(|| format!("writing {}", o.display()))?;
        write(o, &buf)?;
        println!("-> {}", o.display());
    }
    if let Some(mp) = &args.map {
        let vt = VertexTriangles::new(original);
        let mut s = String::from(
            "# for each vertex of the perturbed mesh (in order): original triangle, then the barycentric\n\
             # coordinates of the point in the order of that triangle's corners (-1 = on no triangle)\n",
        );
        let (mut approx, mut none) = (0usize, 0usize);
        for c in &combos {
            let (entry, approximate) = to_triangle(c, original, &vt);
            approx += usize::from(approximate);
            match entry {
                Some((t, b)) => s.push_str(&format!("{t} {:?} {:?} {:?}\n", b[0], b[1], b[2])),
                None => {
                    none += 1;
                    s.push_str("-1 0 0 0\n");
                }
            }
        }
        write(mp, s.as_bytes())?;
        println!("map -> {}", mp.display());
        if approx > 0 {
            println!(
                "note: {approx} vertices combine points of several original triangles (chained re-triangulations); their entry is the closest point on the original surface"
            );
        }
        if none > 0 {
            println!("note: {none} vertices correspond to no original triangle (-1)");
        }
    }
    Ok(())
}
