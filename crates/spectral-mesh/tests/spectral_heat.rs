//! Heat kernel: exact properties on the full spectrum, references, the analytic sphere.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod spectral_util;

use spectral_mesh::spectral::heat::{
    HeatSolver, Kernel, ScaleNormalization, basis_function, diffuse, normalize_basis,
    reference_basis_function_dense, reference_heat_time_stepping, sphere_heat_kernel, total_mass,
};
use spectral_mesh::{Eigenbasis, Laplacian, Operators};
use spectral_util::*;

fn b_inner(basis: &Eigenbasis, f: &[f64], g: &[f64]) -> f64 {
    dot(&basis.mass.mul_vec(f), g)
}

fn signal(n: usize, seed: u64) -> Vec<f64> {
    let mut r = Lcg(seed);
    (0..n).map(|_| r.next() - 0.3).collect()
}

#[test]
fn full_spectrum_kernel_properties() {
    for (mesh, lap) in [
        (planar_patch(8, 3), Laplacian::Fem),
        (torus(9, 6, 1.0, 0.4, 0.4, 5), Laplacian::Fem),
        (planar_patch(7, 9), Laplacian::VoronoiCot),
    ] {
        let ops = Operators::new(&mesh, lap);
        let n = ops.n();
        let basis = Eigenbasis::dense(&ops, n).unwrap();
        let kind = if lap == Laplacian::Fem {
            Kernel::Wfem
        } else {
            Kernel::VoronoiCot
        };
        let f = signal(n, 1);
        let g = signal(n, 2);
        let (s, t) = (0.013, 0.021);
        let kf = diffuse(&basis, &f, t, kind).unwrap();
        // Mass conservation.
        let ones = vec![1.0; n];
        let m0 = b_inner(&basis, &ones, &f);
        let m1 = b_inner(&basis, &ones, &kf);
        assert!((m0 - m1).abs() <= 1e-10 * m0.abs(), "{m0} {m1}");
        // Semigroup.
        let ks_kt = diffuse(&basis, &kf, s, kind).unwrap();
        let kst = diffuse(&basis, &f, s + t, kind).unwrap();
        assert!(max_diff(&ks_kt, &kst) <= 1e-10 * max_abs(&kst));
        // B-self-adjointness.
        let kg = diffuse(&basis, &g, t, kind).unwrap();
        let (a, b) = (b_inner(&basis, &kf, &g), b_inner(&basis, &f, &kg));
        assert!((a - b).abs() <= 1e-10 * a.abs().max(b.abs()), "{a} {b}");
        // t = 0 is the identity on the full spectrum.
        let k0 = diffuse(&basis, &f, 0.0, kind).unwrap();
        assert!(max_diff(&k0, &f) <= 1e-10 * max_abs(&f));
        // Convergence to the B-weighted mean.
        let mean = m0 / b_inner(&basis, &ones, &ones);
        let big = 50.0 / basis.values[1];
        let kb = diffuse(&basis, &f, big, kind).unwrap();
        let dev = kb.iter().fold(0.0f64, |m, v| m.max((v - mean).abs()));
        assert!(dev <= 1e-10 * mean.abs(), "{dev}");
        // Basis function = diffusion of e_i.
        let mut e = vec![0.0; n];
        e[3] = 1.0;
        let a = basis_function(&basis, 3, t, kind).unwrap();
        let b = diffuse(&basis, &e, t, kind).unwrap();
        assert!(max_diff(&a, &b) <= 1e-12 * max_abs(&b));
    }
}

#[test]
fn wfem_s_t_is_symmetric_positive_definite() {
    let (ops, basis) = fem_full_basis(&icosphere(1));
    let n = ops.n();
    let t = 0.05;
    // S_t = B K_t (columns B K_t e_j).
    let mut st = vec![vec![0.0; n]; n];
    for j in 0..n {
        let col = ops
            .mass
            .mul_vec(&basis_function(&basis, j, t, Kernel::Wfem).unwrap());
        for i in 0..n {
            st[i][j] = col[i];
        }
    }
    let scale = st.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..n {
        for j in 0..i {
            assert!((st[i][j] - st[j][i]).abs() <= 1e-12 * scale);
        }
    }
    assert!(cholesky(&st).is_some(), "S_t is not positive definite");
    // The paper: ||x_i - x_j||_t^2 = exp(-lambda_i t) + exp(-lambda_j t) for i != j.
    let (a, b) = (4, 9);
    let d: Vec<f64> = basis
        .vector(a)
        .iter()
        .zip(basis.vector(b))
        .map(|(x, y)| x - y)
        .collect();
    let sd: Vec<f64> = (0..n).map(|i| dot(&st[i], &d)).collect();
    let lhs = dot(&d, &sd);
    let rhs = (-basis.values[a] * t).exp() + (-basis.values[b] * t).exp();
    assert!((lhs - rhs).abs() <= 1e-10 * rhs, "{lhs} {rhs}");
}

