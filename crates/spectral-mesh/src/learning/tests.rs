use super::*;
use crate::mesh::{add, cross, dot, norm, normalize, scale, sub};
use crate::operators::Operators;
use crate::spectral::eigenbasis::compute_eigenbasis;

/// A small deterministic generator (xorshift), values in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// An orthonormal pair spanning a generic plane, and its origin.
fn plane() -> ([f64; 3], [f64; 3], [f64; 3]) {
    let s = normalize([0.6, -0.3, 0.74]);
    let t = normalize(cross([0.2, 0.9, -0.1], s));
    (s, t, [0.3, -1.2, 2.0])
}

fn on_plane(u: f64, v: f64) -> [f64; 3] {
    let (s, t, o) = plane();
    add(o, add(scale(s, u), scale(t, v)))
}

/// A jittered `m x m` grid on a generic plane, triangulated (two triangles a cell).
fn flat_mesh(m: usize) -> Mesh {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let h = 1.0 / (m - 1) as f64;
    crate::test_support::grid(m, |i, j| {
        let interior = i > 0 && j > 0 && i + 1 < m && j + 1 < m;
        let (du, dv) = if interior {
            (0.3 * h * (rng.next() - 0.5), 0.3 * h * (rng.next() - 0.5))
        } else {
            (0.0, 0.0)
        };
        on_plane(i as f64 * h + du, j as f64 * h + dv)
    })
}

fn flat_cloud(n: usize) -> PointCloud {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let p = (0..n).map(|_| on_plane(rng.next(), rng.next())).collect();
    PointCloud::new(p, None).unwrap()
}

fn run(shape: LearningShape<'_>, params: &LearningParams) -> LearningOperators {
    compute_operators(shape, None, params, &mut |_| {}, &CancelToken::new()).unwrap()
}

/// The operators of `shape` and their gradients' error on a linear function ([`linear_error`]).
fn fit(shape: LearningShape<'_>, params: &LearningParams) -> (LearningOperators, f64) {
    let ops = run(shape, params);
    let err = linear_error(&ops, shape.positions());
    (ops, err)
}

/// `max_i |(G_x f)_i - a . X_i|` and the same for Y, for `f = a . p`, relative to `|a|`.
fn linear_error(ops: &LearningOperators, positions: &[[f64; 3]]) -> f64 {
    let a = [0.7, -1.3, 0.4];
    let f: Vec<f64> = positions.iter().map(|&p| dot(a, p)).collect();
    let gx = ops.grad_x.mul_vec(&f);
    let gy = ops.grad_y.mul_vec(&f);
    let mut worst: f64 = 0.0;
    for (i, fr) in ops.frames.iter().enumerate() {
        worst = worst.max((gx[i] - dot(a, fr[0])).abs());
        worst = worst.max((gy[i] - dot(a, fr[1])).abs());
    }
    worst / norm(a)
}

fn exact() -> LearningParams {
    LearningParams {
        k_eig: 10,
        grad_regularization: 0.0,
        ..LearningParams::default()
    }
}

#[test]
fn gradients_are_exact_on_linear_functions_of_a_flat_mesh() {
    let mesh = flat_mesh(12);
    let (ops, err) = fit(LearningShape::Mesh(&mesh), &exact());
    assert!(err < 1e-12, "mesh: {err:e}");
    // The frames' normal is the plane's (either side).
    let (s, t, _) = plane();
    let nrm = normalize(cross(s, t));
    for fr in &ops.frames {
        assert!((dot(fr[2], nrm).abs() - 1.0).abs() < 1e-12);
    }
    // DiffusionNet's regularization (1e-5, absolute) moves the fit a little on this
    // unit-sized patch, and no more than its size relative to the normal matrix.
    let (_, err) = fit(LearningShape::Mesh(&mesh), &LearningParams::default());
    assert!(err > 1e-9 && err < 1e-2, "regularized: {err:e}");
}

#[test]
fn gradients_are_exact_on_linear_functions_of_a_flat_point_cloud() {
    let cloud = flat_cloud(300);
    let (ops, err) = fit(LearningShape::Cloud(&cloud), &exact());
    assert!(err < 1e-11, "cloud: {err:e}");
    // 30 neighbours each, plus the diagonal.
    assert_eq!(ops.grad_x.nnz(), 300 * 31);
}

