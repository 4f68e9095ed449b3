//! `spectral_mesh._native`: the native module behind the Python package `spectral_mesh`.
//!
//! It binds the library's analysis type ([`spectral_mesh::Analysis`]) and request type
//! ([`spectral_mesh::FieldRequest`], built from the JSON the Python layer writes from
//! keyword arguments), the operators, the generic sparse eigensolver, the basis archive
//! and the figure code. The Python layer (`python/spectral_mesh/`) normalizes user input,
//! documents every function and is the public API; this module is private.
//!
//! Every computation goes through [`run::run`]: a worker thread, the GIL released, Ctrl-C
//! honoured within a second, panics turned into exceptions.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde_json::{Value, json};
use spectral_mesh::analysis::request::KINDS;
use spectral_mesh::analysis::{AnalysisOptions, Signal, SignatureSpec};
use spectral_mesh::operators::{Laplacian, Operators, PointCloudParams};
use spectral_mesh::spectral::eigenbasis::{EigenMethod, EigenParams, EigenSolver};
use spectral_mesh::spectral::store::{BasisMeta, load_npz, save_npz};
use spectral_mesh::{Analysis, Eigenbasis, FieldRequest, Mesh, SparseMatrix};
use spectral_mesh_render::{Colormap, Figure, FigureOptions, View};

mod analysis;
mod arrays;
mod batch;
mod errors;
mod geodesic;
mod pyjson;
mod run;

use arrays::{
    Archive, MeshArrays, Pairs, csc_from, csc_parts, csc_to_py, mesh_arrays, mesh_from, to_columns,
    to_rows, to_vector,
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
    Ok((to_rows(py, n, 3, v)?, to_rows(py, m, 3, f)?))
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
    let (s, b, total) = run(py, move |_| {
        let mut ops = Operators::new(&mesh, lap);
        let total: f64 = ops.mass.values().iter().sum();
        if normalize && total > 0.0 && total.is_finite() {
            ops.mass = ops.mass.add_scaled(1.0 / total, &ops.mass, 0.0);
        }
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
        Some(nr) => Some(to_rows(py, n, 3, nr)?),
        None => None,
    };
    Ok((to_rows(py, n, 3, p)?, normals, pyjson::to_py(py, &info)?))
}

/// The point-cloud Laplacian `(S, B)` of `P` (`n x n` each, as CSC arrays) and the total
/// mass `1^T B 1` as assembled ([`Operators::from_points`]).
#[pyfunction]
#[pyo3(signature = (p, normals, neighbors, mollify_factor, normalize))]
fn point_laplacian<'py>(
    py: Python<'py>,
    p: PyReadonlyArray2<'_, f64>,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    neighbors: usize,
    mollify_factor: f64,
    normalize: bool,
) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyTuple>, f64)> {
    let cloud = arrays::cloud_from(&p, normals.as_ref()).map_err(|e| e.into_pyerr(py))?;
    // Given normals give the tangent planes (where non-zero), as documented; without them
    // the planes are estimated.
    let params = analysis::cloud_params(Some(neighbors), Some(mollify_factor), normals.is_some());
    let (s, b, total) = run(py, move |_| {
        let mut ops =
            Operators::from_points(&cloud, &params).map_err(|e| Failure::value(e.to_string()))?;
        let total: f64 = ops.mass.values().iter().sum();
        if normalize && total > 0.0 && total.is_finite() {
            ops.mass = ops.mass.add_scaled(1.0 / total, &ops.mass, 0.0);
        }
        Ok((csc_parts(&ops.stiffness), csc_parts(&ops.mass), total))
    })?;
    Ok((csc_to_py(py, s)?, csc_to_py(py, b)?, total))
}

