//! The paper's experiments as every face runs them, with the summary each reports
//! (`summary.json`):
//!
//! - the field experiments: the diffusion basis `K_t e_anchor` (Figs. 4-6), the filtered
//!   spectral distance from a source (Figs. 8-10, 14) and any [`FieldRequest`] of an
//!   experiment file's `experiment = "field"`: [`run_field`];
//! - the harmonic maps with 2, 4 and 6 constraints or explicit ones (Figs. 2, 3):
//!   [`run_harmonic`].
//!
//! The library computes and summarises; a face writes the files, under the names of
//! [`field_outputs`], [`harmonic_outputs`] and [`SUMMARY_FILE`].

use serde::Serialize;

use crate::analysis::{Analysis, AnalysisError, CriticalReport, Field, FieldRequest};
use crate::cancel::CancelToken;
use crate::experiments::file::HarmonicConstraints;
use crate::experiments::harmonic::{
    HarmonicExperimentError, HarmonicExperimentParams, harmonic_experiment,
};
use crate::fields::critical_points::{CriticalPointFinder, critical_points};
use crate::fields::harmonic::{Constraint, ConstraintSpec, harmonic_map_with_operators};
use crate::fields::persistence::persistence;
use crate::linalg::{EigenProgress, b_orthogonality_error};
use crate::mesh::Mesh;
use crate::mesh::topology::{Topology, VertexComponents};
use crate::operators::{Laplacian, Operators, PointCloudParams};
use crate::spectral::Eigenbasis;
use crate::spectral::filters::ZERO_EIGENVALUE_EPS;

/// The name of every experiment's summary file.
pub const SUMMARY_FILE: &str = "summary.json";

/// The stem of a field experiment's outputs: the paper's names for its two field
/// experiments (`diffusion-basis`, `filtered-spectral-distance`), the request's kind for
/// `experiment = "field"` (`heat`, `hks`, ...).
pub fn output_stem(experiment: &str, request: &FieldRequest) -> String {
    match experiment {
        "diffusion-basis" => "diffusion-basis".into(),
        "spectral-distance" => "filtered-spectral-distance".into(),
        _ => request.kind().into(),
    }
}

/// The three outputs of a field experiment, in the order written: `STEM.wrl` (VRML scene),
/// `STEM.png` (picture), `STEM.txt` (the field, one value per line).
pub fn field_outputs(stem: &str) -> [String; 3] {
    [
        format!("{stem}.wrl"),
        format!("{stem}.png"),
        format!("{stem}.txt"),
    ]
}

/// The three outputs of map `i` (1-based) of the harmonic experiment:
/// `harmonic-map-i.wrl`, `harmonic-map-i.png`, `harmonic-field-i.txt`.
pub fn harmonic_outputs(i: usize) -> [String; 3] {
    [
        format!("harmonic-map-{i}.wrl"),
        format!("harmonic-map-{i}.png"),
        format!("harmonic-field-{i}.txt"),
    ]
}

/// The mesh as a summary names it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshSummary {
    /// The file name (not the path, so that a replay from another folder writes the same
    /// summary) or the shape spec.
    pub source: String,
    /// [`Mesh::content_hash`] of the mesh as read (before any repair).
    pub mesh_hash: String,
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Connected components.
    pub components: usize,
    /// Euler characteristic `V - E + F`.
    pub euler_characteristic: i64,
    /// Genus of each component (`None` where undefined: non-manifold or non-orientable).
    pub genus: Vec<Option<i64>>,
    /// Boundary loops.
    pub boundary_loops: usize,
    /// Total area (of the triangle union, for a point cloud).
    pub area: f64,
    /// The point-cloud Laplacian's parameters, when the input is a point cloud (its
    /// triangles, counted above, are the union that Laplacian was built on).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point_cloud: Option<PointCloudParams>,
}

impl MeshSummary {
    /// The summary of `mesh` (as analysed, after any repair) named `source`, whose file as
    /// read hashed to `mesh_hash`.
    pub fn new(
        source: impl Into<String>,
        mesh_hash: impl Into<String>,
        mesh: &Mesh,
        topology: &Topology,
    ) -> Self {
        Self {
            source: source.into(),
            mesh_hash: mesh_hash.into(),
            vertices: mesh.n_vertices(),
            triangles: mesh.n_triangles(),
            components: topology.n_components(),
            euler_characteristic: topology.euler_characteristic(),
            genus: topology.components.iter().map(|c| c.genus).collect(),
            boundary_loops: topology.boundary_loops.len(),
            area: mesh.area(),
            point_cloud: None,
        }
    }

