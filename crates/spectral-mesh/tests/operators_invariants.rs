//! Invariants of the operators over every shared real mesh and rescaled copies of it
//! (x1e-8, x1, x1e8), in the manner of libigl's test suite.
//!
//! The folder comes from `SPECTRAL_MESH_SHARED_MESHES`; unset, these tests say they were
//! skipped; set to a missing folder, they fail.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::Mesh;
use spectral_mesh::io::read_mesh;
use spectral_mesh::linalg::{SparseCholesky, dense_generalized_eigen};
use spectral_mesh::operators::{MassKind, cotan_stiffness, mass_matrix, uniform_laplacian};

fn shared_meshes() -> Option<Vec<(String, Mesh)>> {
    let mut out = Vec::new();
    for p in spectral_mesh_testkit::shared_mesh_files(None)? {
        if let Ok(l) = read_mesh(&p) {
            out.push((
                p.file_name().unwrap().to_string_lossy().into_owned(),
                l.mesh,
            ));
        }
    }
    assert!(out.len() >= 15, "only {} shared meshes loaded", out.len());
    Some(out)
}

fn scaled(m: &Mesh, s: f64) -> Mesh {
    m.map_positions(|p| [p[0] * s, p[1] * s, p[2] * s]).unwrap()
}

fn check_invariants(name: &str, mesh: &Mesh) {
    let n = mesh.n_vertices();
    let s = cotan_stiffness(mesh);
    let smax = s.max_abs();
    assert_eq!(s.asymmetry(), 0.0, "{name}: S not bit-symmetric");
    let rows = s.row_sums();
    let worst = rows.iter().fold(0.0f64, |a, r| a.max(r.abs()));
    assert!(
        worst <= 1e-12 * smax,
        "{name}: |S 1| = {worst:e}, max |S| = {smax:e}"
    );
    let u = uniform_laplacian(mesh);
    assert_eq!(u.asymmetry(), 0.0);
    assert!(
        u.row_sums().iter().all(|&r| r == 0.0),
        "{name}: uniform rows"
    );

    let area = mesh.area();
    let fem = mass_matrix(mesh, MassKind::Fem);
    let bary = mass_matrix(mesh, MassKind::Barycentric);
    let mixed = mass_matrix(mesh, MassKind::MixedVoronoi);
    assert_eq!(fem.asymmetry(), 0.0, "{name}: fem mass not bit-symmetric");
    for (kind, b) in [("fem", &fem), ("barycentric", &bary), ("mixed", &mixed)] {
        let total: f64 = b.values().iter().sum();
        assert!(
            (total - area).abs() <= 1e-12 * area,
            "{name}: {kind} mass sums to {total:e}, area {area:e}"
        );
    }
    let row = fem.row_sums();
    let d = bary.diag();
    let dmax = d.iter().fold(0.0f64, |a, v| a.max(*v));
    for i in 0..n {
        assert!(
            (row[i] - d[i]).abs() <= 1e-13 * dmax,
            "{name}: lumped mass differs from FEM row sum at {i}"
        );
    }
    // Positive semi-definite: S + eps B has a Cholesky factorization for a tiny eps
    // (B restricted to referenced vertices; unreferenced ones get a unit diagonal).
    let mut diag_fix = vec![0.0; n];
    for (i, v) in d.iter().enumerate() {
        if *v == 0.0 {
            diag_fix[i] = 1.0;
        }
    }
    let eps = 1e-8 * smax / dmax.max(f64::MIN_POSITIVE);
    let shifted = s.add_scaled(1.0, &bary, eps).add_scaled(
        1.0,
        &spectral_mesh::SparseMatrix::diagonal(&diag_fix),
        smax,
    );
    assert!(
        SparseCholesky::new(&shifted).is_ok(),
        "{name}: S + eps B is not positive definite"
    );
    if n <= 1000 && diag_fix.iter().all(|&v| v == 0.0) {
        let (vals, _) = dense_generalized_eigen(&s, &bary).unwrap();
        let lmax = vals.last().copied().unwrap();
        assert!(
            vals[0] >= -1e-9 * lmax,
            "{name}: smallest eigenvalue {:e} < 0",
            vals[0]
        );
    }
}

#[test]
fn operator_invariants_on_shared_meshes_and_rescaled_copies() {
    let Some(meshes) = shared_meshes() else {
        return;
    };
    for (name, mesh) in &meshes {
        for s in [1e-8, 1.0, 1e8] {
            check_invariants(&format!("{name} x{s:e}"), &scaled(mesh, s));
        }
    }
}

#[test]
fn operators_scale_as_expected() {
    // S is scale-invariant; masses scale with the square of the length scale.
    let Some(meshes) = shared_meshes() else {
        return;
    };
    for (name, mesh) in meshes.iter().take(6) {
        let s1 = cotan_stiffness(mesh);
        let s2 = cotan_stiffness(&scaled(mesh, 1e3));
        let diff = s1.add_scaled(1.0, &s2, -1.0).max_abs();
        assert!(
            diff <= 1e-10 * s1.max_abs(),
            "{name}: S changed under scaling"
        );
        let b1 = mass_matrix(mesh, MassKind::Fem);
        let b2 = mass_matrix(&scaled(mesh, 1e3), MassKind::Fem);
        let diff = b1.add_scaled(1e6, &b2, -1.0).max_abs();
        assert!(
            diff <= 1e-9 * b2.max_abs(),
            "{name}: B did not scale by 1e6"
        );
    }
}
