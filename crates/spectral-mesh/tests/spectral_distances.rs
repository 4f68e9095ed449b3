//! Filtered spectral distances: metric axioms, closed forms, truncation, isometry, filters.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod spectral_util;

use spectral_mesh::Eigenbasis;
use spectral_mesh::spectral::distances::{
    all_pairs, distances_from, distances_from_many, green_row, spectral_function,
    wfem_diffusion_distances_from, wfem_diffusion_kernel_row,
};
use spectral_mesh::spectral::embedding::{embedding_mesh, spectral_embedding};
use spectral_mesh::spectral::filters::{Filter, FilterError};
use spectral_mesh::spectral::heat::{ScaleNormalization, normalize_basis};
use spectral_util::*;

fn filters() -> Vec<Filter> {
    vec![
        Filter::Diffusion { t: 0.01 },
        Filter::CommuteTime,
        Filter::Biharmonic,
    ]
}

#[test]
fn metric_axioms_on_random_triples() {
    let mesh = torus(10, 6, 1.0, 0.4, 0.4, 7);
    let (ops, basis) = fem_full_basis(&mesh);
    let n = ops.n();
    let mut rng = Lcg(42);
    for f in filters() {
        let d = all_pairs(&basis, &f).unwrap();
        let scale = max_abs(&d);
        for i in 0..n {
            assert_eq!(d[i * n + i], 0.0);
            for j in 0..n {
                assert_eq!(d[i * n + j], d[j * n + i]);
                if i != j {
                    assert!(d[i * n + j] > 1e-6 * scale, "{f}: zero off the diagonal");
                }
            }
        }
        for _ in 0..2000 {
            let (a, b, c) = (rng.index(n), rng.index(n), rng.index(n));
            assert!(
                d[a * n + c] <= d[a * n + b] + d[b * n + c] + 1e-12 * scale,
                "{f}: triangle inequality fails at ({a}, {b}, {c})"
            );
        }
        // Rows of all_pairs = distances_from.
        let row = distances_from(&basis, 5, &f).unwrap();
        assert!(max_diff(&row, &d[5 * n..6 * n]) <= 1e-12 * scale);
        let many = distances_from_many(&basis, &[5, 9], &f).unwrap();
        assert_eq!(many[0], row);
    }
}

/// G = (S + b b^T / A)^-1 - 1 1^T / A is the B-pseudo-inverse X Lambda^+ X^T (one
/// component), and X Lambda^+2 X^T = G B G.
#[test]
fn commute_and_biharmonic_match_pseudo_inverse_closed_forms() {
    let mesh = planar_patch(9, 5);
    let (ops, basis) = fem_full_basis(&mesh);
    let n = ops.n();
    let s = dense(&ops.stiffness);
    let bm = dense(&ops.mass);
    let b1 = ops.mass.row_sums();
    let a: f64 = b1.iter().sum();
    let mut m = s.clone();
    for i in 0..n {
        for j in 0..n {
            m[i][j] += b1[i] * b1[j] / a;
        }
    }
    let mut g = spd_inverse(&m);
    for row in g.iter_mut() {
        for v in row.iter_mut() {
            *v -= 1.0 / a;
        }
    }
    let g2 = matmul(&matmul(&g, &bm), &g);
    for (f, gm) in [(Filter::CommuteTime, &g), (Filter::Biharmonic, &g2)] {
        let gscale = gm.iter().flatten().fold(0.0f64, |x, v| x.max(v.abs()));
        for p in [0usize, 17, 40] {
            let row = green_row(&basis, p, &f).unwrap();
            let err = max_diff(&row, &gm[p]) / gscale;
            assert!(err < 1e-9, "{f} green row error {err:.2e}");
            let d = distances_from(&basis, p, &f).unwrap();
            let want: Vec<f64> = (0..n)
                .map(|q| (gm[p][p] - 2.0 * gm[p][q] + gm[q][q]).max(0.0).sqrt())
                .collect();
            let err = max_diff(&d, &want) / max_abs(&want);
            println!("{f}: distances vs pseudo-inverse closed form, rel. error {err:.2e}");
            assert!(err < 1e-9, "{f} distance error {err:.2e}");
        }
        let sf = spectral_function(&basis, &f).unwrap();
        let diag: Vec<f64> = (0..n).map(|i| gm[i][i]).collect();
        assert!(max_diff(&sf, &diag) <= 1e-9 * max_abs(&diag));
    }
    // Truncation: error of the first k pairs decreases with k.
    for f in [Filter::CommuteTime, Filter::Biharmonic] {
        let full = distances_from(&basis, 17, &f).unwrap();
        let mut last = f64::INFINITY;
        for k in [5usize, 10, 20, 40] {
            let tb = Eigenbasis::dense(&ops, k).unwrap();
            let d = distances_from(&tb, 17, &f).unwrap();
            let err = max_diff(&d, &full) / max_abs(&full);
            println!("{f}: k = {k} truncation rel. error {err:.3e}");
            assert!(err < last, "{f}: k = {k}: {err} !< {last}");
            last = err;
        }
    }
}

