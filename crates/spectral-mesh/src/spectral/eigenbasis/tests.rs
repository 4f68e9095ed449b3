use std::sync::Arc;

use super::test_meshes::*;
use super::*;
use crate::cancel::CancelToken;
use crate::operators::{Laplacian, Operators};

/// The default parameters with `k` pairs by `method`.
fn params(k: usize, method: EigenMethod) -> EigenParams {
    EigenParams {
        k,
        method,
        ..Default::default()
    }
}

fn iterative(k: usize) -> EigenParams {
    params(k, EigenMethod::ShiftInvertBlock)
}

fn check_against_dense(ops: &Operators, k: usize) {
    let dense = compute_eigenbasis(ops, &params(k, EigenMethod::Dense), &mut |_| {}).unwrap();
    let it = compute_eigenbasis(ops, &iterative(k), &mut |_| {}).unwrap();
    let scale = dense.values[k - 1].abs().max(1e-300);
    for j in 0..k {
        assert!(
            (it.values[j] - dense.values[j]).abs() <= 1e-9 * scale,
            "{}: pair {j}: {} vs dense {}",
            ops.laplacian,
            it.values[j],
            dense.values[j]
        );
    }
    assert!(
        it.residuals.iter().all(|&r| r <= 1e-8),
        "{:?}",
        it.residuals
    );
    assert_eq!(it.residuals, it.compute_residuals(&ops.stiffness));
    assert!(it.orthogonality_error() <= 1e-10);
    // Sign rule holds.
    for j in 0..k {
        let x = it.vector(j);
        let big = x
            .iter()
            .cloned()
            .fold(0.0f64, |m, v| if v.abs() > m.abs() { v } else { m });
        assert!(big > 0.0);
    }
}

#[test]
fn iterative_matches_dense_for_every_mass() {
    let mesh = disk(12); // bordered, 469 vertices
    for lap in [Laplacian::Fem, Laplacian::VoronoiCot, Laplacian::Cot] {
        let ops = Operators::new(&mesh, lap);
        check_against_dense(&ops, 30);
    }
}

#[test]
fn sphere_multiplicities() {
    let mesh = icosphere(3, 1.0); // 642 vertices
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let b9 = compute_eigenbasis(&ops, &iterative(9), &mut |_| {}).unwrap();
    let l = |i: usize| match i {
        0 => 0.0,
        1..=3 => 2.0,
        _ => 6.0,
    };
    for j in 0..9 {
        assert!(
            (b9.values[j] - l(j)).abs() < 0.05 * l(j).max(1.0),
            "{:?}",
            b9.values
        );
    }
    let b4 = compute_eigenbasis(&ops, &iterative(4), &mut |_| {}).unwrap();
    for j in 0..4 {
        assert!((b4.values[j] - b9.values[j]).abs() < 1e-9 * b9.values[8]);
    }
    // k = 3 cuts the l = 1 triple: still the right values.
    let b3 = compute_eigenbasis(&ops, &iterative(3), &mut |_| {}).unwrap();
    for j in 0..3 {
        assert!((b3.values[j] - b9.values[j]).abs() < 1e-9 * b9.values[8]);
    }
    assert!(b3.residuals.iter().all(|&r| r <= 1e-8));
    // Large k through many clusters agrees with dense.
    check_against_dense(&ops, 60);
}

/// The FEM operators of three disjoint unit icospheres (level 2): three components, every
/// eigenvalue of multiplicity 3 times that of one sphere.
fn three_spheres() -> Operators {
    let s = icosphere(2, 1.0);
    let mesh = union(&[
        (s.clone(), [0.0; 3]),
        (s.clone(), [3.0, 0.0, 0.0]),
        (s, [0.0, 3.0, 0.0]),
    ]);
    Operators::new(&mesh, Laplacian::Fem)
}

#[test]
fn components_give_zero_eigenvalues() {
    let ops = three_spheres();
    let b = compute_eigenbasis(&ops, &iterative(8), &mut |_| {}).unwrap();
    for j in 0..3 {
        assert!(b.values[j].abs() < 1e-8, "{:?}", b.values);
    }
    assert!(b.values[3] > 1.0);
    assert!(b.orthogonality_error() < 1e-10);
}

