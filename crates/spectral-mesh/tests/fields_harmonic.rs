//! Harmonic and bi-harmonic maps: maximum principle, topology of the critical points,
//! linear precision, solver reuse, scale invariance, locality and errors.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod fields_util;
mod spectral_util;

use fields_util::{flat_square, icosphere, torus, union};
use spectral_mesh::fields::critical_points::critical_points;
use spectral_mesh::fields::harmonic::{
    Constraint, ConstraintSpec, FloatingComponent, HarmonicError, HarmonicParams, HarmonicSolver,
    harmonic_map, max_change_near, vertex_adjacency,
};
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::operators::cotan_stiffness;
use spectral_mesh::{Laplacian, Mesh, Operators};
use spectral_util::max_diff;

fn params(order: u32, laplacian: Laplacian) -> HarmonicParams {
    HarmonicParams { order, laplacian }
}

/// The constraint `f(vertex) = value`.
fn fixed(vertex: usize, value: f64) -> Constraint {
    Constraint { vertex, value }
}

#[test]
fn maximum_principle_on_a_torus_with_nonnegative_cot_weights() {
    let m = torus(3.0, 1.0, 48, 16);
    // Precondition: every off-diagonal entry of S is <= 0 (cot weights >= 0).
    let s = cotan_stiffness(&m);
    for c in 0..s.ncols() {
        let (rows, vals) = s.col(c);
        for (&r, &v) in rows.iter().zip(vals) {
            assert!(r == c || v <= 1e-14, "negative cot weight on ({r}, {c})");
        }
    }
    for k in [2, 4, 6] {
        let cons = ConstraintSpec::Extremes(k).resolve(&m).unwrap();
        let f = harmonic_map(&m, &cons, &HarmonicParams::default()).unwrap();
        let (lo, hi) = f
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert_eq!(lo, 0.0);
        assert_eq!(hi, 1.0);
        // No free vertex is a local extremum.
        let cp = critical_points(&m, &f).unwrap();
        let is_con = |v: usize| cons.iter().any(|c| c.vertex == v);
        for &v in cp.minima.iter().chain(&cp.maxima) {
            assert!(is_con(v), "k={k}: free vertex {v} is an extremum");
        }
        // Euler: torus chi = 0.
        let (sum, chi) = cp.euler_check(0);
        assert_eq!(sum, chi, "k={k}: {cp:?}");
    }
}

#[test]
fn torus_with_two_constraints_has_two_saddles() {
    let m = torus(3.0, 1.0, 48, 16);
    let cons = ConstraintSpec::Extremes(2).resolve(&m).unwrap();
    for lap in [Laplacian::Fem, Laplacian::Cot] {
        for order in [1, 2] {
            let f = harmonic_map(&m, &cons, &params(order, lap)).unwrap();
            let cp = critical_points(&m, &f).unwrap();
            if order == 1 {
                assert_eq!(cp.minima, vec![cons[0].vertex]);
                assert_eq!(cp.maxima, vec![cons[1].vertex]);
                assert_eq!(cp.saddle_count(), 2, "{cp:?}");
            }
            let (sum, chi) = cp.euler_check(0);
            assert_eq!(sum, chi);
        }
    }
}

