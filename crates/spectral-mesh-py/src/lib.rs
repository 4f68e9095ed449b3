//! `spectral_mesh._native`: the native module behind the Python package `spectral_mesh`.
//!
//! It binds the library's analysis type ([`spectral_mesh::Analysis`]) and request type
//! ([`spectral_mesh::FieldRequest`], built from the JSON the Python layer writes from
//! keyword arguments), the operators, the generic sparse eigensolver, the basis archive
//! and the figure code. The Python layer (`python/spectral_mesh/`) normalizes user input,
//! documents every function and is the public API; this module is private.
//!
//! Every computation goes through `run::run` (the heavy ones through `run::run_heavy`, on
//! a thread pool of the call's own): a worker thread, the GIL released, Ctrl-C honoured
//! within a second, panics turned into exceptions.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde_json::{Value, json};
use spectral_mesh::analysis::{AnalysisOptions, Signal, SignatureSpec};
use spectral_mesh::operators::{Laplacian, NormalSource, Operators, PointCloudParams};
use spectral_mesh::spectral::eigenbasis::{
    CertifyReport, EigenMethod, EigenParams, EigenSolver, certify_eigenbasis,
};
use spectral_mesh::spectral::store::{BasisDtype, BasisMeta, load_npz, save_npz};
use spectral_mesh::{Analysis, Eigenbasis, FieldRequest, Mesh, PointCloud, SparseMatrix};
use spectral_mesh_render::{Canvas, Colormap, Figure, FigureOptions, View};

mod analysis;
mod arrays;
mod batch;
mod correspondence;
mod errors;
mod geodesic;
mod learning;
mod pyjson;
mod run;

use arrays::{
    Archive, Layout, MeshArrays, Pairs, csc_from, csc_parts, csc_to_py, mesh_arrays, mesh_from,
    to_matrix, to_vector,
};
use errors::Failure;
use run::run;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// `(V, F, info)` of a mesh file.
type MeshFile<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyAny>,
);

fn mesh_to_py<'py>(py: Python<'py>, v: Vec<f64>, f: Vec<i64>) -> PyResult<MeshArrays<'py>> {
    let (n, m) = (v.len() / 3, f.len() / 3);
    Ok((
        to_matrix(py, Layout::Rows, n, 3, v)?,
        to_matrix(py, Layout::Rows, m, 3, f)?,
    ))
}

/// Parses a discretization name.
pub(crate) fn laplacian_of(kind: &str) -> Result<Laplacian, Failure> {
    kind.parse::<Laplacian>().map_err(Failure::Value)
}

/// The keyword `tol` of every function (`eigenbasis`, `eigsh`, `Analysis`, `batch`), with
/// one meaning (as in SciPy's `eigsh`): a target relative residual `> 0`, or `0` for the
/// library's default.
pub(crate) fn tolerance_of(tol: f64) -> Result<f64, Failure> {
    if tol == 0.0 {
        Ok(EigenParams::default().tolerance)
    } else if tol.is_finite() && tol > 0.0 {
        Ok(tol)
    } else {
        Err(Failure::value(format!(
            "tol = {tol}: must be a finite number > 0, or 0 for the default ({:e})",
            EigenParams::default().tolerance
        )))
    }
}

/// The eigensolver's Python keywords as the wrappers pass them: one tuple
/// `(tol, seed, dirichlet, method)`.
#[derive(FromPyObject)]
pub(crate) struct SolverArgs(f64, u64, Option<Vec<usize>>, String);

impl SolverArgs {
    /// The library's eigensolver parameters (checked by [`eigen_params`]).
    pub(crate) fn params(self) -> Result<EigenParams, Failure> {
        let Self(tol, seed, dirichlet, method) = self;
        eigen_params(tol, seed, dirichlet, &method)
    }
}

/// The point-cloud Laplacian's Python keywords as the wrappers pass them: one tuple
/// `(n_neighbors, mollify_factor)`, `None` for the library's default.
#[derive(FromPyObject)]
pub(crate) struct CloudArgs(Option<usize>, Option<f64>);

