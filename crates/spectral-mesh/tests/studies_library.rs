//! The truncation and robustness study machinery of `experiments::{truncation, study}`.

#![allow(clippy::unwrap_used)]

use spectral_mesh::Laplacian;
use spectral_mesh::experiments::study::{
    Quantity, StudyMesh, StudyParams, projection_map, resampled_as, run_study,
};
use spectral_mesh::experiments::truncation::{
    TruncationParams, TruncationReference, truncation_study,
};
use spectral_mesh::perturb::{self, SurfaceMap};
use spectral_mesh::shapes::build_str;

#[test]
fn truncation_error_falls_with_k_and_vanishes_with_all_pairs() {
    let mesh = build_str("torus:res=1").unwrap();
    let n = mesh.n_vertices();
    let params = TruncationParams {
        ks: vec![5, 20, 60, usize::MAX],
        reference: TruncationReference::Dense,
        ..TruncationParams::default()
    };
    let r = truncation_study(&mesh, &params, &mut |_| {}).unwrap();
    assert!(r.dense);
    assert_eq!(r.rows.len(), 3 * 3 * 4);
    for lap in [Laplacian::Cot, Laplacian::VoronoiCot, Laplacian::Fem] {
        for &t in &params.times {
            let rows: Vec<_> = r
                .rows
                .iter()
                .filter(|x| x.laplacian == lap && x.t == t)
                .collect();
            assert_eq!(rows.len(), 4);
            let (first, last) = (rows[0], rows[3]);
            assert_eq!(last.k, n);
            assert!(first.linf_relative > 1e-6, "{lap} t={t}: {first:?}");
            assert!(
                last.linf_relative < first.linf_relative,
                "{lap} t={t}: {} !< {}",
                last.linf_relative,
                first.linf_relative
            );
            assert!(last.linf_relative < 1e-10, "{lap} t={t}: {last:?}");
            // Monotone up to rounding for this smooth case.
            assert!(rows[2].linf_relative <= rows[0].linf_relative);
        }
    }
}

#[test]
fn truncation_time_stepping_reference_agrees_with_dense() {
    let mesh = build_str("sphere:res=2").unwrap();
    let base = TruncationParams {
        laplacians: vec![Laplacian::Fem],
        times: vec![0.05],
        ks: vec![10, 40],
        ..TruncationParams::default()
    };
    let with = |reference| TruncationParams {
        reference,
        ..base.clone()
    };
    let study = |p: &TruncationParams| truncation_study(&mesh, p, &mut |_| {}).unwrap();
    let d = study(&with(TruncationReference::Dense));
    let s = study(&with(TruncationReference::TimeStepping { tol: 1e-10 }));
    assert!(!s.dense);
    for (a, b) in d.rows.iter().zip(&s.rows) {
        assert_eq!(a.k, b.k);
        assert!(
            (a.linf_error - b.linf_error).abs() < 1e-6 * a.reference_max + 1e-9 * a.linf_error,
            "{a:?} vs {b:?}"
        );
    }
}

#[test]
fn truncation_refuses_bad_parameters_naming_them() {
    let mesh = build_str("sphere:res=1").unwrap();
    for (p, key) in [
        (
            TruncationParams {
                times: vec![-1.0],
                ..Default::default()
            },
            "t",
        ),
        (
            TruncationParams {
                ks: vec![0],
                ..Default::default()
            },
            "k",
        ),
        (
            TruncationParams {
                anchor: Some(100000),
                ..Default::default()
            },
            "anchor",
        ),
    ] {
        let e = truncation_study(&mesh, &p, &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(key), "{e}");
    }
}

// k = 25 = 1 + 3 + 5 + 7 + 9: whole clusters of the sphere's repeated eigenvalues (a
// cut inside a cluster makes the truncated fields depend on the rotation of the basis
// inside it).
fn small_params() -> StudyParams {
    StudyParams {
        k: 25,
        ..StudyParams::default()
    }
}

#[test]
fn rigid_motion_changes_nothing_and_scaling_changes_no_normalised_eigenvalue() {
    let mesh = build_str("sphere:res=2").unwrap();
    let rot = perturb::apply(
        &mesh,
        &perturb::parse_perturbation("rotate:axis=1/2/3,angle=40,t=0.5/-1/2").unwrap(),
    )
    .unwrap();
    let sc = perturb::apply(&mesh, &perturb::parse_perturbation("scale:3").unwrap()).unwrap();
    let meshes = vec![StudyMesh {
        name: "sphere:res=2".into(),
        mesh,
        perturbations: vec![("rotate".into(), rot), ("scale:3".into(), sc)],
    }];
    let laps = [Laplacian::VoronoiCot, Laplacian::Fem];
    let rows = run_study(&meshes, &laps, &Quantity::ALL, &small_params(), &|_| {}).unwrap();
    assert_eq!(rows.len(), 2 * 2 * Quantity::ALL.len());
    for r in &rows {
        assert!(r.rel_l2 < 1e-8, "{r:?}");
        assert!(r.linf_rel < 1e-8, "{r:?}");
        assert!(r.eig_drift_max < 1e-8, "{r:?}");
        assert_eq!(r.source_original, r.source_perturbed);
    }
}

#[test]
fn noise_gives_growing_differences() {
    let mesh = build_str("sphere:res=2").unwrap();
    let p = |s: &str| {
        (
            s.to_string(),
            perturb::apply(&mesh, &perturb::parse_perturbation(s).unwrap()).unwrap(),
        )
    };
    let meshes = vec![StudyMesh {
        name: "s".into(),
        perturbations: vec![p("noise:0.01,seed=1"), p("noise:0.2,seed=1")],
        mesh: mesh.clone(),
    }];
    let rows = run_study(
        &meshes,
        &[Laplacian::Fem],
        &[Quantity::Heat, Quantity::Biharmonic],
        &small_params(),
        &|_| {},
    )
    .unwrap();
    for q in [Quantity::Heat, Quantity::Biharmonic] {
        let v: Vec<_> = rows.iter().filter(|r| r.quantity == q).collect();
        assert!(v[0].rel_l2 > 0.0 && v[0].rel_l2.is_finite());
        assert!(v[0].rel_l2 < v[1].rel_l2, "{q:?}: {v:?}");
    }
}

#[test]
fn projection_map_recovers_the_vertices_of_a_refinement() {
    // Every vertex of a mesh lies on its own surface: projecting it gives back its
    // position exactly.
    let mesh = build_str("irregular-sphere:res=2").unwrap();
    let map = projection_map(&mesh, &mesh);
    let pts = map.original_points(&mesh, mesh.n_vertices()).unwrap();
    for (a, b) in pts.iter().zip(mesh.positions()) {
        for d in 0..3 {
            assert!((a[d] - b[d]).abs() < 1e-12);
        }
    }
    assert!(matches!(map, SurfaceMap::Barycentric(_)));
    // A different sampling of the sphere maps every vertex within the chord error of the
    // coarse part (an icosahedron's faces).
    let other = build_str("sphere:res=3").unwrap();
    let p = resampled_as(&mesh, other, "sphere:res=3");
    let pts = p.map.original_points(&mesh, p.mesh.n_vertices()).unwrap();
    for (a, b) in pts.iter().zip(p.mesh.positions()) {
        let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        assert!(d < 0.2, "{d}");
    }
}
