//! Critical points of piecewise-linear fields: height functions and the Euler identities,
//! on closed and bordered surfaces, and with several components.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod fields_util;

use fields_util::{Rng, flat_square, icosphere, torus, union};
use spectral_mesh::fields::critical_points::{BoundaryRule, critical_points, critical_points_with};
use spectral_mesh::fields::harmonic::{ConstraintSpec, HarmonicParams, harmonic_map};
use spectral_mesh::mesh::topology::Topology;

#[test]
fn height_on_a_sphere_has_one_min_one_max() {
    let m = icosphere(3);
    for axis in 0..3 {
        let f: Vec<f64> = m.positions().iter().map(|p| p[axis]).collect();
        let cp = critical_points(&m, &f).unwrap();
        assert_eq!(cp.minima.len(), 1);
        assert_eq!(cp.maxima.len(), 1);
        assert!(cp.saddles.is_empty());
        let lo = (0..f.len()).min_by(|&a, &b| f[a].total_cmp(&f[b])).unwrap();
        assert_eq!(cp.minima[0], lo);
        assert_eq!(cp.euler_check(2), (2, 2));
    }
}

#[test]
fn height_on_a_torus_satisfies_euler() {
    let m = torus(3.0, 1.0, 40, 16);
    // Along an axis in the torus plane: min, max and two saddles on the inner circle.
    let f: Vec<f64> = m.positions().iter().map(|p| p[0]).collect();
    let cp = critical_points(&m, &f).unwrap();
    assert_eq!(cp.euler_check(0), (0, 0));
    assert!(!cp.minima.is_empty() && !cp.maxima.is_empty());
    assert!(cp.saddle_count() >= 2);
    // Along the axis of the torus: z has circles of extrema, broken by index into
    // min/max plus saddles; Euler still holds.
    let g: Vec<f64> = m.positions().iter().map(|p| p[2]).collect();
    assert_eq!(critical_points(&m, &g).unwrap().euler_check(0), (0, 0));
}

#[test]
fn random_fields_satisfy_euler_on_closed_surfaces() {
    let mut rng = Rng(11);
    let sphere = icosphere(2);
    let tor = torus(3.0, 1.0, 24, 10);
    let two = union(&sphere, &tor, [10.0, 0.0, 0.0]);
    for (m, chi) in [(&sphere, 2), (&tor, 0), (&two, 2)] {
        assert_eq!(Topology::new(m).euler_characteristic(), chi);
        for _ in 0..5 {
            let f: Vec<f64> = (0..m.n_vertices()).map(|_| rng.next()).collect();
            let cp = critical_points(m, &f).unwrap();
            assert!(cp.minima.len() > 3 && !cp.saddles.is_empty());
            let (s, c) = cp.euler_check(chi);
            assert_eq!(s, c);
            assert!(cp.on_boundary.is_empty() && cp.non_manifold.is_empty());
        }
        // Quantized values: many ties, broken by index.
        let f: Vec<f64> = (0..m.n_vertices())
            .map(|_| (rng.next() * 3.0).floor())
            .collect();
        let cp = critical_points(m, &f).unwrap();
        assert_eq!(cp.euler_check(chi).0, chi);
    }
}

#[test]
fn boundary_aware_counts_on_a_disk() {
    let (m, _) = flat_square(10, 0.25, 3);
    let chi = Topology::new(&m).euler_characteristic();
    assert_eq!(chi, 1);
    let mut rng = Rng(5);
    for _ in 0..10 {
        let f: Vec<f64> = (0..m.n_vertices()).map(|_| rng.next()).collect();
        let d = critical_points(&m, &f).unwrap();
        assert_eq!(d.boundary_rule, BoundaryRule::Double);
        let (s, c) = d.euler_check_doubled(chi);
        assert_eq!(s, c, "doubled count");
        let l = critical_points_with(&m, &f, BoundaryRule::LowerLink).unwrap();
        let (s, c) = l.euler_check(chi);
        assert_eq!(s, c, "lower-link count");
    }
    // A harmonic map with 2 constraints on the disk: one min, one max (both on the
    // boundary), no saddle -- the doubled surface is a sphere.
    let cons = ConstraintSpec::Extremes(2).resolve(&m).unwrap();
    let f = harmonic_map(&m, &cons, &HarmonicParams::default()).unwrap();
    let cp = critical_points(&m, &f).unwrap();
    assert_eq!(cp.minima, vec![cons[0].vertex]);
    assert_eq!(cp.maxima, vec![cons[1].vertex]);
    assert!(cp.saddles.is_empty());
    assert_eq!(cp.euler_check_doubled(1), (2, 2));
}

#[test]
fn non_manifold_vertices_are_listed_and_classified_conservatively() {
    // Two spheres glued at one vertex (a pinch): vertex 0 of the second is merged into
    // vertex 0 of the first after translating the second so the two points coincide.
    let a = icosphere(1);
    let pa = a.positions()[0];
    let b = a
        .map_positions(|q| [2.0 * pa[0] - q[0], 2.0 * pa[1] - q[1], 2.0 * pa[2] - q[2]])
        .unwrap();
    let n = a.n_vertices();
    let mut p = a.positions().to_vec();
    p.extend(b.positions().iter().skip(1));
    let remap = |v: usize| if v == 0 { 0 } else { v + n - 1 };
    let mut t = a.triangles().to_vec();
    t.extend(b.triangles().iter().map(|tri| tri.map(remap)));
    let m = spectral_mesh::Mesh::new(p, t).unwrap();
    // Distance from the pinch: the pinch is the unique minimum, no vertex is missed.
    let f: Vec<f64> = m
        .positions()
        .iter()
        .map(|q| ((q[0] - pa[0]).powi(2) + (q[1] - pa[1]).powi(2) + (q[2] - pa[2]).powi(2)).sqrt())
        .collect();
    let cp = critical_points(&m, &f).unwrap();
    assert_eq!(cp.non_manifold, vec![0]);
    assert_eq!(cp.minima, vec![0]);
    assert_eq!(cp.maxima.len(), 2, "{cp:?}");
    // A non-manifold edge (three triangles on edge 0-1) does not panic and is reported.
    let m3 = spectral_mesh::Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    )
    .unwrap();
    let cp3 = critical_points(&m3, &[0.0, 1.0, 2.0, 3.0, 4.0]).unwrap();
    assert!(cp3.non_manifold.contains(&0) && cp3.non_manifold.contains(&1));
    assert_eq!(cp3.minima, vec![0]);
}