impl CloudArgs {
    /// The library's parameters (it checks them when it builds the Laplacian);
    /// `use_normals`: the cloud's normals give the tangent planes where they are non-zero.
    pub(crate) fn params(&self, use_normals: bool) -> PointCloudParams {
        let d = PointCloudParams::default();
        PointCloudParams {
            neighbors: self.0.unwrap_or(d.neighbors),
            mollify_factor: self.1.unwrap_or(d.mollify_factor),
            normals: if use_normals {
                NormalSource::FromCloud
            } else {
                d.normals
            },
            ..d
        }
    }

    /// The Python keywords given (not `None`), by name.
    pub(crate) fn given(&self) -> Vec<&'static str> {
        [
            (self.0.is_some(), "n_neighbors"),
            (self.1.is_some(), "mollify_factor"),
        ]
        .into_iter()
        .filter_map(|(set, name)| set.then_some(name))
        .collect()
    }
}

/// A point cloud as the wrappers pass it: one tuple `(P, normals, cloud)`, `normals`
/// `None` or `(n, 3)` (zero rows: unknown) and `cloud` the Laplacian's keywords.
#[derive(FromPyObject)]
pub(crate) struct PointsArgs<'py>(
    PyReadonlyArray2<'py, f64>,
    Option<PyReadonlyArray2<'py, f64>>,
    CloudArgs,
);

impl PointsArgs<'_> {
    /// The cloud (checked) and its Laplacian's parameters: given normals give the tangent
    /// planes where they are non-zero; without them the planes are estimated.
    pub(crate) fn build(&self) -> Result<(PointCloud, PointCloudParams), Failure> {
        let Self(p, normals, cloud) = self;
        let points = arrays::cloud_from(p, normals.as_ref())?;
        Ok((points, cloud.params(normals.is_some())))
    }
}

/// Eigensolver parameters from the Python keywords.
pub(crate) fn eigen_params(
    tol: f64,
    seed: u64,
    dirichlet: Option<Vec<usize>>,
    method: &str,
) -> Result<EigenParams, Failure> {
    let tol = tolerance_of(tol)?;
    let method = match method
        .trim()
        .to_ascii_lowercase()
        .replace('_', "-")
        .as_str()
    {
        "auto" => EigenMethod::Auto,
        "dense" => EigenMethod::Dense,
        "shift-invert" | "shift-invert-block" | "sparse" => EigenMethod::ShiftInvertBlock,
        other => {
            return Err(Failure::value(format!(
                "method = '{other}': expected 'auto', 'dense' or 'shift-invert'"
            )));
        }
    };
    Ok(EigenParams {
        tolerance: tol,
        seed,
        dirichlet,
        method,
        ..EigenParams::default()
    })
}

/// Reads a mesh file (OFF, OBJ, PLY, STL): `(V, F, info)`.
#[pyfunction]
fn read_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<MeshFile<'py>> {
    let (v, f, info) = run(py, move |_| {
        let loaded = spectral_mesh::io::read_mesh(&path)?;
        let (v, f) = mesh_arrays(&loaded.mesh);
        let info = json!({
            "format": format!("{:?}", loaded.format).to_ascii_lowercase(),
            "polygons_triangulated": loaded.polygons_triangulated,
            "warnings": loaded.warnings,
        });
        Ok((v, f, info))
    })?;
    let (v, f) = mesh_to_py(py, v, f)?;
    Ok((v, f, pyjson::to_py(py, &info)?))
}

/// Writes a mesh file; the format comes from the extension.
#[pyfunction]
fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
) -> PyResult<()> {
    let mesh = mesh_from(&v, &f).map_err(|e| e.into_pyerr(py))?;
    run(py, move |_| {
        spectral_mesh::io::write_mesh(&path, &mesh, &Default::default())?;
        Ok(())
    })
}

/// A built-in shape from its spec (`"3torus"`, `"sphere:res=4"`, ...): `(V, F)`.
#[pyfunction]
fn shape<'py>(py: Python<'py>, spec: String) -> PyResult<MeshArrays<'py>> {
    let (v, f) = run(py, move |_| {
        let mesh =
            spectral_mesh::shapes::build_str(&spec).map_err(|e| Failure::value(e.to_string()))?;
        Ok(mesh_arrays(&mesh))
    })?;
    mesh_to_py(py, v, f)
}

