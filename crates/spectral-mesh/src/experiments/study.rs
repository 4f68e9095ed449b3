//! Robustness studies: how much a field changes when the shape is perturbed, for several
//! meshes, perturbations, discretizations and quantities (the paper's claims of Sects. 4.4
//! and 5, Figs. 5, 6, 11, 13).
//!
//! For every cell (mesh, perturbation, Laplacian, quantity) the field is computed on the
//! original mesh and on the perturbed one; the original field is pulled back to the
//! perturbed vertices through the perturbation's [`SurfaceMap`] and compared there with
//! [`compare_fields`]: relative L2 in the norm of the linear FEM mass of the perturbed mesh
//! (the L2 norm of the piecewise-linear function, the same for every Laplacian so that the
//! columns are comparable) and relative L-infinity. The eigenvalue drift of the cell is the
//! relative change `|lambda'_j - lambda_j| / lambda_j` of the first `k` eigenvalues, both
//! computed for the shape scaled to unit total mass `1^T B 1` (the documented scale
//! normalisation of [`crate::spectral::heat`]); zero eigenvalues are skipped.
//!
//! # Correspondence of sources and constraints
//!
//! The source (anchor) is picked on the original mesh (default: the vertex of largest x,
//! lowest index on ties). On the perturbed mesh it is the vertex whose point on the
//! *original* surface (through the map) is nearest to the original source (lowest index on
//! ties): the same index for deformations, the nearest surviving or new vertex otherwise.
//! The harmonic map's two constraints (min x -> 0, max x -> 1 on the original) are mapped
//! the same way.
//!
//! # Quantities
//!
//! - `harmonic`: the harmonic map with the two constraints above (order 1; it depends on the
//!   stiffness only, which is the cotangent one for cot, voronoi-cot and fem);
//! - `heat`: the basis function `K_t e_i` (`t` for the unit-area shape) divided by its
//!   maximum, so that the comparison is about its shape and not about the mass at the
//!   anchor, which depends on the sampling;
//! - `diffusion`, `commute`, `biharmonic`: the filtered spectral distances from the source
//!   (diffusion at time `diffusion_t`), on the unit-area basis;
//! - `hks`: the heat kernel signature at time `hks_t`, on the unit-area basis.
//!
//! A different sampling of the same surface ([`projection_map`]) maps each of its
//! vertices to the closest point of the original surface.

use rayon::prelude::*;

use crate::Laplacian;
use crate::fields::harmonic::{Constraint, HarmonicParams, harmonic_map};
use crate::mesh::{Mesh, dot, sub};
use crate::operators::{MassKind, Operators};
pub use crate::perturb::remesh::closest_point_barycentric;
use crate::perturb::{Perturbed, SurfaceMap, compare_fields};
use crate::spectral::Eigenbasis;
use crate::spectral::distances::distances_from;
use crate::spectral::eigenbasis::{EigenParams, compute_eigenbasis};
use crate::spectral::filters::Filter;
use crate::spectral::heat::{HeatSolver, Kernel, ScaleNormalization, normalize_basis};
use crate::spectral::signatures::hks;

/// Errors of a study.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum StudyError {
    /// A parameter is invalid.
    #[error("{name}: {reason}")]
    InvalidParameter {
        /// The parameter (as in a study file).
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// A computation failed in a cell.
    #[error("{mesh}, {perturbation}, {laplacian}: {message}")]
    Cell {
        /// Mesh name.
        mesh: String,
        /// Perturbation label (`original` for the unperturbed mesh).
        perturbation: String,
        /// Discretization.
        laplacian: &'static str,
        /// What went wrong.
        message: String,
    },
}

/// A quantity compared between the original and the perturbed shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    /// Harmonic map with two constraints (min x -> 0, max x -> 1).
    Harmonic,
    /// Heat basis function `K_t e_i`, divided by its maximum.
    Heat,
    /// Diffusion distance from the source.
    Diffusion,
    /// Commute-time distance from the source.
    Commute,
    /// Bi-harmonic distance from the source.
    Biharmonic,
    /// Heat kernel signature.
    Hks,
}

impl Quantity {
    /// Every quantity, in a stable order.
    pub const ALL: [Quantity; 6] = [
        Quantity::Harmonic,
        Quantity::Heat,
        Quantity::Diffusion,
        Quantity::Commute,
        Quantity::Biharmonic,
        Quantity::Hks,
    ];

