//! # spectral-mesh
//!
//! Harmonic maps, heat diffusion and filtered spectral distances on triangle meshes.
//!
//! Data flows one way: a file or a built-in shape becomes a [`Mesh`]; the mesh gives
//! operators ([`operators::Operators`]: the stiffness S, positive semi-definite, and a
//! mass B); operators give an eigenbasis; the basis (or a direct solve) gives fields.
//! Conventions are those of the repository's `docs/MATH.md` (every formula with its sign,
//! scale and implementing file); the layout is in `docs/ARCHITECTURE.md`.

pub mod analysis;
pub mod batch;
pub mod cancel;
pub mod correspondence;
pub mod defaults;
pub mod experiments;
pub mod fields;
pub mod geodesic;
pub mod io;
pub mod learning;
pub mod linalg;
pub mod mesh;
pub mod operators;
pub mod perturb;
pub mod shapes;
pub mod spectral;
#[cfg(test)]
mod test_support;

pub use analysis::{Analysis, AnalysisOptions, Field, FieldRequest};
pub use cancel::CancelToken;
pub use linalg::SparseMatrix;
pub use mesh::{Mesh, PointCloud};
pub use operators::{Laplacian, Operators};
pub use spectral::{BasisView, Eigenbasis};