/// The built-in shapes: name, description, parameters, default vertex count.
#[pyfunction]
fn shape_names(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let list: Vec<Value> = spectral_mesh::shapes::shape_names()
        .into_iter()
        .map(|s| {
            json!({
                "name": s.name,
                "description": s.description,
                "default_vertices": s.default_vertices,
                "vertex_formula": s.vertex_formula,
                "params": s.params.iter().map(|p| json!({
                    "name": p.name, "default": p.default, "meaning": p.meaning
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    pyjson::to_py(py, &Value::Array(list))
}

/// The operators `(S, B)` of a mesh as CSC arrays, and the total mass `1^T B 1` as
/// assembled.
#[pyfunction]
fn laplacian<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    kind: &str,
    normalize: bool,
) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyTuple>, f64)> {
    let mesh = mesh_from(&v, &f).map_err(|e| e.into_pyerr(py))?;
    let lap = laplacian_of(kind).map_err(|e| e.into_pyerr(py))?;
    let rows = Some(mesh.n_vertices());
    let (s, b, total) = run::run_heavy(py, rows, move |_| {
        let mut ops = Operators::new(&mesh, lap);
        let total = ops.normalize_mass(normalize);
        Ok((csc_parts(&ops.stiffness), csc_parts(&ops.mass), total))
    })?;
    Ok((csc_to_py(py, s)?, csc_to_py(py, b)?, total))
}

/// `(P, normals or None, info)` of a point-cloud file.
type PointsFile<'py> = (
    Bound<'py, PyArray2<f64>>,
    Option<Bound<'py, PyArray2<f64>>>,
    Bound<'py, PyAny>,
);

/// Reads a point-cloud file (`.xyz`, `.pts`, `.txt`, PLY with or without faces):
/// `(P (n, 3), normals (n, 3) or None, info)`.
#[pyfunction]
fn read_points<'py>(py: Python<'py>, path: PathBuf) -> PyResult<PointsFile<'py>> {
    let (p, normals, info) = run(py, move |_| {
        let loaded = spectral_mesh::io::read_points(&path)?;
        let info = json!({
            "format": format!("{:?}", loaded.format).to_ascii_lowercase(),
            "warnings": loaded.warnings,
        });
        let (positions, normals) = loaded.cloud.into_parts();
        let flat = |rows: Vec<[f64; 3]>| rows.into_iter().flatten().collect::<Vec<f64>>();
        Ok((flat(positions), normals.map(flat), info))
    })?;
    let n = p.len() / 3;
    let normals = match normals {
        Some(nr) => Some(to_matrix(py, Layout::Rows, n, 3, nr)?),
        None => None,
    };
    Ok((
        to_matrix(py, Layout::Rows, n, 3, p)?,
        normals,
        pyjson::to_py(py, &info)?,
    ))
}

/// The point-cloud Laplacian `(S, B)` of `P` (`n x n` each, as CSC arrays) and the total
/// mass `1^T B 1` as assembled ([`Operators::from_points`]).
#[pyfunction]
#[pyo3(signature = (points, normalize))]
fn point_laplacian<'py>(
    py: Python<'py>,
    points: PointsArgs<'_>,
    normalize: bool,
) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyTuple>, f64)> {
    let (cloud, params) = points.build().map_err(|e| e.into_pyerr(py))?;
    let (s, b, total) = run(py, move |_| {
        let mut ops =
            Operators::from_points(&cloud, &params).map_err(|e| Failure::value(e.to_string()))?;
        let total = ops.normalize_mass(normalize);
        Ok((csc_parts(&ops.stiffness), csc_parts(&ops.mass), total))
    })?;
    Ok((csc_to_py(py, s)?, csc_to_py(py, b)?, total))
}

/// `(evals, evecs, certificate or None)` of [`eigenbasis`]: float64 or float32 arrays.
type CertifiedPairs<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
);

