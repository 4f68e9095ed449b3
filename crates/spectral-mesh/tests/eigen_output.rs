//! What `eigs` hands out (issue 27): a float32 archive holds the float64 basis rounded
//! once, and the tolerance is the target relative residual (a looser one takes fewer
//! solves, and the residuals reported are the true ones).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::linalg::{SparseEigenOptions, relative_residuals, sparse_generalized_eigen};
use spectral_mesh::spectral::eigenbasis::{EigenMethod, EigenParams, compute_eigenbasis};
use spectral_mesh::spectral::store::{BasisDtype, BasisMeta, load_npz, save_npz};
use spectral_mesh::{Laplacian, Operators};

#[test]
fn float32_archive_is_the_float64_basis_rounded_once() {
    let mesh = spectral_mesh::shapes::build_str("torus:res=1").unwrap();
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let params = EigenParams {
        k: 12,
        method: EigenMethod::ShiftInvertBlock,
        ..Default::default()
    };
    let basis = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
    let dir = std::env::temp_dir().join(format!("sm-dtype-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p64 = dir.join("b64.npz");
    let p32 = dir.join("b32.npz");
    let meta = BasisMeta::new(&basis, Some(&mesh), &params);
    save_npz(&basis, &p64, &meta).unwrap();
    save_npz(&basis, &p32, &meta.clone().with_dtype(BasisDtype::Float32)).unwrap();
    let (b64, m64) = load_npz(&p64).unwrap();
    let (b32, m32) = load_npz(&p32).unwrap();
    assert_eq!(m64.dtype, BasisDtype::Float64);
    assert_eq!(m32.dtype, BasisDtype::Float32);
    assert_eq!(b64.values, basis.values);
    assert_eq!(b64.vectors, basis.vectors);
    let round = |v: &[f64]| v.iter().map(|&x| x as f32 as f64).collect::<Vec<f64>>();
    assert_eq!(b32.values, round(&basis.values));
    assert_eq!(b32.vectors, round(&basis.vectors));
    // Rounding changed something (the test would pass trivially otherwise).
    assert_ne!(b32.vectors, basis.vectors);
    // The float32 file is smaller by about the eigenvectors' half.
    let (s64, s32) = (
        std::fs::metadata(&p64).unwrap().len(),
        std::fs::metadata(&p32).unwrap().len(),
    );
    assert!(
        s32 < s64 - (basis.vectors.len() as u64) * 3,
        "{s32} vs {s64}"
    );
    assert_eq!(BasisDtype::parse("f4").unwrap(), BasisDtype::Float32);
    assert!(BasisDtype::parse("float16").is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_looser_tolerance_takes_fewer_solves_and_reports_true_residuals() {
    let mesh = spectral_mesh::shapes::build_str("irregular-double-torus:res=2").unwrap();
    let ops = Operators::new(&mesh, Laplacian::Fem);
    let (s, b) = (&ops.stiffness, &ops.mass);
    let mut solves = Vec::new();
    for tol in [1e-10, 1e-6] {
        let opts = SparseEigenOptions {
            k: 50,
            tolerance: tol,
            ..Default::default()
        };
        let r = sparse_generalized_eigen(s, b, &opts, &mut |_| {}).unwrap();
        let truth = relative_residuals(s, b, &r.values, &r.vectors);
        assert_eq!(r.residuals, truth);
        assert!(truth.iter().all(|&x| x <= tol), "tol {tol}: {truth:?}");
        solves.push(r.solves);
    }
    assert!(solves[1] < solves[0], "solves at 1e-10, 1e-6: {solves:?}");
}
