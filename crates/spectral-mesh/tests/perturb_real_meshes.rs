//! Perturbations of the project's real meshes (`/work/shared/meshes`, or the folder named
//! by `SPECTRAL_MESH_MESHES`): the re-triangulations keep the topology of imperfect
//! inputs and every new vertex on the surface. Skipped when the folder is absent.

#![allow(clippy::unwrap_used)]

use std::path::PathBuf;
use std::time::Instant;

use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::mesh::{Mesh, norm, sub};
use spectral_mesh::perturb::{self, SurfaceMap};

fn meshes_dir() -> Option<PathBuf> {
    let d = std::env::var_os("SPECTRAL_MESH_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/work/shared/meshes"));
    d.is_dir().then_some(d)
}

/// Minimal OFF reader for triangle-only files (enough for these tests).
fn read_off(path: &std::path::Path) -> Mesh {
    let text = std::fs::read_to_string(path).unwrap();
    let mut tokens = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or(""))
        .flat_map(str::split_whitespace);
    assert!(tokens.next().unwrap().ends_with("OFF"));
    let nv: usize = tokens.next().unwrap().parse().unwrap();
    let nf: usize = tokens.next().unwrap().parse().unwrap();
    let _ne = tokens.next();
    let mut p = Vec::with_capacity(nv);
    for _ in 0..nv {
        let x: Vec<f64> = (0..3)
            .map(|_| tokens.next().unwrap().parse().unwrap())
            .collect();
        p.push([x[0], x[1], x[2]]);
    }
    let mut f = Vec::with_capacity(nf);
    for _ in 0..nf {
        let k: usize = tokens.next().unwrap().parse().unwrap();
        assert_eq!(k, 3, "triangle meshes only");
        let t: Vec<usize> = (0..3)
            .map(|_| tokens.next().unwrap().parse().unwrap())
            .collect();
        f.push([t[0], t[1], t[2]]);
    }
    Mesh::new(p, f).unwrap()
}

fn signature(t: &Topology) -> (usize, usize, i64, usize, usize, usize) {
    (
        t.n_components(),
        t.boundary_loops.len(),
        t.euler_characteristic(),
        t.non_manifold_edges.len(),
        t.non_manifold_vertices.len(),
        t.inconsistently_oriented_edges,
    )
}

fn max_off_surface(orig: &Mesh, p: &perturb::Perturbed) -> f64 {
    let pts = p.map.original_points(orig, p.mesh.n_vertices()).unwrap();
    pts.iter()
        .zip(p.mesh.positions())
        .map(|(a, b)| norm(sub(*a, *b)))
        .fold(0.0, f64::max)
        / orig.diagonal()
}

#[test]
fn retriangulations_of_real_meshes_keep_topology_and_surface() {
    let Some(dir) = meshes_dir() else {
        eprintln!("meshes folder not found; skipped");
        return;
    };
    for name in [
        "elephant-with-holes.off",
        "blobby_3cc.off",
        "fandisk.off",
        "cylinder_locally_refined.off",
        "knot1.off",
    ] {
        let path = dir.join(name);
        if !path.is_file() {
            continue;
        }
        let m = read_off(&path);
        let sig = signature(&Topology::new(&m));
        let start = Instant::now();
        let r = perturb::resample(&m, 2 * m.n_vertices(), 1).unwrap();
        let t_resample = start.elapsed();
        assert_eq!(r.mesh.n_vertices(), 2 * m.n_vertices());
        assert_eq!(signature(&Topology::new(&r.mesh)), sig, "{name} resample");
        let off = max_off_surface(&m, &r);
        assert!(off < 1e-12, "{name}: {off}");
        let tiny = perturb::tiny_triangles(&m, 100, 2).unwrap();
        assert_eq!(signature(&Topology::new(&tiny.mesh)), sig, "{name} tiny");
        assert!(max_off_surface(&m, &tiny) < 1e-12);
        let c = m.positions()[0];
        let refined = perturb::refine_locally(&m, c, 0.1 * m.diagonal(), 2).unwrap();
        assert_eq!(
            signature(&Topology::new(&refined.mesh)),
            sig,
            "{name} refine"
        );
        assert!(refined.mesh.n_vertices() > m.n_vertices());
        assert!(max_off_surface(&m, &refined) < 1e-12);
        let h = perturb::hole(&m, c, 0.1 * m.diagonal()).unwrap();
        let ht = Topology::new(&h.mesh);
        assert!(h.mesh.n_triangles() < m.n_triangles());
        if sig.1 == 0 {
            assert!(
                !ht.boundary_loops.is_empty(),
                "{name}: hole made no boundary"
            );
        }
        assert!(ht.non_manifold_vertices.len() <= sig.4);
        assert!(matches!(h.map, SurfaceMap::Vertices(_)));
        eprintln!(
            "{name}: n = {}, resample x2 in {:?}, refine 2 levels +{} vertices",
            m.n_vertices(),
            t_resample,
            refined.mesh.n_vertices() - m.n_vertices()
        );
    }
}