    /// The name used in study files and tables.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Harmonic => "harmonic",
            Quantity::Heat => "heat",
            Quantity::Diffusion => "diffusion",
            Quantity::Commute => "commute",
            Quantity::Biharmonic => "biharmonic",
            Quantity::Hks => "hks",
        }
    }

    /// Parses a name.
    pub fn from_name(s: &str) -> Option<Quantity> {
        Quantity::ALL.into_iter().find(|q| q.name() == s)
    }

    fn needs_basis(self) -> bool {
        self != Quantity::Harmonic
    }
}

crate::defaults::declare::with_defaults! {
    /// Parameters of a study. `Default`: k = 60, heat t = 0.05, diffusion t = 0.05,
    /// HKS t = 0.01 (unit-area times), the default source.
    #[derive(Debug, Clone, PartialEq)]
    pub struct StudyParams {
        /// Number of eigenpairs.
        pub k: usize = 60,
        /// Time of the heat basis function.
        pub heat_t: f64 = 0.05,
        /// Time of the diffusion distance.
        pub diffusion_t: f64 = 0.05,
        /// Time of the heat kernel signature.
        pub hks_t: f64 = 0.01,
        /// Source on the original meshes; `None`: the vertex of largest x.
        pub source: Option<usize> = None,
    }
}

impl StudyParams {
    /// Checks the values, naming the parameter.
    pub fn validate(&self) -> Result<(), StudyError> {
        let bad = |name, reason: String| Err(StudyError::InvalidParameter { name, reason });
        if self.k < 2 {
            return bad("k", format!("{}: need at least 2 eigenpairs", self.k));
        }
        for (name, t) in [
            ("heat_t", self.heat_t),
            ("diffusion_t", self.diffusion_t),
            ("hks_t", self.hks_t),
        ] {
            if !(t.is_finite() && t > 0.0) {
                return bad(name, format!("{t}: must be a positive number"));
            }
        }
        Ok(())
    }
}

/// A mesh of a study with its perturbed versions.
#[derive(Debug, Clone)]
pub struct StudyMesh {
    /// Name in tables (the spec or file as written).
    pub name: String,
    /// The original mesh.
    pub mesh: Mesh,
    /// `(label, perturbed mesh)` pairs.
    pub perturbations: Vec<(String, Perturbed)>,
}

/// One row of a study table.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StudyRow {
    /// Mesh name.
    pub mesh: String,
    /// Perturbation label.
    pub perturbation: String,
    /// Discretization.
    pub laplacian: Laplacian,
    /// Quantity.
    pub quantity: Quantity,
    /// Vertices of the original.
    pub n_original: usize,
    /// Vertices of the perturbed mesh.
    pub n_perturbed: usize,
    /// Source on the original.
    pub source_original: usize,
    /// Corresponding source on the perturbed mesh.
    pub source_perturbed: usize,
    /// Relative L2 difference (FEM-mass norm of the perturbed mesh).
    pub rel_l2: f64,
    /// Relative L-infinity difference.
    pub linf_rel: f64,
    /// Largest relative eigenvalue change over the first k (unit area).
    pub eig_drift_max: f64,
    /// Mean relative eigenvalue change over the first k (unit area).
    pub eig_drift_mean: f64,
}

/// Progress of [`run_study`]: one more unit of work done out of `total`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StudyProgress {
    /// Units done so far (in completion order; not monotone across threads).
    pub done: usize,
    /// Units in all: one per (mesh, Laplacian) and per (mesh, perturbation, Laplacian).
    pub total: usize,
}

/// The vertex of largest x (lowest index on ties).
pub fn vertex_of_largest_x(mesh: &Mesh) -> usize {
    mesh.vertex_of_largest_x()
}

/// The vertex of `perturbed` whose point on the original surface (through `map`) is
/// nearest to `point` (lowest index on ties).
pub fn corresponding_vertex(
    original: &Mesh,
    perturbed: &Perturbed,
    point: [f64; 3],
) -> Result<usize, StudyError> {
    let pts = perturbed
        .map
        .original_points(original, perturbed.mesh.n_vertices())
        .map_err(|e| StudyError::InvalidParameter {
            name: "perturbation",
            reason: e.to_string(),
        })?;
    let mut best = (f64::INFINITY, 0usize);
    for (i, q) in pts.iter().enumerate() {
        let d = sub(*q, point);
        let d2 = dot(d, d);
        if d2 < best.0 {
            best = (d2, i);
        }
    }
    Ok(best.1)
}

