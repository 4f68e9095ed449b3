//! Properties of the mesh perturbations: magnitudes, invariances, surface preservation,
//! topology, exact pull-back of linear functions and determinism.

// Test helpers (not `#[test]` functions themselves) unwrap freely.
#![allow(clippy::unwrap_used)]

use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::mesh::{Mesh, dot, norm, sub};
use spectral_mesh::operators::MassKind;
use spectral_mesh::perturb::{self, PerturbError, Perturbed, ResampleMode, SurfaceMap};
use spectral_mesh::{Eigenbasis, Laplacian, Operators, SparseMatrix};

/// The built-in unit icosphere with `level` subdivisions (10 * 4^level + 2 vertices).
fn icosphere(level: usize) -> Mesh {
    spectral_mesh::shapes::build_str(&format!("sphere:res={level}")).unwrap()
}

/// A flat `nx x ny` grid of `[0, lx] x [0, ly]` in the plane z = 0 (open, one boundary loop),
/// with alternating diagonals.
fn grid(nx: usize, ny: usize, lx: f64, ly: f64) -> Mesh {
    let mut p = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            p.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64, 0.0]);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut f = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            let pair = if (i + j) % 2 == 0 {
                [[a, b, c], [a, c, d]]
            } else {
                [[a, b, d], [b, c, d]]
            };
            f.extend(pair);
        }
    }
    Mesh::new(p, f).unwrap()
}

fn max_abs_diff(a: &SparseMatrix, b: &SparseMatrix) -> f64 {
    let n = a.nrows();
    let mut m = 0.0f64;
    for c in 0..n {
        let (rows, vals) = a.col(c);
        for (&r, &v) in rows.iter().zip(vals) {
            m = m.max((v - b.get(r, c)).abs());
        }
        let (rows, vals) = b.col(c);
        for (&r, &v) in rows.iter().zip(vals) {
            m = m.max((v - a.get(r, c)).abs());
        }
    }
    m
}

/// Checks the barycentric map of a re-triangulation: coordinates in [0, 1] summing to 1,
/// every vertex on the original triangle it names, original vertices unmoved.
fn assert_on_surface(orig: &Mesh, p: &Perturbed) {
    let SurfaceMap::Barycentric(map) = &p.map else {
        panic!("expected a barycentric map");
    };
    assert_eq!(map.len(), p.mesh.n_vertices());
    let diag = orig.diagonal();
    for (v, &(t, b)) in map.iter().enumerate() {
        assert!(t < orig.n_triangles());
        assert!(
            b.iter().all(|&x| (0.0..=1.0).contains(&x)),
            "vertex {v}: {b:?}"
        );
        assert!(
            (b.iter().sum::<f64>() - 1.0).abs() < 1e-12,
            "vertex {v}: {b:?}"
        );
        let [a, bb, c] = orig.corners(t);
        let q = [
            b[0] * a[0] + b[1] * bb[0] + b[2] * c[0],
            b[0] * a[1] + b[1] * bb[1] + b[2] * c[1],
            b[0] * a[2] + b[1] * bb[2] + b[2] * c[2],
        ];
        let d = norm(sub(p.mesh.positions()[v], q));
        assert!(
            d < 1e-12 * diag,
            "vertex {v} is {d} off its original triangle"
        );
        // Also independently: distance to the triangle itself.
        let dt = perturb::remesh::point_triangle_distance(p.mesh.positions()[v], a, bb, c);
        assert!(
            dt < 1e-12 * diag,
            "vertex {v}: distance {dt} to triangle {t}"
        );
    }
    for v in 0..orig.n_vertices() {
        assert_eq!(p.mesh.positions()[v], orig.positions()[v]);
    }
}

fn assert_closed_manifold_like(orig: &Mesh, m: &Mesh) {
    let a = Topology::new(orig);
    let b = Topology::new(m);
    assert!(b.non_manifold_edges.is_empty());
    assert!(b.non_manifold_vertices.is_empty());
    assert_eq!(b.inconsistently_oriented_edges, 0);
    assert!(b.unreferenced_vertices.is_empty());
    assert_eq!(a.is_closed_manifold(), b.is_closed_manifold());
    assert_eq!(a.boundary_loops.len(), b.boundary_loops.len());
    assert_eq!(a.euler_characteristic(), b.euler_characteristic());
    assert_eq!(a.n_components(), b.n_components());
}