    /// The summary naming the point-cloud Laplacian's parameters (`None` for a mesh).
    pub fn with_point_cloud(self, params: Option<PointCloudParams>) -> Self {
        Self {
            point_cloud: params,
            ..self
        }
    }
}

/// The Euler check of a field's critical points.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EulerCheck {
    /// The check in words.
    pub formula: &'static str,
    /// Its sides (`lhs`, `rhs`) and whether they agree (`holds`).
    #[serde(flatten)]
    pub sides: crate::analysis::CheckSides,
}

/// Critical points as a summary reports them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CriticalSummary {
    /// Number of minima.
    pub minima: usize,
    /// Number of maxima.
    pub maxima: usize,
    /// Saddles counted with multiplicity.
    pub saddles_with_multiplicity: usize,
    /// The minima, ascending.
    pub minima_vertices: Vec<usize>,
    /// The maxima, ascending.
    pub maxima_vertices: Vec<usize>,
    /// The saddles with their multiplicity.
    pub saddle_vertices: Vec<(usize, usize)>,
    /// The Euler check (doubled across the boundary on bordered surfaces).
    pub euler_check: EulerCheck,
    /// The check on each connected component counted (meshes of several components).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub per_component: Vec<crate::analysis::ComponentCheck>,
    /// Components left out of the counts: those of a harmonic map that hold no constraint
    /// (they hold a constant; see `unconstrained_components`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub excluded_components: Vec<usize>,
    /// Values within this fraction of the field's largest magnitude of each other on a
    /// component make it one plateau, without critical points
    /// ([`crate::fields::critical_points::FLAT_RELATIVE_TOLERANCE`]).
    pub flat_relative_tolerance: f64,
    /// Components on which the field is constant within that tolerance (left out of the
    /// counts and the check).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub plateau_components: Vec<usize>,
    /// True when the field is constant within the tolerance on every component counted:
    /// no critical points.
    pub flat: bool,
    /// The counts above are the points shown, simplified by persistence
    /// ([`crate::fields::persistence`]); these many raw points are hidden.
    pub hidden: crate::analysis::CriticalCounts,
    /// The raw counts and their check.
    pub raw: crate::analysis::RawCritical,
    /// Pairs of persistence below this are hidden.
    pub persistence_threshold: f64,
}

impl From<&CriticalReport> for CriticalSummary {
    fn from(r: &CriticalReport) -> Self {
        Self {
            minima: r.counts.minima,
            maxima: r.counts.maxima,
            saddles_with_multiplicity: r.counts.saddles,
            minima_vertices: r.points.minima.clone(),
            maxima_vertices: r.points.maxima.clone(),
            saddle_vertices: r.points.saddles.clone(),
            euler_check: EulerCheck {
                formula: r.formula,
                sides: r.check,
            },
            per_component: if r.components.len() > 1 {
                r.components.clone()
            } else {
                Vec::new()
            },
            excluded_components: r.left_out.excluded_components.clone(),
            flat_relative_tolerance: r.left_out.flat_tolerance,
            plateau_components: r.left_out.plateau_components.clone(),
            flat: r.left_out.flat,
            hidden: r.hidden,
            raw: r.raw.clone(),
            persistence_threshold: r.persistence.threshold,
        }
    }
}

/// Smallest and largest value of a field and where they are (lowest vertex on ties).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FieldStats {
    /// Smallest value.
    pub min: f64,
    /// A vertex where it is reached (the lowest).
    pub argmin: usize,
    /// Largest value.
    pub max: f64,
    /// A vertex where it is reached (the lowest).
    pub argmax: usize,
}

impl FieldStats {
    /// The statistics of the finite `values` (NaN and the `+inf` of a geodesic distance's
    /// unreachable vertices are skipped; a field without a finite value gives
    /// `min = +inf`, `max = -inf` at vertex 0).
    pub fn of(values: &[f64]) -> Self {
        let mut s = Self {
            min: f64::INFINITY,
            argmin: 0,
            max: f64::NEG_INFINITY,
            argmax: 0,
        };
        for (i, &v) in values.iter().enumerate().filter(|(_, v)| v.is_finite()) {
            if v < s.min {
                s.min = v;
                s.argmin = i;
            }
            if v > s.max {
                s.max = v;
                s.argmax = i;
            }
        }
        s
    }
}