/// A map from the vertices of `other` (a different sampling of the same surface) to the
/// surface of `original`: each vertex goes to the closest point of the closest triangle
/// (lowest triangle index on ties), as barycentric coordinates. O(n_other x n_triangles)
/// with a cheap bound; parallel over vertices.
pub fn projection_map(original: &Mesh, other: &Mesh) -> SurfaceMap {
    let tris = original.triangles();
    let pos = original.positions();
    // Triangle centroids and bounding radii for a lower bound on the distance.
    let bounds: Vec<([f64; 3], f64)> = tris
        .iter()
        .map(|t| {
            let c = [
                (pos[t[0]][0] + pos[t[1]][0] + pos[t[2]][0]) / 3.0,
                (pos[t[0]][1] + pos[t[1]][1] + pos[t[2]][1]) / 3.0,
                (pos[t[0]][2] + pos[t[1]][2] + pos[t[2]][2]) / 3.0,
            ];
            let r = t
                .iter()
                .map(|&v| dot(sub(pos[v], c), sub(pos[v], c)).sqrt())
                .fold(0.0, f64::max);
            (c, r)
        })
        .collect();
    let entries: Vec<(usize, [f64; 3])> = other
        .positions()
        .par_iter()
        .map(|&p| {
            let lbs: Vec<f64> = bounds
                .iter()
                .map(|(c, r)| {
                    let d = sub(p, *c);
                    (dot(d, d).sqrt() - r).max(0.0)
                })
                .collect();
            // Upper bound from the triangle of smallest lower bound, then every triangle
            // whose lower bound does not exceed the best distance so far.
            let first = (0..lbs.len()).fold(0, |b, i| if lbs[i] < lbs[b] { i } else { b });
            let mut best = (f64::INFINITY, usize::MAX, [1.0, 0.0, 0.0]);
            for i in std::iter::once(first).chain(0..lbs.len()) {
                if lbs[i] * lbs[i] > best.0 {
                    continue;
                }
                let t = tris[i];
                let (w, d2) = closest_point_barycentric(p, pos[t[0]], pos[t[1]], pos[t[2]]);
                if d2 < best.0 || (d2 == best.0 && i < best.1) {
                    best = (d2, i, w);
                }
            }
            (best.1, best.2)
        })
        .collect();
    SurfaceMap::Barycentric(entries)
}

/// A different sampling `other` of the surface of `original` as a [`Perturbed`], mapped by
/// [`projection_map`].
pub fn resampled_as(original: &Mesh, other: Mesh, label: &str) -> Perturbed {
    let map = projection_map(original, &other);
    Perturbed {
        description: format!(
            "another sampling of the same surface ({label}, {} vertices), mapped by closest-point projection",
            other.n_vertices()
        ),
        mesh: other,
        map,
    }
}

/// The fields of one mesh for one Laplacian, and its unit-area eigenvalues.
#[derive(Debug, Clone)]
pub struct FieldSet {
    /// `(quantity, field)` pairs, in the order asked.
    pub fields: Vec<(Quantity, Vec<f64>)>,
    /// Eigenvalues of the unit-area shape (empty when no quantity needs a basis).
    pub eigenvalues: Vec<f64>,
}