fn linear(p: [f64; 3]) -> f64 {
    2.0 * p[0] - 3.0 * p[1] + 0.5 * p[2] + 1.0
}

fn assert_linear_pull_back_exact(orig: &Mesh, p: &Perturbed) {
    let f: Vec<f64> = orig.positions().iter().map(|&q| linear(q)).collect();
    let g = p.map.pull_back(&f, orig).unwrap();
    assert_eq!(g.len(), p.mesh.n_vertices());
    for (v, &x) in g.iter().enumerate() {
        let exact = linear(p.mesh.positions()[v]);
        assert!((x - exact).abs() < 1e-12, "vertex {v}: {x} vs {exact}");
    }
}

fn normal_displacement_std(m: &Mesh, p: &Mesh) -> (f64, f64) {
    let normals = m.vertex_normals();
    let mut s2 = 0.0;
    let mut tangential = 0.0f64;
    for ((a, b), n) in m.positions().iter().zip(p.positions()).zip(&normals) {
        let d = sub(*b, *a);
        let z = dot(d, *n);
        s2 += z * z;
        tangential = tangential.max(norm([d[0] - z * n[0], d[1] - z * n[1], d[2] - z * n[2]]));
    }
    ((s2 / m.n_vertices() as f64).sqrt(), tangential)
}

#[test]
fn noise_has_the_requested_magnitude() {
    let m = icosphere(4); // 2562 vertices
    assert_eq!(m.n_vertices(), 2562);
    let h = m.mean_edge_length();
    for (mag, seed) in [(0.1, 1), (0.5, 2)] {
        let p = perturb::noise(&m, mag, seed).unwrap();
        assert_eq!(p.map, SurfaceMap::Identity);
        assert_eq!(p.mesh.triangles(), m.triangles());
        let (std, tangential) = normal_displacement_std(&m, &p.mesh);
        let target = mag * h;
        assert!(
            (std / target - 1.0).abs() < 0.1,
            "std {std} vs target {target}"
        );
        assert!(tangential < 1e-12, "tangential displacement {tangential}");
    }
    // Zero noise is the identity.
    let p = perturb::noise(&m, 0.0, 3).unwrap();
    assert_eq!(p.mesh, m);
    assert!(perturb::noise(&m, -0.1, 3).is_err());
    assert!(perturb::noise(&m, f64::NAN, 3).is_err());
}

#[test]
fn scaling_divides_eigenvalues_by_alpha_squared() {
    let m = perturb::noise(&icosphere(2), 0.2, 5).unwrap().mesh; // 162 vertices, no symmetry
    let alpha = 2.5;
    let p = perturb::scale(&m, alpha).unwrap();
    assert!((p.mesh.area() / m.area() - alpha * alpha).abs() < 1e-12 * alpha * alpha);
    let e0 = Eigenbasis::dense(&Operators::new(&m, Laplacian::Fem), 30).unwrap();
    let e1 = Eigenbasis::dense(&Operators::new(&p.mesh, Laplacian::Fem), 30).unwrap();
    let lmax = e0.values[29];
    for (a, b) in e0.values.iter().zip(&e1.values) {
        let err = (b * alpha * alpha - a).abs();
        assert!(err <= 1e-10 * a.abs().max(1e-3 * lmax), "{a} vs {b}");
    }
    // Local scaling: points outside the ball do not move; inside, the radial law holds.
    let c = m.positions()[0];
    let r = 0.5;
    let q = perturb::local_scale(&m, c, r, 1.5).unwrap();
    let mut moved = 0;
    for (a, b) in m.positions().iter().zip(q.mesh.positions()) {
        let d = norm(sub(*a, c));
        if d >= r {
            assert_eq!(a, b);
        } else {
            let x = d / r;
            let w = (1.0 - x * x).powi(3);
            let expect = d * (1.0 + 0.5 * w);
            assert!((norm(sub(*b, c)) - expect).abs() < 1e-12);
            moved += usize::from(d > 0.0);
        }
    }
    assert!(moved > 5);
    assert!(perturb::scale(&m, 0.0).is_err());
    assert!(perturb::local_scale(&m, c, r, 3.0).is_err());
}