/// The `k` smallest pairs of a mesh's `(S, B)`: `(evals (k,), evecs (n, k))`, the vectors
/// moved into NumPy without a copy.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (v, f, k, kind, normalize, tol, seed, dirichlet, method, progress=None))]
fn eigenbasis<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    k: usize,
    kind: &str,
    normalize: bool,
    tol: f64,
    seed: u64,
    dirichlet: Option<Vec<usize>>,
    method: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<Pairs<'py>> {
    let progress = run::Progress::new(progress);
    let mesh = mesh_from(&v, &f).map_err(|e| e.into_pyerr(py))?;
    let options = AnalysisOptions {
        laplacian: laplacian_of(kind).map_err(|e| e.into_pyerr(py))?,
        normalize,
        eigen: eigen_params(tol, seed, dirichlet, method).map_err(|e| e.into_pyerr(py))?,
    };
    let (n, values, vectors) = run(py, move |token| {
        let an = Analysis::new(mesh, options);
        let basis = an.basis(k, &mut |p| progress.report(&p, token), token);
        let basis = progress.finish(basis.map_err(Failure::from))?;
        drop(an);
        Ok(take_pairs(basis, k))
    })?;
    Ok((to_vector(py, values), to_columns(py, n, k, vectors)?))
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
    let (n, values, vectors) = run(py, move |token| {
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
    Ok((to_vector(py, values), to_columns(py, n, k, vectors)?))
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
        let values = arrays::values(&evals, "evals")?;
        let (n, k, vectors) = arrays::columns(&evecs_t, "evecs")?;
        if k != values.len() {
            return Err(Failure::value(format!(
                "evecs has {k} columns but evals has {} values",
                values.len()
            )));
        }
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
        to_columns(py, n, k, basis.vectors)?,
        mass,
        pyjson::to_py(py, &meta)?,
    ))
}

/// The figure keywords added after the first ones (keyword-only in the native calls).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FigureExtra {
    /// Draw the legend.
    pub legend: bool,
    /// Picture height.
    pub height: Option<u32>,
    /// Picture pixels per screen pixel.
    pub scale: Option<f64>,
    /// Print resolution.
    pub dpi: Option<u32>,
}

/// Figure options from the Python keywords.
pub(crate) fn figure_options(
    levels: usize,
    colormap: &str,
    view: &str,
    size: u32,
    transparent: bool,
    critical_points: bool,
    colorbar: bool,
    extra: FigureExtra,
) -> Result<FigureOptions, Failure> {
    if let Some(s) = extra.scale
        && !(s.is_finite() && s > 0.0)
    {
        return Err(Failure::value(format!("scale must be positive, got {s}")));
    }
    Ok(FigureOptions {
        height: extra.height,
        scale: extra.scale,
        dpi: extra.dpi,
        legend: extra.legend,
        levels,
        colormap: colormap
            .parse::<Colormap>()
            .map_err(|e| Failure::value(e.to_string()))?,
        view: view
            .parse::<View>()
            .map_err(|e| Failure::value(format!("view: {e}")))?,
        size,
        transparent,
        critical_points,
        colorbar,
    })
}

/// Draws `values` on `mesh`: writes `path` (format from its extension) and returns
/// `None`, or returns the `(size, size, 4)` RGBA picture. `point_radius`: draw the vertices
/// as discs of this radius (a point cloud; its triangle union carries the level sets).
#[allow(clippy::too_many_arguments)]
pub(crate) fn draw(
    py: Python<'_>,
    mesh: Arc<Mesh>,
    values: Vec<f64>,
    marks: Vec<usize>,
    labels: Option<Vec<usize>>,
    options: FigureOptions,
    point_radius: Option<f64>,
    path: Option<PathBuf>,
) -> PyResult<Py<PyAny>> {
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
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (v, f, values, marks, labels, levels, colormap, view, size, transparent, critical_points, colorbar, path, *, legend=true, height=None, scale=None, dpi=None))]
fn render(
    py: Python<'_>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    values: PyReadonlyArray1<'_, f64>,
    marks: Vec<usize>,
    labels: Option<Vec<usize>>,
    levels: usize,
    colormap: &str,
    view: &str,
    size: u32,
    transparent: bool,
    critical_points: bool,
    colorbar: bool,
    path: Option<PathBuf>,
    legend: bool,
    height: Option<u32>,
    scale: Option<f64>,
    dpi: Option<u32>,
) -> PyResult<Py<PyAny>> {
    let extra = FigureExtra {
        legend,
        height,
        scale,
        dpi,
    };
    let prepare = || -> Result<(Mesh, Vec<f64>, FigureOptions), Failure> {
        Ok((
            mesh_from(&v, &f)?,
            arrays::values(&values, "values")?,
            figure_options(
                levels,
                colormap,
                view,
                size,
                transparent,
                critical_points,
                colorbar,
                extra,
            )?,
        ))
    };
    let (mesh, values, options) = prepare().map_err(|e| e.into_pyerr(py))?;
    draw(
        py,
        Arc::new(mesh),
        values,
        marks,
        labels,
        options,
        None,
        path,
    )
}

