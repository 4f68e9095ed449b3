//! The inertia certificate (issue 27): the number of eigenvalues below a shift just above
//! `lambda_k`, from the negative pivots of `L D L^T` of `S - sigma B`, against the
//! computed ones; and the search for the pairs a solve missed.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Arc;

use spectral_mesh::cancel::CancelToken;
use spectral_mesh::linalg::{
    SparseEigenOptions, SparseMatrix, certificate, certify_and_complete, count_below,
    dense_generalized_eigen, sparse_generalized_eigen,
};
use spectral_mesh::spectral::eigenbasis::{
    EigenMethod, EigenParams, Eigenbasis, certify_eigenbasis, compute_eigenbasis,
};
use spectral_mesh::{Laplacian, Mesh, Operators};

fn shape(spec: &str) -> Mesh {
    spectral_mesh::shapes::build_str(spec).unwrap()
}

fn iterative(k: usize) -> EigenParams {
    EigenParams {
        k,
        method: EigenMethod::ShiftInvertBlock,
        ..Default::default()
    }
}

/// The cotangent stiffness and FEM mass of the flat torus `[0, 1)^2` (periodic), an
/// `m x m` grid of squares each cut along its diagonal: built from the intrinsic (flat)
/// triangles, which no mesh in R^3 has. Its spectrum has multiplicity 4 and more
/// (`4 pi^2 (a^2 + b^2)` in the limit, `(a, b)` and its sign changes and swap).
fn flat_torus(m: usize) -> (SparseMatrix, SparseMatrix) {
    let n = m * m;
    let h = 1.0 / m as f64;
    let id = |i: usize, j: usize| (i % m) * m + (j % m);
    let mut st = Vec::new();
    let mut bt = Vec::new();
    for i in 0..m {
        for j in 0..m {
            // Two right triangles of legs h: (i,j), (i+1,j), (i+1,j+1) and
            // (i,j), (i+1,j+1), (i,j+1), in local coordinates.
            let tris = [
                (
                    [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                    [[0.0, 0.0], [h, 0.0], [h, h]],
                ),
                (
                    [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
                    [[0.0, 0.0], [h, h], [0.0, h]],
                ),
            ];
            for (v, p) in tris {
                let area = 0.5
                    * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                        - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
                        .abs();
                for c in 0..3 {
                    // The angle at corner c faces the edge (c+1, c+2).
                    let (a, b) = ((c + 1) % 3, (c + 2) % 3);
                    let u = [p[a][0] - p[c][0], p[a][1] - p[c][1]];
                    let w = [p[b][0] - p[c][0], p[b][1] - p[c][1]];
                    let cot = (u[0] * w[0] + u[1] * w[1]) / (u[0] * w[1] - u[1] * w[0]).abs();
                    let x = 0.5 * cot;
                    st.push((v[a], v[b], -x));
                    st.push((v[b], v[a], -x));
                    st.push((v[a], v[a], x));
                    st.push((v[b], v[b], x));
                }
                for a in 0..3 {
                    for b in 0..3 {
                        let val = if a == b { area / 6.0 } else { area / 12.0 };
                        bt.push((v[a], v[b], val));
                    }
                }
            }
        }
    }
    (
        SparseMatrix::from_triplets(n, n, &st),
        SparseMatrix::from_triplets(n, n, &bt),
    )
}

/// Eigenvalues below `sigma` by the dense solver (the reference count).
fn dense_count(s: &SparseMatrix, b: &SparseMatrix, sigma: f64) -> usize {
    let (vals, _) = dense_generalized_eigen(s, b).unwrap();
    vals.iter().filter(|&&v| v < sigma).count()
}

/// The inertia count equals the dense count at shifts between and far from eigenvalues,
/// on the sphere (multiplicities 1, 3, 5, 7, 9 in the limit).
#[test]
fn inertia_counts_match_the_dense_spectrum() {
    let ops = Operators::new(&shape("sphere:res=2"), Laplacian::Fem); // 162 vertices
    let (s, b) = (&ops.stiffness, &ops.mass);
    let (vals, _) = dense_generalized_eigen(s, b).unwrap();
    // Every cluster end (and the last eigenvalue): sigma between distinct eigenvalues.
    let ends: Vec<usize> = (0..vals.len())
        .filter(|&j| j + 1 == vals.len() || vals[j + 1] - vals[j] > 1e-6 * vals[j + 1])
        .collect();
    assert!(ends.starts_with(&[0, 3, 8]), "{ends:?}");
    for j in ends {
        let sigma = if j + 1 < vals.len() {
            0.5 * (vals[j] + vals[j + 1])
        } else {
            vals[j] * 1.01
        };
        let got = count_below(s, b, sigma, None)
            .unwrap()
            .unwrap_or_else(|| panic!("zero pivot at sigma {sigma} (j = {j})"));
        assert_eq!(got, dense_count(s, b, sigma), "sigma {sigma}");
        assert_eq!(got, j + 1);
    }
    // Below the spectrum: S - sigma B positive definite, no negative pivot.
    assert_eq!(count_below(s, b, -1.0, None).unwrap(), Some(0));
}

/// Sphere: k = 1, 4, 9, 16, 25 end each l-cluster (1 + 3 + 5 + 7 + 9); the solver's pairs
/// are certified, and so is the dense path's.
#[test]
fn sphere_multiplicities_are_certified() {
    let ops = Operators::new(&shape("sphere:res=3"), Laplacian::Fem); // 642 vertices
    for k in [1usize, 4, 9, 16, 25] {
        for params in [
            iterative(k),
            EigenParams {
                k,
                method: EigenMethod::Dense,
                ..Default::default()
            },
        ] {
            let basis = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
            let (changed, report) =
                certify_eigenbasis(&ops, &params, &basis, &CancelToken::new()).unwrap();
            assert!(report.first.agrees(), "k = {k}: {:?}", report.lines());
            assert_eq!(report.first.below, k);
            assert!(changed.is_none());
            assert!(report.certified());
        }
    }
    // k = 6 cuts the l = 2 cluster (five equal eigenvalues on the icosphere, by its
    // symmetry): the count above lambda_6 sees the whole cluster (9), the search computes
    // the rest of it, and the eigenvalues stand.
    let basis = compute_eigenbasis(&ops, &iterative(6), &mut |_| {}).unwrap();
    let (changed, report) =
        certify_eigenbasis(&ops, &iterative(6), &basis, &CancelToken::new()).unwrap();
    assert_eq!(report.first.below, 9, "{:?}", report.lines());
    assert_eq!(report.first.found, 6);
    assert!(report.certified(), "{:?}", report.lines());
    assert_eq!(report.values_changed, 0);
    assert!(changed.is_none());
}

/// Flat torus (multiplicities 4 and more): the sparse solver's pairs are certified for
/// every k that ends a cluster, against the dense count.
#[test]
fn flat_torus_is_certified() {
    let (s, b) = flat_torus(24); // 576 vertices
    let (vals, _) = dense_generalized_eigen(&s, &b).unwrap();
    // Cluster ends among the first 40.
    let ends: Vec<usize> = (1..40)
        .filter(|&k| vals[k] - vals[k - 1] > 1e-3 * vals[k])
        .collect();
    assert!(ends.len() >= 5, "{:?}", &vals[..40]);
    // A multiplicity of at least 4 right after the zero eigenvalue.
    assert!(ends[1] - ends[0] >= 4, "{ends:?} {:?}", &vals[..10]);
    for &k in &ends[..5] {
        let opts = SparseEigenOptions {
            k,
            block_size: 2,
            ..Default::default()
        };
        let r = sparse_generalized_eigen(&s, &b, &opts, &mut |_| {}).unwrap();
        let c = certificate(&s, &b, &r.values, k, None).unwrap();
        assert!(c.agrees(), "k = {k}: {c:?}");
        assert_eq!(c.below, k);
        assert_eq!(c.below, dense_count(&s, &b, c.shift));
    }
}

/// Several components (three spheres of different radii, 486 vertices): the whole pencil
/// is counted,
/// the merged pairs of the component solves are certified, and so are `k <= 3` (zero
/// eigenvalues only, the margin then from the solver's shift).
#[test]
fn several_components_are_certified() {
    let mut p = Vec::new();
    let mut f = Vec::new();
    for (i, r) in [1.0, 1.3, 0.8].iter().enumerate() {
        let m = shape("sphere:res=2");
        let base = p.len();
        p.extend(
            m.positions()
                .iter()
                .map(|v| [v[0] * r + 5.0 * i as f64, v[1] * r, v[2] * r]),
        );
        f.extend(
            m.triangles()
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    let ops = Operators::new(&Mesh::new(p, f).unwrap(), Laplacian::Fem);
    for k in [2usize, 3, 12, 40] {
        let params = iterative(k);
        let basis = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
        let (changed, report) =
            certify_eigenbasis(&ops, &params, &basis, &CancelToken::new()).unwrap();
        assert!(report.certified(), "k = {k}: {:?}", report.lines());
        assert_eq!(report.values_changed, 0, "k = {k}: {:?}", report.lines());
        assert!(changed.is_none());
        let sigma = report.last.shift;
        assert_eq!(
            report.last.below,
            dense_count(&ops.stiffness, &ops.mass, sigma)
        );
    }
}

/// A solve built to miss an eigenvector: the start block and every block after it are
/// kept B-orthogonal to the eigenvector of a simple eigenvalue `lambda_j` of a torus, so the solve returns the other 20 smallest. The certificate disagrees (more
/// eigenvalues below the shift than computed), the search finds the missing pair, and the
/// completed pairs equal the dense ones.
#[test]
fn a_solve_that_misses_an_eigenvector_is_caught_and_completed() {
    let ops = Operators::new(&shape("torus:res=1"), Laplacian::Fem); // 392 vertices
    let (s, b) = (&ops.stiffness, &ops.mass);
    let n = s.ncols();
    let (vals, vecs) = dense_generalized_eigen(s, b).unwrap();
    let k = 20;
    // A simple eigenvalue to hide.
    let j = (3..k)
        .find(|&j| vals[j] - vals[j - 1] > 1e-3 * vals[j] && vals[j + 1] - vals[j] > 1e-3 * vals[j])
        .expect("a simple eigenvalue among the first 20");
    let hidden = vecs[j * n..(j + 1) * n].to_vec();
    let opts = SparseEigenOptions {
        k,
        deflate_vectors: Some(Arc::new(hidden)),
        ..Default::default()
    };
    let r = sparse_generalized_eigen(s, b, &opts, &mut |_| {}).unwrap();
    // The solve missed lambda_j.
    let miss = r
        .values
        .iter()
        .all(|&v| (v - vals[j]).abs() > 1e-6 * vals[j]);
    assert!(miss, "{:?} vs {}", r.values, vals[j]);
    let c = certificate(s, b, &r.values, k, None).unwrap();
    assert!(!c.agrees());
    assert!(c.below > c.found, "{c:?}");
    let done = certify_and_complete(
        s,
        b,
        r.values.clone(),
        r.vectors.clone(),
        k,
        &SparseEigenOptions {
            k,
            ..Default::default()
        },
        None,
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap();
    assert!(!done.first.agrees());
    assert!(done.last.agrees(), "{:?}", done.last);
    assert!(done.added >= 1);
    assert!(done.values_changed >= 1);
    for i in 0..k {
        assert!(
            (done.values[i] - vals[i]).abs() <= 1e-9 * vals[k - 1],
            "{i}: {} vs {}",
            done.values[i],
            vals[i]
        );
    }
    // The completed vectors are B-orthonormal.
    let basis = Eigenbasis {
        laplacian: Laplacian::Fem,
        n,
        values: done.values.clone(),
        vectors: done.vectors.clone(),
        mass: b.clone(),
        residuals: Vec::new(),
    };
    assert!(basis.orthogonality_error() < 1e-9);
    assert!(basis.compute_residuals(s).iter().all(|&r| r < 1e-8));

    // The same through the eigenbasis API, with a basis that lacks lambda_j.
    let keep: Vec<usize> = (0..=k).filter(|&i| i != j).collect();
    let mut given = Eigenbasis {
        laplacian: Laplacian::Fem,
        n,
        values: keep.iter().map(|&i| vals[i]).collect(),
        vectors: keep
            .iter()
            .flat_map(|&i| vecs[i * n..(i + 1) * n].iter().copied())
            .collect(),
        mass: b.clone(),
        residuals: Vec::new(),
    };
    given.fix_signs();
    let (fixed, report) =
        certify_eigenbasis(&ops, &iterative(k), &given, &CancelToken::new()).unwrap();
    assert!(!report.first.agrees());
    assert!(report.certified(), "{:?}", report.lines());
    let fixed = fixed.expect("a completed basis");
    assert_eq!(fixed.k(), k);
    for i in 0..k {
        assert!((fixed.values[i] - vals[i]).abs() <= 1e-9 * vals[k - 1]);
    }
    assert!(report.lines().iter().any(|l| l.contains("DISAGREES")));
}