#[test]
fn rigid_motion_changes_no_operator_entry() {
    let m = perturb::noise(&icosphere(2), 0.2, 7).unwrap().mesh;
    let p = perturb::rigid_motion(&m, [1.0, -2.0, 0.5], 1.234, [3.0, -1.0, 2.0]).unwrap();
    // It did move.
    assert!(norm(sub(p.mesh.positions()[0], m.positions()[0])) > 0.1);
    // Edge lengths are preserved.
    for tri in m.triangles() {
        let (a, b) = (tri[0], tri[1]);
        let l0 = norm(sub(m.positions()[a], m.positions()[b]));
        let l1 = norm(sub(p.mesh.positions()[a], p.mesh.positions()[b]));
        assert!((l0 - l1).abs() < 1e-12 * l0);
    }
    let o0 = Operators::new(&m, Laplacian::Fem);
    let o1 = Operators::new(&p.mesh, Laplacian::Fem);
    assert!(max_abs_diff(&o0.stiffness, &o1.stiffness) <= 1e-12 * o0.stiffness.max_abs());
    assert!(max_abs_diff(&o0.mass, &o1.mass) <= 1e-12 * o0.mass.max_abs());
    // Hence no field changes: the eigenvectors (distinct eigenvalues, fixed signs) agree.
    let e0 = Eigenbasis::dense(&o0, 6).unwrap();
    let e1 = Eigenbasis::dense(&o1, 6).unwrap();
    for j in 1..6 {
        let d =
            perturb::compare_fields(&p.mesh, e0.vector(j), e1.vector(j), MassKind::Fem).unwrap();
        assert!(d.rel_l2 < 1e-8, "eigenvector {j}: {d:?}");
    }
    assert!(perturb::rigid_motion(&m, [0.0; 3], 1.0, [0.0; 3]).is_err());
}

#[test]
fn resample_stays_on_the_surface_and_hits_the_target() {
    let m = icosphere(2); // 162 vertices
    for (target, seed, mode) in [
        (324, 5, ResampleMode::AreaWeighted),
        (1000, 6, ResampleMode::AreaWeighted),
        (162, 7, ResampleMode::AreaWeighted),
        (324, 5, ResampleMode::Irregular),
        (1000, 6, ResampleMode::Irregular),
    ] {
        let p = perturb::resample_with(&m, target, seed, mode).unwrap();
        assert_eq!(p.mesh.n_vertices(), target);
        // Closed genus-0 surface: F = 2V - 4.
        assert_eq!(p.mesh.n_triangles(), 2 * target - 4);
        assert_on_surface(&m, &p);
        assert_closed_manifold_like(&m, &p.mesh);
        assert_linear_pull_back_exact(&m, &p);
        // No degenerate triangle was created.
        let amin = p
            .mesh
            .triangle_areas()
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        assert!(
            amin > 1e-4 * m.area() / m.n_triangles() as f64,
            "min area {amin}"
        );
    }
    // An open surface keeps its single boundary loop; boundary vertices stay on it.
    let g = grid(8, 5, 2.0, 1.0);
    let p = perturb::resample(&g, 2 * g.n_vertices(), 11).unwrap();
    assert_eq!(p.mesh.n_vertices(), 2 * g.n_vertices());
    assert_on_surface(&g, &p);
    assert_closed_manifold_like(&g, &p.mesh);
    assert_linear_pull_back_exact(&g, &p);
    let topo = Topology::new(&p.mesh);
    let perimeter: f64 = topo.boundary_loops[0]
        .windows(2)
        .map(|w| norm(sub(p.mesh.positions()[w[0]], p.mesh.positions()[w[1]])))
        .sum::<f64>()
        + {
            let l = &topo.boundary_loops[0];
            norm(sub(
                p.mesh.positions()[l[0]],
                p.mesh.positions()[l[l.len() - 1]],
            ))
        };
    assert!((perimeter - 6.0).abs() < 1e-12);
    // Area-weighted picking keeps the sampling far more even than picking by index (the
    // largest to smallest triangle area of one sampling of 648 points, seed 3: 61 against
    // 243 on the built-in icosphere).
    let spread = |mode| {
        let p = perturb::resample_with(&m, 4 * m.n_vertices(), 3, mode).unwrap();
        let a = p.mesh.triangle_areas();
        let max = a.iter().copied().fold(0.0, f64::max);
        max / a.iter().copied().fold(f64::INFINITY, f64::min)
    };
    let (even, irregular) = (
        spread(ResampleMode::AreaWeighted),
        spread(ResampleMode::Irregular),
    );
    assert!(
        even < 100.0 && irregular > 3.0 * even,
        "{even} vs {irregular}"
    );
    assert!(matches!(
        perturb::resample(&m, 100, 1),
        Err(PerturbError::InvalidParameter { .. })
    ));
}

