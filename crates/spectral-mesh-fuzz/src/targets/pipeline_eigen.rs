//! The whole pipeline on tiny inputs: read a mesh (the bytes after the first, format
//! sniffed from the content), or draw one from the input with the top bit of the first
//! byte set; build the operators of the discretization the first byte picks
//! (`Operators::new`); compute 10 eigenpairs (`spectral::eigenbasis::compute_eigenbasis`,
//! optionally with a Dirichlet vertex). Meshes over 1 500 vertices are skipped (the run
//! must stay under the 2 s hang limit). The solver may refuse a mesh (zero mass, too few
//! vertices); what it returns must be k finite eigenvalues in ascending order with finite
//! vectors.

use arbitrary::Unstructured;
use spectral_mesh::operators::{Laplacian, Operators};
use spectral_mesh::spectral::eigenbasis::{EigenParams, compute_eigenbasis};

const MAX_VERTICES: usize = 1_500;

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let Some((&b, rest)) = data.split_first() else {
        return;
    };
    let mesh = if b & 0x80 != 0 {
        let mut u = Unstructured::new(rest);
        match crate::arbitrary_mesh(&mut u, 255) {
            Some(m) => m,
            None => return,
        }
    } else {
        match crate::read_and_check(rest, "upload") {
            Some(l) => l.mesh,
            None => return,
        }
    };
    if mesh.n_vertices() > MAX_VERTICES {
        return;
    }
    let laplacian = Laplacian::ALL[usize::from(b & 7) % Laplacian::ALL.len()];
    let ops = Operators::new(&mesh, laplacian);
    assert_eq!(ops.n(), mesh.n_vertices());
    let params = EigenParams {
        k: 10,
        dirichlet: (b & 0x40 != 0).then(|| vec![0]),
        ..EigenParams::default()
    };
    let Ok(basis) = compute_eigenbasis(&ops, &params, &mut |_| {}) else {
        return;
    };
    assert_eq!(basis.values.len(), 10);
    assert_eq!(basis.vectors.len(), 10 * mesh.n_vertices());
    assert!(
        basis.values.iter().all(|v| v.is_finite()),
        "non-finite eigenvalue: {:?}",
        basis.values
    );
    assert!(
        basis.values.windows(2).all(|w| w[0] <= w[1]),
        "eigenvalues not ascending: {:?}",
        basis.values
    );
    assert!(
        basis.vectors.iter().all(|v| v.is_finite()),
        "non-finite eigenvector entry"
    );
}
