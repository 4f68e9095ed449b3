//! Perturbations of the shared real meshes (`SPECTRAL_MESH_SHARED_MESHES`, see the
//! testkit crate): the re-triangulations keep the topology of imperfect inputs and every
//! new vertex on the surface.

#![allow(clippy::unwrap_used)]

use std::time::Instant;

use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::mesh::{Mesh, norm, sub};
use spectral_mesh::perturb::{self, SurfaceMap};

/// A shared mesh, read by the library's reader.
fn read_off(path: &std::path::Path) -> Mesh {
    spectral_mesh::io::read_mesh(path).unwrap().mesh
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
    let Some(dir) = spectral_mesh_testkit::shared_meshes() else {
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
        assert!(path.is_file(), "{} is missing", path.display());
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