#[test]
fn refine_locally_adds_vertices_in_the_ball() {
    let m = icosphere(2);
    let c = m.positions()[5];
    let r = 0.4;
    let inside = |mesh: &Mesh| {
        mesh.positions()
            .iter()
            .filter(|&&q| norm(sub(q, c)) < r)
            .count()
    };
    let n_in = inside(&m);
    let p1 = perturb::refine_locally(&m, c, r, 1).unwrap();
    let p2 = perturb::refine_locally(&m, c, r, 2).unwrap();
    for p in [&p1, &p2] {
        assert_on_surface(&m, p);
        assert_closed_manifold_like(&m, &p.mesh);
        assert_linear_pull_back_exact(&m, p);
    }
    let (i1, i2) = (inside(&p1.mesh), inside(&p2.mesh));
    assert!(i1 as f64 >= 1.8 * n_in as f64, "{n_in} -> {i1}");
    assert!(i2 as f64 >= 1.8 * i1 as f64, "{i1} -> {i2}");
    // Far from the ball nothing changes: the vertices added lie near it.
    for q in &p2.mesh.positions()[m.n_vertices()..] {
        assert!(norm(sub(*q, c)) < r + 3.0 * m.mean_edge_length());
    }
    let p0 = perturb::refine_locally(&m, c, r, 0).unwrap();
    assert_eq!(p0.mesh.n_vertices(), m.n_vertices());
    assert!(perturb::refine_locally(&m, c, -1.0, 1).is_err());
}

#[test]
fn tiny_triangles_are_tiny_but_not_degenerate() {
    let m = icosphere(3);
    let count = 60;
    let p = perturb::tiny_triangles(&m, count, 3).unwrap();
    assert_eq!(p.mesh.n_vertices(), m.n_vertices() + count);
    assert_eq!(p.mesh.n_triangles(), m.n_triangles() + 2 * count);
    assert_on_surface(&m, &p);
    assert_closed_manifold_like(&m, &p.mesh);
    assert_linear_pull_back_exact(&m, &p);
    let a0 = m.triangle_areas().into_iter().fold(f64::INFINITY, f64::min);
    let areas = p.mesh.triangle_areas();
    let amin = areas.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(amin > 0.0);
    assert!(amin < 0.01 * a0, "smallest area {amin} vs original {a0}");
    let tiny = areas.iter().filter(|&&a| a < 0.01 * a0).count();
    assert!(tiny >= count, "{tiny} tiny triangles");
    assert!((p.mesh.area() - m.area()).abs() < 1e-12 * m.area());
    assert!(perturb::tiny_triangles(&m, m.n_triangles() + 1, 0).is_err());
}

#[test]
fn missing_triangles_open_separate_small_holes() {
    let m = icosphere(3);
    let p = perturb::missing_triangles(&m, 20, 4).unwrap();
    assert_eq!(p.map, SurfaceMap::Identity);
    assert_eq!(p.mesh.n_vertices(), m.n_vertices());
    assert_eq!(p.mesh.n_triangles(), m.n_triangles() - 20);
    let t = Topology::new(&p.mesh);
    assert_eq!(t.boundary_loops.len(), 20);
    assert!(t.boundary_loops.iter().all(|l| l.len() == 3));
    assert!(t.non_manifold_vertices.is_empty());
    assert!(t.unreferenced_vertices.is_empty());
    assert_eq!(t.n_components(), 1);
    // Asking for too many removes what it can and says so.
    let q = perturb::missing_triangles(&icosphere(0), 20, 4).unwrap();
    assert!(q.mesh.n_triangles() < 20);
    assert!(q.description.contains("only"));
}