/// Computes the quantities on `mesh` with `laplacian`, source `source` and harmonic
/// constraints `constraints`.
pub fn compute_fields(
    mesh: &Mesh,
    laplacian: Laplacian,
    quantities: &[Quantity],
    params: &StudyParams,
    source: usize,
    constraints: &[Constraint],
) -> Result<FieldSet, String> {
    let need_basis = quantities.iter().any(|q| q.needs_basis()) || quantities.is_empty();
    let basis: Option<Eigenbasis> = if need_basis {
        let ops = Operators::new(mesh, laplacian);
        let ep = EigenParams {
            k: params.k.min(mesh.n_vertices()),
            ..EigenParams::default()
        };
        Some(compute_eigenbasis(&ops, &ep, &mut |_| {}).map_err(|e| e.to_string())?)
    } else {
        None
    };
    let nb = basis
        .as_ref()
        .map(|b| normalize_basis(b, ScaleNormalization::UnitArea));
    let mut fields = Vec::with_capacity(quantities.len());
    for &q in quantities {
        let f = match (q, &basis, &nb) {
            (Quantity::Harmonic, _, _) => harmonic_map(
                mesh,
                constraints,
                &HarmonicParams {
                    order: 1,
                    laplacian,
                },
            )
            .map_err(|e| e.to_string())?,
            (Quantity::Heat, Some(b), _) => {
                let solver = HeatSolver::new(b, Kernel::Wfem, ScaleNormalization::UnitArea);
                let mut f = solver
                    .basis_function(source, params.heat_t)
                    .map_err(|e| e.to_string())?;
                let m = f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if m > 0.0 {
                    f.iter_mut().for_each(|v| *v /= m);
                }
                f
            }
            (Quantity::Diffusion, _, Some(b)) => distances_from(
                b,
                source,
                &Filter::Diffusion {
                    t: params.diffusion_t,
                },
            )
            .map_err(|e| e.to_string())?,
            (Quantity::Commute, _, Some(b)) => {
                distances_from(b, source, &Filter::CommuteTime).map_err(|e| e.to_string())?
            }
            (Quantity::Biharmonic, _, Some(b)) => {
                distances_from(b, source, &Filter::Biharmonic).map_err(|e| e.to_string())?
            }
            (Quantity::Hks, _, Some(b)) => hks(b, &[params.hks_t], false)
                .into_iter()
                .next()
                .unwrap_or_default(),
            _ => return Err(format!("no basis for {}", q.name())),
        };
        fields.push((q, f));
    }
    Ok(FieldSet {
        fields,
        eigenvalues: nb.map(|b| b.values).unwrap_or_default(),
    })
}

/// `(max, mean)` of `|b_j - a_j| / a_j` over the common prefix, skipping `a_j` below
/// `1e-8 * max(a)` (the zero eigenvalues of the components).
pub fn eigenvalue_drift(a: &[f64], b: &[f64]) -> (f64, f64) {
    let top = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut max = 0.0f64;
    let (mut sum, mut count) = (0.0, 0usize);
    for (x, y) in a.iter().zip(b) {
        if x.abs() > 1e-8 * top {
            let r = (y - x).abs() / x.abs();
            max = max.max(r);
            sum += r;
            count += 1;
        }
    }
    (max, if count > 0 { sum / count as f64 } else { 0.0 })
}

/// The two default harmonic constraints on `mesh`: the vertex of smallest x gets 0, that
/// of largest x gets 1 (lowest index on ties).
pub fn default_constraint_vertices(mesh: &Mesh) -> [usize; 2] {
    let p = mesh.positions();
    let lo = (0..p.len()).fold(0, |best, i| if p[i][0] < p[best][0] { i } else { best });
    [lo, vertex_of_largest_x(mesh)]
}

