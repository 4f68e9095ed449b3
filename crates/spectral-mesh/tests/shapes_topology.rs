//! Topology, orientation, geometry and determinism of every built-in shape.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::Mesh;
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::mesh::{cross, dot, norm, sub};
use spectral_mesh::shapes::{ShapeKind, ShapeSpec, build};

fn min_angle_deg(m: &Mesh) -> f64 {
    let mut best = f64::INFINITY;
    for t in 0..m.n_triangles() {
        let c = m.corners(t);
        for k in 0..3 {
            let u = sub(c[(k + 1) % 3], c[k]);
            let v = sub(c[(k + 2) % 3], c[k]);
            let cos = dot(u, v) / (norm(u) * norm(v));
            best = best.min(cos.clamp(-1.0, 1.0).acos().to_degrees());
        }
    }
    best
}

fn signed_volume(m: &Mesh) -> f64 {
    (0..m.n_triangles())
        .map(|t| {
            let [a, b, c] = m.corners(t);
            dot(a, cross(b, c)) / 6.0
        })
        .sum()
}

fn area_ratio(m: &Mesh) -> f64 {
    let a = m.triangle_areas();
    let max = a.iter().cloned().fold(0.0, f64::max);
    let min = a.iter().cloned().fold(f64::INFINITY, f64::min);
    max / min
}

/// Checks everything a shape promises except vertex counts; returns the mesh.
fn check(spec: &ShapeSpec) -> Mesh {
    let m = build(spec).unwrap();
    let name = spec.to_string();
    let t = Topology::new(&m);
    let want = spec.kind.expected_topology();
    assert_eq!(t.n_components(), 1, "{name}: components");
    assert!(t.unreferenced_vertices.is_empty(), "{name}: unreferenced");
    assert!(
        t.non_manifold_edges.is_empty(),
        "{name}: non-manifold edges"
    );
    assert!(
        t.non_manifold_vertices.is_empty(),
        "{name}: non-manifold vertices"
    );
    assert_eq!(t.inconsistently_oriented_edges, 0, "{name}: orientation");
    assert!(t.orientable, "{name}: orientable");
    assert_eq!(
        t.euler_characteristic(),
        want.euler_characteristic,
        "{name}: chi"
    );
    assert_eq!(t.components[0].genus, Some(want.genus), "{name}: genus");
    assert_eq!(
        t.boundary_loops.len(),
        want.boundary_loops,
        "{name}: boundary loops"
    );
    assert_eq!(
        t.is_closed_manifold(),
        want.boundary_loops == 0,
        "{name}: closed"
    );
    assert!(
        t.edge_face_count.iter().all(|&c| c == 1 || c == 2),
        "{name}"
    );
    // No degenerate triangles: every angle above 3 degrees (5 in most cases, see below).
    let ang = min_angle_deg(&m);
    assert!(ang > 3.0, "{name}: min angle {ang}");
    let areas = m.triangle_areas();
    assert!(areas.iter().all(|&a| a > 0.0), "{name}: zero-area triangle");
    // Outward orientation.
    let normals = m.triangle_normals();
    match spec.kind {
        ShapeKind::Disk => {
            assert!(
                normals.iter().all(|n| n[2] > 0.999_999),
                "{name}: disk normal"
            );
            for p in m.positions() {
                assert_eq!(p[2], 0.0);
                assert!(p[0].hypot(p[1]) <= 1.0 + 1e-15);
            }
            for &v in &t.boundary_vertices() {
                let p = m.positions()[v];
                assert!(
                    (p[0].hypot(p[1]) - 1.0).abs() < 1e-15,
                    "{name}: boundary radius"
                );
            }
        }
        ShapeKind::Cylinder => {
            let (r, h) = (spec.values[0], spec.values[1]);
            for tri in 0..m.n_triangles() {
                let [a, b, c] = m.corners(tri);
                let radial = [a[0] + b[0] + c[0], a[1] + b[1] + c[1], 0.0];
                assert!(dot(normals[tri], radial) > 0.0, "{name}: cylinder inward");
            }
            for p in m.positions() {
                assert!((p[0].hypot(p[1]) - r).abs() < 1e-12 * r, "{name}: radius");
            }
            for l in &t.boundary_loops {
                let z = m.positions()[l[0]][2];
                assert!((z.abs() - 0.5 * h).abs() < 1e-12, "{name}: loop z {z}");
                assert!(
                    l.iter().all(|&v| m.positions()[v][2] == z),
                    "{name}: flat loop"
                );
            }
        }
        _ => {
            let vol = signed_volume(&m);
            assert!(vol > 0.0, "{name}: signed volume {vol}");
        }
    }
    m
}

fn specs(kind: ShapeKind) -> [u32; 2] {
    match kind {
        ShapeKind::Sphere => [2, 3],
        _ => [1, 2],
    }
}

#[test]
fn regular_shapes_have_stated_topology_and_vertex_counts() {
    for kind in ShapeKind::ALL {
        for res in specs(kind) {
            let spec = ShapeSpec::new(kind).with_res(res);
            let m = check(&spec);
            assert_eq!(Some(m.n_vertices()), spec.vertex_count(), "{spec}");
            let ang = min_angle_deg(&m);
            assert!(ang > 5.0, "{spec}: min angle {ang}");
        }
    }
}