/// The eigenpairs a field used.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BasisSummary {
    /// Pairs used (the first `k` of the basis).
    pub k: usize,
    /// Pairs the basis held.
    pub basis_k: usize,
    /// The `k` eigenvalues used, ascending (of the operators analysed: for the shape
    /// scaled to unit area when normalizing).
    pub eigenvalues: Vec<f64>,
    /// Largest relative residual `||S x - lambda B x|| / ((||S|| + |lambda| ||B||) ||x||)`
    /// of the `k` pairs (`None` when the basis carries no residuals, e.g. loaded from an
    /// archive without them).
    pub max_relative_residual: Option<f64>,
    /// `max |X^T B X - I|` over the `k` pairs.
    pub max_orthonormality_error: f64,
}

impl BasisSummary {
    /// The summary of the first `k` pairs of `basis` (`k <= basis.k()`).
    pub fn of(basis: &Eigenbasis, k: usize) -> Self {
        Self::with_orthogonality(basis, k, None)
    }

    /// [`BasisSummary::of`] with `max |X^T B X - I|` of the whole basis when already
    /// known (the solver reports it: [`EigenProgress::Finished`]); it is used when the
    /// summary covers every pair, and computed otherwise.
    pub fn with_orthogonality(basis: &Eigenbasis, k: usize, whole: Option<f64>) -> Self {
        let k = k.min(basis.k());
        let view = basis.view(k);
        Self {
            k,
            basis_k: basis.k(),
            eigenvalues: view.values.to_vec(),
            max_relative_residual: basis
                .residuals
                .get(..k)
                .map(|r| r.iter().copied().fold(0.0, f64::max)),
            max_orthonormality_error: match whole {
                Some(e) if k == basis.k() => e,
                _ => b_orthogonality_error(view.mass, view.vectors, k),
            },
        }
    }
}

/// What a field experiment reports (`summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldSummary {
    /// `diffusion-basis`, `spectral-distance` or `field`.
    pub experiment: String,
    /// The mesh.
    pub mesh: MeshSummary,
    /// The request with every default resolved (source or anchor filled in).
    pub request: FieldRequest,
    /// The discretization.
    pub laplacian: String,
    /// `unit area` (times and values for the shape scaled to unit area) or `none`.
    pub scale_normalization: &'static str,
    /// The eigenpairs used (`None` for fields without an eigenbasis).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub basis: Option<BasisSummary>,
    /// Smallest and largest value and where.
    #[serde(flatten)]
    pub stats: FieldStats,
    /// The value at the source or anchor, for requests that have one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_at_source: Option<f64>,
    /// Number of patches of a segmentation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub patches: Option<usize>,
    /// Critical points with the Euler check (not for segmentations: their values are
    /// labels).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_points: Option<CriticalSummary>,
    /// A geodesic distance's vertices its sources cannot reach (infinite there, `inf` in
    /// the text file), in words ([`Field::unreachable_message`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unreachable: Option<String>,
}

/// The summary of `field`, computed on `an` (whose held basis it used).
pub fn field_summary(
    an: &Analysis,
    experiment: &str,
    mesh: MeshSummary,
    field: &Field,
) -> Result<FieldSummary, AnalysisError> {
    summary_with(an, experiment, mesh, field, None)
}

