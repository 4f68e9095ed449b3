//! Mesh validation and repair (`mesh::validate::report` and `repair`) on small meshes
//! drawn from the input: coarse integer coordinates (coincident points, zero-area and
//! duplicate triangles, pinched vertices, non-manifold edges, flipped triangles are all
//! common) at scales from 1e-300 to 1e300. `repair` either fails cleanly (every triangle
//! removed) or returns a mesh whose report shows none of the problems it promises to fix,
//! with a vertex map that points at the same positions.

use arbitrary::{Arbitrary, Unstructured};
use spectral_mesh::mesh::validate::{RepairOptions, repair, report};

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let mut u = Unstructured::new(data);
    let Ok(switches) = u8::arbitrary(&mut u) else {
        return;
    };
    let Some(mesh) = crate::arbitrary_mesh(&mut u, 64) else {
        return;
    };
    let before = report(&mesh);
    assert_eq!(before.vertices, mesh.n_vertices());
    assert_eq!(before.faces, mesh.n_triangles());
    assert!(before.components >= 1);
    let opts = RepairOptions {
        remove_duplicate_faces: switches & 1 != 0,
        remove_degenerate_faces: switches & 2 != 0,
        split_non_manifold_vertices: switches & 4 != 0,
        orient_consistently: switches & 8 != 0,
        remove_unreferenced_vertices: switches & 16 != 0,
    };
    let Ok(fixed) = repair(&mesh, &opts) else {
        return;
    };
    crate::check_mesh(&fixed.mesh);
    let after = report(&fixed.mesh);
    assert_eq!(fixed.vertex_map.len(), mesh.n_vertices());
    for (v, m) in fixed.vertex_map.iter().enumerate() {
        if let Some(w) = *m {
            assert_eq!(
                mesh.positions()[v].map(f64::to_bits),
                fixed.mesh.positions()[w].map(f64::to_bits),
                "vertex {v} maps to {w} at another position"
            );
        }
    }
    let ctx = format!(
        "options {opts:?}, before {:?}, after {:?}",
        before.problems(),
        after.problems()
    );
    if opts.remove_duplicate_faces {
        assert!(after.duplicate_faces.is_empty(), "duplicates left: {ctx}");
    }
    if opts.remove_degenerate_faces {
        assert!(
            after.degenerate_faces.is_empty(),
            "degenerate triangles left: {ctx}"
        );
    }
    if opts.split_non_manifold_vertices {
        assert!(
            after.non_manifold_vertices.is_empty(),
            "pinched vertices left: {ctx}"
        );
    }
    if opts.remove_unreferenced_vertices {
        assert!(
            after.unreferenced_vertices.is_empty(),
            "unreferenced vertices left: {ctx}"
        );
    }
    if opts.orient_consistently && after.orientable {
        assert_eq!(
            after.inconsistently_oriented_edges, 0,
            "orientation left: {ctx}"
        );
    }
    // Repairing again with the same options changes nothing more.
    let twice = repair(&fixed.mesh, &opts).expect("a repaired mesh repairs again");
    assert_eq!(twice.mesh, fixed.mesh, "repair is not idempotent: {ctx}");
}