#[test]
fn frames_are_right_handed_orthonormal_and_normals_point_out_of_a_sphere() {
    let mesh = crate::shapes::build_str("sphere:res=2").unwrap();
    let ops = run(LearningShape::Mesh(&mesh), &exact());
    for (fr, &p) in ops.frames.iter().zip(mesh.positions()) {
        for a in 0..3 {
            for b in 0..3 {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((dot(fr[a], fr[b]) - want).abs() < 1e-14);
            }
        }
        let c = cross(fr[0], fr[1]);
        assert!(norm(sub(c, fr[2])) < 1e-14);
        assert!(dot(fr[2], normalize(p)) > 0.99);
    }
    // Gradient rows sum to zero (constants have no gradient).
    let ones = vec![1.0; mesh.n_vertices()];
    for g in [&ops.grad_x, &ops.grad_y] {
        assert!(g.mul_vec(&ones).iter().all(|x| x.abs() < 1e-9));
    }
}

#[test]
fn the_eigenpairs_are_the_library_s_eigenbasis_of_the_returned_operators() {
    let mesh = crate::shapes::build_str("irregular-torus:res=2").unwrap();
    let params = LearningParams {
        k_eig: 40,
        ..LearningParams::default()
    };
    let ops = run(LearningShape::Mesh(&mesh), &params);
    // The library's basis of (S, diag(mass)): bit for bit.
    let pair = Operators {
        laplacian: Laplacian::VoronoiCot,
        stiffness: ops.laplacian.clone(),
        mass: SparseMatrix::diagonal(&ops.mass),
    };
    let eigen = EigenParams {
        k: 40,
        ..EigenParams::default()
    };
    let basis = compute_eigenbasis(&pair, &eigen, &mut |_| {}).unwrap();
    assert_eq!(basis.values, ops.evals);
    assert_eq!(basis.vectors, ops.evecs);
    // And the library's voronoi-cot basis of the mesh, up to the mass raise (1e-8).
    let plain = Operators::new(&mesh, Laplacian::VoronoiCot);
    assert_eq!(plain.stiffness, ops.laplacian);
    let d = plain.mass.diag();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    for (m, x) in ops.mass.iter().zip(&d) {
        assert_eq!(*m, x + MASS_EPS * mean);
    }
    let lib = compute_eigenbasis(&plain, &eigen, &mut |_| {}).unwrap();
    for (a, b) in ops.evals.iter().zip(&lib.values) {
        assert!((a - b).abs() <= 1e-6 * b.abs().max(1.0), "{a} {b}");
    }
    // M-orthonormal in the returned mass.
    let n = ops.n();
    for i in 0..3 {
        for j in 0..3 {
            let v = &ops.evecs[i * n..(i + 1) * n];
            let w = &ops.evecs[j * n..(j + 1) * n];
            let ip: f64 = (0..n).map(|t| v[t] * ops.mass[t] * w[t]).sum();
            assert!((ip - if i == j { 1.0 } else { 0.0 }).abs() < 1e-9);
        }
    }
}

#[test]
fn float32_is_the_float64_result_rounded_once() {
    let mesh = crate::shapes::build_str("sphere:res=1").unwrap();
    let ops = run(LearningShape::Mesh(&mesh), &exact());
    let r = ops.rounded(BasisDtype::Float32);
    let same = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (*x as f32 as f64) == *y)
    };
    assert!(same(&ops.mass, &r.mass));
    assert!(same(&ops.evals, &r.evals));
    assert!(same(&ops.evecs, &r.evecs));
    assert!(same(ops.grad_x.values(), r.grad_x.values()));
    assert!(same(ops.grad_y.values(), r.grad_y.values()));
    assert!(same(ops.laplacian.values(), r.laplacian.values()));
    assert_eq!(ops.grad_x.row_idx(), r.grad_x.row_idx());
    let f: Vec<f64> = ops.frames.iter().flatten().flatten().copied().collect();
    let g: Vec<f64> = r.frames.iter().flatten().flatten().copied().collect();
    assert!(same(&f, &g));
    assert_ne!(ops.evecs, r.evecs);
    assert_eq!(ops.rounded(BasisDtype::Float64), ops);
}

#[test]
fn a_second_call_reads_the_cache_and_other_parameters_get_their_own_file() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = crate::shapes::build_str("sphere:res=2").unwrap();
    let shape = LearningShape::Mesh(&mesh);
    let params = LearningParams {
        k_eig: 12,
        ..LearningParams::default()
    };
    let go = |p: &LearningParams| {
        load_or_compute(dir.path(), shape, None, p, &mut |_| {}, &CancelToken::new()).unwrap()
    };
    let (first, hit, path) = go(&params);
    assert!(!hit && path.is_file());
    let stamp = std::fs::metadata(&path).unwrap().modified().unwrap();
    let (second, hit, path2) = go(&params);
    assert!(hit);
    assert_eq!(path, path2);
    assert_eq!(first, second);
    assert_eq!(std::fs::metadata(&path).unwrap().modified().unwrap(), stamp);
    // Another k: another file, computed.
    let more = LearningParams {
        k_eig: 13,
        ..params.clone()
    };
    let (_, hit, other) = go(&more);
    assert!(!hit && other != path);
    // A damaged archive is recomputed and replaced.
    std::fs::write(&path, b"not a zip").unwrap();
    let (third, hit, _) = go(&params);
    assert!(!hit);
    assert_eq!(third, first);
    assert!(go(&params).1);
    // The file name starts with the library's content hash.
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    assert!(name.starts_with(&mesh.content_hash()[..16]), "{name}");
}