/// The `k` smallest pairs of a mesh's `(S, B)`: `(evals (k,), evecs (n, k), certificate)`,
/// the vectors moved into NumPy without a copy. `certify`: the library's inertia
/// certificate ([`certify_eigenbasis`]) is run on the pairs, the completed basis returned
/// when pairs were missing, and its report is the third item (else `None`); a count that
/// still disagrees is a `SolverError`. `dtype`: `"float64"` or `"float32"` (computed in
/// double precision, rounded once); `None`: the library's default.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (v, f, k, kind, normalize, solver, progress=None, certify=false, dtype=None))]
fn eigenbasis<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    k: usize,
    kind: &str,
    normalize: bool,
    solver: SolverArgs,
    progress: Option<Py<PyAny>>,
    certify: bool,
    dtype: Option<&str>,
) -> PyResult<CertifiedPairs<'py>> {
    let progress = run::Progress::new(progress);
    let mesh = mesh_from(&v, &f).map_err(|e| e.into_pyerr(py))?;
    let dtype = match dtype {
        None => BasisDtype::default(),
        Some(d) => BasisDtype::parse(d)
            .map_err(|e| Failure::value(format!("dtype = '{d}': {e}")).into_pyerr(py))?,
    };
    let options = AnalysisOptions {
        laplacian: laplacian_of(kind).map_err(|e| e.into_pyerr(py))?,
        normalize,
        eigen: solver.params().map_err(|e| e.into_pyerr(py))?,
    };
    let rows = Some(mesh.n_vertices());
    let (n, values, vectors, report) = run::run_heavy(py, rows, move |token| {
        let an = Analysis::new(mesh, options);
        let basis = an.basis(k, &mut |p| progress.report(&p, token), token);
        let basis = progress.finish(basis.map_err(Failure::from))?;
        let mut report = None;
        let basis = if certify {
            let params = EigenParams {
                k,
                ..an.options().eigen.clone()
            };
            let (n, values, vectors) = take_pairs(basis, k);
            let given = Eigenbasis {
                laplacian: an.operators().laplacian,
                n,
                values,
                vectors,
                mass: an.operators().mass.clone(),
                residuals: Vec::new(),
            };
            let (completed, r) = certify_eigenbasis(an.operators(), &params, &given, token)
                .map_err(Failure::from)?;
            if !r.certified() {
                return Err(Failure::Solver(format!(
                    "certify: the eigenvalue count disagrees: {}",
                    r.lines().join("; ")
                )));
            }
            report = Some(certificate_json(&r));
            Arc::new(completed.unwrap_or(given))
        } else {
            basis
        };
        drop(an);
        let (n, values, vectors) = take_pairs(basis, k);
        Ok((n, values, vectors, report))
    })?;
    let (evals, evecs) = match dtype {
        BasisDtype::Float64 => (
            to_vector(py, values).into_any(),
            to_matrix(py, Layout::Columns, n, k, vectors)?.into_any(),
        ),
        BasisDtype::Float32 => (
            to_vector(py, values.iter().map(|&x| x as f32).collect()).into_any(),
            to_matrix(
                py,
                Layout::Columns,
                n,
                k,
                vectors.iter().map(|&x| x as f32).collect(),
            )?
            .into_any(),
        ),
    };
    let report = match report {
        Some(r) => Some(pyjson::to_py(py, &r)?),
        None => None,
    };
    Ok((evals, evecs, report))
}

/// The certificate's report as the dictionary the Python call returns.
fn certificate_json(r: &CertifyReport) -> Value {
    let cert = |c: &spectral_mesh::linalg::Certificate| json!({"shift": c.shift, "below": c.below, "found": c.found});
    json!({
        "certified": r.certified(),
        "k": r.k,
        "first": cert(&r.first),
        "last": cert(&r.last),
        "added": r.added,
        "searches": r.searches,
        "values_changed": r.values_changed,
        "lines": r.lines(),
    })
}

/// The first `k` pairs of a basis, moved out when nobody else holds it.
pub(crate) fn take_pairs(basis: Arc<Eigenbasis>, k: usize) -> (usize, Vec<f64>, Vec<f64>) {
    let n = basis.n;
    match Arc::try_unwrap(basis) {
        Ok(mut b) => {
            b.values.truncate(k);
            b.vectors.truncate(n * k);
            (n, b.values, b.vectors)
        }
        Err(b) => (n, b.values[..k].to_vec(), b.vectors[..n * k].to_vec()),
    }
}

