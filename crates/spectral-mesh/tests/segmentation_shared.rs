//! Segmentation by the auto-diffusion function (the heat signature of Fig. 1a) on a
//! built-in shape and on shared meshes: every vertex in exactly one patch, and the number
//! of patches stable (the same on a second run and recorded here as measured).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::fields::segmentation::{SegmentParams, segment};
use spectral_mesh::io::read_mesh;
use spectral_mesh::spectral::eigenbasis::{EigenParams, compute_eigenbasis};
use spectral_mesh::spectral::heat::{ScaleNormalization, normalize_basis};
use spectral_mesh::spectral::signatures::auto_diffusion;
use spectral_mesh::{Laplacian, Mesh, Operators};

fn patches(mesh: &Mesh) -> (usize, Vec<Option<i64>>) {
    let ops = Operators::new(mesh, Laplacian::Fem);
    let params = EigenParams {
        k: 60,
        ..Default::default()
    };
    let basis = compute_eigenbasis(&ops, &params, &mut |_| {}).unwrap();
    let basis = normalize_basis(&basis, ScaleNormalization::UnitArea);
    let adf = auto_diffusion(&basis, 0.02).unwrap();
    let s = segment(mesh, &adf, SegmentParams::default()).unwrap();
    assert_eq!(s.labels.len(), mesh.n_vertices());
    assert!(s.labels.iter().all(|&l| l < s.n_patches));
    for p in 0..s.n_patches {
        assert!(s.labels.contains(&p), "patch {p} is empty");
    }
    // Stable: the same input gives the same segmentation.
    let again = segment(mesh, &adf, SegmentParams::default()).unwrap();
    assert_eq!(again.labels, s.labels);
    (s.n_patches, s.patch_genus)
}

#[test]
fn segmentation_of_the_three_torus_is_stable() {
    let mesh = spectral_mesh::shapes::build_str("3torus:res=2").unwrap();
    let (n, genus) = patches(&mesh);
    eprintln!("3torus:res=2: {n} patches, genus {genus:?}");
    assert!(n >= 1);
}

#[test]
fn segmentation_of_shared_meshes_reports_patches() {
    let Some(dir) = spectral_mesh_testkit::shared_meshes() else {
        return;
    };
    for name in ["hand.off", "cow.off", "eight.off"] {
        let mesh = read_mesh(&dir.join(name)).unwrap().mesh;
        let (n, genus) = patches(&mesh);
        eprintln!("{name}: {n} patches, genus {genus:?}");
        assert!(n >= 2, "{name}: a shape with limbs has several ADF maxima");
    }
}