#[test]
fn multiplicities_larger_than_the_block_are_complete() {
    // Three identical spheres: every eigenvalue has multiplicity 3 (2l + 1), up to 15
    // here, with blocks of 4; the result must equal the dense one pair for pair.
    let ops = three_spheres();
    let k = 40;
    let dense = compute_eigenbasis(&ops, &params(k, EigenMethod::Dense), &mut |_| {}).unwrap();
    let it = compute_eigenbasis(
        &ops,
        &EigenParams {
            block_size: 4,
            ..iterative(k)
        },
        &mut |_| {},
    )
    .unwrap();
    for j in 0..k {
        assert!(
            (it.values[j] - dense.values[j]).abs() <= 1e-9 * dense.values[k - 1],
            "pair {j}: {} vs {}",
            it.values[j],
            dense.values[j]
        );
    }
    assert!(it.orthogonality_error() < 1e-10);
}

#[test]
fn k_close_to_n_with_the_iterative_solver() {
    // k = 600 of n = 642: the Krylov space fills the whole space.
    let ops = Operators::new(&icosphere(3, 1.0), Laplacian::VoronoiCot);
    check_against_dense(&ops, 600);
}

#[test]
fn davidson_and_krylov_schur_agree() {
    use crate::linalg::{SparseAlgorithm, SparseEigenOptions, sparse_generalized_eigen};
    let ops = Operators::new(&disk(12), Laplacian::Fem);
    let run = |algorithm| {
        let o = SparseEigenOptions {
            k: 25,
            algorithm,
            ..Default::default()
        };
        sparse_generalized_eigen(&ops.stiffness, &ops.mass, &o, &mut |_| {}).unwrap()
    };
    let a = run(SparseAlgorithm::KrylovSchur);
    let b = run(SparseAlgorithm::Davidson);
    for j in 0..25 {
        assert!((a.values[j] - b.values[j]).abs() <= 1e-9 * a.values[24]);
    }
    assert!(a.residuals.iter().all(|&r| r <= 1e-10));
}

#[test]
fn k_larger_than_n_is_an_error() {
    let mesh = icosphere(0, 1.0);
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let e = compute_eigenbasis(&ops, &params(13, EigenMethod::Auto), &mut |_| {});
    assert_eq!(e.unwrap_err(), EigenError::TooMany { k: 13, n: 12 });
    // Auto on a tiny mesh with k = n works (dense path).
    let b = compute_eigenbasis(&ops, &params(12, EigenMethod::Auto), &mut |_| {}).unwrap();
    assert_eq!(b.k(), 12);
    // The iterative path also handles k = n.
    let b2 = compute_eigenbasis(&ops, &iterative(12), &mut |_| {}).unwrap();
    for j in 0..12 {
        assert!((b.values[j] - b2.values[j]).abs() < 1e-9 * b.values[11]);
    }
}

#[test]
fn dirichlet_disk() {
    let mesh = disk(12);
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let n = ops.n();
    let boundary: Vec<usize> = (n - 6 * 12..n).collect();
    let params = EigenParams {
        k: 6,
        dirichlet: Some(boundary.clone()),
        method: EigenMethod::ShiftInvertBlock,
        ..Default::default()
    };
    let b = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
    // Unit disk, Dirichlet: lambda_1 = j_{0,1}^2 = 5.783; then j_{1,1}^2 = 14.68 (x2).
    assert!((b.values[0] - 5.783).abs() < 0.1, "{:?}", b.values);
    assert!((b.values[1] - 14.68).abs() < 0.4 && (b.values[2] - 14.68).abs() < 0.4);
    for j in 0..6 {
        for &i in &boundary {
            assert_eq!(b.vector(j)[i], 0.0);
        }
    }
    assert!(b.orthogonality_error() < 1e-10);
    let dense = compute_eigenbasis(
        &ops,
        &EigenParams {
            method: EigenMethod::Dense,
            ..params.clone()
        },
        &mut |_| {},
    )
    .unwrap();
    for j in 0..6 {
        assert!((b.values[j] - dense.values[j]).abs() < 1e-9 * dense.values[5]);
    }
    let bad = EigenParams {
        dirichlet: Some(vec![n]),
        ..params
    };
    assert!(matches!(
        compute_eigenbasis(&ops, &bad, &mut |_| {}),
        Err(EigenError::DirichletOutOfRange { .. })
    ));
}

#[test]
fn hard_locking_variant_agrees() {
    use crate::linalg::{SparseEigenOptions, sparse_generalized_eigen};
    let mesh = icosphere(3, 1.0);
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let mk = |locking| SparseEigenOptions {
        k: 30,
        locking,
        ..Default::default()
    };
    let a = sparse_generalized_eigen(&ops.stiffness, &ops.mass, &mk(true), &mut |_| {}).unwrap();
    let b = sparse_generalized_eigen(&ops.stiffness, &ops.mass, &mk(false), &mut |_| {}).unwrap();
    for j in 0..30 {
        assert!((a.values[j] - b.values[j]).abs() < 1e-9 * b.values[29]);
    }
    assert!(a.orthogonality_error < 1e-10 && a.residuals.iter().all(|&r| r <= 1e-10));
}

