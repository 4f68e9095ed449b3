//! Meshes with many connected components (issue 17): the null space (one indicator per
//! component) is deflated exactly, so any number of components works for every `k`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Arc;

use spectral_mesh::cancel::CancelToken;
use spectral_mesh::linalg::{SparseEigenError, SparseEigenOptions, dense_generalized_eigen};
use spectral_mesh::spectral::eigenbasis::{
    EigenError, EigenMethod, EigenParams, EigenSolver, Eigenbasis, compute_eigenbasis,
};
use spectral_mesh::{Laplacian, Mesh, Operators};

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Vertex positions and triangles of one component.
type Part = (Vec<[f64; 3]>, Vec<[usize; 3]>);

fn part(mesh: &Mesh, scale: f64, offset: [f64; 3]) -> Part {
    let p = mesh
        .positions()
        .iter()
        .map(|v| {
            [
                v[0] * scale + offset[0],
                v[1] * scale + offset[1],
                v[2] * scale + offset[2],
            ]
        })
        .collect();
    (p, mesh.triangles().to_vec())
}

/// `count` tetrahedra (closed 4-vertex surfaces) of random shape and edge lengths from
/// 0.4 to 1.6, on a grid far from the origin.
fn tetrahedra(count: usize, seed: u64) -> Vec<Part> {
    let mut rng = Lcg(seed);
    let base = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    (0..count)
        .map(|t| {
            let size = 0.2 + 0.6 * rng.next();
            let off = [20.0 + 4.0 * (t % 20) as f64, 4.0 * (t / 20) as f64, 0.0];
            let p = base
                .iter()
                .map(|v| {
                    let mut q = [0.0; 3];
                    for i in 0..3 {
                        q[i] = off[i] + size * (v[i] + 0.6 * (rng.next() - 0.5));
                    }
                    q
                })
                .collect();
            (p, vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
        })
        .collect()
}

/// The disjoint union of the parts (vertex indices shifted, in order), plus `isolated`
/// unreferenced vertices at the end.
fn union(parts: &[Part], isolated: usize) -> Mesh {
    let mut pos = Vec::new();
    let mut tri = Vec::new();
    for (p, t) in parts {
        let base = pos.len();
        pos.extend_from_slice(p);
        tri.extend(t.iter().map(|f| [f[0] + base, f[1] + base, f[2] + base]));
    }
    for i in 0..isolated {
        pos.push([-50.0 - i as f64, 0.0, 0.0]);
    }
    Mesh::new(pos, tri).unwrap()
}

/// Spheres `(res, scale, x offset)` as parts.
fn spheres(list: &[(usize, f64, f64)]) -> Vec<Part> {
    list.iter()
        .map(|&(res, scale, x)| part(&sphere(res), scale, [x, 0.0, 0.0]))
        .collect()
}

fn sphere(res: usize) -> Mesh {
    spectral_mesh::shapes::build_str(&format!("sphere:res={res}")).unwrap()
}

/// The spectrum of the union from the dense spectra of its parts, sorted.
fn spectrum_of_parts(parts: &[Part], lap: Laplacian) -> Vec<f64> {
    let mut all = Vec::new();
    for (p, t) in parts {
        let ops = Operators::new(&Mesh::new(p.clone(), t.clone()).unwrap(), lap);
        all.extend(
            dense_generalized_eigen(&ops.stiffness, &ops.mass)
                .unwrap()
                .0,
        );
    }
    all.sort_by(f64::total_cmp);
    all
}

fn iterative(k: usize) -> EigenParams {
    with_method(k, EigenMethod::ShiftInvertBlock)
}

fn dense(k: usize) -> EigenParams {
    with_method(k, EigenMethod::Dense)
}

/// `k` pairs, the method chosen by the library.
fn auto(k: usize) -> EigenParams {
    EigenParams {
        k,
        ..Default::default()
    }
}

fn with_method(k: usize, method: EigenMethod) -> EigenParams {
    EigenParams { method, ..auto(k) }
}

/// The sparse solver's `k` pairs of the pencil `(s, b)`, default options.
fn pencil(
    s: &spectral_mesh::linalg::SparseMatrix,
    b: &spectral_mesh::linalg::SparseMatrix,
    k: usize,
) -> Result<spectral_mesh::linalg::PartialEigen, SparseEigenError> {
    spectral_mesh::linalg::sparse_generalized_eigen(
        s,
        b,
        &SparseEigenOptions {
            k,
            ..Default::default()
        },
        &mut |_| {},
    )
}

/// The first `c` pairs are the B-normalized indicators of the components whose vertex
/// ranges are `ranges` (in that order), with eigenvalue exactly 0.
fn assert_indicators(basis: &Eigenbasis, ops: &Operators, ranges: &[std::ops::Range<usize>]) {
    let n = basis.n;
    let b1 = ops.mass.mul_vec(&vec![1.0; n]);
    for (j, r) in ranges.iter().enumerate() {
        assert_eq!(basis.values[j], 0.0, "pair {j}");
        let x = basis.vector(j);
        let mass: f64 = r.clone().map(|v| b1[v]).sum();
        let want = 1.0 / mass.sqrt();
        for (v, &xv) in x.iter().enumerate() {
            if r.contains(&v) {
                assert!((xv - want).abs() <= 1e-12 * want, "pair {j} vertex {v}");
            } else {
                assert_eq!(xv, 0.0, "pair {j} vertex {v}");
            }
        }
    }
}

/// Vertex ranges of the parts of a union, in order.
fn ranges(parts: &[Part]) -> Vec<std::ops::Range<usize>> {
    let mut start = 0;
    parts
        .iter()
        .map(|(p, _)| {
            let r = start..start + p.len();
            start += p.len();
            r
        })
        .collect()
}

/// `got` within `1e-9 lambda_k` of `want` (`1e-12` absolute when all are zeros: the
/// dense solver's zeros are rounding errors, the deflated ones exact).
fn assert_values_close(got: &[f64], want: &[f64], what: &str) {
    let scale = want[got.len() - 1].abs().max(1e-3);
    for (j, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= 1e-9 * scale,
            "{what}: pair {j}: {g} against {w}"
        );
    }
}