#[test]
fn the_cache_key_follows_the_normals_and_every_parameter() {
    let h = "ab".repeat(32);
    let p = LearningParams::default();
    let k0 = cache_key(&h, None, &p);
    assert_ne!(k0, cache_key(&"cd".repeat(32), None, &p));
    assert_ne!(k0, cache_key(&h, Some(&[[0.0, 0.0, 1.0]]), &p));
    for q in [
        LearningParams {
            k_eig: 5,
            ..p.clone()
        },
        LearningParams {
            laplacian: Laplacian::Robust,
            ..p.clone()
        },
        LearningParams {
            grad_regularization: 0.0,
            ..p.clone()
        },
        LearningParams {
            neighbors: 12,
            ..p.clone()
        },
        LearningParams {
            tolerance: 1e-8,
            ..p.clone()
        },
    ] {
        assert_ne!(k0, cache_key(&h, None, &q), "{q:?}");
    }
}

#[test]
fn bad_requests_are_errors_that_say_why() {
    let mesh = crate::shapes::build_str("sphere:res=1").unwrap();
    let n = mesh.n_vertices();
    let shape = LearningShape::Mesh(&mesh);
    let err = |p: LearningParams, normals: Option<&[[f64; 3]]>| {
        compute_operators(shape, normals, &p, &mut |_| {}, &CancelToken::new())
            .unwrap_err()
            .to_string()
    };
    let d = LearningParams::default;
    assert!(
        err(
            LearningParams {
                k_eig: n + 1,
                ..d()
            },
            None
        )
        .contains("k_eig")
    );
    let e = err(
        LearningParams {
            laplacian: Laplacian::Fem,
            ..d()
        },
        None,
    );
    assert!(e.contains("lumped"), "{e}");
    let e = err(
        LearningParams {
            grad_regularization: -1.0,
            ..d()
        },
        None,
    );
    assert!(e.contains("grad_regularization"), "{e}");
    let e = err(
        LearningParams {
            neighbors: 1,
            ..d()
        },
        None,
    );
    assert!(e.contains("neighbors"), "{e}");
    let e = err(LearningParams { k_eig: 4, ..d() }, Some(&[[0.0, 0.0, 1.0]]));
    assert!(e.contains("normals has 1 rows"), "{e}");
    let mut z = vec![[0.0, 0.0, 1.0]; n];
    z[3] = [0.0; 3];
    let e = err(LearningParams { k_eig: 4, ..d() }, Some(&z));
    assert!(e.contains("normals[3]"), "{e}");
}

#[test]
fn given_normals_make_the_frames_and_k_zero_gives_no_pairs() {
    let mesh = crate::shapes::build_str("sphere:res=1").unwrap();
    let up = vec![[0.0, 0.0, 2.0]; mesh.n_vertices()];
    let p = LearningParams {
        k_eig: 0,
        ..LearningParams::default()
    };
    let ops = compute_operators(
        LearningShape::Mesh(&mesh),
        Some(&up),
        &p,
        &mut |_| {},
        &CancelToken::new(),
    )
    .unwrap();
    assert!(ops.evals.is_empty() && ops.evecs.is_empty());
    for fr in &ops.frames {
        assert_eq!(fr, &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    }
}

#[test]
fn an_unreferenced_vertex_gets_a_frame_a_mass_and_a_zero_gradient_row() {
    let mut p = flat_mesh(5).positions().to_vec();
    let t = flat_mesh(5).triangles().to_vec();
    p.push([5.0, 5.0, 5.0]);
    let mesh = Mesh::new(p, t).unwrap();
    let ops = run(
        LearningShape::Mesh(&mesh),
        &LearningParams {
            k_eig: 4,
            ..exact()
        },
    );
    let last = mesh.n_vertices() - 1;
    assert_eq!(ops.frames[last][2], [0.0, 0.0, 1.0]);
    assert!(ops.mass[last] > 0.0);
    assert!(ops.evals.iter().all(|x| x.is_finite()));
    let e = vec![1.0; mesh.n_vertices()];
    assert!(ops.grad_x.mul_vec(&e).iter().all(|x| x.abs() < 1e-12));
    assert_eq!(ops.grad_x.col(last).0, &[last]);
}