/// Runs a study: every mesh x perturbation x Laplacian x quantity, in parallel. Rows come
/// in the order meshes, perturbations, Laplacians, quantities. `progress` is called after
/// each unit of work (from worker threads).
pub fn run_study(
    meshes: &[StudyMesh],
    laplacians: &[Laplacian],
    quantities: &[Quantity],
    params: &StudyParams,
    progress: &(dyn Fn(StudyProgress) + Sync),
) -> Result<Vec<StudyRow>, StudyError> {
    params.validate()?;
    if laplacians.is_empty() {
        return Err(StudyError::InvalidParameter {
            name: "laplacians",
            reason: "give at least one Laplacian".into(),
        });
    }
    if quantities.is_empty() {
        return Err(StudyError::InvalidParameter {
            name: "quantities",
            reason: "give at least one quantity".into(),
        });
    }
    // Sources and constraints on the originals, and their images on the perturbed meshes.
    struct Setup {
        source: usize,
        constraints: Vec<Constraint>,
        perturbed: Vec<(usize, Vec<Constraint>)>,
    }
    let mut setups = Vec::with_capacity(meshes.len());
    for m in meshes {
        let n = m.mesh.n_vertices();
        let source = params
            .source
            .unwrap_or_else(|| vertex_of_largest_x(&m.mesh));
        if source >= n {
            return Err(StudyError::InvalidParameter {
                name: "source",
                reason: format!("{source}: mesh {} has only {n} vertices", m.name),
            });
        }
        let [lo, hi] = default_constraint_vertices(&m.mesh);
        let constraints = vec![
            Constraint {
                vertex: lo,
                value: 0.0,
            },
            Constraint {
                vertex: hi,
                value: 1.0,
            },
        ];
        let p = m.mesh.positions();
        let mut perturbed = Vec::new();
        for (label, pm) in &m.perturbations {
            let at = |v: usize| {
                corresponding_vertex(&m.mesh, pm, p[v]).map_err(|e| StudyError::Cell {
                    mesh: m.name.clone(),
                    perturbation: label.clone(),
                    laplacian: "-",
                    message: e.to_string(),
                })
            };
            let (s, clo, chi) = (at(source)?, at(lo)?, at(hi)?);
            if clo == chi {
                return Err(StudyError::Cell {
                    mesh: m.name.clone(),
                    perturbation: label.clone(),
                    laplacian: "-",
                    message: "both harmonic constraints map to the same vertex".into(),
                });
            }
            perturbed.push((
                s,
                vec![
                    Constraint {
                        vertex: clo,
                        value: 0.0,
                    },
                    Constraint {
                        vertex: chi,
                        value: 1.0,
                    },
                ],
            ));
        }
        setups.push(Setup {
            source,
            constraints,
            perturbed,
        });
    }
    let total = meshes.len() * laplacians.len()
        + meshes
            .iter()
            .map(|m| m.perturbations.len() * laplacians.len())
            .sum::<usize>();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let tick = || {
        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        progress(StudyProgress { done: d, total });
    };
    // Phase 1: originals.
    let jobs: Vec<(usize, usize)> = (0..meshes.len())
        .flat_map(|i| (0..laplacians.len()).map(move |l| (i, l)))
        .collect();
    let originals: Vec<FieldSet> = jobs
        .par_iter()
        .map(|&(i, l)| {
            let m = &meshes[i];
            let s = &setups[i];
            let r = compute_fields(
                &m.mesh,
                laplacians[l],
                quantities,
                params,
                s.source,
                &s.constraints,
            )
            .map_err(|message| StudyError::Cell {
                mesh: m.name.clone(),
                perturbation: "original".into(),
                laplacian: laplacians[l].name(),
                message,
            });
            tick();
            r
        })
        .collect::<Result<_, _>>()?;
    // Phase 2: perturbed meshes, compared with the originals.
    let jobs: Vec<(usize, usize, usize)> = (0..meshes.len())
        .flat_map(|i| {
            (0..meshes[i].perturbations.len())
                .flat_map(move |p| (0..laplacians.len()).map(move |l| (i, p, l)))
        })
        .collect();
    let cells: Vec<Vec<StudyRow>> = jobs
        .par_iter()
        .map(|&(i, p, l)| {
            let m = &meshes[i];
            let (label, pm) = &m.perturbations[p];
            let (src, cons) = &setups[i].perturbed[p];
            let lap = laplacians[l];
            let err = |message: String| StudyError::Cell {
                mesh: m.name.clone(),
                perturbation: label.clone(),
                laplacian: lap.name(),
                message,
            };
            let fs = compute_fields(&pm.mesh, lap, quantities, params, *src, cons).map_err(err)?;
            let orig = &originals[i * laplacians.len() + l];
            let (dmax, dmean) = eigenvalue_drift(&orig.eigenvalues, &fs.eigenvalues);
            let mut rows = Vec::with_capacity(quantities.len());
            for ((q, fo), (_, fp)) in orig.fields.iter().zip(&fs.fields) {
                let pulled = pm
                    .map
                    .pull_back(fo, &m.mesh)
                    .map_err(|e| err(e.to_string()))?;
                let d = compare_fields(&pm.mesh, &pulled, fp, MassKind::Fem)
                    .map_err(|e| err(e.to_string()))?;
                rows.push(StudyRow {
                    mesh: m.name.clone(),
                    perturbation: label.clone(),
                    laplacian: lap,
                    quantity: *q,
                    n_original: m.mesh.n_vertices(),
                    n_perturbed: pm.mesh.n_vertices(),
                    source_original: setups[i].source,
                    source_perturbed: *src,
                    rel_l2: d.rel_l2,
                    linf_rel: d.linf_rel,
                    eig_drift_max: dmax,
                    eig_drift_mean: dmean,
                });
            }
            tick();
            Ok(rows)
        })
        .collect::<Result<_, StudyError>>()?;
    Ok(cells.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drift_skips_zero_eigenvalues() {
        let (m, mean) = eigenvalue_drift(&[0.0, 1.0, 2.0], &[1e-15, 1.1, 2.0]);
        assert!((m - 0.1).abs() < 1e-12);
        assert!((mean - 0.05).abs() < 1e-12);
    }
}