/// [`field_summary`] with the orthogonality error of the held basis when known.
fn summary_with(
    an: &Analysis,
    experiment: &str,
    mesh: MeshSummary,
    field: &Field,
    orthogonality: Option<f64>,
) -> Result<FieldSummary, AnalysisError> {
    let basis = match field.k {
        Some(k) => {
            let held = an.held_basis().ok_or(AnalysisError::NoBasis)?;
            if held.k() < k {
                return Err(AnalysisError::BasisTooSmall { k, held: held.k() });
            }
            Some(BasisSummary::with_orthogonality(&held, k, orthogonality))
        }
        None => None,
    };
    let critical_points = match &field.labels {
        Some(_) => None,
        None => Some(CriticalSummary::from(&an.field_critical_points(field)?)),
    };
    Ok(FieldSummary {
        experiment: experiment.into(),
        mesh,
        request: field.request.clone(),
        laplacian: an.options().laplacian.name().into(),
        scale_normalization: if field.normalized {
            "unit area"
        } else {
            "none"
        },
        basis,
        stats: FieldStats::of(&field.values),
        value_at_source: field
            .request
            .source()
            .and_then(|s| field.values.get(s).copied()),
        patches: field
            .labels
            .as_ref()
            .map(|l| l.iter().max().map_or(0, |m| m + 1)),
        critical_points,
        unreachable: field.unreachable_message(),
    })
}

/// A field experiment's result.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldRun {
    /// The field.
    pub field: Field,
    /// Its summary.
    pub summary: FieldSummary,
}

/// Runs a field experiment: computes `basis_k` pairs first when given (more than the
/// request's `k`: the request then uses the first `k`, which is how a replay reproduces a
/// field computed from a larger basis bit for bit), then the field and its summary.
pub fn run_field(
    an: &Analysis,
    experiment: &str,
    mesh: MeshSummary,
    request: &FieldRequest,
    basis_k: Option<usize>,
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<FieldRun, AnalysisError> {
    request.validate()?;
    // The solver reports the orthogonality error of what it computed: not measured twice.
    let mut orthogonality = None;
    let mut report = |p: EigenProgress| {
        if let EigenProgress::Finished {
            orthogonality_error,
            ..
        } = p
        {
            orthogonality = Some(orthogonality_error);
        }
        progress(p)
    };
    if let (Some(k), Some(bk)) = (request.eigenpairs(), basis_k)
        && bk > k
    {
        an.basis(bk, &mut report, cancel)?;
    }
    let field = an.field_with(request, &mut report, cancel)?;
    let summary = summary_with(an, experiment, mesh, &field, orthogonality)?;
    Ok(FieldRun { field, summary })
}

/// One map of the harmonic experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct HarmonicMap {
    /// The constraints used (after merging a vertex given twice).
    pub constraints: Vec<Constraint>,
    /// The field, `n` values.
    pub field: Vec<f64>,
    /// Its critical points with the Euler check.
    pub critical: CriticalReport,
}

/// How much a map changed from the previous one (the locality property).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Locality {
    /// Rings around the previous map's constraints.
    pub rings: usize,
    /// Largest change within those rings (`None` for the first map).
    pub max_change_near_previous_constraints: Option<f64>,
    /// Largest change anywhere (`None` for the first map).
    pub max_change_anywhere: Option<f64>,
}

/// One map as the summary reports it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HarmonicMapSummary {
    /// 1-based index (the file names' `i`).
    pub map: usize,
    /// The constraints used.
    pub constraints: Vec<Constraint>,
    /// Critical points with the Euler check.
    pub critical_points: CriticalSummary,
    /// Minima.
    pub m: usize,
    /// Maxima.
    #[serde(rename = "M")]
    pub big_m: usize,
    /// Saddles with multiplicity.
    pub s: usize,
    /// Euler characteristic of the mesh.
    pub chi: i64,
    /// Genus of each component.
    pub genus: Vec<Option<i64>>,
    /// Components that hold no constraint: not solved, they hold the mean of the
    /// constraint values and are left out of the critical points.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unconstrained_components: Vec<UnconstrainedComponent>,
    /// Number of default constraints asked for (maps from counts only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraint_count: Option<usize>,
    /// Change from the previous map (maps from counts only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub locality: Option<Locality>,
}

/// A component of a harmonic map that holds no constraint, and the constant it holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnconstrainedComponent {
    /// Component index.
    pub component: usize,
    /// Its lowest vertex.
    pub first_vertex: usize,
    /// Its vertices.
    pub vertices: usize,
    /// The constant it holds (the mean of the constraint values).
    pub value: f64,
}

