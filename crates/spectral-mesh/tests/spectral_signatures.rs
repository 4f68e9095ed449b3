//! Signatures (HKS, WKS, ADF) and segmentation by persistence-merged watersheds.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod spectral_util;

use spectral_mesh::Eigenbasis;
use spectral_mesh::fields::segmentation::{SegmentParams, segment};
use spectral_mesh::spectral::distances::spectral_function;
use spectral_mesh::spectral::filters::Filter;
use spectral_mesh::spectral::heat::{Kernel, basis_function};
use spectral_mesh::spectral::signatures::{
    auto_diffusion, hks, hks_auto_times, wks, wks_auto_energies,
};
use spectral_util::*;

#[test]
fn hks_is_the_kernel_diagonal_and_auto_times_follow_pyfm() {
    let mesh = torus(9, 6, 1.0, 0.4, 0.3, 8);
    let basis = Eigenbasis::dense(&fem(&mesh), 20).unwrap();
    let times = hks_auto_times(&basis, 5).unwrap();
    let c = 4.0 * 10f64.ln();
    assert!((times[0] - c / basis.values[19]).abs() <= 1e-12 * times[0]);
    assert!((times[4] - c / basis.values[1]).abs() <= 1e-12 * times[4]);
    let ratio = times[1] / times[0];
    for w in times.windows(2) {
        assert!((w[1] / w[0] - ratio).abs() < 1e-9);
    }
    let h = hks(&basis, &times, false);
    let hs = hks(&basis, &times, true);
    for (ti, &t) in times.iter().enumerate() {
        let trace: f64 = basis.values.iter().map(|l| (-l * t).exp()).sum();
        for p in [0usize, 13, 40] {
            let col = basis_function(&basis, p, t, Kernel::Standard).unwrap();
            assert!((h[ti][p] - col[p]).abs() <= 1e-12 * col[p]);
            assert!((hs[ti][p] * trace - h[ti][p]).abs() <= 1e-12 * h[ti][p]);
        }
    }
    // ADF = generalized spectral function with the diffusion weight (zero pair skipped).
    let adf = auto_diffusion(&basis, 0.05).unwrap();
    let g = spectral_function(&basis, &Filter::Diffusion { t: 0.05 }).unwrap();
    assert_eq!(adf, g);
    let h0 = hks(&basis, &[0.05], false);
    let x0 = basis.vector(0);
    for p in 0..mesh.n_vertices() {
        assert!((h0[0][p] - x0[p] * x0[p] - adf[p]).abs() <= 1e-12 * h0[0][p]);
    }
}

#[test]
fn wks_auto_energies_follow_pyfm_and_are_sign_invariant() {
    let mesh = planar_patch(7, 3);
    let mut basis = Eigenbasis::dense(&fem(&mesh), 15).unwrap();
    let (e, sigma) = wks_auto_energies(&basis, 6).unwrap();
    let (emin, emax) = (basis.values[1].ln(), basis.values[14].ln());
    assert!((sigma - 7.0 * (emax - emin) / 6.0).abs() < 1e-12);
    assert!((e[0] - (emin + 2.0 * sigma)).abs() < 1e-12);
    assert!((e[5] - (emax - 2.0 * sigma)).abs() < 1e-12);
    let w1 = wks(&basis, &e, sigma, true).unwrap();
    // Flip the sign of some eigenvectors: nothing changes.
    let n = basis.n;
    for j in [2usize, 5] {
        basis.vectors[j * n..(j + 1) * n]
            .iter_mut()
            .for_each(|v| *v = -*v);
    }
    let w2 = wks(&basis, &e, sigma, true).unwrap();
    assert_eq!(w1, w2);
    // Scaled WKS with the full constant-free B-normalised basis: sum_p of B-weighted
    // unscaled WKS equals sum of coefficients (x_k B-normalised).
    let wu = wks(&basis, &e[..1], sigma, false).unwrap();
    let bw = basis.mass.mul_vec(&vec![1.0; n]);
    let lumped_integral: f64 = wu[0].iter().zip(&bw).map(|(a, b)| a * b).sum();
    assert!(lumped_integral > 0.0);
    assert!(wks(&basis, &e, 0.0, true).is_err());
}

fn two_bumps(mesh: &spectral_mesh::Mesh, noise: f64) -> Vec<f64> {
    let mut rng = Lcg(99);
    mesh.positions()
        .iter()
        .map(|p| {
            let a = (p[0] * p[0] + p[1] * p[1] + (p[2] - 1.0).powi(2)) / 0.3;
            let b = ((p[0] - 1.0).powi(2) + p[1] * p[1] + p[2] * p[2]) / 0.3;
            (-a).exp() + 0.8 * (-b).exp() + noise * rng.next()
        })
        .collect()
}

#[test]
fn segmentation_of_two_bumps_on_a_sphere() {
    let mesh = icosphere(3);
    let n = mesh.n_vertices();
    let f = two_bumps(&mesh, 0.0);
    let s = segment(&mesh, &f, SegmentParams { persistence: 0.05 }).unwrap();
    assert_eq!(s.labels.len(), n);
    assert_eq!(s.n_patches, 2);
    assert!(s.labels.iter().all(|&l| l < s.n_patches));
    for l in 0..s.n_patches {
        assert!(s.labels.contains(&l));
    }
    assert_eq!(s.patch_genus, vec![Some(0), Some(0)]);
    // Patch 0 holds the highest maximum (near the north pole).
    assert!(mesh.positions()[s.maxima[0]][2] > 0.9);
    // Deterministic.
    let s2 = segment(&mesh, &f, SegmentParams { persistence: 0.05 }).unwrap();
    assert_eq!(s, s2);
    // Noise: without merging there are many patches; with merging the two bumps return.
    let g = two_bumps(&mesh, 0.02);
    let raw = segment(&mesh, &g, SegmentParams { persistence: 0.0 }).unwrap();
    let merged = segment(&mesh, &g, SegmentParams { persistence: 0.1 }).unwrap();
    assert!(raw.n_patches > 2, "{}", raw.n_patches);
    assert_eq!(merged.n_patches, 2);
    // Raising the threshold only merges.
    let all = segment(&mesh, &g, SegmentParams { persistence: 2.0 }).unwrap();
    assert_eq!(all.n_patches, 1);
    assert_eq!(all.patch_genus, vec![Some(0)]);
    assert!(segment(&mesh, &g[..10], SegmentParams::default()).is_err());
}

#[test]
fn segmentation_of_a_torus_by_a_signature_covers_every_vertex() {
    let mesh = torus(16, 8, 1.0, 0.35, 0.2, 4);
    let basis = Eigenbasis::dense(&fem(&mesh), 30).unwrap();
    let times = hks_auto_times(&basis, 3).unwrap();
    let h = hks(&basis, &times[1..2], true);
    let s = segment(&mesh, &h[0], SegmentParams::default()).unwrap();
    assert!(s.n_patches >= 1);
    let mut count = vec![0usize; s.n_patches];
    for &l in &s.labels {
        count[l] += 1;
    }
    assert!(count.iter().all(|&c| c > 0));
    assert_eq!(count.iter().sum::<usize>(), mesh.n_vertices());
    let one = segment(&mesh, &h[0], SegmentParams { persistence: 10.0 }).unwrap();
    assert_eq!(one.n_patches, 1);
    assert_eq!(one.patch_genus, vec![Some(1)]);
}
