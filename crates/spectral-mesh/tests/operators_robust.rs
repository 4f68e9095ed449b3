//! The robust Laplacian (tufted cover, mollification, intrinsic Delaunay) and the
//! point-cloud Laplacian: invariants on generated non-manifold and degenerate inputs,
//! agreement with the cotangent Laplacian where they must agree, analytic spectra of the
//! sphere (mesh and random points), and every shared point cloud.
//!
//! Shared clouds come from the `points` folder next to `SPECTRAL_MESH_SHARED_MESHES`;
//! unset, those tests say they were skipped.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::SparseMatrix;
use spectral_mesh::mesh::{Mesh, PointCloud};
use spectral_mesh::operators::{
    Laplacian, MassKind, Operators, PointCloudParams, RobustLaplacian, RobustParams, TriangleUnion,
    cotan_stiffness, mass_matrix, point_cloud_laplacian, robust_laplacian,
};
use spectral_mesh::perturb::rng::Rng;
use spectral_mesh::shapes::build_str;
use spectral_mesh::spectral::eigenbasis::{EigenParams, Eigenbasis, compute_eigenbasis};

/// Checks S symmetric to the bit, S 1 = 0, off-diagonal <= `offdiag_max * max|S|`, mass
/// finite, > 0 exactly on the vertices `tris` uses (every vertex when `tris` is `None`).
/// Returns the total mass.
fn check(
    name: &str,
    n: usize,
    tris: Option<&[[usize; 3]]>,
    s: &SparseMatrix,
    b: &SparseMatrix,
    offdiag_max: f64,
) -> f64 {
    assert_eq!(s.nrows(), n);
    assert_eq!(s.asymmetry(), 0.0, "{name}: S not bit-symmetric");
    let smax = s.max_abs();
    let worst = s.row_sums().iter().fold(0.0f64, |a, r| a.max(r.abs()));
    assert!(
        worst <= 1e-12 * smax,
        "{name}: |S 1| = {worst:e}, max |S| = {smax:e}"
    );
    for c in 0..n {
        let (rows, vals) = s.col(c);
        for (&r, &v) in rows.iter().zip(vals) {
            assert!(v.is_finite(), "{name}: S({r},{c}) = {v}");
            if r != c {
                assert!(v <= offdiag_max * smax, "{name}: S({r},{c}) = {v:e} > 0");
            } else {
                assert!(v >= 0.0, "{name}: S({r},{r}) = {v}");
            }
        }
    }
    assert!(b.is_diagonal(), "{name}: B not diagonal");
    let mut used = vec![tris.is_none(); n];
    for t in tris.unwrap_or(&[]) {
        for &v in t {
            used[v] = true;
        }
    }
    let d = b.diag();
    for i in 0..n {
        assert!(d[i].is_finite());
        if used[i] {
            assert!(d[i] > 0.0, "{name}: mass {i} = {}", d[i]);
        } else {
            assert_eq!(d[i], 0.0, "{name}: unreferenced vertex {i} has mass");
            assert_eq!(s.col(i).1.iter().map(|v| v.abs()).sum::<f64>(), 0.0);
        }
    }
    d.iter().sum()
}