/// 200 small tetrahedra and one large sphere (642 vertices): c = 201. At k = 20 the pairs
/// are the first 20 indicators (the sphere's, then the tetrahedra's in vertex order) and
/// nothing is factored; at k = 250 and 400 the 201 zeros are followed by the sphere's and
/// the tetrahedra's pairs, equal to the dense spectra of the parts.
#[test]
fn two_hundred_tetrahedra_and_a_sphere() {
    let mut parts = vec![part(&sphere(3), 3.0, [0.0; 3])];
    parts.extend(tetrahedra(200, 17));
    let mesh = union(&parts, 0);
    let ops = Arc::new(Operators::new(&mesh, Laplacian::Fem));
    let want = spectrum_of_parts(&parts, Laplacian::Fem);
    let ranges = ranges(&parts);
    let mut solver = EigenSolver::new(ops.clone(), iterative(0));
    let none = CancelToken::new();

    let b20 = solver.solve(20, &mut |_| {}, &none).unwrap();
    assert_eq!(solver.factorizations(), 0, "indicators only: no factor");
    assert_indicators(&b20, &ops, &ranges[..20]);
    assert!(b20.residuals.iter().all(|&r| r <= 1e-14));

    for k in [250, 400] {
        let b = solver.solve(k, &mut |_| {}, &none).unwrap();
        assert_eq!(b.k(), k);
        assert_indicators(&b, &ops, &ranges);
        assert!(b.values[201] > 0.0);
        assert_values_close(&b.values, &want[..k], &format!("k = {k}"));
        assert!(b.residuals.iter().all(|&r| r <= 1e-10), "k = {k}");
        assert!(b.orthogonality_error() <= 1e-10, "k = {k}");
        // The pairs after the zeros live on the sphere and on tetrahedra, mixed.
        let on_sphere = (201..k)
            .filter(|&j| {
                b.vector(j)[ranges[0].clone()]
                    .iter()
                    .any(|x| x.abs() > 1e-6)
            })
            .count();
        eprintln!(
            "k = {k}: {on_sphere} of the {} nonzero pairs on the sphere, lambda_201 = {}, lambda_k = {}",
            k - 201,
            b.values[201],
            b.values[k - 1]
        );
        assert!(on_sphere > 10 && on_sphere < k - 201 - 10, "{on_sphere}");
    }
    assert_eq!(solver.factorizations(), 1);
}

/// The same construction with a smaller sphere (n = 962) against the dense solver on the
/// whole mesh (which gives the same indicators, bit for bit).
#[test]
fn tetrahedra_and_a_small_sphere_against_the_dense_solver() {
    let mut parts = vec![part(&sphere(2), 3.0, [0.0; 3])];
    parts.extend(tetrahedra(200, 5));
    let ops = Operators::new(&union(&parts, 0), Laplacian::Fem);
    for k in [20, 250, 400] {
        let dense = compute_eigenbasis(&ops, &dense(k), &mut |_| {}).unwrap();
        let it = compute_eigenbasis(&ops, &iterative(k), &mut |_| {}).unwrap();
        assert_values_close(&it.values, &dense.values, &format!("k = {k}"));
        let c = k.min(201);
        assert_eq!(it.vectors[..ops.n() * c], dense.vectors[..ops.n() * c]);
        assert!(it.residuals.iter().all(|&r| r <= 1e-10));
        assert!(it.orthogonality_error() <= 1e-10);
    }
}

