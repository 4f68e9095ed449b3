//! The library's [`Analysis`] as a Python class: one mesh, its operators, the
//! factorization and a basis that grows with `k`, answering field requests.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde_json::json;
use spectral_mesh::analysis::{AnalysisInput, AnalysisOptions, Signal, SignatureSpec};
use spectral_mesh::io::read_input;
use spectral_mesh::operators::{Laplacian, PointCloudParams};
use spectral_mesh::spectral::BasisView;
use spectral_mesh::spectral::distances::{
    distances_from_many, green_row, spectral_function, weighted_pairs, weights_of_pairs,
};
use spectral_mesh::spectral::embedding::{embedding_component, spectral_embedding_weights};
use spectral_mesh::spectral::filters::{Filter, FilterError};
use spectral_mesh::spectral::signatures::{hks, hks_auto_times, wks, wks_auto_energies};
use spectral_mesh::spectral::store::{BasisMeta, load_npz, save_npz};
use spectral_mesh::{Analysis, CancelToken, Eigenbasis, FieldRequest};
use spectral_mesh_render::figure::POINT_RADIUS_FACTOR;

use crate::arrays::{
    self, FieldOut, Layout, MeshArrays, Pairs, csc_parts, csc_to_py, mesh_from, to_matrix,
    to_vector,
};
use crate::errors::Failure;
use crate::pyjson;
use crate::run::{Progress, run, run_heavy};
use crate::{CloudArgs, Picture, PointsArgs, SolverArgs, draw, laplacian_of, with_values};

/// The `k` weights of a Python weight function from its values at the eigenvalues of
/// [`weighted_pairs`] (the library's checks: strictly positive and finite).
fn pair_weights(b: BasisView<'_>, given: &[f64], name: &str) -> Result<Vec<f64>, Failure> {
    weights_of_pairs(b.values, given, name).map_err(value_error)
}

/// A weight function's values as given (not-finite ones included: [`weights_of_pairs`]
/// refuses them naming the eigenpair).
fn raw_weights(a: &PyReadonlyArray1<'_, f64>) -> Result<Vec<f64>, Failure> {
    Ok(a.as_slice()
        .map_err(|e| Failure::value(format!("weights: {e}")))?
        .to_vec())
}

/// A filter given as text (`what`: the keyword, for the message).
fn parse_filter(text: &str, what: &str) -> Result<Filter, Failure> {
    text.parse()
        .map_err(|e: FilterError| Failure::value(format!("{what}: {e}")))
}

/// A `ValueError` from a library error's message.
fn value_error(e: impl std::fmt::Display) -> Failure {
    Failure::value(e.to_string())
}

/// An embedding's rows as `(n, d, row-major data)`.
fn embedding_rows(rows: Vec<Vec<f64>>) -> (usize, usize, Vec<f64>) {
    let d = rows.first().map_or(0, Vec::len);
    (rows.len(), d, rows.concat())
}

/// How the pairs of the basis are weighted, as the wrappers pass it: a filter's text, or
/// a Python weight function's values at [`PyAnalysis::filter_eigenvalues`] and its name.
#[derive(FromPyObject)]
enum Weights<'a> {
    /// A filter (`biharmonic`, `heat:t=0.1`, ...), parsed by the library.
    Filter(String),
    /// A weight function's values and its name (for the messages).
    Function(PyReadonlyArray1<'a, f64>, String),
}

/// [`Weights`] ready for the worker thread: the filter parsed, the values copied.
enum PairWeights {
    Filter(Filter),
    Given(Vec<f64>, String),
}

impl Weights<'_> {
    /// Parses or copies the weights (`what`: the keyword a bad filter is reported under).
    fn prepare(&self, what: &str) -> Result<PairWeights, Failure> {
        Ok(match self {
            Weights::Filter(text) => PairWeights::Filter(parse_filter(text, what)?),
            Weights::Function(values, name) => {
                PairWeights::Given(raw_weights(values)?, name.clone())
            }
        })
    }
}