/// The components holding none of `constraints`, with the constant they hold.
fn unconstrained(
    topo: &crate::mesh::topology::Topology,
    constraints: &[Constraint],
) -> Vec<UnconstrainedComponent> {
    let nc = topo.n_components();
    let mut has = vec![false; nc];
    for c in constraints {
        if let Some(&k) = topo.vertex_component.get(c.vertex)
            && k < nc
        {
            has[k] = true;
        }
    }
    let mean = constraints.iter().map(|c| c.value).sum::<f64>() / constraints.len().max(1) as f64;
    (0..nc)
        .filter(|&k| !has[k])
        .map(|k| UnconstrainedComponent {
            component: k,
            first_vertex: topo
                .vertex_component
                .iter()
                .position(|&x| x == k)
                .unwrap_or(usize::MAX),
            vertices: topo.components[k].vertices,
            value: mean,
        })
        .collect()
}

/// What the harmonic experiment reports (`summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HarmonicSummary {
    /// `harmonic`.
    pub experiment: &'static str,
    /// The mesh.
    pub mesh: MeshSummary,
    /// 1 = harmonic, 2 = bi-harmonic.
    pub order: u32,
    /// The discretization.
    pub laplacian: String,
    /// One entry per map.
    pub maps: Vec<HarmonicMapSummary>,
}

/// The harmonic experiment's result.
#[derive(Debug, Clone, PartialEq)]
pub struct HarmonicRun {
    /// The maps, in order.
    pub maps: Vec<HarmonicMap>,
    /// The summary.
    pub summary: HarmonicSummary,
}

/// Runs the harmonic experiment on `mesh`: one map per constraint count (the paper's
/// 2, 4, 6, with the locality measure between consecutive maps), or one map with explicit
/// constraints.
pub fn run_harmonic(
    mesh: &Mesh,
    mesh_summary: MeshSummary,
    constraints: &HarmonicConstraints,
    order: u32,
    laplacian: Laplacian,
) -> Result<HarmonicRun, HarmonicExperimentError> {
    let topo = Topology::new(mesh);
    let finder_cell = std::sync::OnceLock::new();
    let finder = || finder_cell.get_or_init(|| CriticalPointFinder::new(mesh));
    let chi = topo.euler_characteristic();
    let genus: Vec<Option<i64>> = topo.components.iter().map(|c| c.genus).collect();
    let mut maps = Vec::new();
    let mut summaries = Vec::new();
    let mut push = |maps: &mut Vec<HarmonicMap>,
                    constraints: Vec<Constraint>,
                    field: Vec<f64>,
                    critical: CriticalReport,
                    count: Option<usize>,
                    locality: Option<Locality>| {
        let unconstrained_components = unconstrained(&topo, &constraints);
        summaries.push(HarmonicMapSummary {
            unconstrained_components,
            map: maps.len() + 1,
            constraints: constraints.clone(),
            critical_points: CriticalSummary::from(&critical),
            m: critical.counts.minima,
            big_m: critical.counts.maxima,
            s: critical.counts.saddles,
            chi,
            genus: genus.clone(),
            constraint_count: count,
            locality,
        });
        maps.push(HarmonicMap {
            constraints,
            field,
            critical,
        });
    };
    match constraints {
        HarmonicConstraints::Counts(counts) => {
            let params = HarmonicExperimentParams {
                constraint_counts: counts.clone(),
                order,
                laplacian,
                ..Default::default()
            };
            for r in harmonic_experiment(mesh, &params)? {
                let excluded: Vec<usize> = unconstrained(&topo, &r.constraints)
                    .iter()
                    .map(|u| u.component)
                    .collect();
                let p = persistence(finder(), &r.field, r.critical)?;
                let critical = CriticalReport::new(p, &topo, &excluded);
                let locality = Locality {
                    rings: params.locality_rings,
                    max_change_near_previous_constraints: r.change_near_previous,
                    max_change_anywhere: r.change_anywhere,
                };
                push(
                    &mut maps,
                    r.constraints,
                    r.field,
                    critical,
                    Some(r.count),
                    Some(locality),
                );
            }
        }
        HarmonicConstraints::Explicit(list) => {
            let c = ConstraintSpec::Explicit(list.clone()).resolve(mesh)?;
            let ops = Operators::new(mesh, laplacian);
            let field = harmonic_map_with_operators(mesh, &ops, &c, order)?;
            let excluded: Vec<usize> = unconstrained(&topo, &c)
                .iter()
                .map(|u| u.component)
                .collect();
            let raw = critical_points(mesh, &field)?;
            let critical =
                CriticalReport::new(persistence(finder(), &field, raw)?, &topo, &excluded);
            push(&mut maps, c, field, critical, None, None);
        }
    }
    Ok(HarmonicRun {
        maps,
        summary: HarmonicSummary {
            experiment: "harmonic",
            mesh: mesh_summary,
            order,
            laplacian: laplacian.name().into(),
            maps: summaries,
        },
    })
}