/// The `k` smallest pairs of `A x = lambda M x` for any sparse symmetric positive
/// semi-definite `A` and symmetric positive definite `M` (identity when absent), both
/// given as CSC arrays of an `n x n` matrix.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (n, a, m, k, tol, seed, method, progress=None))]
fn eigsh<'py>(
    py: Python<'py>,
    n: usize,
    a: (
        PyReadonlyArray1<'_, f64>,
        PyReadonlyArray1<'_, i64>,
        PyReadonlyArray1<'_, i64>,
    ),
    m: Option<(
        PyReadonlyArray1<'_, f64>,
        PyReadonlyArray1<'_, i64>,
        PyReadonlyArray1<'_, i64>,
    )>,
    k: usize,
    tol: f64,
    seed: u64,
    method: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<Pairs<'py>> {
    let progress = run::Progress::new(progress);
    let build = || -> Result<(SparseMatrix, SparseMatrix, EigenParams), Failure> {
        let s = csc_from("A", n, &a.0, &a.1, &a.2)?;
        let b = match &m {
            Some((d, i, p)) => csc_from("M", n, d, i, p)?,
            None => SparseMatrix::identity(n),
        };
        Ok((s, b, eigen_params(tol, seed, None, method)?))
    };
    let (s, b, params) = build().map_err(|e| e.into_pyerr(py))?;
    if k == 0 || k > n {
        return Err(
            Failure::value(format!("k = {k}: must be between 1 and n = {n}")).into_pyerr(py),
        );
    }
    let (n, values, vectors) = run::run_heavy(py, Some(n), move |token| {
        let ops = Operators {
            laplacian: Laplacian::Cot,
            stiffness: s,
            mass: b,
        };
        let mut solver = EigenSolver::new(Arc::new(ops), params);
        let basis = solver.solve(k, &mut |p| progress.report(&p, token), token);
        let basis = progress.finish(basis.map_err(Failure::from))?;
        drop(solver);
        Ok(take_pairs(basis, k))
    })?;
    Ok((
        to_vector(py, values),
        to_matrix(py, Layout::Columns, n, k, vectors)?,
    ))
}

/// Writes an eigenbasis archive (`.npz`) from arrays: eigenvalues `(k,)`, the
/// eigenvectors' `(k, n)` transpose, the mass as CSC arrays; the mesh (for its hash) is
/// optional.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (path, evals, evecs_t, mass, kind, v=None, f=None))]
fn save_basis(
    py: Python<'_>,
    path: PathBuf,
    evals: PyReadonlyArray1<'_, f64>,
    evecs_t: PyReadonlyArray2<'_, f64>,
    mass: (
        PyReadonlyArray1<'_, f64>,
        PyReadonlyArray1<'_, i64>,
        PyReadonlyArray1<'_, i64>,
    ),
    kind: &str,
    v: Option<PyReadonlyArray2<'_, f64>>,
    f: Option<PyReadonlyArray2<'_, i64>>,
) -> PyResult<()> {
    let prepare = || -> Result<(Eigenbasis, Option<Mesh>), Failure> {
        let (n, values, vectors) = arrays::pairs(&evals, &evecs_t)?;
        let mass = csc_from("B", n, &mass.0, &mass.1, &mass.2)?;
        let mesh = match (&v, &f) {
            (Some(v), Some(f)) => {
                let m = mesh_from(v, f)?;
                if m.n_vertices() != n {
                    return Err(Failure::value(format!(
                        "V has {} vertices but evecs has {n} rows",
                        m.n_vertices()
                    )));
                }
                Some(m)
            }
            _ => None,
        };
        let basis = Eigenbasis {
            laplacian: laplacian_of(kind)?,
            n,
            values,
            vectors,
            mass,
            residuals: Vec::new(),
        };
        Ok((basis, mesh))
    };
    let (basis, mesh) = prepare().map_err(|e| e.into_pyerr(py))?;
    run(py, move |_| {
        let params = EigenParams {
            k: basis.k(),
            ..EigenParams::default()
        };
        let meta = BasisMeta::new(&basis, mesh.as_ref(), &params);
        save_npz(&basis, &path, &meta)?;
        Ok(())
    })
}