impl PairWeights {
    /// One weight per pair of `b`: the filter's, or the function's values checked by the
    /// library ([`weights_of_pairs`]).
    fn of(&self, b: BasisView<'_>) -> Result<Vec<f64>, Failure> {
        match self {
            PairWeights::Filter(f) => f.weights(b.values).map_err(value_error),
            PairWeights::Given(given, name) => pair_weights(b, given, name),
        }
    }
}

/// A `ValueError` from a serde message.
fn request_error(e: serde_json::Error) -> Failure {
    let s = e.to_string();
    let s = s.split(" at line ").next().unwrap_or(&s).to_string();
    Failure::value(format!("invalid request: {s}"))
}

/// The analysis object (see the module documentation).
#[pyclass(frozen, name = "Analysis", module = "spectral_mesh._native")]
pub struct PyAnalysis {
    inner: Arc<Analysis>,
    /// The point-cloud Laplacian's parameters of a point-cloud analysis.
    cloud: Option<PointCloudParams>,
    /// Number of vertices.
    #[pyo3(get)]
    n: usize,
    /// True for the analysis of a point cloud.
    #[pyo3(get)]
    is_point_cloud: bool,
    /// The mean spacing of a point cloud's points (the mean edge length of its triangle
    /// union), `None` for a mesh.
    #[pyo3(get)]
    point_spacing: Option<f64>,
    /// Whether the operators are normalized to unit total mass.
    #[pyo3(get)]
    normalized: bool,
    /// The discretization's name.
    #[pyo3(get)]
    kind: &'static str,
    /// `1^T B 1` of the mass as assembled (the area for area-based masses).
    #[pyo3(get)]
    input_total_mass: f64,
    /// The vertex of largest x (lowest index on ties): the default source and anchor.
    #[pyo3(get)]
    default_source: usize,
}

impl PyAnalysis {
    /// The Python object of an analysis (its fixed properties read once).
    fn wrap(inner: Arc<Analysis>, cloud: Option<PointCloudParams>) -> Self {
        Self {
            n: inner.n(),
            is_point_cloud: inner.is_point_cloud(),
            point_spacing: inner.point_spacing(),
            normalized: inner.options().normalize,
            kind: inner.options().laplacian.name(),
            input_total_mass: inner.input_total_mass(),
            default_source: inner.default_source(),
            inner,
            cloud,
        }
    }