/// Icospheres at three resolutions: the first 16 eigenvalues (l = 0..3, multiplicities
/// 1, 3, 5, 7) approach l(l+1) with order about 2 in the edge length.
#[test]
fn analytic_sphere_convergence() {
    let exact = |j: usize| {
        let l = (j as f64).sqrt().floor();
        l * (l + 1.0)
    };
    let mut errs = Vec::new();
    for level in [2usize, 3, 4] {
        let ops = Operators::new(&icosphere(level, 1.0), Laplacian::Fem);
        let b = compute_eigenbasis(&ops, &iterative(16), &mut |_| {}).unwrap();
        // Each group stays within 10% of l(l+1) (coarsest mesh: 8% for l = 3).
        for j in 1..16 {
            assert!(
                (b.values[j] - exact(j)).abs() < 0.1 * exact(j),
                "{:?}",
                b.values
            );
        }
        let e = (1..16)
            .map(|j| (b.values[j] - exact(j)).abs() / exact(j))
            .fold(0.0, f64::max);
        errs.push(e);
    }
    let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    eprintln!("sphere relative errors {errs:?}, orders {orders:?}");
    for o in orders {
        assert!((1.7..2.3).contains(&o), "order {o}");
    }
}

#[test]
fn progress_reports_phases() {
    let mesh = icosphere(3, 1.0);
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let mut events = Vec::new();
    compute_eigenbasis(&ops, &iterative(10), &mut |e| events.push(e)).unwrap();
    assert!(matches!(events[0], EigenProgress::Factorization { .. }));
    assert!(
        events
            .iter()
            .any(|e| matches!(e, EigenProgress::Iteration { .. }))
    );
    assert!(matches!(
        events.last(),
        Some(EigenProgress::Finished { .. })
    ));
}

fn same_bits(a: &Eigenbasis, b: &Eigenbasis) {
    assert_eq!(a.values, b.values);
    assert_eq!(a.vectors, b.vectors);
    assert_eq!(a.residuals, b.residuals);
}

/// Factor reuse: solve(100) then solve(105) (the same interior target) factors once,
/// solve(200) (another target) once more, and the pairs equal, bit for bit, those of a
/// fresh solver and of `compute_eigenbasis`.
#[test]
fn solver_keeps_the_factor_and_the_history_does_not_matter() {
    use crate::linalg::interior_target;
    let ops = Arc::new(Operators::new(&icosphere(4, 1.0), Laplacian::Fem)); // 2562
    let params = EigenParams::default();
    let none = CancelToken::new();
    let mut solver = EigenSolver::new(ops.clone(), params.clone());
    assert_eq!(solver.factorizations(), 0);
    let mut events = Vec::new();
    let b100 = solver.solve(100, &mut |e| events.push(e), &none).unwrap();
    assert_eq!(b100.k(), 100);
    assert_eq!(solver.factorizations(), 1);
    assert!(matches!(events[0], EigenProgress::Factorization { .. }));
    events.clear();
    assert_eq!(interior_target(100), interior_target(105));
    let b105 = solver.solve(105, &mut |e| events.push(e), &none).unwrap();
    assert_eq!(solver.factorizations(), 1);
    assert!(
        !events
            .iter()
            .any(|e| matches!(e, EigenProgress::Factorization { .. }))
    );
    let direct = compute_eigenbasis(
        &ops,
        &EigenParams {
            k: 105,
            ..params.clone()
        },
        &mut |_| {},
    )
    .unwrap();
    same_bits(&b105, &direct);
    events.clear();
    assert_ne!(interior_target(105), interior_target(200));
    let b200 = solver.solve(200, &mut |e| events.push(e), &none).unwrap();
    assert_eq!(solver.factorizations(), 2);
    assert!(
        events
            .iter()
            .any(|e| matches!(e, EigenProgress::Factorization { .. }))
    );
    assert!(matches!(
        events.last(),
        Some(EigenProgress::Finished { .. })
    ));
    // Fewer pairs than held: the held basis.
    let again = solver.solve(150, &mut |_| {}, &none).unwrap();
    assert!(Arc::ptr_eq(&again, &b200));
    assert!(Arc::ptr_eq(&solver.held().unwrap(), &b200));

    let mut fresh = EigenSolver::new(ops.clone(), params.clone());
    let f200 = fresh.solve(200, &mut |_| {}, &none).unwrap();
    assert_eq!(fresh.factorizations(), 1);
    same_bits(&b200, &f200);
    let direct = compute_eigenbasis(
        &ops,
        &EigenParams {
            k: 200,
            ..params.clone()
        },
        &mut |_| {},
    )
    .unwrap();
    same_bits(&b200, &direct);
    // And the first solve is the k = 100 one of compute_eigenbasis.
    let direct100 =
        compute_eigenbasis(&ops, &EigenParams { k: 100, ..params }, &mut |_| {}).unwrap();
    same_bits(&b100, &direct100);
    assert!(b200.residuals.iter().all(|&r| r <= 1e-10));
}