/// Two disjoint tori: two exact zeros, then the pairs of the dense solver.
#[test]
fn two_disjoint_tori() {
    let torus = spectral_mesh::shapes::build_str("torus:res=1").unwrap(); // 392 vertices
    let parts = vec![
        part(&torus, 1.0, [0.0; 3]),
        part(&torus, 1.3, [5.0, 0.0, 0.0]),
    ];
    let ops = Operators::new(&union(&parts, 0), Laplacian::Fem);
    let k = 40;
    let it = compute_eigenbasis(&ops, &iterative(k), &mut |_| {}).unwrap();
    assert_indicators(&it, &ops, &ranges(&parts));
    assert!(it.values[2] > 0.1);
    let dense = Eigenbasis::dense(&ops, k).unwrap();
    assert_values_close(&it.values, &dense.values, "tori");
    assert!(it.residuals.iter().all(|&r| r <= 1e-10));
}

/// B = I (cot, uniform) with isolated vertices: each isolated vertex is a component of
/// its own (indicator e_v); under the FEM mass it has no mass, which is an error naming
/// it.
#[test]
fn identity_mass_and_isolated_vertices() {
    let parts = spheres(&[(2, 1.0, 0.0), (1, 0.5, 3.0), (2, 2.0, 8.0)]);
    let mesh = union(&parts, 4); // 162 + 42 + 162 + 4 = 370 vertices
    let n = mesh.positions().len();
    let mut r = ranges(&parts);
    r.extend((n - 4..n).map(|v| v..v + 1));
    for lap in [Laplacian::Cot, Laplacian::Uniform] {
        let ops = Operators::new(&mesh, lap);
        let k = 30;
        let it = compute_eigenbasis(&ops, &iterative(k), &mut |_| {}).unwrap();
        assert_indicators(&it, &ops, &r);
        assert!(it.values[7] > 0.0);
        let dense = compute_eigenbasis(&ops, &dense(k), &mut |_| {}).unwrap();
        assert_values_close(&it.values, &dense.values, lap.name());
        assert!(it.residuals.iter().all(|&r| r <= 1e-10), "{lap}");
        assert!(it.orthogonality_error() <= 1e-10, "{lap}");
    }
    let fem = Operators::new(&mesh, Laplacian::Fem);
    let e = compute_eigenbasis(&fem, &iterative(10), &mut |_| {}).unwrap_err();
    match e {
        EigenError::Numerical(m) => assert!(m.contains(&format!("vertex {}", n - 4)), "{m}"),
        other => panic!("{other}"),
    }
    let raw = pencil(&fem.stiffness, &fem.mass, 10);
    assert_eq!(
        raw.unwrap_err(),
        SparseEigenError::ZeroMass { vertex: n - 4 }
    );
}

/// Dirichlet vertices: a component that touches one has no zero mode.
#[test]
fn components_touching_dirichlet_vertices_have_no_zero_mode() {
    let parts = spheres(&[(2, 1.0, 0.0), (2, 1.0, 3.0), (2, 1.0, 6.0)]);
    let ops = Operators::new(&union(&parts, 0), Laplacian::Fem);
    // One vertex of the second sphere is fixed.
    let params = EigenParams {
        k: 12,
        dirichlet: Some(vec![170]),
        method: EigenMethod::ShiftInvertBlock,
        ..Default::default()
    };
    let it = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
    assert_eq!(&it.values[..2], &[0.0, 0.0]);
    assert!(it.values[2] > 0.01, "{:?}", it.values);
    // The zero modes are the first and third spheres' indicators.
    assert!(it.vector(0)[..162].iter().all(|&x| x > 0.0));
    assert!(it.vector(1)[324..].iter().all(|&x| x > 0.0));
    assert_eq!(it.vector(1)[170], 0.0);
    let dense_params = EigenParams {
        method: EigenMethod::Dense,
        ..params
    };
    let dense = compute_eigenbasis(&ops, &dense_params, &mut |_| {}).unwrap();
    assert_values_close(&it.values, &dense.values, "dirichlet");
}