/// Groups of consecutive eigenvalues whose gaps are at most `tol * max(|lambda|, |previous|)`
/// (magnitudes below `ZERO_EIGENVALUE_EPS * max |lambda|` count as that floor); returns
/// `(first index, count)` of each group, singletons included.
pub fn eigenvalue_clusters(values: &[f64], tol: f64) -> Vec<(usize, usize)> {
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut out: Vec<(usize, usize)> = Vec::new();
    for (i, &v) in values.iter().enumerate() {
        let joins = i > 0 && {
            let prev = values[i - 1];
            let mag = v.abs().max(prev.abs()).max(ZERO_EIGENVALUE_EPS * scale);
            (v - prev).abs() <= tol * mag
        };
        match out.last_mut() {
            Some(last) if joins => last.1 += 1,
            _ => out.push((i, 1)),
        }
    }
    out
}

/// What `eigs` reports about a computed basis: its quality and what its spectrum says
/// about the mesh (one near-zero eigenvalue per component not pinned by a Dirichlet
/// vertex; repeated eigenvalues).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BasisReport {
    /// Vertices.
    pub n: usize,
    /// Pairs.
    pub k: usize,
    /// Vertices with a zero Dirichlet condition.
    pub dirichlet_vertices: usize,
    /// Smallest relative residual (`None` without residuals).
    pub min_relative_residual: Option<f64>,
    /// Largest relative residual (`None` without residuals).
    pub max_relative_residual: Option<f64>,
    /// `max |X^T B X - I|`.
    pub orthonormality_error: f64,
    /// Eigenvalues with `|lambda| <= ZERO_EIGENVALUE_EPS * max |lambda|`.
    pub near_zero: usize,
    /// Connected components of the mesh.
    pub components: usize,
    /// Near-zero eigenvalues expected: components touching no Dirichlet vertex, at most
    /// `k` (the pairs computed).
    pub expected_near_zero: usize,
    /// The relative gap of [`eigenvalue_clusters`].
    pub cluster_tolerance: f64,
    /// Groups of more than one eigenvalue: `(first index, count)`.
    pub clusters: Vec<(usize, usize)>,
    /// True when the last group ends at the `k`-th pair (it may continue beyond).
    pub last_cluster_reaches_k: bool,
}

impl BasisReport {
    /// The report of `basis` on a mesh of vertex components `components` (see
    /// [`crate::analysis::Analysis::components`]), with the Dirichlet vertices the basis
    /// was computed with.
    pub fn new(
        basis: &Eigenbasis,
        components: &VertexComponents,
        dirichlet: Option<&[usize]>,
        cluster_tolerance: f64,
    ) -> Self {
        Self::with_orthogonality(basis, components, dirichlet, cluster_tolerance, None)
    }

