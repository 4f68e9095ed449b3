//! Mesh perturbations for robustness studies (the paper's Sects. 4.4 and 5, Figs. 5, 6,
//! 11 and 13): noise, global and local scaling, rigid motions, near-isometric bending,
//! re-triangulations of the same surface, local refinement, tiny and missing triangles,
//! and holes.
//!
//! Every perturbation returns a [`Perturbed`]: the new mesh, a [`SurfaceMap`] that sends
//! each vertex of the new mesh back to the original surface, and a one-line description.
//! With the map, a field computed on the original mesh is pulled back to the perturbed
//! vertices ([`SurfaceMap::pull_back`]) and compared there with the field computed on the
//! perturbed mesh ([`compare_fields`]).
//!
//! Everything random is deterministic given a seed (a SplitMix64 generator and
//! Box-Muller normals, see [`rng`]): the same seed gives the same mesh bit for bit.
//!
//! The command-line form of every perturbation (`noise:0.1,seed=3`, `hole:x,y,z,r`, ...)
//! is parsed by [`parse_perturbation`] and applied by [`apply`].

pub mod geometric;
pub mod remesh;
pub mod remove;
pub mod rng;
pub mod spec;

pub use geometric::{bend, local_scale, noise, rigid_motion, scale};
pub use remesh::{ResampleMode, refine_locally, resample, resample_with, tiny_triangles};
pub use remove::{hole, missing_triangles};
pub use spec::{Center, PerturbationSpec, apply, parse_perturbation};

use crate::mesh::{Mesh, MeshError};
use crate::operators::{MassKind, mass_matrix};

/// Errors of the perturbations, of their command-line specs and of field comparison.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum PerturbError {
    /// A spec could not be parsed; `token` is the offending part of the text.
    #[error("bad perturbation spec at '{token}': {reason}")]
    Parse {
        /// The offending token, as typed.
        token: String,
        /// What was expected.
        reason: String,
    },
    /// A parameter is out of its valid range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Its value, as text.
        value: String,
        /// Why it is invalid.
        reason: String,
    },
    /// The perturbation would leave no triangle.
    #[error("the perturbation removes every triangle of the mesh")]
    EmptyResult,
    /// A re-triangulating perturbation needs every vertex to be used by some triangle.
    #[error(
        "the mesh has {0} vertices that no triangle uses; remove them first (e.g. `info --repair`)"
    )]
    UnreferencedVertices(usize),
    /// A field does not have one value per vertex.
    #[error("field '{name}' has {got} values, expected {expected}")]
    FieldLength {
        /// Which field.
        name: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A surface map does not fit the meshes it is used with.
    #[error("the surface map does not fit the meshes: {0}")]
    MapMismatch(String),
    /// The perturbed arrays do not form a valid mesh (e.g. non-finite coordinates).
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

/// How the vertices of a perturbed mesh correspond to the original surface.
#[derive(Debug, Clone, PartialEq)]
pub enum SurfaceMap {
    /// Vertex `i` of the perturbed mesh is vertex `i` of the original (same count, same
    /// order). The position may have moved (noise, scaling, rigid motion, bending): the
    /// correspondence is by index, the natural one for deformations.
    Identity,
    /// Vertex `i` of the perturbed mesh is vertex `v[i]` of the original, unmoved (a
    /// subset of the vertices survives, e.g. after cutting a hole).
    Vertices(Vec<usize>),
    /// Vertex `i` of the perturbed mesh lies on original triangle `t` at barycentric
    /// coordinates `b` (in the order of the triangle's corners): its position is
    /// `b[0] p_t0 + b[1] p_t1 + b[2] p_t2`, exactly on the original piecewise-linear surface.
    Barycentric(Vec<(usize, [f64; 3])>),
}

impl SurfaceMap {
    /// Interpolates a per-vertex field of the original mesh (`original_field`, one value
    /// per original vertex, linear on each triangle) at the perturbed vertices. The result
    /// has one value per perturbed vertex. For [`SurfaceMap::Identity`] it is a copy.
    pub fn pull_back(
        &self,
        original_field: &[f64],
        original: &Mesh,
    ) -> Result<Vec<f64>, PerturbError> {
        let n = original.n_vertices();
        if original_field.len() != n {
            return Err(PerturbError::FieldLength {
                name: "original field",
                expected: n,
                got: original_field.len(),
            });
        }
        match self {
            SurfaceMap::Identity => Ok(original_field.to_vec()),
            SurfaceMap::Vertices(v) => v
                .iter()
                .map(|&i| {
                    original_field.get(i).copied().ok_or_else(|| {
                        PerturbError::MapMismatch(format!(
                            "vertex {i} does not exist in the original ({n} vertices)"
                        ))
                    })
                })
                .collect(),
            SurfaceMap::Barycentric(b) => {
                let tris = original.triangles();
                b.iter()
                    .map(|&(t, w)| {
                        let tri = tris.get(t).ok_or_else(|| {
                            PerturbError::MapMismatch(format!(
                                "triangle {t} does not exist in the original ({} triangles)",
                                tris.len()
                            ))
                        })?;
                        Ok(w[0] * original_field[tri[0]]
                            + w[1] * original_field[tri[1]]
                            + w[2] * original_field[tri[2]])
                    })
                    .collect()
            }
        }
    }

    /// The point of the original surface each perturbed vertex corresponds to
    /// (`n_perturbed` entries): the pull-back of the coordinate functions.
    pub fn original_points(
        &self,
        original: &Mesh,
        n_perturbed: usize,
    ) -> Result<Vec<[f64; 3]>, PerturbError> {
        let mut out = vec![[0.0; 3]; n_perturbed];
        for d in 0..3 {
            let f: Vec<f64> = original.positions().iter().map(|p| p[d]).collect();
            let g = self.pull_back(&f, original)?;
            if g.len() != n_perturbed {
                return Err(PerturbError::MapMismatch(format!(
                    "the map has {} entries, the perturbed mesh {n_perturbed} vertices",
                    g.len()
                )));
            }
            for (o, v) in out.iter_mut().zip(g) {
                o[d] = v;
            }
        }
        Ok(out)
    }
}

/// A perturbed mesh with its correspondence to the original.
#[derive(Debug, Clone, PartialEq)]
pub struct Perturbed {
    /// The perturbed mesh.
    pub mesh: Mesh,
    /// Where each of its vertices lies on the original surface.
    pub map: SurfaceMap,
    /// What was done, in one line (parameters included).
    pub description: String,
}

/// The difference of two fields on the same mesh.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FieldDifference {
    /// `sqrt((a-b)^T B (a-b) / a^T B a)` with the chosen mass B (0 when both are zero,
    /// infinite when only `a` is zero).
    pub rel_l2: f64,
    /// `max |a - b| / max |a|` (same conventions for zero).
    pub linf_rel: f64,
}