/// Reads an eigenbasis archive: `(evals, evecs (n, k), mass CSC arrays, meta)`.
#[pyfunction]
fn load_basis<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Archive<'py>> {
    let (basis, meta) = run(py, move |_| {
        let (basis, meta) = load_npz(&path)?;
        let meta = serde_json::to_value(&meta).map_err(|e| Failure::Internal(e.to_string()))?;
        Ok((basis, meta))
    })?;
    let mass = csc_to_py(py, csc_parts(&basis.mass))?;
    let (n, k) = (basis.n, basis.k());
    Ok((
        to_vector(py, basis.values),
        to_matrix(py, Layout::Columns, n, k, basis.vectors)?,
        mass,
        pyjson::to_py(py, &meta)?,
    ))
}

/// The picture options as the Python layer passes them to both `render`s: a dict of
/// these keys, checked and converted there (`_render_args`).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct FigureArgs {
    levels: usize,
    colormap: String,
    view: String,
    size: u32,
    transparent: bool,
    critical_points: bool,
    colorbar: bool,
    legend: bool,
    height: Option<u32>,
    scale: Option<f64>,
    dpi: Option<u32>,
}

impl FigureArgs {
    /// The render crate's options; an unknown colour map or view, or a scale that is not
    /// positive, is a `ValueError`.
    pub(crate) fn options(&self) -> Result<FigureOptions, Failure> {
        if let Some(s) = self.scale
            && !(s.is_finite() && s > 0.0)
        {
            return Err(Failure::value(format!("scale must be positive, got {s}")));
        }
        Ok(FigureOptions {
            levels: self.levels,
            colormap: self
                .colormap
                .parse::<Colormap>()
                .map_err(|e| Failure::value(e.to_string()))?,
            view: self
                .view
                .parse::<View>()
                .map_err(|e| Failure::value(format!("view: {e}")))?,
            canvas: Canvas {
                size: self.size,
                height: self.height,
                scale: self.scale,
                dpi: self.dpi,
            },
            legend: self.legend,
            transparent: self.transparent,
            critical_points: self.critical_points,
            colorbar: self.colorbar,
        })
    }
}

/// What both native `render`s draw after the mesh, as `_render_args` passes it: one tuple
/// `(values, marks, labels, figure, path)`.
#[derive(FromPyObject)]
pub(crate) struct Picture<'py>(
    PyReadonlyArray1<'py, f64>,
    Vec<usize>,
    Option<Vec<usize>>,
    FigureArgs,
    Option<PathBuf>,
);

/// Draws a picture's values on `mesh`: writes its path (format from its extension) and
/// returns `None`, or returns the `(size, size, 4)` RGBA picture. `point_radius`: draw the
/// vertices as discs of this radius (a point cloud; its triangle union carries the level
/// sets).
pub(crate) fn draw(
    py: Python<'_>,
    mesh: Arc<Mesh>,
    point_radius: Option<f64>,
    picture: Picture<'_>,
) -> PyResult<Py<PyAny>> {
    let Picture(values, marks, labels, figure, path) = picture;
    let prepare =
        || -> Result<_, Failure> { Ok((arrays::values(&values, "values")?, figure.options()?)) };
    let (values, options) = prepare().map_err(|e| e.into_pyerr(py))?;
    let out = run(py, move |_| {
        let n = mesh.n_vertices();
        if let Some(&m) = marks.iter().find(|&&m| m >= n) {
            return Err(Failure::value(format!(
                "marked vertex {m} is out of range: the mesh has {n} vertices"
            )));
        }
        let options = match labels {
            Some(_) => FigureOptions {
                levels: 0,
                critical_points: false,
                ..options
            },
            None => options,
        };
        let mut fig = Figure::new(&mesh, &values, marks, options)?;
        fig.point_radius = point_radius;
        if let Some(l) = &labels {
            if l.len() != n {
                return Err(Failure::value(format!(
                    "labels has {} entries but the mesh has {n} vertices",
                    l.len()
                )));
            }
            fig.colors = Some(spectral_mesh_render::colormap::label_colors(l));
        }
        match path {
            Some(p) => {
                fig.write(&p)?;
                Ok(None)
            }
            None => Ok(Some(fig.image()?)),
        }
    })?;
    match out {
        None => Ok(py.None()),
        Some(img) => {
            let (w, h) = (img.width as usize, img.height as usize);
            let a = numpy::ndarray::Array3::from_shape_vec((h, w, 4), img.rgba)
                .map_err(|e| Failure::Internal(e.to_string()).into_pyerr(py))?;
            Ok(numpy::PyArray3::from_owned_array(py, a).into_any().unbind())
        }
    }
}

