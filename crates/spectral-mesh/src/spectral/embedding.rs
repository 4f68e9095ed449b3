//! Spectral embeddings `p -> (sqrt(w(lambda_k)) x_k(p))_k` (Sect. 5 of the paper): the
//! Euclidean distance between embedded points is the filtered spectral distance.

use super::BasisView;
use super::distances::{DistanceError, check_weights};
use super::filters::Filter;
use crate::mesh::{Mesh, MeshError};

/// Errors of the embeddings.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum EmbeddingError {
    /// The filter is refused on this spectrum.
    #[error(transparent)]
    Distance(#[from] DistanceError),
    /// The embedded mesh could not be built.
    #[error("cannot build the embedded mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The basis does not match the mesh.
    #[error("the basis has {basis} vertices but the mesh has {mesh}")]
    SizeMismatch {
        /// Vertices of the basis.
        basis: usize,
        /// Vertices of the mesh.
        mesh: usize,
    },
}

/// The spectral embedding: one vector of `min(dims, number of non-zero pairs)` coordinates
/// per vertex, coordinate `c` = `sqrt(w(lambda)) x(p)` of the `c`-th pair with non-zero
/// weight (zero eigenvalues and suppressed pairs are skipped), in basis order.
pub fn spectral_embedding<'a>(
    basis: impl Into<BasisView<'a>>,
    filter: &Filter,
    dims: usize,
) -> Result<Vec<Vec<f64>>, EmbeddingError> {
    let basis: BasisView<'a> = basis.into();
    let w = filter.weights(basis.values).map_err(DistanceError::from)?;
    spectral_embedding_weights(basis, &w, dims)
}

/// [`spectral_embedding`] with the per-pair weights given (`k` entries, 0 for the pairs
/// left out; from [`Filter::weights`] or [`super::distances::weights_of_pairs`]).
pub fn spectral_embedding_weights<'a>(
    basis: impl Into<BasisView<'a>>,
    w: &[f64],
    dims: usize,
) -> Result<Vec<Vec<f64>>, EmbeddingError> {
    let basis: BasisView<'a> = basis.into();
    check_weights(basis, w)?;
    let n = basis.n;
    let used: Vec<usize> = (0..w.len()).filter(|&j| w[j] > 0.0).take(dims).collect();
    Ok((0..n)
        .map(|i| {
            used.iter()
                .map(|&j| w[j].sqrt() * basis.vectors[j * n + i])
                .collect()
        })
        .collect())
}

/// One coordinate of the embedding as a field: `sqrt(w_c) x_c(p)` for the pair `c` of the
/// basis (0-based; a pair of weight 0, such as a zero eigenvalue, gives zeros).
pub fn embedding_component<'a>(
    basis: impl Into<BasisView<'a>>,
    w: &[f64],
    component: usize,
) -> Result<Vec<f64>, DistanceError> {
    let basis: BasisView<'a> = basis.into();
    check_weights(basis, w)?;
    if component >= w.len() {
        return Err(DistanceError::ComponentOutOfRange {
            component,
            k: w.len(),
        });
    }
    let s = w[component].sqrt();
    Ok(basis.vector(component).iter().map(|x| s * x).collect())
}

/// The mesh with the same triangles whose positions are the first three coordinates of
/// the spectral embedding (missing coordinates are 0).
pub fn embedding_mesh<'a>(
    mesh: &Mesh,
    basis: impl Into<BasisView<'a>>,
    filter: &Filter,
) -> Result<Mesh, EmbeddingError> {
    let basis: BasisView<'a> = basis.into();
    if mesh.n_vertices() != basis.n {
        return Err(EmbeddingError::SizeMismatch {
            basis: basis.n,
            mesh: mesh.n_vertices(),
        });
    }
    let e = spectral_embedding(basis, filter, 3)?;
    let pos: Vec<[f64; 3]> = e
        .iter()
        .map(|v| std::array::from_fn(|d| v.get(d).copied().unwrap_or(0.0)))
        .collect();
    Ok(Mesh::new(pos, mesh.triangles().to_vec())?)
}