#[test]
fn vertex_count_formulas_match_documented_values() {
    #[rustfmt::skip]
    let want = [
        (ShapeKind::ThreeTorus, [96, 396, 1596, 6396, 25596, 102396, 409596]),
        (ShapeKind::DoubleTorus, [72, 294, 1182, 4734, 18942, 75774, 303102]),
        (ShapeKind::Torus, [98, 392, 1568, 6272, 25088, 100352, 401408]),
        (ShapeKind::Sphere, [12, 42, 162, 642, 2562, 10242, 40962]),
        (ShapeKind::UvSphere, [86, 366, 1514, 6162, 24866, 99906, 400514]),
        (ShapeKind::Disk, [127, 469, 1801, 7057, 27937, 111169, 443521]),
        (ShapeKind::Cylinder, [112, 420, 1624, 6384, 25312, 100800, 402304]),
    ];
    for (kind, counts) in want {
        for (res, &c) in counts.iter().enumerate() {
            assert_eq!(kind.vertex_count(res as u32), Some(c), "{kind:?} res {res}");
        }
        assert_eq!(kind.vertex_count(kind.max_res() + 1), None);
    }
    // The formula is what build produces, at res 0 and 3 as well.
    for kind in ShapeKind::ALL {
        for res in [0, 3] {
            let m = build(&ShapeSpec::new(kind).with_res(res)).unwrap();
            assert_eq!(
                Some(m.n_vertices()),
                kind.vertex_count(res),
                "{kind:?} {res}"
            );
        }
    }
}

#[test]
fn irregular_shapes_keep_topology_and_vary_triangle_size() {
    for kind in ShapeKind::ALL {
        let mut last = 0;
        for res in [2, 3] {
            let spec = ShapeSpec::new(kind).with_res(res).with_irregular(true);
            let m = check(&spec);
            assert!(m.n_vertices() > last, "{spec}: grows with res");
            last = m.n_vertices();
            let ratio = area_ratio(&m);
            let regular = area_ratio(&build(&spec.clone().with_irregular(false)).unwrap());
            if res >= 3 {
                assert!(ratio > 50.0, "{spec}: area ratio {ratio}");
            }
            assert!(
                ratio > 4.0 * regular,
                "{spec}: {ratio} vs regular {regular}"
            );
            // The uv-sphere inherits thin pole fans; the subdivision surfaces use curved
            // edges on a coarse base: both stay above 4.5 degrees; the others above 10.
            let ang = min_angle_deg(&m);
            let floor = match kind {
                ShapeKind::UvSphere | ShapeKind::ThreeTorus | ShapeKind::DoubleTorus => 4.5,
                _ => 10.0,
            };
            assert!(ang > floor, "{spec}: min angle {ang}");
        }
    }
}

#[test]
fn sphere_vertices_are_on_the_unit_sphere() {
    for spec in [
        ShapeSpec::new(ShapeKind::Sphere).with_res(4),
        ShapeSpec::new(ShapeKind::Sphere)
            .with_res(4)
            .with_irregular(true),
        ShapeSpec::new(ShapeKind::UvSphere).with_res(2),
        ShapeSpec::new(ShapeKind::UvSphere)
            .with_res(3)
            .with_irregular(true),
    ] {
        let m = build(&spec).unwrap();
        let worst = m
            .positions()
            .iter()
            .map(|&p| (norm(p) - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-15, "{spec}: |r - 1| = {worst}");
    }
}

#[test]
fn torus_vertices_are_on_the_torus() {
    for (res, irregular, big_r, small_r) in [(2, false, 1.0, 0.4), (3, true, 2.0, 0.5)] {
        let mut spec = ShapeSpec::new(ShapeKind::Torus)
            .with_res(res)
            .with_irregular(irregular);
        spec.values = vec![big_r, small_r];
        let m = check(&spec);
        for p in m.positions() {
            let d = (p[0].hypot(p[1]) - big_r).hypot(p[2]);
            assert!(
                (d - small_r).abs() < 1e-12,
                "{spec}: off the torus by {}",
                d - small_r
            );
        }
    }
}

#[test]
fn smooth_genus_surfaces_are_smooth_and_converge() {
    for kind in [ShapeKind::ThreeTorus, ShapeKind::DoubleTorus] {
        // Adjacent triangles bend by little: the surface is smooth at this resolution.
        let m = build(&ShapeSpec::new(kind).with_res(3)).unwrap();
        let t = Topology::new(&m);
        let n = m.triangle_normals();
        let mut edge_tris: std::collections::HashMap<[usize; 2], Vec<usize>> =
            std::collections::HashMap::new();
        for (i, tri) in m.triangles().iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                edge_tris.entry([a.min(b), a.max(b)]).or_default().push(i);
            }
        }
        assert_eq!(edge_tris.len(), t.edges.len());
        let worst = edge_tris
            .values()
            .map(|ts| dot(n[ts[0]], n[ts[1]]).clamp(-1.0, 1.0).acos().to_degrees())
            .fold(0.0, f64::max);
        assert!(worst < 20.0, "{kind:?}: dihedral bend {worst} degrees");
        // Limit positions: the volume changes little between levels.
        let v2 = signed_volume(&build(&ShapeSpec::new(kind).with_res(2)).unwrap());
        let v3 = signed_volume(&m);
        assert!((v2 - v3).abs() < 0.01 * v3, "{kind:?}: volume {v2} vs {v3}");
    }
}

#[test]
fn building_twice_is_bit_identical() {
    for kind in ShapeKind::ALL {
        for irregular in [false, true] {
            let spec = ShapeSpec::new(kind).with_res(2).with_irregular(irregular);
            let (p1, t1) = build(&spec).unwrap().into_parts();
            let (p2, t2) = build(&spec).unwrap().into_parts();
            assert_eq!(t1, t2, "{spec}");
            let bits = |p: &[[f64; 3]]| -> Vec<u64> {
                p.iter().flat_map(|q| q.map(f64::to_bits)).collect()
            };
            assert_eq!(bits(&p1), bits(&p2), "{spec}");
        }
    }
}