    /// [`BasisReport::new`] with `max |X^T B X - I|` of the basis when already known (the
    /// solver reports it: [`EigenProgress::Finished`]); computed when `None`.
    pub fn with_orthogonality(
        basis: &Eigenbasis,
        components: &VertexComponents,
        dirichlet: Option<&[usize]>,
        cluster_tolerance: f64,
        orthogonality: Option<f64>,
    ) -> Self {
        let values = &basis.values;
        let lmax = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let near_zero = values
            .iter()
            .filter(|v| v.abs() <= ZERO_EIGENVALUE_EPS * lmax)
            .count();
        let mut pinned = vec![false; components.count];
        for &v in dirichlet.unwrap_or(&[]) {
            if let Some(&c) = components.of_vertex.get(v)
                && let Some(p) = pinned.get_mut(c)
            {
                *p = true;
            }
        }
        let clusters: Vec<(usize, usize)> = eigenvalue_clusters(values, cluster_tolerance)
            .into_iter()
            .filter(|g| g.1 > 1)
            .collect();
        let has_residuals = !basis.residuals.is_empty();
        Self {
            n: basis.n,
            k: basis.k(),
            dirichlet_vertices: dirichlet.map_or(0, <[usize]>::len),
            min_relative_residual: has_residuals.then(|| {
                basis
                    .residuals
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min)
            }),
            max_relative_residual: has_residuals
                .then(|| basis.residuals.iter().copied().fold(0.0, f64::max)),
            orthonormality_error: orthogonality.unwrap_or_else(|| basis.orthogonality_error()),
            near_zero,
            components: components.count,
            expected_near_zero: pinned.iter().filter(|p| !**p).count().min(basis.k()),
            cluster_tolerance,
            last_cluster_reaches_k: clusters.last().is_some_and(|&(i, c)| i + c == basis.k()),
            clusters,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::AnalysisOptions;
    use crate::shapes::build_str;

    fn summary_of(an: &Analysis) -> MeshSummary {
        MeshSummary::new("x", an.mesh().content_hash(), an.mesh(), an.topology())
    }

    #[test]
    fn a_geodesic_run_reports_finite_stats_and_what_it_cannot_reach() {
        let t = build_str("sphere:res=2").unwrap();
        let (p, f) = (t.positions().to_vec(), t.triangles().to_vec());
        let n0 = p.len();
        let mut pos = p.clone();
        pos.extend(p.iter().map(|q| [q[0] + 5.0, q[1], q[2]]));
        let mut tris = f.clone();
        tris.extend(f.iter().map(|t| [t[0] + n0, t[1] + n0, t[2] + n0]));
        let an = Analysis::new(
            crate::mesh::Mesh::new(pos, tris).unwrap(),
            AnalysisOptions::default(),
        );
        let req: FieldRequest =
            serde_json::from_str(r#"{"kind": "geodesic", "source": 2}"#).unwrap();
        let run = run_field(
            &an,
            "field",
            summary_of(&an),
            &req,
            None,
            &mut |_| {},
            &CancelToken::new(),
        )
        .unwrap();
        let s = &run.summary;
        assert!(s.basis.is_none());
        assert_eq!(s.scale_normalization, "none");
        assert_eq!(s.value_at_source, Some(0.0));
        assert_eq!((s.stats.min, s.stats.argmin), (0.0, 2));
        assert!(s.stats.max.is_finite() && s.stats.argmax < n0);
        let msg = s.unreachable.as_deref().unwrap();
        assert!(
            msg.contains(&format!("{n0} of {} vertices", 2 * n0)),
            "{msg}"
        );
        let cp = s.critical_points.as_ref().unwrap();
        assert!(cp.euler_check.sides.holds);
        let json = serde_json::to_value(s).unwrap();
        assert!(json["max"].is_f64(), "{json}");
        assert_eq!(json["unreachable"], msg);
        assert_eq!(output_stem("field", &req), "geodesic");
    }

    #[test]
    fn field_run_uses_the_first_k_of_basis_k_and_reports_them() {
        let an = Analysis::new(
            build_str("sphere:res=2").unwrap(),
            AnalysisOptions::default(),
        );
        let req = FieldRequest::default_with_k(20);
        let run = run_field(
            &an,
            "spectral-distance",
            summary_of(&an),
            &req,
            Some(30),
            &mut |_| {},
            &CancelToken::new(),
        )
        .unwrap();
        assert_eq!(run.field.basis_k, Some(30));
        let b = run.summary.basis.as_ref().unwrap();
        assert_eq!((b.k, b.basis_k, b.eigenvalues.len()), (20, 30, 20));
        assert!(b.max_orthonormality_error < 1e-10);
        assert!(b.max_relative_residual.unwrap() < 1e-8);
        // The distance from the source is 0 there, and it is the smallest value.
        let s = run.field.request.source().unwrap();
        assert_eq!(s, an.default_source());
        assert_eq!(run.summary.value_at_source, Some(0.0));
        assert_eq!(run.summary.stats.min, 0.0);
        let cp = run.summary.critical_points.as_ref().unwrap();
        assert!(cp.euler_check.sides.holds);
        assert_eq!(cp.euler_check.sides.rhs, 2);
        // The same field as the analysis gives for the request on the held basis.
        assert_eq!(an.field(&req).unwrap().values, run.field.values);
        let json = serde_json::to_value(&run.summary).unwrap();
        assert_eq!(json["request"]["kind"], "distance");
        assert_eq!(json["argmin"], s);
        assert_eq!(
            output_stem("spectral-distance", &req),
            "filtered-spectral-distance"
        );
        assert_eq!(output_stem("field", &req), "distance");
    }

    #[test]
    fn the_solvers_orthogonality_error_is_the_one_measured_afterwards() {
        // 642 vertices and k = 20: the iterative solver, which reports the error.
        let an = Analysis::new(
            build_str("sphere:res=3").unwrap(),
            AnalysisOptions::default(),
        );
        let run = run_field(
            &an,
            "field",
            summary_of(&an),
            &FieldRequest::default_with_k(20),
            None,
            &mut |_| {},
            &CancelToken::new(),
        )
        .unwrap();
        let held = an.held_basis().unwrap();
        let measured = BasisSummary::of(&held, 20).max_orthonormality_error;
        let reported = run.summary.basis.unwrap().max_orthonormality_error;
        assert_eq!(reported.to_bits(), measured.to_bits());
        let r = BasisReport::with_orthogonality(&held, an.components(), None, 1e-6, Some(reported));
        assert_eq!(
            r.orthonormality_error.to_bits(),
            held.orthogonality_error().to_bits()
        );
    }

    #[test]
    fn harmonic_counts_and_explicit_constraints() {
        let mesh = build_str("torus:res=1").unwrap();
        let topo = Topology::new(&mesh);
        let ms = MeshSummary::new("torus", mesh.content_hash(), &mesh, &topo);
        let run = run_harmonic(
            &mesh,
            ms.clone(),
            &HarmonicConstraints::Counts(vec![2, 4]),
            1,
            Laplacian::Fem,
        )
        .unwrap();
        assert_eq!(run.maps.len(), 2);
        let first = &run.summary.maps[0];
        assert_eq!((first.m, first.big_m, first.s, first.chi), (1, 1, 2, 0));
        assert!(first.critical_points.euler_check.sides.holds);
        assert!(
            run.summary.maps[1]
                .locality
                .as_ref()
                .unwrap()
                .max_change_anywhere
                .is_some()
        );
        let list = vec![
            Constraint {
                vertex: 3,
                value: 0.0,
            },
            Constraint {
                vertex: 100,
                value: 1.5,
            },
        ];
        let run = run_harmonic(
            &mesh,
            ms,
            &HarmonicConstraints::Explicit(list.clone()),
            2,
            Laplacian::Fem,
        )
        .unwrap();
        assert_eq!(run.maps.len(), 1);
        assert_eq!(run.maps[0].constraints, list);
        assert_eq!(run.maps[0].field[100], 1.5);
        assert!(run.summary.maps[0].locality.is_none());
        let json = serde_json::to_value(&run.summary).unwrap();
        assert_eq!(json["maps"][0]["M"], run.summary.maps[0].big_m);
    }

    #[test]
    fn clusters_and_the_basis_report_of_a_sphere() {
        assert_eq!(
            eigenvalue_clusters(&[0.0, 1e-16, 2.0, 2.0 + 1e-9, 2.0 + 2e-9, 6.0], 1e-6),
            vec![(0, 2), (2, 3), (5, 1)]
        );
        let an = Analysis::new(
            build_str("sphere:res=2").unwrap(),
            AnalysisOptions::default(),
        );
        let b = an.basis(16, &mut |_| {}, &CancelToken::new()).unwrap();
        let r = BasisReport::new(&b, an.components(), None, 1e-6);
        assert_eq!((r.near_zero, r.expected_near_zero, r.components), (1, 1, 1));
        // l = 1 is triple, l = 2 five-fold; the icosahedral symmetry splits l = 3 into
        // 3 + 4, the last group ending at k = 16.
        assert_eq!(r.clusters, vec![(1, 3), (4, 5), (9, 3), (12, 4)]);
        assert!(r.last_cluster_reaches_k);
        assert!(r.orthonormality_error < 1e-10);
    }

    #[test]
    fn stats_take_the_lowest_vertex_on_ties() {
        let s = FieldStats::of(&[1.0, 3.0, -2.0, 3.0, -2.0]);
        assert_eq!((s.min, s.argmin, s.max, s.argmax), (-2.0, 2, 3.0, 1));
    }
}