    /// Runs `f` on the first `k` pairs of the basis (computed when needed).
    fn with_basis<T, F>(&self, py: Python<'_>, k: usize, f: F) -> PyResult<T>
    where
        T: Send + 'static,
        F: FnOnce(BasisView<'_>) -> Result<T, Failure> + Send + 'static,
    {
        self.with_basis_progress(py, k, Progress::default(), f)
    }

    /// [`PyAnalysis::with_basis`] with the per-pair weights of a filter or a Python weight
    /// function ([`PairWeights::of`]), handed to `f` as one weight per pair of the basis
    /// (`what`: the keyword a bad filter is reported under).
    fn with_weights<T, F>(
        &self,
        py: Python<'_>,
        k: usize,
        (weights, what): (Weights<'_>, &str),
        f: F,
    ) -> PyResult<T>
    where
        T: Send + 'static,
        F: FnOnce(BasisView<'_>, &[f64]) -> Result<T, Failure> + Send + 'static,
    {
        let weights = weights.prepare(what).map_err(|e| e.into_pyerr(py))?;
        self.with_basis(py, k, move |b| {
            let w = weights.of(b)?;
            f(b, &w)
        })
    }

    /// [`PyAnalysis::with_weights`] for a library computation of one value per vertex:
    /// the `(n,)` array, a `ValueError` with the library's message when it fails.
    fn vertex_values_weighted<'py, E, F>(
        &self,
        py: Python<'py>,
        k: usize,
        weights: Weights<'_>,
        f: F,
    ) -> PyResult<Bound<'py, PyArray1<f64>>>
    where
        E: std::fmt::Display,
        F: FnOnce(BasisView<'_>, &[f64]) -> Result<Vec<f64>, E> + Send + 'static,
    {
        let data = self.with_weights(py, k, (weights, "filter"), move |b, w| {
            f(b, w).map_err(value_error)
        })?;
        Ok(to_vector(py, data))
    }

    /// The `(n, cols)` array of the per-vertex columns a computation returns (`n` values
    /// each).
    fn columns<'py>(
        &self,
        py: Python<'py>,
        columns: PyResult<Vec<Vec<f64>>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let columns = columns?;
        let cols = columns.len();
        to_matrix(py, Layout::Columns, self.inner.n(), cols, columns.concat())
    }

    /// [`PyAnalysis::with_basis`] reporting the eigensolve to a Python callback.
    fn with_basis_progress<T, F>(
        &self,
        py: Python<'_>,
        k: usize,
        progress: Progress,
        f: F,
    ) -> PyResult<T>
    where
        T: Send + 'static,
        F: FnOnce(BasisView<'_>) -> Result<T, Failure> + Send + 'static,
    {
        let an = self.inner.clone();
        let work = move |token: &CancelToken| {
            let b = an.basis(k, &mut |p| progress.report(&p, token), token);
            let b = progress.finish(b.map_err(Failure::from))?;
            f(b.view(k))
        };
        // An eigensolve to come gets a pool of its own (see `run_heavy`); a held basis does not
        // pay for the pool's threads.
        if self.inner.held_k() < k {
            run_heavy(py, Some(self.inner.n()), work)
        } else {
            run(py, work)
        }
    }
}

#[pymethods]
impl PyAnalysis {
    /// Builds the analysis of `(V, F)` (assembles the operators; nothing is factored yet).
    #[new]
    fn new(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        kind: &str,
        normalize: bool,
        solver: SolverArgs,
    ) -> PyResult<Self> {
        let prepare = || -> Result<_, Failure> {
            Ok((
                mesh_from(&v, &f)?,
                AnalysisOptions {
                    laplacian: laplacian_of(kind)?,
                    normalize,
                    eigen: solver.params()?,
                },
            ))
        };
        let (mesh, options) = prepare().map_err(|e| e.into_pyerr(py))?;
        let rows = Some(mesh.n_vertices());
        let inner = run_heavy(py, rows, move |_| {
            Ok(Arc::new(Analysis::new(mesh, options)))
        })?;
        Ok(Self::wrap(inner, None))
    }

    /// Builds the analysis of a point cloud `P` (its point-cloud Laplacian, built now):
    /// `normals` (when given) give the tangent planes where they are non-zero; `None`
    /// parameters take the library's defaults.
    #[staticmethod]
    #[pyo3(signature = (points, normalize, solver))]
    fn from_points(
        py: Python<'_>,
        points: PointsArgs<'_>,
        normalize: bool,
        solver: SolverArgs,
    ) -> PyResult<Self> {
        let prepare = || -> Result<_, Failure> {
            let (cloud, params) = points.build()?;
            let options = AnalysisOptions {
                laplacian: Laplacian::Robust,
                normalize,
                eigen: solver.params()?,
            };
            Ok((cloud, params, options))
        };
        let (cloud, params, options) = prepare().map_err(|e| e.into_pyerr(py))?;
        let rows = Some(cloud.positions().len());
        let inner = run_heavy(py, rows, move |_| {
            Ok(Arc::new(Analysis::from_points(cloud, &params, options)?))
        })?;
        Ok(Self::wrap(inner, Some(params)))
    }

    /// Builds the analysis of a mesh or point-cloud file (`read_input`: a PLY without
    /// faces and the point formats are clouds). `kind`: `None` for the input's default
    /// (fem for a mesh, robust for a cloud). The point-cloud keywords (`None` / `False`:
    /// the library's defaults) are refused with a mesh, as on the command line.
    #[staticmethod]
    #[pyo3(signature = (path, kind, cloud, use_normals, normalize, solver))]
    fn from_file(
        py: Python<'_>,
        path: PathBuf,
        kind: Option<String>,
        cloud: CloudArgs,
        use_normals: bool,
        normalize: bool,
        solver: SolverArgs,
    ) -> PyResult<Self> {
        let prepare = || -> Result<_, Failure> {
            let kind = kind.as_deref().map(laplacian_of).transpose()?;
            Ok((kind, solver.params()?))
        };
        let (kind, eigen) = prepare().map_err(|e| e.into_pyerr(py))?;
        let (inner, params) = run_heavy(py, None, move |_| {
            let (input, params) = match AnalysisInput::from(read_input(&path)?) {
                AnalysisInput::Points { cloud: points, .. } => {
                    let params = cloud.params(use_normals);
                    (
                        AnalysisInput::Points {
                            cloud: points,
                            params,
                        },
                        Some(params),
                    )
                }
                mesh => {
                    let mut given = cloud.given();
                    if use_normals {
                        given.push("use_normals");
                    }
                    if !given.is_empty() {
                        return Err(Failure::value(format!(
                            "{} {} only to point clouds, and {} is a mesh (its Laplacian is chosen with kind)",
                            given.join(", "),
                            if given.len() == 1 { "applies" } else { "apply" },
                            path.display()
                        )));
                    }
                    (mesh, None)
                }
            };
            let laplacian = spectral_mesh::defaults::laplacian_for(kind, params.is_some())?;
            let options = AnalysisOptions {
                laplacian,
                normalize,
                eigen,
            };
            Ok((Arc::new(Analysis::from_input(input, options)?), params))
        })?;
        Ok(Self::wrap(inner, params))
    }

    /// Eigenpairs held (0 before the first spectral request).
    #[getter]
    fn held_k(&self) -> usize {
        self.inner.held_k()
    }

    /// How many times the shifted pencil was factored.
    #[getter]
    fn factorizations(&self) -> usize {
        self.inner.factorizations()
    }

    /// `(V, F)` of the mesh (copies).
    fn mesh<'py>(&self, py: Python<'py>) -> PyResult<MeshArrays<'py>> {
        let (v, f) = arrays::mesh_arrays(self.inner.mesh());
        let (n, m) = (v.len() / 3, f.len() / 3);
        Ok((
            to_matrix(py, Layout::Rows, n, 3, v)?,
            to_matrix(py, Layout::Rows, m, 3, f)?,
        ))
    }

    /// The operators in use `(S, B)` as CSC arrays (`B / A` when normalizing).
    fn operators<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyTuple>)> {
        let ops = self.inner.operators();
        Ok((
            csc_to_py(py, csc_parts(&ops.stiffness))?,
            csc_to_py(py, csc_parts(&ops.mass))?,
        ))
    }

    /// The first `k` pairs `(evals (k,), evecs (n, k))` (copies; the basis is computed or
    /// grown when it holds fewer), the solve reported to `progress` when given.
    #[pyo3(signature = (k, progress=None))]
    fn basis<'py>(
        &self,
        py: Python<'py>,
        k: usize,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Pairs<'py>> {
        let progress = Progress::new(progress);
        let (n, values, vectors) = self.with_basis_progress(py, k, progress, move |b| {
            Ok((b.n, b.values.to_vec(), b.vectors.to_vec()))
        })?;
        Ok((
            to_vector(py, values),
            to_matrix(py, Layout::Columns, n, k, vectors)?,
        ))
    }