#[test]
fn linear_precision_on_an_irregular_flat_patch() {
    let (m, boundary) = flat_square(12, 0.3, 7);
    let lin = |p: [f64; 3]| 0.7 * p[0] - 1.3 * p[1] + 0.25;
    let exact: Vec<f64> = m.positions().iter().map(|&p| lin(p)).collect();
    let on_boundary: Vec<Constraint> = boundary.iter().map(|&v| fixed(v, exact[v])).collect();
    for lap in Laplacian::ALL {
        if lap == Laplacian::Uniform {
            continue; // the graph Laplacian has no linear precision on irregular meshes
        }
        let f = harmonic_map(&m, &on_boundary, &params(1, lap)).unwrap();
        let err = max_diff(&f, &exact);
        assert!(err < 1e-10, "{lap}: harmonic error {err}");
    }
    // Bi-harmonic: boundary plus its first ring fixed reproduces linear functions (S f = 0
    // at every non-boundary vertex, so Q f = 0 two rings in), for every lumped mass.
    let adj = vertex_adjacency(&m);
    let mut ring: Vec<usize> = boundary.clone();
    for &b in &boundary {
        ring.extend(&adj[b]);
    }
    ring.sort_unstable();
    ring.dedup();
    let two: Vec<Constraint> = ring.iter().map(|&v| fixed(v, exact[v])).collect();
    for lap in [
        Laplacian::Fem,
        Laplacian::VoronoiCot,
        Laplacian::MixedVoronoi,
        Laplacian::Cot,
    ] {
        let f = harmonic_map(&m, &two, &params(2, lap)).unwrap();
        let err = max_diff(&f, &exact);
        assert!(err < 1e-10, "{lap}: bi-harmonic error {err}");
        // With the boundary alone, the natural boundary condition of the bi-harmonic
        // energy is not satisfied by a linear function: no linear precision.
        let g = harmonic_map(&m, &on_boundary, &params(2, lap)).unwrap();
        let err_b = max_diff(&g, &exact);
        assert!(
            err_b > 1e-6,
            "{lap}: boundary-only bi-harmonic unexpectedly exact"
        );
    }
}

#[test]
fn solver_reuse_is_linear_and_reproduces_constants() {
    let m = icosphere(2);
    let cons = ConstraintSpec::Extremes(6).resolve(&m).unwrap();
    let verts: Vec<usize> = cons.iter().map(|c| c.vertex).collect();
    for order in [1, 2] {
        let p = params(order, Laplacian::MixedVoronoi);
        let solver = HarmonicSolver::new(&m, &verts, &p).unwrap();
        let vi = solver.constrained_vertices().to_vec();
        let a: Vec<f64> = (0..vi.len()).map(|k| k as f64).collect();
        let b: Vec<f64> = (0..vi.len()).map(|k| 1.0 - k as f64).collect();
        let fa = solver.solve(&a).unwrap();
        let fb = solver.solve(&b).unwrap();
        // a + b = 1 at every constraint: the sum is the constant 1.
        for (x, y) in fa.iter().zip(&fb) {
            assert!((x + y - 1.0).abs() < 1e-10);
        }
        // Same as the one-shot function.
        let cs: Vec<Constraint> = vi
            .iter()
            .zip(&a)
            .map(|(&vertex, &value)| Constraint { vertex, value })
            .collect();
        let f1 = harmonic_map(&m, &cs, &p).unwrap();
        let d = max_diff(&f1, &fa);
        assert!(d < 1e-12);
        // solve_many = columns of solve.
        let mut ab = a.clone();
        ab.extend(&b);
        let many = solver.solve_many(&ab, 2).unwrap();
        assert_eq!(&many[..m.n_vertices()], &fa[..]);
        assert!(matches!(
            solver.solve(&a[1..]),
            Err(HarmonicError::ValueCount { .. })
        ));
    }
}

#[test]
fn scale_invariance() {
    let m = torus(3.0, 1.0, 32, 12);
    let cons = ConstraintSpec::Extremes(4).resolve(&m).unwrap();
    for order in [1, 2] {
        for lap in [Laplacian::Fem, Laplacian::MixedVoronoi] {
            let f = harmonic_map(&m, &cons, &params(order, lap)).unwrap();
            for s in [1e-8, 1e8] {
                let ms = m.map_positions(|p| [p[0] * s, p[1] * s, p[2] * s]).unwrap();
                let g = harmonic_map(&ms, &cons, &params(order, lap)).unwrap();
                let d = max_diff(&f, &g);
                assert!(d < 1e-9, "order {order} {lap} scale {s}: {d}");
            }
        }
    }
}