/// The shared mesh with three components, against the dense path.
#[test]
fn blobby_three_components_against_dense() {
    let Some(dir) = std::env::var_os("SPECTRAL_MESH_SHARED_MESHES") else {
        eprintln!("skipped: SPECTRAL_MESH_SHARED_MESHES unset");
        return;
    };
    let path = std::path::PathBuf::from(dir).join("blobby_3cc.off");
    let mesh = spectral_mesh::io::read_mesh(&path).unwrap().mesh;
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let k = 30;
    let it = compute_eigenbasis(&ops, &iterative(k), &mut |_| {}).unwrap();
    let dense = compute_eigenbasis(&ops, &dense(k), &mut |_| {}).unwrap();
    assert_eq!(&it.values[..3], &[0.0; 3]);
    assert!(it.values[3] > 0.0);
    assert_values_close(&it.values, &dense.values, "blobby_3cc");
    assert_eq!(it.vectors[..3 * ops.n()], dense.vectors[..3 * ops.n()]);
    assert!(it.residuals.iter().all(|&r| r <= 1e-10));
    assert!(it.orthogonality_error() <= 1e-10);
}

/// k = n with components: the deflated iteration fills the whole complement.
#[test]
fn every_pair_of_a_mesh_with_components() {
    let parts = spheres(&[(1, 1.0, 0.0), (0, 1.0, 3.0), (1, 0.7, 6.0)]);
    let ops = Operators::new(&union(&parts, 0), Laplacian::VoronoiCot);
    let n = ops.n(); // 42 + 12 + 42
    for k in [n - 1, n] {
        let it = compute_eigenbasis(&ops, &iterative(k), &mut |_| {}).unwrap();
        assert_indicators(&it, &ops, &ranges(&parts));
        let dense = Eigenbasis::dense(&ops, k).unwrap();
        assert_values_close(&it.values, &dense.values, &format!("k = {k}"));
        assert!(it.orthogonality_error() <= 1e-10);
    }
}

/// The sparse solver on the whole pencil (no split into components): the null space is
/// deflated, the rest found in its B-orthogonal complement.
fn whole(ops: &Operators, k: usize) -> spectral_mesh::linalg::PartialEigen {
    pencil(&ops.stiffness, &ops.mass, k).unwrap()
}

/// `compute_eigenbasis` solves components separately; the lower-level solver deflates
/// the null space of the whole pencil. The latter on the 201-component mesh, against the
/// dense spectra of the parts, and its indicators equal the former's.
#[test]
fn whole_pencil_deflation_with_two_hundred_and_one_components() {
    let mut parts = vec![part(&sphere(3), 3.0, [0.0; 3])];
    parts.extend(tetrahedra(200, 17));
    let ops = Operators::new(&union(&parts, 0), Laplacian::Fem);
    let n = ops.n();
    let want = spectrum_of_parts(&parts, Laplacian::Fem);
    for k in [20, 250, 400] {
        let r = whole(&ops, k);
        let split = compute_eigenbasis(&ops, &iterative(k), &mut |_| {}).unwrap();
        let c = k.min(201);
        assert!(r.values[..c].iter().all(|&v| v == 0.0));
        assert_eq!(r.vectors[..n * c], split.vectors[..n * c], "k = {k}");
        assert_values_close(&r.values, &want[..k], &format!("whole, k = {k}"));
        assert!(r.residuals.iter().all(|&x| x <= 1e-10), "k = {k}");
        assert!(r.orthogonality_error <= 1e-10, "k = {k}");
        if k == 20 {
            assert_eq!((r.iterations, r.solves), (0, 0), "indicators only");
        }
    }
}

/// The whole-pencil deflation with k = n - 1, n (the complement filled), with B = I and
/// isolated vertices, and on two tori.
#[test]
fn whole_pencil_deflation_edge_cases() {
    let parts = spheres(&[(1, 1.0, 0.0), (0, 1.0, 3.0), (1, 0.7, 6.0)]);
    let mesh = union(&parts, 3);
    for lap in [Laplacian::VoronoiCot, Laplacian::Cot] {
        let ops = Operators::new(&mesh, lap);
        let n = ops.n();
        let c = if lap == Laplacian::Cot { 6 } else { 3 };
        if lap == Laplacian::VoronoiCot {
            // Isolated vertices have no mass under a lumped mass.
            assert!(matches!(
                pencil(&ops.stiffness, &ops.mass, 5),
                Err(SparseEigenError::ZeroMass { vertex: 96 })
            ));
            continue;
        }
        let dense = Eigenbasis::dense(&ops, n).unwrap();
        for k in [c + 1, n - 1, n] {
            let r = whole(&ops, k);
            assert!(r.values[..c].iter().all(|&v| v == 0.0));
            assert!(r.values[c] > 1e-3);
            assert_values_close(&r.values, &dense.values[..k], &format!("{lap}, k = {k}"));
            assert!(r.orthogonality_error <= 1e-10);
        }
    }
    let torus = spectral_mesh::shapes::build_str("torus:res=1").unwrap();
    let tori = vec![
        part(&torus, 1.0, [0.0; 3]),
        part(&torus, 1.3, [5.0, 0.0, 0.0]),
    ];
    let ops = Operators::new(&union(&tori, 0), Laplacian::Fem);
    let r = whole(&ops, 40);
    let dense = Eigenbasis::dense(&ops, 40).unwrap();
    assert_eq!(&r.values[..2], &[0.0, 0.0]);
    assert_values_close(&r.values, &dense.values, "tori, whole");
    assert!(r.residuals.iter().all(|&x| x <= 1e-10));
}