    /// Relative residuals of the held basis' pairs (empty without a basis).
    fn residuals<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let r = self
            .inner
            .held_basis()
            .map(|b| b.residuals.clone())
            .unwrap_or_default();
        to_vector(py, r)
    }

    /// Evaluates a field request (the library's serde form, as a dict); `values` replaces
    /// a diffusion's signal or a segmentation's field. Returns `(values, labels, info)`.
    #[pyo3(signature = (request, values=None))]
    fn field<'py>(
        &self,
        py: Python<'py>,
        request: &Bound<'py, PyAny>,
        values: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<FieldOut<'py>> {
        let prepare = || -> Result<FieldRequest, Failure> {
            let value = pyjson::from_py(request, "request")?;
            let mut req: FieldRequest = serde_json::from_value(value).map_err(request_error)?;
            if let Some(v) = &values {
                with_values(&mut req, arrays::values(v, "values")?)?;
            }
            Ok(req)
        };
        let req = prepare().map_err(|e| e.into_pyerr(py))?;
        let an = self.inner.clone();
        let (values, labels, info) = run(py, move |token| {
            let mut field = an.field_with(&req, &mut |_| {}, token)?;
            let unreachable = field.unreachable_message();
            let values = std::mem::take(&mut field.values);
            let labels = field.labels.take();
            // Per-vertex payloads stay out of the info.
            match &mut field.request {
                FieldRequest::Diffusion { signal, .. } if matches!(signal, Signal::Values(_)) => {
                    *signal = Signal::Values(Vec::new())
                }
                FieldRequest::Segmentation { signature, .. }
                    if matches!(signature, SignatureSpec::Values(_)) =>
                {
                    *signature = SignatureSpec::Values(Vec::new())
                }
                _ => {}
            }
            let mut info =
                serde_json::to_value(&field).map_err(|e| Failure::Internal(e.to_string()))?;
            if let (Some(m), Some(o)) = (unreachable, info.as_object_mut()) {
                o.insert("unreachable_message".into(), m.into());
            }
            Ok((values, labels, info))
        })?;
        let labels = labels.map(|l| to_vector(py, l.into_iter().map(|x| x as i64).collect()));
        Ok((to_vector(py, values), labels, pyjson::to_py(py, &info)?))
    }

    /// Critical points of a field with the Euler check, as a dict.
    fn critical_points<'py>(
        &self,
        py: Python<'py>,
        values: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let values = arrays::values(&values, "values").map_err(|e| e.into_pyerr(py))?;
        let an = self.inner.clone();
        let report = run(py, move |_| {
            let report = an.critical_points(&values)?;
            serde_json::to_value(&report).map_err(|e| Failure::Internal(e.to_string()))
        })?;
        pyjson::to_py(py, &report)
    }

    /// Level sets of a field at `levels`, or at `count` evenly spaced values inside its
    /// range (the library's `level_values`, as figures draw them): a list of
    /// `(value, segments)` with the segments as an `(s, 6)` array of end points.
    #[pyo3(signature = (values, levels, count=None))]
    fn level_sets<'py>(
        &self,
        py: Python<'py>,
        values: PyReadonlyArray1<'_, f64>,
        levels: Vec<f64>,
        count: Option<usize>,
    ) -> PyResult<Vec<(f64, Bound<'py, PyArray2<f64>>)>> {
        let values = arrays::values(&values, "values").map_err(|e| e.into_pyerr(py))?;
        let an = self.inner.clone();
        let sets = run(py, move |_| {
            let n = an.n();
            if values.len() != n {
                return Err(Failure::value(format!(
                    "values has {} entries but the mesh has {n} vertices",
                    values.len()
                )));
            }
            if let Some(l) = levels.iter().find(|l| !l.is_finite()) {
                return Err(Failure::value(format!("level {l} is not finite")));
            }
            let levels = match count {
                Some(c) => {
                    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    spectral_mesh::fields::level_sets::level_values(lo, hi, c)
                }
                None => levels,
            };
            let sets =
                spectral_mesh::fields::level_sets::extract_level_sets(an.mesh(), &values, &levels);
            Ok(sets
                .into_iter()
                .map(|s| {
                    let flat: Vec<f64> = s.segments.iter().flatten().flatten().copied().collect();
                    (s.value, flat)
                })
                .collect::<Vec<_>>())
        })?;
        sets.into_iter()
            .map(|(v, flat)| {
                let s = flat.len() / 6;
                Ok((v, to_matrix(py, Layout::Rows, s, 6, flat)?))
            })
            .collect()
    }

    /// HKS at each time: `(n, len(times))` (pyFM's convention: every pair, the zero
    /// eigenvalue included; `scaled` divides by the heat trace).
    fn hks_many<'py>(
        &self,
        py: Python<'py>,
        times: Vec<f64>,
        scaled: bool,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        if let Some(t) = times.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
            return Err(
                Failure::value(format!("t = {t}: times must be finite and > 0")).into_pyerr(py),
            );
        }
        let data = self.with_basis(py, k, move |b| Ok(hks(b, &times, scaled)));
        self.columns(py, data)
    }

    /// pyFM's automatic HKS times for the first `k` pairs.
    fn hks_auto_times(&self, py: Python<'_>, count: usize, k: usize) -> PyResult<Vec<f64>> {
        self.with_basis(py, k, move |b| {
            hks_auto_times(b, count).map_err(value_error)
        })
    }

    /// WKS at each energy: `(n, len(energies))` (pyFM's convention).
    fn wks_many<'py>(
        &self,
        py: Python<'py>,
        energies: Vec<f64>,
        sigma: f64,
        scaled: bool,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        if let Some(e) = energies.iter().find(|e| !e.is_finite()) {
            return Err(Failure::value(format!("energy {e} is not finite")).into_pyerr(py));
        }
        let data = self.with_basis(py, k, move |b| {
            wks(b, &energies, sigma, scaled).map_err(value_error)
        });
        self.columns(py, data)
    }

    /// pyFM's automatic WKS energies and bandwidth for the first `k` pairs.
    fn wks_auto_energies(
        &self,
        py: Python<'_>,
        count: usize,
        k: usize,
    ) -> PyResult<(Vec<f64>, f64)> {
        self.with_basis(py, k, move |b| {
            wks_auto_energies(b, count).map_err(value_error)
        })
    }

    /// The spectral embedding of a filter or of a weight function's values: `(n, d)`,
    /// `d` = pairs with non-zero weight.
    fn embedding_matrix<'py>(
        &self,
        py: Python<'py>,
        weights: Weights<'_>,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (n, d, data) = self.with_weights(py, k, (weights, "filter"), move |b, w| {
            spectral_embedding_weights(b, w, usize::MAX)
                .map(embedding_rows)
                .map_err(value_error)
        })?;
        to_matrix(py, Layout::Rows, n, d, data)
    }

    /// The eigenvalues of the first `k` pairs that a filter weighs (the library's
    /// zero-eigenvalue rule): `(pair indices, eigenvalues)`. A Python weight function is
    /// evaluated at these values and its values passed as [`Weights`] to the methods
    /// that take them.
    fn filter_eigenvalues<'py>(
        &self,
        py: Python<'py>,
        k: usize,
    ) -> PyResult<(Vec<usize>, Bound<'py, PyArray1<f64>>)> {
        let (used, values) = self.with_basis(py, k, move |b| {
            weighted_pairs(b.values).map_err(value_error)
        })?;
        Ok((used, to_vector(py, values)))
    }

    /// A row `G(source, .)` of the Green kernel with the weights of a function: `(n,)`.
    fn green_weighted<'py>(
        &self,
        py: Python<'py>,
        source: usize,
        weights: Weights<'_>,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.vertex_values_weighted(py, k, weights, move |b, w| green_row(b, source, w))
    }

    /// The generalized spectral function `G(p, p)` with the weights of a function: `(n,)`.
    fn spectral_function_weighted<'py>(
        &self,
        py: Python<'py>,
        weights: Weights<'_>,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.vertex_values_weighted(py, k, weights, |b, w| spectral_function(b, w))
    }

    /// One coordinate `sqrt(w_c) x_c` of the embedding with the weights of a function
    /// (`c` 0-based in the basis; zeros for a pair of weight 0): `(n,)`.
    fn embedding_component_weighted<'py>(
        &self,
        py: Python<'py>,
        weights: Weights<'_>,
        component: usize,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.vertex_values_weighted(py, k, weights, move |b, w| {
            embedding_component(b, w, component)
        })
    }

    /// Spectral distances from several sources with the weights of a filter or of a
    /// weight function's values: `(n, len(sources))`.
    fn distances_many<'py>(
        &self,
        py: Python<'py>,
        sources: Vec<usize>,
        weights: Weights<'_>,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let data = self.with_weights(py, k, (weights, "distance"), move |b, w| {
            distances_from_many(b, &sources, w).map_err(value_error)
        });
        self.columns(py, data)
    }

    /// Installs a basis given as arrays: eigenvalues `(k,)` and the eigenvectors' `(k, n)`
    /// transpose, B-orthonormal for this analysis' mass.
    fn set_basis(
        &self,
        py: Python<'_>,
        evals: PyReadonlyArray1<'_, f64>,
        evecs_t: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let prepare = || -> Result<Eigenbasis, Failure> {
            let (n, values, vectors) = arrays::pairs(&evals, &evecs_t)?;
            if values.is_empty() {
                return Err(Failure::value("the basis is empty (k = 0)"));
            }
            if values.windows(2).any(|w| w[1] < w[0]) {
                return Err(Failure::value("evals must be ascending"));
            }
            let ops = self.inner.operators();
            let mut b = Eigenbasis {
                laplacian: ops.laplacian,
                n,
                values,
                vectors,
                mass: ops.mass.clone(),
                residuals: Vec::new(),
            };
            if n == self.inner.n() {
                b.residuals = b.compute_residuals(&ops.stiffness);
            }
            Ok(b)
        };
        let basis = prepare().map_err(|e| e.into_pyerr(py))?;
        let an = self.inner.clone();
        run(py, move |_| Ok(an.set_basis(basis)?))
    }

    /// Saves the held basis (with the mesh hash and the solver parameters).
    fn save_basis(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let an = self.inner.clone();
        run(py, move |_| {
            let b = an
                .held_basis()
                .ok_or_else(|| Failure::value("no basis to save: ask for one first (basis(k))"))?;
            let params = spectral_mesh::spectral::eigenbasis::EigenParams {
                k: b.k(),
                ..an.options().eigen.clone()
            };
            let meta = BasisMeta::new(&b, Some(an.mesh()), &params);
            save_npz(&b, &path, &meta)?;
            Ok(())
        })
    }

    /// Loads a basis saved for this mesh, discretization and normalisation (refused
    /// otherwise) and holds it. Returns the number of pairs.
    fn load_basis(&self, py: Python<'_>, path: PathBuf) -> PyResult<usize> {
        let an = self.inner.clone();
        run(py, move |_| {
            let (basis, meta) = load_npz(&path)?;
            let p = path.display();
            if basis.n != an.n() {
                return Err(Failure::value(format!(
                    "{p}: the basis has {} vertices but the mesh has {}",
                    basis.n,
                    an.n()
                )));
            }
            if basis.laplacian != an.options().laplacian {
                return Err(Failure::value(format!(
                    "{p}: the basis is for the '{}' discretization, this analysis uses '{}'",
                    basis.laplacian.name(),
                    an.options().laplacian.name()
                )));
            }
            if !meta.mesh_hash.is_empty() && meta.mesh_hash != an.mesh().content_hash() {
                return Err(Failure::value(format!(
                    "{p}: the basis was computed for another mesh (its hash differs)"
                )));
            }
            let ours = &an.operators().mass;
            let same_mass = basis.mass.col_ptr() == ours.col_ptr()
                && basis.mass.row_idx() == ours.row_idx()
                && basis
                    .mass
                    .values()
                    .iter()
                    .zip(ours.values())
                    .all(|(a, b)| (a - b).abs() <= 1e-12 * b.abs().max(f64::MIN_POSITIVE));
            if !same_mass {
                return Err(Failure::value(format!(
                    "{p}: the basis was computed with another mass matrix (normalize = {} here; was it saved with the other setting?)",
                    an.options().normalize
                )));
            }
            let k = basis.k();
            an.set_basis(basis)?;
            Ok(k)
        })
    }

    /// Draws a field on this mesh (see the module-level `render`).
    fn render(&self, py: Python<'_>, picture: Picture<'_>) -> PyResult<Py<PyAny>> {
        let radius = self.inner.point_spacing().map(|h| POINT_RADIUS_FACTOR * h);
        draw(py, self.inner.mesh_arc().clone(), radius, picture)
    }

    fn __repr__(&self) -> String {
        let o = self.inner.options();
        format!(
            "Analysis({}={}, kind='{}', normalize={}, held_k={})",
            if self.cloud.is_some() { "points" } else { "n" },
            self.inner.n(),
            o.laplacian.name(),
            if o.normalize { "True" } else { "False" },
            self.inner.held_k()
        )
    }

    /// The analysis' options as a dict.
    fn options<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let o = self.inner.options();
        let v = json!({
            "kind": o.laplacian.name(),
            "normalize": o.normalize,
            "tol": o.eigen.tolerance,
            "seed": o.eigen.seed,
            "dirichlet": o.eigen.dirichlet,
            "point_cloud": self.cloud,
        });
        pyjson::to_py(py, &v)
    }
}