#[test]
fn locality_of_added_constraints() {
    let m = torus(3.0, 1.0, 48, 16);
    let c2 = ConstraintSpec::Extremes(2).resolve(&m).unwrap();
    let c4 = ConstraintSpec::Extremes(4).resolve(&m).unwrap();
    let p = HarmonicParams::default();
    let f2 = harmonic_map(&m, &c2, &p).unwrap();
    let f4 = harmonic_map(&m, &c4, &p).unwrap();
    let seeds: Vec<usize> = c2.iter().map(|c| c.vertex).collect();
    assert_eq!(max_change_near(&m, &f2, &f4, &seeds, 0), 0.0);
    let near = max_change_near(&m, &f2, &f4, &seeds, 1);
    let far = max_change_near(&m, &f2, &f4, &seeds, 100);
    assert!(near > 0.0 && near < far, "near {near}, far {far}");
    // The largest change over everything is the global max |f4 - f2|.
    let global = max_diff(&f2, &f4);
    assert_eq!(far, global);
}

#[test]
fn unconstrained_component_floats_at_the_mean_and_is_named() {
    let a = torus(3.0, 1.0, 24, 8);
    let b = icosphere(1);
    let m = union(&a, &b, [20.0, 0.0, 0.0]);
    let topo = Topology::new(&m);
    assert_eq!(topo.n_components(), 2);
    let cons = vec![fixed(0, 0.0), fixed(5, 1.0)];
    let f = harmonic_map(&m, &cons, &HarmonicParams::default()).unwrap();
    // The constrained torus is solved; the sphere holds the mean of the values, 0.5.
    let na = a.n_vertices();
    assert!(f[na..].iter().all(|&v| v == 0.5), "{:?}", &f[na..na + 4]);
    assert!(f[..na].iter().any(|&v| v != 0.5));
    let on_torus = harmonic_map(&a, &cons, &HarmonicParams::default()).unwrap();
    assert_eq!(&f[..na], &on_torus[..]);
    let solver =
        HarmonicSolver::with_operators(&m, &Operators::new(&m, Laplacian::Fem), &[0, 5], 1)
            .unwrap();
    let want_comp = topo.vertex_component[na];
    assert_eq!(
        solver.floating_components(),
        &[FloatingComponent {
            component: want_comp,
            first_vertex: na,
            vertices: b.n_vertices(),
        }]
    );
}

#[test]
fn unreferenced_vertices_get_zero_and_cannot_be_constrained() {
    let (m, _) = flat_square(5, 0.0, 1);
    let (mut p, t) = m.into_parts();
    p.push([5.0, 5.0, 5.0]);
    let m = Mesh::new(p, t).unwrap();
    let extra = m.n_vertices() - 1;
    let cons = ConstraintSpec::Extremes(2).resolve(&m).unwrap();
    assert!(cons.iter().all(|c| c.vertex != extra));
    let f = harmonic_map(&m, &cons, &HarmonicParams::default()).unwrap();
    assert_eq!(f[extra], 0.0);
    let bad = vec![fixed(extra, 1.0), cons[0]];
    assert!(matches!(
        harmonic_map(&m, &bad, &HarmonicParams::default()),
        Err(HarmonicError::UnreferencedConstraint { .. })
    ));
}

#[test]
fn degenerate_free_vertex_is_reported() {
    // A square whose centre vertex only has zero-area (collinear) triangles hanging off it.
    #[rustfmt::skip]
    let p = vec![
        [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0],
        [2.0, 0.0, 0.0], // collinear with 0 and 1
    ];
    let t = vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]];
    let m = Mesh::new(p, t).unwrap();
    let cons = vec![fixed(0, 0.0), fixed(2, 1.0)];
    let e = harmonic_map(&m, &cons, &HarmonicParams::default()).unwrap_err();
    assert!(
        matches!(e, HarmonicError::DegenerateVertex { vertex: 4 }),
        "{e}"
    );
}