#[test]
fn hole_creates_one_boundary_loop() {
    let m = icosphere(3);
    let c = m.positions()[0];
    let p = perturb::hole(&m, c, 0.35).unwrap();
    let t = Topology::new(&p.mesh);
    assert_eq!(t.boundary_loops.len(), 1);
    assert!(t.non_manifold_vertices.is_empty());
    assert!(t.non_manifold_edges.is_empty());
    assert!(t.unreferenced_vertices.is_empty());
    assert_eq!(t.euler_characteristic(), 1); // a disc
    assert!(p.mesh.n_vertices() < m.n_vertices());
    let SurfaceMap::Vertices(old) = &p.map else {
        panic!("expected a vertex map");
    };
    assert_eq!(old.len(), p.mesh.n_vertices());
    for (i, &v) in old.iter().enumerate() {
        assert_eq!(p.mesh.positions()[i], m.positions()[v]);
        assert!(norm(sub(m.positions()[v], c)) > 0.2);
    }
    // Boundary vertices are near the sphere of the cut.
    for &v in &t.boundary_vertices() {
        let d = norm(sub(p.mesh.positions()[v], c));
        assert!(d > 0.2 && d < 0.35 + 2.0 * m.mean_edge_length(), "{d}");
    }
    assert_linear_pull_back_exact(&m, &p);
    assert!(matches!(
        perturb::hole(&m, c, 10.0),
        Err(PerturbError::EmptyResult)
    ));
}

#[test]
fn bend_rolls_a_flat_strip_onto_a_cylinder() {
    let g = grid(40, 4, 10.0, 1.0);
    let angle = std::f64::consts::FRAC_PI_2;
    let p = perturb::bend(&g, None, angle).unwrap();
    // The strip (x in [0, 10], flat in z) rolls onto a cylinder of radius R = L / angle
    // about the line x = 5, z = R (parallel to y), with arc length along x preserved.
    let r = 10.0 / angle;
    for (a, b) in g.positions().iter().zip(p.mesh.positions()) {
        let (dx, dz) = (b[0] - 5.0, b[2] - r);
        assert!(((dx * dx + dz * dz).sqrt() - r).abs() < 1e-12 * r);
        let phi = dx.atan2(-dz);
        assert!((phi * r - (a[0] - 5.0)).abs() < 1e-12 * r, "arc length");
        assert_eq!(a[1], b[1]);
    }
    // Edge lengths change only by the chord-vs-arc factor, 1 - (h/R)^2/24 + ...
    let h = 0.25;
    let bound = (h / r) * (h / r) / 24.0 * 1.01;
    for tri in g.triangles() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let l0 = norm(sub(g.positions()[a], g.positions()[b]));
            let l1 = norm(sub(p.mesh.positions()[a], p.mesh.positions()[b]));
            assert!(
                l1 <= l0 * (1.0 + 1e-12) && l1 >= l0 * (1.0 - bound),
                "{l0} vs {l1}"
            );
        }
    }
    // Hence the operators change at the same (second) order only.
    let o0 = Operators::new(&g, Laplacian::Fem);
    let o1 = Operators::new(&p.mesh, Laplacian::Fem);
    assert!(max_abs_diff(&o0.stiffness, &o1.stiffness) <= 1e-3 * o0.stiffness.max_abs());
    assert!(max_abs_diff(&o0.mass, &o1.mass) <= 1e-3 * o0.mass.max_abs());
    // The two ends now point at right angles.
    let first = sub(p.mesh.positions()[1], p.mesh.positions()[0]);
    let last = sub(p.mesh.positions()[40], p.mesh.positions()[39]);
    let cos = dot(first, last) / (norm(first) * norm(last));
    assert!(cos.abs() < 0.05, "cos {cos}");
    // The chord between the ends of the mid line is R sqrt(2).
    let chord = norm(sub(p.mesh.positions()[40], p.mesh.positions()[0]));
    assert!((chord - r * 2f64.sqrt()).abs() < 1e-9);
    assert!(perturb::bend(&g, Some(3), 1.0).is_err());
    assert!(perturb::bend(&g, None, 7.0).is_err());
    assert_eq!(perturb::bend(&g, None, 0.0).unwrap().mesh, g);
}