#[test]
fn dense_reference_matches_time_stepping() {
    let mesh = planar_patch(8, 11);
    let ops = fem(&mesh);
    let n = ops.n();
    let tol = 1e-10;
    for (anchor, t) in [(20usize, 0.01), (5, 0.1)] {
        let dense = reference_basis_function_dense(&ops, anchor, t).unwrap();
        let mut e = vec![0.0; n];
        e[anchor] = 1.0;
        let ts = reference_heat_time_stepping(&ops, &e, t, tol).unwrap();
        let err = max_diff(&dense, &ts.values) / max_abs(&dense);
        println!(
            "time stepping vs dense: t = {t}, N = {}, estimate {:.2e}, error {err:.2e}",
            ts.base_steps, ts.estimated_error
        );
        assert!(err < 1e-9, "{err}");
    }
}

#[test]
fn sphere_kernel_converges_with_refinement() {
    let t = 0.1;
    let mut errs = Vec::new();
    let mut hs = Vec::new();
    for level in [1usize, 2, 3] {
        let mesh = icosphere(level);
        let (ops, basis) = fem_full_basis(&mesh);
        let anchor = 0;
        let k = basis_function(&basis, anchor, t, Kernel::Wfem).unwrap();
        let area = ops.mass.row_sums()[anchor];
        let p0 = mesh.positions()[anchor];
        let mut err: f64 = 0.0;
        let mut peak: f64 = 0.0;
        for (i, p) in mesh.positions().iter().enumerate() {
            let c = (p[0] * p0[0] + p[1] * p0[1] + p[2] * p0[2]).clamp(-1.0, 1.0);
            let exact = sphere_heat_kernel(c.acos(), t, 1.0, 150);
            err = err.max((k[i] / area - exact).abs());
            peak = peak.max(exact);
        }
        errs.push(err / peak);
        hs.push(mesh.mean_edge_length());
    }
    for i in 1..errs.len() {
        let rate = (errs[i - 1] / errs[i]).ln() / (hs[i - 1] / hs[i]).ln();
        println!(
            "sphere heat kernel t = {t}: h = {:.4} rel. L_inf error {:.3e} -> h = {:.4} {:.3e}, rate {rate:.2}",
            hs[i - 1],
            errs[i - 1],
            hs[i],
            errs[i]
        );
        assert!(errs[i] < errs[i - 1], "{errs:?}");
    }
    assert!(errs[2] < 0.05, "{errs:?}");
}

#[test]
fn solver_matches_free_functions_and_normalisation_is_documented() {
    let mesh = torus(10, 6, 1.0, 0.35, 0.3, 2);
    let ops = fem(&mesh);
    let basis = Eigenbasis::dense(&ops, 30).unwrap();
    let a = total_mass(&basis);
    assert!((a - mesh.area()).abs() <= 1e-12 * a);
    let t = 0.002;
    for kind in [Kernel::Wfem, Kernel::VoronoiCot, Kernel::Standard] {
        let plain = HeatSolver::new(&basis, kind, ScaleNormalization::None);
        let x = plain.basis_function(7, t).unwrap();
        let y = basis_function(&basis, 7, t, kind).unwrap();
        assert!(max_diff(&x, &y) <= 1e-13 * max_abs(&y));
        // Unit area: time t on the normalised shape = time A t on the input.
        let unit = HeatSolver::new(&basis, kind, ScaleNormalization::UnitArea);
        let u = unit.basis_function(7, t).unwrap();
        let v = basis_function(&basis, 7, a * t, kind).unwrap();
        let factor = if kind == Kernel::Standard { a } else { 1.0 };
        let vs: Vec<f64> = v.iter().map(|z| z * factor).collect();
        assert!(max_diff(&u, &vs) <= 1e-12 * max_abs(&vs), "{kind:?}");
        let many = unit.basis_functions(&[7, 2], t).unwrap();
        assert_eq!(many[0], u);
    }
    // A scaled copy of the mesh gives the same unit-area kernel.
    let scaled = mesh
        .map_positions(|p| [3.0 * p[0], 3.0 * p[1], 3.0 * p[2]])
        .unwrap();
    let b2 = Eigenbasis::dense(&fem(&scaled), 30).unwrap();
    let n1 = normalize_basis(&basis, ScaleNormalization::UnitArea);
    let n2 = normalize_basis(&b2, ScaleNormalization::UnitArea);
    for j in 0..30 {
        assert!((n1.values[j] - n2.values[j]).abs() <= 1e-9 * n1.values[29]);
    }
    let s1 = HeatSolver::new(&basis, Kernel::Wfem, ScaleNormalization::UnitArea);
    let s2 = HeatSolver::new(&b2, Kernel::Wfem, ScaleNormalization::UnitArea);
    let (k1, k2) = (
        s1.basis_function(3, 0.01).unwrap(),
        s2.basis_function(3, 0.01).unwrap(),
    );
    assert!(max_diff(&k1, &k2) <= 1e-9 * max_abs(&k1));
}

#[test]
fn bad_inputs_are_errors() {
    let mesh = planar_patch(5, 1);
    let ops = fem(&mesh);
    let basis = Eigenbasis::dense(&ops, 5).unwrap();
    assert!(basis_function(&basis, 99, 0.1, Kernel::Wfem).is_err());
    assert!(basis_function(&basis, 0, -1.0, Kernel::Wfem).is_err());
    assert!(basis_function(&basis, 0, f64::NAN, Kernel::Wfem).is_err());
    assert!(diffuse(&basis, &[1.0, 2.0], 0.1, Kernel::Wfem).is_err());
    assert!(reference_heat_time_stepping(&ops, &[0.0; 25], 0.1, 0.0).is_err());
}
