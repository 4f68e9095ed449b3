//! The Harmonic_function experiment's claims on the built-in 3-torus and on every closed
//! shared mesh: Euler's relation m - s + M = chi for the critical points, and the maximum
//! principle where the cotangent weights allow it.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::Mesh;
use spectral_mesh::experiments::harmonic::{HarmonicExperimentParams, harmonic_experiment};
use spectral_mesh::fields::critical_points::critical_points;
use spectral_mesh::fields::harmonic::{ConstraintSpec, HarmonicParams, harmonic_map};
use spectral_mesh::io::read_mesh;
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::operators::cotan_stiffness;
use spectral_mesh::shapes::build_str;

#[test]
fn three_torus_with_two_constraints_has_one_min_one_max_and_six_saddles() {
    let mesh = build_str("3torus").unwrap();
    let topo = Topology::new(&mesh);
    assert_eq!(topo.euler_characteristic(), -4);
    let runs = harmonic_experiment(&mesh, &HarmonicExperimentParams::default()).unwrap();
    assert_eq!(runs.len(), 3);
    let first = &runs[0];
    assert_eq!(first.critical.minima.len(), 1);
    assert_eq!(first.critical.maxima.len(), 1);
    assert_eq!(first.critical.saddle_count(), 6, "2g saddles for g = 3");
    for r in &runs {
        assert_eq!(
            r.euler,
            (-4, -4),
            "m - s + M = chi for {} constraints",
            r.count
        );
    }
    // Extrema of a harmonic map sit on the constraints (maximum principle).
    let cv: Vec<usize> = first.constraints.iter().map(|c| c.vertex).collect();
    assert!(cv.contains(&first.critical.minima[0]));
    assert!(cv.contains(&first.critical.maxima[0]));
}

/// True when every cotangent weight (-S(i,j), i != j) is non-negative.
fn weights_non_negative(mesh: &Mesh) -> bool {
    let s = cotan_stiffness(mesh);
    (0..s.ncols()).all(|c| {
        let (rows, vals) = s.col(c);
        rows.iter().zip(vals).all(|(&r, &v)| r == c || v <= 0.0)
    })
}

#[test]
fn euler_relation_and_maximum_principle_on_closed_shared_meshes() {
    let Some(names) = spectral_mesh_testkit::shared_mesh_files(Some("off")) else {
        return;
    };
    let mut checked = 0;
    let mut negative_weight_meshes = Vec::new();
    for path in names {
        let Ok(loaded) = read_mesh(&path) else {
            continue;
        };
        let mesh = loaded.mesh;
        let topo = Topology::new(&mesh);
        if !topo.is_closed_manifold() || topo.n_components() != 1 || mesh.n_vertices() > 20000 {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let chi = topo.euler_characteristic();
        let constraints = match ConstraintSpec::Extremes(2).resolve(&mesh) {
            Ok(c) => c,
            Err(e) => panic!("{name}: {e}"),
        };
        let f = harmonic_map(&mesh, &constraints, &HarmonicParams::default()).unwrap();
        let cp = critical_points(&mesh, &f).unwrap();
        assert_eq!(cp.euler_check(chi), (chi, chi), "{name}: m - s + M != chi");
        let cv: Vec<usize> = constraints.iter().map(|c| c.vertex).collect();
        // Maximum principle: no extremum away from the constraints, values in [0, 1].
        // Guaranteed when every cotangent weight is non-negative; every closed shared
        // mesh has some negative weights (obtuse pairs), and the principle was observed
        // to hold on all of them anyway, so it is asserted as measured. The test below
        // shows a mesh where negative weights do break it.
        for v in cp.minima.iter().chain(&cp.maxima) {
            assert!(cv.contains(v), "{name}: interior extremum at {v}");
        }
        let (lo, hi) = f
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(
            lo >= -1e-12 && hi <= 1.0 + 1e-12,
            "{name}: range [{lo}, {hi}]"
        );
        if !weights_non_negative(&mesh) {
            negative_weight_meshes.push(name);
        }
        checked += 1;
    }
    eprintln!("meshes with negative cotangent weights: {negative_weight_meshes:?}");
    assert!(checked >= 8, "only {checked} closed shared meshes checked");
}

#[test]
fn negative_cotangent_weights_break_the_maximum_principle() {
    // A flat fan around vertex 0 whose spoke 0-1 sees two nearly straight angles (at 2
    // and 6), so its cotangent weight is strongly negative. With the rim fixed to 0 at
    // vertex 1 and to 1 elsewhere, the harmonic value at the centre leaves [0, 1].
    #[rustfmt::skip]
    let positions = vec![
        [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.05, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0], [0.5, -0.05, 0.0],
    ];
    #[rustfmt::skip]
    let triangles = vec![
        [0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5], [0, 5, 6], [0, 6, 1],
    ];
    let mesh = Mesh::new(positions, triangles).unwrap();
    assert!(!weights_non_negative(&mesh));
    let constraints: Vec<_> = (1..7)
        .map(|v| spectral_mesh::fields::harmonic::Constraint {
            vertex: v,
            value: if v == 1 { 0.0 } else { 1.0 },
        })
        .collect();
    let f = harmonic_map(&mesh, &constraints, &HarmonicParams::default()).unwrap();
    assert!(
        f[0] > 1.0,
        "centre value {} should exceed the rim maximum",
        f[0]
    );
    let cp = critical_points(&mesh, &f).unwrap();
    assert_eq!(
        cp.maxima,
        vec![0],
        "the interior vertex is a spurious maximum"
    );
}