/// A thin torus has many more low eigenvalues than its area (Weyl's law) suggests: the
/// first estimate of its share is too small and it is solved again with more pairs; the
/// merged result equals the dense spectra of the parts.
#[test]
fn split_components_whose_share_was_underestimated() {
    let thin = spectral_mesh::shapes::build_str("torus:res=2,R=3,r=0.15").unwrap();
    let parts = vec![
        part(&sphere(3), 2.0, [0.0; 3]),
        part(&thin, 1.0, [10.0, 0.0, 0.0]),
        part(&sphere(2), 1.0, [-5.0, 0.0, 0.0]),
    ];
    let ops = Operators::new(&union(&parts, 0), Laplacian::Fem);
    let want = spectrum_of_parts(&parts, Laplacian::Fem);
    for k in [10, 60, 150] {
        let b = compute_eigenbasis(&ops, &auto(k), &mut |_| {}).unwrap();
        assert_eq!(&b.values[..3], &[0.0; 3]);
        assert_values_close(&b.values, &want[..k], &format!("k = {k}"));
        assert!(b.residuals.iter().all(|&r| r <= 1e-10), "k = {k}");
        assert!(b.orthogonality_error() <= 1e-10, "k = {k}");
    }
}

/// A solver keeps one factorization per component solved on the sparse path, and a
/// larger k gives the bits of a fresh solver.
#[test]
fn split_solver_keeps_one_factor_per_component() {
    let parts = spheres(&[(3, 1.0, 0.0), (3, 1.5, 5.0), (1, 1.0, 9.0)]);
    let ops = Arc::new(Operators::new(&union(&parts, 0), Laplacian::Fem));
    let none = CancelToken::new();
    let mut solver = EigenSolver::new(ops.clone(), iterative(0));
    solver.solve(30, &mut |_| {}, &none).unwrap();
    assert_eq!(solver.factorizations(), 2, "the two large spheres");
    let b = solver.solve(80, &mut |_| {}, &none).unwrap();
    assert_eq!(solver.factorizations(), 2);
    let fresh = EigenSolver::new(ops.clone(), iterative(0))
        .solve(80, &mut |_| {}, &none)
        .unwrap();
    assert_eq!(b.values, fresh.values);
    assert_eq!(b.vectors, fresh.vectors);
    let direct = compute_eigenbasis(&ops, &iterative(80), &mut |_| {}).unwrap();
    assert_eq!(b.vectors, direct.vectors);
    assert_values_close(
        &b.values,
        &spectrum_of_parts(&parts, Laplacian::Fem)[..80],
        "split",
    );
}

/// Components solved separately under Dirichlet conditions agree with the whole-pencil
/// deflation of the free block.
#[test]
fn split_with_dirichlet_vertices_agrees_with_the_whole_pencil() {
    let parts = spheres(&[(3, 1.0, 0.0), (3, 1.2, 4.0)]);
    let ops = Operators::new(&union(&parts, 0), Laplacian::Fem);
    let fixed = vec![700usize, 800];
    let k = 40;
    let split = compute_eigenbasis(
        &ops,
        &EigenParams {
            k,
            dirichlet: Some(fixed.clone()),
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap();
    let free: Vec<usize> = (0..ops.n()).filter(|v| !fixed.contains(v)).collect();
    let (s, b) = (
        ops.stiffness.submatrix(&free, &free),
        ops.mass.submatrix(&free, &free),
    );
    let r = pencil(&s, &b, k).unwrap();
    assert_eq!(split.values[0], 0.0);
    assert!(split.values[1] > 0.0, "the second sphere has no zero mode");
    assert_values_close(&split.values, &r.values, "dirichlet");
    assert!(
        fixed
            .iter()
            .all(|&v| (0..k).all(|j| split.vector(j)[v] == 0.0))
    );
}