#[test]
fn isometry_and_scale() {
    let mesh = torus(11, 7, 1.0, 0.35, 0.4, 13);
    let alpha = 2.5;
    let (c, s) = (0.6f64, 0.8f64);
    let moved = mesh
        .map_positions(|p| {
            // Rotation about z and about x, then scale and translate.
            let q = [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
            let r = [q[0], c * q[1] - s * q[2], s * q[1] + c * q[2]];
            [alpha * r[0] + 1.0, alpha * r[1] - 2.0, alpha * r[2] + 0.5]
        })
        .unwrap();
    let n = mesh.n_vertices();
    let b1 = Eigenbasis::dense(&fem(&mesh), n).unwrap();
    let b2 = Eigenbasis::dense(&fem(&moved), n).unwrap();
    let (u1, u2) = (
        normalize_basis(&b1, ScaleNormalization::UnitArea),
        normalize_basis(&b2, ScaleNormalization::UnitArea),
    );
    for f in [
        Filter::Diffusion { t: 0.001 },
        Filter::CommuteTime,
        Filter::Biharmonic,
        Filter::Mix { a: 0.4, t: 0.001 },
    ] {
        let (d1, d2) = (
            distances_from(&u1, 4, &f).unwrap(),
            distances_from(&u2, 4, &f).unwrap(),
        );
        let err = max_diff(&d1, &d2) / max_abs(&d1);
        assert!(err < 1e-8, "{f}: unit-area distances differ by {err:.2e}");
    }
    // Without normalisation: bi-harmonic scales by alpha, commute time is invariant,
    // diffusion at time alpha^2 t scales by 1/alpha.
    let check = |f1: Filter, f2: Filter, factor: f64| {
        let d1 = distances_from(&b1, 4, &f1).unwrap();
        let d2 = distances_from(&b2, 4, &f2).unwrap();
        let want: Vec<f64> = d1.iter().map(|v| v * factor).collect();
        let err = max_diff(&d2, &want) / max_abs(&want);
        assert!(err < 1e-8, "{f1}: scaled distances differ by {err:.2e}");
    };
    check(Filter::Biharmonic, Filter::Biharmonic, alpha);
    check(Filter::CommuteTime, Filter::CommuteTime, 1.0);
    check(
        Filter::Diffusion { t: 0.01 },
        Filter::Diffusion {
            t: 0.01 * alpha * alpha,
        },
        1.0 / alpha,
    );
}

#[test]
fn mix_goes_from_diffusion_to_biharmonic() {
    let mesh = planar_patch(7, 2);
    let basis = Eigenbasis::dense(&fem(&mesh), 30).unwrap();
    let t = 0.02;
    let diff = distances_from(&basis, 3, &Filter::Diffusion { t }).unwrap();
    let bih = distances_from(&basis, 3, &Filter::Biharmonic).unwrap();
    let m0 = distances_from(&basis, 3, &Filter::Mix { a: 0.0, t }).unwrap();
    let m1 = distances_from(&basis, 3, &Filter::Mix { a: 1.0, t }).unwrap();
    assert!(max_diff(&m0, &diff) <= 1e-14 * max_abs(&diff));
    assert!(max_diff(&m1, &bih) <= 1e-14 * max_abs(&bih));
    // In between: d_a^2 = (1-a) d_diff^2 + a d_bih^2.
    let mh = distances_from(&basis, 3, &Filter::Mix { a: 0.3, t }).unwrap();
    for i in 0..mh.len() {
        let want = (0.7 * diff[i] * diff[i] + 0.3 * bih[i] * bih[i]).sqrt();
        assert!((mh[i] - want).abs() <= 1e-12 * max_abs(&bih));
    }
}

#[test]
fn filter_validation_names_the_failing_eigenvalue() {
    let mesh = planar_patch(6, 4);
    let basis = Eigenbasis::dense(&fem(&mesh), 20).unwrap();
    // w(s) = c - s is negative from the first eigenvalue above c.
    let c = 0.5 * (basis.values[6] + basis.values[7]);
    let f: Filter = format!("custom-w:c - s;c={c}").parse().unwrap();
    match distances_from(&basis, 0, &f) {
        Err(spectral_mesh::spectral::distances::DistanceError::Filter(
            FilterError::NotPositive { index, value, .. },
        )) => {
            assert_eq!(index, 7);
            assert_eq!(value, basis.values[7]);
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    // phi(s) = s - c is the same refusal, typed as phi.
    let f: Filter = format!("custom-phi:s - c;c={c}").parse().unwrap();
    let e = f.weights(&basis.values).unwrap_err();
    assert!(e.to_string().contains("eigenpair index 1"), "{e}");
    // A positive custom filter equals the built-in one.
    let f: Filter = "custom-phi:s^2".parse().unwrap();
    let a = distances_from(&basis, 0, &f).unwrap();
    let b = distances_from(&basis, 0, &Filter::Biharmonic).unwrap();
    assert!(max_diff(&a, &b) <= 1e-14 * max_abs(&b));
    // Parser errors carry positions.
    match "custom-w:exp(-s*t;t=1".parse::<Filter>() {
        Err(FilterError::Expression { position, .. }) => assert_eq!(position, 8),
        other => panic!("{other:?}"),
    }
    assert!("custom-w:s +".parse::<Filter>().is_err());
    assert!("poly:p=abc".parse::<Filter>().is_err());
    // Band suppression: suppressing pair j removes its contribution.
    let band = Filter::BandSuppression { indices: vec![2] };
    let w = band.weights(&basis.values).unwrap();
    assert_eq!(w[2], 0.0);
    assert_eq!(w[0], 0.0);
    assert!(
        w.iter()
            .enumerate()
            .all(|(i, &v)| i == 0 || i == 2 || v > 0.0)
    );
}

#[test]
fn wfem_diffusion_distance_matches_s_t() {
    let (_, basis) = fem_full_basis(&icosphere(1));
    let t = 0.03;
    let src = 5;
    let d = wfem_diffusion_distances_from(&basis, src, t).unwrap();
    let row_s = wfem_diffusion_kernel_row(&basis, src, t).unwrap();
    for j in [0usize, 7, 30] {
        let row_j = wfem_diffusion_kernel_row(&basis, j, t).unwrap();
        let want = (row_s[src] - 2.0 * row_s[j] + row_j[j]).max(0.0).sqrt();
        assert!((d[j] - want).abs() <= 1e-9 * max_abs(&d), "{} {want}", d[j]);
        assert!(row_s[j] != 0.0);
        assert!((row_j[src] - row_s[j]).abs() <= 1e-12 * max_abs(&row_s));
    }
    assert_eq!(d[src], 0.0);
}

#[test]
fn embedding_reproduces_distances() {
    let mesh = torus(9, 6, 1.0, 0.4, 0.3, 3);
    let basis = Eigenbasis::dense(&fem(&mesh), 25).unwrap();
    let f = Filter::Biharmonic;
    let e = spectral_embedding(&basis, &f, 100).unwrap();
    assert_eq!(e[0].len(), 24);
    let d = distances_from(&basis, 2, &f).unwrap();
    for q in 0..mesh.n_vertices() {
        let s: f64 = e[q].iter().zip(&e[2]).map(|(a, b)| (a - b) * (a - b)).sum();
        assert!((s.sqrt() - d[q]).abs() <= 1e-12 * max_abs(&d));
    }
    let m = embedding_mesh(&mesh, &basis, &f).unwrap();
    assert_eq!(m.triangles(), mesh.triangles());
    assert_eq!(m.positions()[4][1], e[4][1]);
}