/// Three quads sharing the edge 0-1 (a non-manifold "book" of three pages).
fn three_sheets() -> Mesh {
    let mut p = vec![[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let mut t = Vec::new();
    for ang in [0.0f64, 2.0, 4.1] {
        let (c, s) = (ang.cos(), ang.sin());
        let a = p.len();
        p.extend([[c, s, 0.0], [c, s, 1.0], [2.0 * c, 2.0 * s, 0.5]]);
        t.extend([[0, 1, a], [1, a + 1, a], [a, a + 1, a + 2]]);
    }
    Mesh::new(p, t).unwrap()
}

/// Two closed cones whose apexes touch at vertex 0 (a pinched, non-manifold vertex).
fn two_cones() -> Mesh {
    let mut p = vec![[0.0, 0.0, 0.0]];
    let mut t = Vec::new();
    for sgn in [1.0f64, -1.0] {
        let base = p.len();
        let k = 7;
        for i in 0..k {
            let a = 2.0 * std::f64::consts::PI * i as f64 / k as f64;
            p.push([a.cos(), a.sin(), sgn]);
        }
        let cap = p.len();
        p.push([0.0, 0.0, sgn]);
        for i in 0..k {
            let (u, v) = (base + i, base + (i + 1) % k);
            t.push([0, u, v]);
            t.push([cap, v, u]);
        }
    }
    Mesh::new(p, t).unwrap()
}

/// A small sheet with a duplicated triangle (twice, once reversed), zero-area triangles
/// (collinear corners) and an unreferenced vertex.
fn duplicates_and_slivers() -> Mesh {
    #[rustfmt::skip]
    let p = vec![
        [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.2], [2.0, 0.0, 0.0],
        [0.5, 0.0, 0.0], [1.5, 0.0, 0.0], [9.0, 9.0, 9.0],
    ];
    #[rustfmt::skip]
    let t = vec![
        [0, 1, 2], [1, 3, 2], [1, 2, 3], [0, 1, 2], [1, 4, 3], [0, 5, 1], [1, 6, 4], [5, 6, 1],
    ];
    Mesh::new(p, t).unwrap()
}

#[test]
fn generated_nonmanifold_and_degenerate_inputs_satisfy_the_invariants() {
    for (name, mesh) in [
        ("three sheets", three_sheets()),
        ("two cones", two_cones()),
        ("duplicates and slivers", duplicates_and_slivers()),
    ] {
        let n = mesh.n_vertices();
        let r = robust_laplacian(&mesh, &RobustParams::default()).unwrap();
        let total = check(name, n, Some(mesh.triangles()), &r.stiffness, &r.mass, 1e-6);
        // Tufted-cover convention: every input triangle counts once per occurrence (a
        // duplicate twice), with its mollified area (edge lengths + epsilon).
        let eps = r.stats.mollify_epsilon;
        let area: f64 = (0..mesh.n_triangles())
            .map(|t| {
                let c = mesh.corners(t);
                let l = |i: usize, j: usize| {
                    let d = [c[i][0] - c[j][0], c[i][1] - c[j][1], c[i][2] - c[j][2]];
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() + eps
                };
                let (a, b, e) = (l(0, 1), l(1, 2), l(2, 0));
                let s = 0.5 * (a + b + e);
                (s * (s - a) * (s - b) * (s - e)).max(0.0).sqrt()
            })
            .sum();
        let rel = (total - area).abs() / area;
        assert!(
            rel < 1e-12,
            "{name}: total mass {total} against area {area}"
        );
        if eps == 0.0 {
            let plain: f64 = mesh.triangle_areas().iter().sum();
            assert!((total - plain).abs() < 1e-12 * plain, "{name}");
        }
        // A strict Delaunay test: no off-diagonal entry above rounding.
        let strict = robust_laplacian(
            &mesh,
            &RobustParams {
                delaunay_tolerance: 0.0,
                ..Default::default()
            },
        )
        .unwrap();
        check(
            name,
            n,
            Some(mesh.triangles()),
            &strict.stiffness,
            &strict.mass,
            1e-14,
        );
        // The pencil is regular on referenced vertices: as many zero eigenvalues as
        // components.
        assert_eq!(
            r.stats.unreferenced_vertices,
            usize::from(name == "duplicates and slivers")
        );
    }
    let r = robust_laplacian(&three_sheets(), &RobustParams::default()).unwrap();
    assert_eq!(r.stats.non_manifold_edges, 1);
    let r = robust_laplacian(&duplicates_and_slivers(), &RobustParams::default()).unwrap();
    assert!(r.stats.mollify_epsilon > 0.0, "slivers must be mollified");
}

#[test]
fn non_manifold_inputs_give_the_right_number_of_zero_eigenvalues() {
    // The book and the cones are connected: one zero eigenvalue, then positive ones.
    for mesh in [three_sheets(), two_cones()] {
        let ops = Operators::new(&mesh, Laplacian::Robust);
        let basis = eigenbasis(&ops, 4);
        assert!(basis.values[0].abs() < 1e-9, "{:?}", basis.values);
        assert!(basis.values[1] > 1e-3, "{:?}", basis.values);
    }
}

/// The robust pair `r` is the cotangent stiffness and barycentric lumped mass of `mesh`, to
/// `tol` of their largest entries.
fn assert_cot_and_lumped_mass(r: &RobustLaplacian, mesh: &Mesh, tol: f64) {
    let s = cotan_stiffness(mesh);
    let b = mass_matrix(mesh, MassKind::Barycentric);
    let ds = r.stiffness.add_scaled(1.0, &s, -1.0).max_abs();
    let db = r.mass.add_scaled(1.0, &b, -1.0).max_abs();
    assert!(ds <= tol * s.max_abs(), "S differs by {ds:e}");
    assert!(db <= tol * b.max_abs(), "B differs by {db:e}");
}

/// `k` pairs, the method chosen by the library.
fn eigenbasis(ops: &Operators, k: usize) -> Eigenbasis {
    compute_eigenbasis(
        ops,
        &EigenParams {
            k,
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap()
}

#[test]
fn robust_equals_cot_with_lumped_mass_on_a_delaunay_manifold_mesh() {
    // An icosphere: acute triangles, intrinsically Delaunay, no slivers. Nothing flips,
    // nothing is mollified, and the pair is the cotangent stiffness with the barycentric
    // lumped mass (Voronoi-cot).
    let mesh = build_str("sphere:res=2").unwrap();
    let r = robust_laplacian(&mesh, &RobustParams::default()).unwrap();
    assert_eq!(r.stats.flips, 0);
    assert_eq!(r.stats.mollify_epsilon, 0.0);
    assert_cot_and_lumped_mass(&r, &mesh, 1e-13);
    // A quadrilateral split along its long diagonal, both opposite angles obtuse (negative
    // cotangent weight): the robust pair is the cotangent pair of the other split.
    #[rustfmt::skip]
    let p = vec![
        [0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.2, 0.0], [1.0, -0.2, 0.0],
    ];
    let bad = Mesh::new(p.clone(), vec![[0, 1, 2], [1, 0, 3]]).unwrap();
    let good = Mesh::new(p, vec![[0, 3, 2], [1, 2, 3]]).unwrap();
    assert!(cotan_stiffness(&bad).get(0, 1) > 0.0);
    let r = robust_laplacian(&bad, &RobustParams::default()).unwrap();
    assert!(r.stats.flips > 0);
    assert_cot_and_lumped_mass(&r, &good, 1e-12);
    check("quad", 4, Some(bad.triangles()), &r.stiffness, &r.mass, 0.0);
}

#[test]
fn robust_is_scale_covariant() {
    let mesh = two_cones();
    let r1 = robust_laplacian(&mesh, &RobustParams::default()).unwrap();
    for s in [1e-8, 1e8] {
        let m = mesh
            .map_positions(|p| [p[0] * s, p[1] * s, p[2] * s])
            .unwrap();
        let r = robust_laplacian(&m, &RobustParams::default()).unwrap();
        let ds = r.stiffness.add_scaled(1.0, &r1.stiffness, -1.0).max_abs();
        assert!(
            ds <= 1e-12 * r1.stiffness.max_abs(),
            "x{s}: S changed by {ds:e}"
        );
        let db = r.mass.add_scaled(1.0 / (s * s), &r1.mass, -1.0).max_abs();
        assert!(db <= 1e-12 * r1.mass.max_abs(), "x{s}: B changed by {db:e}");
    }
}

/// Largest relative error of eigenvalues 1..=24 against l(l+1) for each l = 1..=4, after
/// checking that the zero eigenvalue is alone.
fn sphere_errors(ops: &Operators) -> [f64; 4] {
    let basis = eigenbasis(ops, 25);
    let v = &basis.values;
    assert!(v[0].abs() < 1e-8, "{v:?}");
    let mut out = [0.0; 4];
    let mut i = 1;
    for l in 1..=4usize {
        let want = (l * (l + 1)) as f64;
        for _ in 0..2 * l + 1 {
            out[l - 1] = f64::max(out[l - 1], (v[i] - want).abs() / want);
            i += 1;
        }
    }
    // Multiplicities: the gap after each multiplet is far larger than its spread.
    assert!(
        v[4] > 1.5 * v[3] && v[9] > 1.5 * v[8] && v[16] > 1.4 * v[15],
        "{v:?}"
    );
    out
}

#[test]
fn unit_sphere_mesh_gives_l_l_plus_1_converging() {
    let coarse = sphere_errors(&Operators::new(
        &build_str("sphere:res=3").unwrap(),
        Laplacian::Robust,
    ));
    let fine = sphere_errors(&Operators::new(
        &build_str("sphere:res=4").unwrap(),
        Laplacian::Robust,
    ));
    for l in 0..4 {
        assert!(fine[l] < coarse[l], "l = {}: {coarse:?} -> {fine:?}", l + 1);
        assert!(fine[l] < 1e-2, "l = {}: {fine:?}", l + 1);
    }
}

fn random_sphere(n: usize, seed: u64) -> PointCloud {
    let mut rng = Rng::new(seed);
    let p = (0..n)
        .map(|_| {
            loop {
                let v = [rng.normal(), rng.normal(), rng.normal()];
                let r = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if r > 1e-9 {
                    break [v[0] / r, v[1] / r, v[2] / r];
                }
            }
        })
        .collect();
    PointCloud::new(p, None).unwrap()
}

#[test]
fn random_sphere_points_give_l_l_plus_1_converging_with_the_right_mass() {
    let mut prev: Option<[f64; 4]> = None;
    for (n, seed) in [(2000, 11u64), (8000, 12)] {
        let cloud = random_sphere(n, seed);
        let r = point_cloud_laplacian(&cloud, &PointCloudParams::default()).unwrap();
        let total: f64 = r.mass.diag().iter().sum();
        let area = 4.0 * std::f64::consts::PI;
        assert!((total - area).abs() < 5e-3 * area, "n = {n}: mass {total}");
        assert!(r.stats.isolated_points.is_empty());
        check("sphere points", n, None, &r.stiffness, &r.mass, 1e-6);
        let ops = Operators {
            laplacian: Laplacian::Robust,
            stiffness: r.stiffness,
            mass: r.mass,
        };
        let e = sphere_errors(&ops);
        for l in 0..4 {
            assert!(e[l] < 0.03, "n = {n}, l = {}: {e:?}", l + 1);
        }
        if let Some(p) = prev {
            assert!(
                e[3] < p[3] && e[2] < p[2],
                "errors must fall: {p:?} -> {e:?}"
            );
        }
        prev = Some(e);
    }
}

#[test]
fn the_peers_union_rule_is_biased_and_ours_is_not() {
    // robust_laplacian's union (copies folded in the tufted cover) lowers every eigenvalue
    // by a few percent; the consensus union does not.
    let cloud = random_sphere(3000, 5);
    let errs = |union| {
        let r = point_cloud_laplacian(
            &cloud,
            &PointCloudParams {
                union,
                ..Default::default()
            },
        )
        .unwrap();
        sphere_errors(&Operators {
            laplacian: Laplacian::Robust,
            stiffness: r.stiffness,
            mass: r.mass,
        })
    };
    let ours = errs(TriangleUnion::Consensus);
    let peer = errs(TriangleUnion::Multiplicity);
    assert!(peer[0] > 0.03, "{peer:?}");
    assert!(ours[0] < 0.01 && ours[3] < peer[3], "{ours:?} vs {peer:?}");
}

#[test]
fn degenerate_clouds_do_not_break_anything() {
    // Collinear points (no triangle anywhere), duplicates, two points, one point.
    let line: Vec<[f64; 3]> = (0..20).map(|i| [i as f64, 0.0, 0.0]).collect();
    let mut dup = random_sphere(200, 3).positions().to_vec();
    dup.extend_from_within(..50);
    for (name, pts) in [
        ("line", line),
        ("duplicates", dup),
        ("two points", vec![[0.0; 3], [1.0, 0.0, 0.0]]),
        ("one point", vec![[0.0; 3]]),
    ] {
        let n = pts.len();
        let cloud = PointCloud::new(pts, None).unwrap();
        let r = point_cloud_laplacian(&cloud, &PointCloudParams::default()).unwrap();
        assert_eq!(r.stiffness.nrows(), n, "{name}");
        assert_eq!(r.stiffness.asymmetry(), 0.0, "{name}");
        assert!(r.stiffness.values().iter().all(|v| v.is_finite()), "{name}");
        assert!(
            r.mass.diag().iter().all(|v| v.is_finite() && *v >= 0.0),
            "{name}"
        );
        let rows = r.stiffness.row_sums();
        assert!(
            rows.iter()
                .all(|x| x.abs() <= 1e-12 * r.stiffness.max_abs().max(1.0)),
            "{name}"
        );
    }
    // Collinear: every point isolated and attached to its nearest neighbour.
    let line: Vec<[f64; 3]> = (0..20).map(|i| [i as f64, 0.0, 0.0]).collect();
    let r = point_cloud_laplacian(
        &PointCloud::new(line, None).unwrap(),
        &PointCloudParams::default(),
    )
    .unwrap();
    assert_eq!(r.stats.isolated_points.len(), 20);
    assert!(r.mass.diag().iter().all(|&m| m > 0.0));
    // Bad parameters are errors, not panics.
    let c = random_sphere(50, 1);
    assert!(
        point_cloud_laplacian(
            &c,
            &PointCloudParams {
                neighbors: 1,
                ..Default::default()
            }
        )
        .is_err()
    );
    assert!(
        point_cloud_laplacian(
            &c,
            &PointCloudParams {
                mollify_factor: f64::NAN,
                ..Default::default()
            }
        )
        .is_err()
    );
    assert!(
        robust_laplacian(
            &two_cones(),
            &RobustParams {
                delaunay_tolerance: -1.0,
                ..Default::default()
            }
        )
        .is_err()
    );
}

#[test]
fn every_shared_point_cloud_loads_and_gives_finite_operators() {
    let Some(dir) = spectral_mesh_testkit::shared_points() else {
        return;
    };
    let mut seen = 0;
    for p in spectral_mesh_testkit::files_in(&dir, None) {
        let input = spectral_mesh::io::read_input(&p).unwrap();
        let spectral_mesh::io::Input::Points(loaded) = input else {
            panic!("{}: read as a mesh", p.display());
        };
        let n = loaded.cloud.n_points();
        for params in [
            PointCloudParams::default(),
            PointCloudParams {
                normals: spectral_mesh::operators::NormalSource::FromCloud,
                ..Default::default()
            },
        ] {
            let r = point_cloud_laplacian(&loaded.cloud, &params).unwrap();
            assert_eq!(r.stiffness.nrows(), n);
            assert_eq!(r.stiffness.asymmetry(), 0.0, "{}", p.display());
            assert!(
                r.stiffness.values().iter().all(|v| v.is_finite()),
                "{}",
                p.display()
            );
            let d = r.mass.diag();
            assert!(
                d.iter().all(|v| v.is_finite() && *v > 0.0),
                "{}: a point has no mass",
                p.display()
            );
            let worst = r
                .stiffness
                .row_sums()
                .iter()
                .fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(worst <= 1e-12 * r.stiffness.max_abs(), "{}", p.display());
        }
        seen += 1;
    }
    assert!(seen >= 6, "only {seen} shared point clouds");
}