/// Compares field `a` (the reference, e.g. pulled back from the original shape) with
/// field `b` on `mesh`, in the B-norm of the given mass kind and in the max norm.
pub fn compare_fields(
    mesh: &Mesh,
    a: &[f64],
    b: &[f64],
    mass_kind: MassKind,
) -> Result<FieldDifference, PerturbError> {
    let n = mesh.n_vertices();
    for (name, f) in [("a", a), ("b", b)] {
        if f.len() != n {
            return Err(PerturbError::FieldLength {
                name,
                expected: n,
                got: f.len(),
            });
        }
    }
    let mass = mass_matrix(mesh, mass_kind);
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let bd = mass.mul_vec(&d);
    let ba = mass.mul_vec(a);
    let num: f64 = d.iter().zip(&bd).map(|(x, y)| x * y).sum();
    let den: f64 = a.iter().zip(&ba).map(|(x, y)| x * y).sum();
    let max_d = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let max_a = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    Ok(FieldDifference {
        rel_l2: ratio(num.max(0.0), den.max(0.0)).sqrt(),
        linf_rel: ratio(max_d, max_a),
    })
}

fn ratio(num: f64, den: f64) -> f64 {
    if num == 0.0 {
        0.0
    } else if den == 0.0 {
        f64::INFINITY
    } else {
        num / den
    }
}

/// Checks that `x` is finite, naming the parameter otherwise.
pub(crate) fn finite(name: &'static str, x: f64) -> Result<f64, PerturbError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(PerturbError::InvalidParameter {
            name,
            value: x.to_string(),
            reason: "must be a finite number".into(),
        })
    }
}

/// `x` when it is finite and `> 0`.
pub(crate) fn positive(name: &'static str, x: f64) -> Result<f64, PerturbError> {
    let x = finite(name, x)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(PerturbError::InvalidParameter {
            name,
            value: x.to_string(),
            reason: "must be > 0".into(),
        })
    }
}

/// Checks that every coordinate of `v` is finite (`names`: the coordinates' names).
pub(crate) fn finite3(names: [&'static str; 3], v: [f64; 3]) -> Result<(), PerturbError> {
    for (name, c) in names.into_iter().zip(v) {
        finite(name, c)?;
    }
    Ok(())
}

/// Checks that every coordinate of a ball's `center` is finite.
pub(crate) fn finite_point(center: [f64; 3]) -> Result<(), PerturbError> {
    finite3(["center x", "center y", "center z"], center)
}

/// The radius of a ball about `center` (`name`: the radius's name): the radius must be
/// finite, then the centre, then the radius `> 0`.
pub(crate) fn ball_radius(
    name: &'static str,
    center: [f64; 3],
    radius: f64,
) -> Result<f64, PerturbError> {
    let radius = finite(name, radius)?;
    finite_point(center)?;
    positive(name, radius)
}

/// Counts the vertices no triangle uses.
pub(crate) fn unreferenced_count(mesh: &Mesh) -> usize {
    let mut used = vec![false; mesh.n_vertices()];
    for t in mesh.triangles() {
        for &v in t {
            used[v] = true;
        }
    }
    used.iter().filter(|u| !**u).count()
}