/// Draws a field on `(V, F)` (see [`draw`]).
#[pyfunction]
fn render(
    py: Python<'_>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    picture: Picture<'_>,
) -> PyResult<Py<PyAny>> {
    let mesh = mesh_from(&v, &f).map_err(|e| e.into_pyerr(py))?;
    draw(py, Arc::new(mesh), None, picture)
}

/// Every default as a dict: the library's ([`spectral_mesh::defaults::to_json`]: every
/// request kind's keys, the analysis, eigensolver, point-cloud, batch and picture
/// defaults, the server limits) with the render crate's figure options
/// ([`spectral_mesh_render::defaults::to_json`]).
#[pyfunction]
fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    pyjson::to_py(py, &spectral_mesh_render::defaults::to_json())
}

/// Threads the computations use (the library's rayon pool).
#[pyfunction]
fn num_threads() -> usize {
    rayon::current_num_threads()
}

/// Test hook: panics on the worker thread (it must become `InternalError`).
#[pyfunction]
fn _panic_for_tests(py: Python<'_>, message: String) -> PyResult<()> {
    run(py, move |_| -> Result<(), Failure> { panic!("{message}") })
}

/// Test hook: a computation of `seconds` that checks its cancel token every 10 ms when
/// `checks` is true (and never otherwise). Returns the seconds it ran.
#[pyfunction]
fn _work_for_tests(py: Python<'_>, seconds: f64, checks: bool) -> PyResult<f64> {
    run(py, move |token| {
        let t0 = std::time::Instant::now();
        while t0.elapsed().as_secs_f64() < seconds {
            if checks && token.is_cancelled() {
                return Err(Failure::Cancelled);
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        Ok(t0.elapsed().as_secs_f64())
    })
}

/// Replaces the per-vertex payload of a request (a diffusion's signal values, a
/// segmentation's given field) by `values`.
pub(crate) fn with_values(req: &mut FieldRequest, values: Vec<f64>) -> Result<(), Failure> {
    match req {
        FieldRequest::Diffusion { signal, .. } => *signal = Signal::Values(values),
        FieldRequest::Segmentation { signature, .. } => *signature = SignatureSpec::Values(values),
        other => {
            return Err(Failure::value(format!(
                "a {} request takes no per-vertex values",
                other.kind()
            )));
        }
    }
    Ok(())
}

/// The native module `spectral_mesh._native`: the functions and classes the Python package
/// wraps.
#[pymodule]
mod _native {
    #[pymodule_export]
    use super::{
        _panic_for_tests, _work_for_tests, defaults, eigenbasis, eigsh, laplacian, load_basis,
        num_threads, point_laplacian, read_mesh, read_points, render, save_basis, shape,
        shape_names, write_mesh,
    };
    #[pymodule_export]
    use crate::analysis::PyAnalysis;
    #[pymodule_export]
    use crate::batch::{
        batch_failed, batch_inputs, batch_one, batch_params, batch_prepare, batch_summary,
    };
    #[pymodule_export]
    use crate::correspondence::{
        correspondence_defaults, functional_map, match_pair, pair_failed, pairs_plan,
        pairs_summary, point_map, zoomout_refine,
    };
    #[pymodule_export]
    use crate::geodesic::PyGeodesicSolver;
    #[pymodule_export]
    use crate::learning::{learning_defaults, learning_operators};
    use pyo3::prelude::*;

    /// The module's `__version__`: the crate's.
    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        m.add("__version__", env!("CARGO_PKG_VERSION"))
    }
}