#[test]
fn same_seed_same_mesh_bit_for_bit() {
    let m = icosphere(2);
    let bits = |p: &Perturbed| -> Vec<u64> {
        p.mesh
            .positions()
            .iter()
            .flat_map(|q| q.iter().map(|x| x.to_bits()))
            .collect()
    };
    type Op = fn(&Mesh, u64) -> Perturbed;
    let ops: [Op; 5] = [
        |m, s| perturb::noise(m, 0.3, s).unwrap(),
        |m, s| perturb::resample(m, 500, s).unwrap(),
        |m, s| perturb::resample_with(m, 500, s, ResampleMode::Irregular).unwrap(),
        |m, s| perturb::tiny_triangles(m, 30, s).unwrap(),
        |m, s| perturb::missing_triangles(m, 10, s).unwrap(),
    ];
    for op in ops {
        let (a, b, c) = (op(&m, 42), op(&m, 42), op(&m, 43));
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a.mesh.triangles(), b.mesh.triangles());
        assert_eq!(a.map, b.map);
        assert!(bits(&a) != bits(&c) || a.mesh.triangles() != c.mesh.triangles());
    }
}

#[test]
fn compare_fields_measures_relative_differences() {
    let m = icosphere(2);
    let a: Vec<f64> = m.positions().iter().map(|&q| linear(q)).collect();
    let same = perturb::compare_fields(&m, &a, &a, MassKind::Fem).unwrap();
    assert_eq!(same.rel_l2, 0.0);
    assert_eq!(same.linf_rel, 0.0);
    let twice: Vec<f64> = a.iter().map(|x| 2.0 * x).collect();
    for kind in [MassKind::Fem, MassKind::Barycentric, MassKind::Identity] {
        let d = perturb::compare_fields(&m, &a, &twice, kind).unwrap();
        assert!((d.rel_l2 - 1.0).abs() < 1e-12);
        assert!((d.linf_rel - 1.0).abs() < 1e-12);
    }
    assert!(matches!(
        perturb::compare_fields(&m, &a, &a[1..], MassKind::Fem),
        Err(PerturbError::FieldLength { .. })
    ));
}

#[test]
fn specs_apply() {
    let m = icosphere(2);
    let p = perturb::apply(
        &m,
        &perturb::parse_perturbation("resample:2,seed=1").unwrap(),
    )
    .unwrap();
    assert_eq!(p.mesh.n_vertices(), 2 * m.n_vertices());
    let p = perturb::apply(&m, &perturb::parse_perturbation("hole:v=0,0.3").unwrap()).unwrap();
    assert_eq!(Topology::new(&p.mesh).boundary_loops.len(), 1);
    let p = perturb::apply(
        &m,
        &perturb::parse_perturbation("refine:v=3,0.3,1").unwrap(),
    )
    .unwrap();
    assert!(p.mesh.n_vertices() > m.n_vertices());
    let p = perturb::apply(
        &m,
        &perturb::parse_perturbation("rotate:axis=z,angle=90").unwrap(),
    )
    .unwrap();
    let (a, b) = (m.positions()[0], p.mesh.positions()[0]);
    assert!(
        (b[0] + a[1]).abs() < 1e-12 && (b[1] - a[0]).abs() < 1e-12 && (b[2] - a[2]).abs() < 1e-15
    );
    let p = perturb::apply(&m, &perturb::parse_perturbation("scale:2").unwrap()).unwrap();
    assert!((p.mesh.area() - 4.0 * m.area()).abs() < 1e-10);
    assert!(
        perturb::apply(
            &m,
            &perturb::parse_perturbation("hole:v=100000,0.3").unwrap()
        )
        .is_err()
    );
    assert!(perturb::apply(&m, &perturb::parse_perturbation("resample:0.5").unwrap()).is_err());
    for s in [
        "noise:0.1",
        "tiny:10",
        "missing:5",
        "bend:30",
        "translate:1,2,3",
        "localscale:v=1,0.3,1.2",
    ] {
        let spec = perturb::parse_perturbation(s).unwrap();
        let p = perturb::apply(&m, &spec).unwrap();
        assert!(!p.description.is_empty());
    }
}