/// Under Dirichlet conditions the kept factor is the free block's.
#[test]
fn solver_with_dirichlet_vertices_reuses_its_factor() {
    let ops = Arc::new(Operators::new(&disk(12), Laplacian::Fem));
    let n = ops.n();
    let params = EigenParams {
        dirichlet: Some((n - 6 * 12..n).collect()),
        method: EigenMethod::ShiftInvertBlock,
        ..Default::default()
    };
    let none = CancelToken::new();
    let mut solver = EigenSolver::new(ops.clone(), params.clone());
    solver.solve(6, &mut |_| {}, &none).unwrap();
    let b = solver.solve(20, &mut |_| {}, &none).unwrap();
    assert_eq!(solver.factorizations(), 1);
    let direct = compute_eigenbasis(&ops, &EigenParams { k: 20, ..params }, &mut |_| {}).unwrap();
    same_bits(&b, &direct);
    assert!((b.values[0] - 5.783).abs() < 0.1);
}

/// Dense-path problems need no factorization; errors leave the counter alone.
#[test]
fn dense_solves_count_no_factorization() {
    let ops = Arc::new(Operators::new(&icosphere(2, 1.0), Laplacian::Fem)); // 162
    let none = CancelToken::new();
    let mut solver = EigenSolver::new(ops.clone(), EigenParams::default());
    let b = solver.solve(10, &mut |_| {}, &none).unwrap();
    solver.solve(40, &mut |_| {}, &none).unwrap();
    assert_eq!(solver.factorizations(), 0);
    assert_eq!(b.k(), 10);
    assert!(matches!(
        solver.solve(163, &mut |_| {}, &none),
        Err(EigenError::TooMany { k: 163, n: 162 })
    ));
    assert!(matches!(
        solver.solve(0, &mut |_| {}, &none),
        Err(EigenError::Zero)
    ));
    assert_eq!(solver.factorizations(), 0);
    assert_eq!(solver.held().unwrap().k(), 40);
}

/// A solve cancelled from another thread 50 ms in returns `Cancelled` (the wait is
/// bounded generously; no assertion on speed), and the solver stays usable: the next
/// solve gives the bits of a fresh solver, on the factor it kept.
#[test]
fn a_cancelled_solve_leaves_the_solver_usable() {
    let ops = Arc::new(Operators::new(&icosphere(5, 1.0), Laplacian::Fem)); // 10242
    let params = EigenParams::default();
    let token = CancelToken::new();
    let remote = token.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let mut solver = EigenSolver::new(ops.clone(), params.clone());
    let worker = std::thread::spawn(move || {
        let r = solver.solve(300, &mut |_| {}, &token).map(|b| b.k());
        let _ = tx.send((r, solver));
    });
    std::thread::sleep(std::time::Duration::from_millis(50));
    remote.cancel();
    let (r, mut solver) = rx
        .recv_timeout(std::time::Duration::from_secs(120))
        .expect("the cancelled solve returns");
    worker.join().unwrap();
    assert_eq!(r, Err(EigenError::Cancelled));
    assert!(solver.held().is_none());
    let made = solver.factorizations();
    assert!(made <= 1);
    // A cancelled token stops the next solve at once...
    assert!(matches!(
        solver.solve(40, &mut |_| {}, &remote),
        Err(EigenError::Cancelled)
    ));
    // ...and a fresh one gives what a fresh solver gives.
    let none = CancelToken::new();
    let b = solver.solve(40, &mut |_| {}, &none).unwrap();
    // k = 40 has another interior target than 300: a factor of its own.
    assert_eq!(solver.factorizations(), made + 1);
    let fresh = EigenSolver::new(ops, params)
        .solve(40, &mut |_| {}, &none)
        .unwrap();
    same_bits(&b, &fresh);
}