/// The library's defaults as a dict: every request kind's keys (from [`FieldRequest`]'s
/// serde form), the analysis and eigensolver options and the figure options.
#[pyfunction]
fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let mut kinds = serde_json::Map::new();
    for kind in KINDS {
        let mut j = json!({ "kind": kind });
        match kind {
            "diffusion" => j["signal"] = json!({ "impulse": 0 }),
            "wks" => j["energy"] = json!(0.0),
            _ => {}
        }
        let internal = |e: serde_json::Error| {
            Failure::Internal(format!("defaults of {kind}: {e}")).into_pyerr(py)
        };
        let req: FieldRequest = serde_json::from_value(j).map_err(internal)?;
        let mut v = serde_json::to_value(&req).map_err(internal)?;
        if let Some(o) = v.as_object_mut() {
            o.remove("kind");
            o.remove("signal");
            o.remove("energy");
        }
        kinds.insert(kind.to_string(), v);
    }
    let a = AnalysisOptions::default();
    let fig = FigureOptions::default();
    let pc = PointCloudParams::default();
    let bp = spectral_mesh::batch::BatchParams::default();
    let all = json!({
        "requests": kinds,
        "analysis": {
            "kind": a.laplacian.name(),
            "normalize": a.normalize,
            "k": spectral_mesh::analysis::request::DEFAULT_K,
            "tol": a.eigen.tolerance,
            "seed": a.eigen.seed,
            "method": "auto",
        },
        "figure": {
            "levels": fig.levels,
            "colormap": fig.colormap.name(),
            "view": spectral_mesh_render::figure::view_name(fig.view),
            "size": fig.size,
            "transparent": fig.transparent,
            "critical_points": fig.critical_points,
            "colorbar": fig.colorbar,
            "legend": fig.legend,
        },
        "point_cloud": {
            "n_neighbors": pc.neighbors,
            "mollify_factor": pc.mollify_factor,
            "delaunay_tolerance": pc.delaunay_tolerance,
            "normals": pc.normals,
            "union": pc.union,
        },
        // `spectral_mesh.batch`'s keywords (Python names) from the library's batch
        // parameters.
        "batch": {
            "k": bp.k,
            "laplacian": bp.laplacian.name(),
            "tol": bp.tolerance,
            "normalize": bp.normalize,
            "eigenvectors": bp.basis,
            "hks": bp.hks.as_ref().map(ToString::to_string),
            "wks": bp.wks.as_ref().map(ToString::to_string),
            "wks_sigma": bp.wks_sigma,
            "adf": bp.adf.as_ref().map(ToString::to_string),
            "scaled": bp.scaled,
            "thumbnail": bp.thumbnail,
        },
        "zero_eigenvalue_eps": spectral_mesh::spectral::filters::ZERO_EIGENVALUE_EPS,
        "shape": spectral_mesh::shapes::DEFAULT_SHAPE,
        "laplacians": Laplacian::ALL.iter().map(|l| l.name()).collect::<Vec<_>>(),
        "colormaps": Colormap::ALL.iter().map(|c| c.name()).collect::<Vec<_>>(),
    });
    pyjson::to_py(py, &all)
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

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(shape, m)?)?;
    m.add_function(wrap_pyfunction!(shape_names, m)?)?;
    m.add_function(wrap_pyfunction!(laplacian, m)?)?;
    m.add_function(wrap_pyfunction!(read_points, m)?)?;
    m.add_function(wrap_pyfunction!(point_laplacian, m)?)?;
    m.add_function(wrap_pyfunction!(eigenbasis, m)?)?;
    m.add_function(wrap_pyfunction!(eigsh, m)?)?;
    m.add_function(wrap_pyfunction!(save_basis, m)?)?;
    m.add_function(wrap_pyfunction!(load_basis, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(defaults, m)?)?;
    m.add_function(wrap_pyfunction!(num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_params, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_inputs, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_prepare, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_one, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_failed, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_summary, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    m.add_function(wrap_pyfunction!(_work_for_tests, m)?)?;
    m.add_class::<analysis::PyAnalysis>()?;
    m.add_class::<geodesic::PyGeodesicSolver>()?;
    Ok(())
}
