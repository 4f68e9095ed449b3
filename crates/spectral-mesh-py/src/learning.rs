//! The learning operators (DiffusionNet's `get_operators`) for `spectral_mesh.learning`:
//! the library's [`spectral_mesh::learning`] with its disk cache, NumPy arrays out.

use std::path::PathBuf;

use numpy::ndarray::{Array2, Array3, ShapeBuilder};
use numpy::{PyArray1, PyArray2, PyArray3, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde_json::json;
use spectral_mesh::learning::{
    self, LearningError, LearningOperators, LearningParams, LearningShape,
};
use spectral_mesh::spectral::store::BasisDtype;
use spectral_mesh::{Mesh, PointCloud, SparseMatrix};

use crate::arrays::{cloud_from, mesh_from};
use crate::errors::Failure;
use crate::{laplacian_of, pyjson, run, tolerance_of};

impl From<LearningError> for Failure {
    fn from(e: LearningError) -> Self {
        match e {
            LearningError::Eigen(e) => e.into(),
            LearningError::Store(e) => e.into(),
            other => Failure::Value(other.to_string()),
        }
    }
}

/// The shape of a call: a mesh, or a point cloud when no faces are given.
enum Input {
    Mesh(Mesh),
    Cloud(PointCloud),
}

/// A float array in the requested type: every value rounded once from its double.
fn vector<'py>(py: Python<'py>, v: Vec<f64>, dtype: BasisDtype) -> Bound<'py, PyAny> {
    match dtype {
        BasisDtype::Float64 => PyArray1::from_vec(py, v).into_any(),
        BasisDtype::Float32 => {
            PyArray1::from_vec(py, v.into_iter().map(|x| x as f32).collect()).into_any()
        }
    }
}

/// `(data, indices, indptr)` of a CSC matrix, `data` in the requested type.
fn csc<'py>(py: Python<'py>, m: SparseMatrix, dtype: BasisDtype) -> PyResult<Bound<'py, PyTuple>> {
    let idx = |v: &[usize]| v.iter().map(|&x| x as i64).collect::<Vec<i64>>();
    let (indices, indptr) = (idx(m.row_idx()), idx(m.col_ptr()));
    let data = m.values().to_vec();
    PyTuple::new(
        py,
        [
            vector(py, data, dtype),
            PyArray1::from_vec(py, indices).into_any(),
            PyArray1::from_vec(py, indptr).into_any(),
        ],
    )
}

fn shaped<'py, T: numpy::Element>(
    py: Python<'py>,
    n: usize,
    k: usize,
    frames: Option<Vec<T>>,
    evecs: Vec<T>,
) -> PyResult<(Option<Bound<'py, PyAny>>, Bound<'py, PyAny>)> {
    let bad = |e: numpy::ndarray::ShapeError| {
        Failure::Internal(format!("array shape: {e}")).into_pyerr(py)
    };
    let f = match frames {
        Some(f) => Some(
            PyArray3::from_owned_array(py, Array3::from_shape_vec((n, 3, 3), f).map_err(bad)?)
                .into_any(),
        ),
        None => None,
    };
    let e = PyArray2::from_owned_array(py, Array2::from_shape_vec((n, k).f(), evecs).map_err(bad)?)
        .into_any();
    Ok((f, e))
}

/// The operators as Python objects: `(frames (n, 3, 3), mass (n,), L (data, indices,
/// indptr), evals (k,), evecs (n, k) Fortran order, gradX (...), gradY (...))` in `dtype`.
fn to_py<'py>(
    py: Python<'py>,
    ops: LearningOperators,
    dtype: BasisDtype,
) -> PyResult<Bound<'py, PyTuple>> {
    let (n, k) = (ops.n(), ops.k());
    let frames: Vec<f64> = ops.frames.iter().flatten().flatten().copied().collect();
    let (frames, evecs) = match dtype {
        BasisDtype::Float64 => shaped(py, n, k, Some(frames), ops.evecs)?,
        BasisDtype::Float32 => {
            let to32 = |v: Vec<f64>| v.into_iter().map(|x| x as f32).collect::<Vec<f32>>();
            shaped(py, n, k, Some(to32(frames)), to32(ops.evecs))?
        }
    };
    let items: Vec<Bound<'py, PyAny>> = vec![
        frames.unwrap_or_else(|| py.None().into_bound(py)),
        vector(py, ops.mass, dtype),
        csc(py, ops.laplacian, dtype)?.into_any(),
        vector(py, ops.evals, dtype),
        evecs,
        csc(py, ops.grad_x, dtype)?.into_any(),
        csc(py, ops.grad_y, dtype)?.into_any(),
    ];
    PyTuple::new(py, items)
}

/// The learning operators of a mesh (`f` given) or a point cloud (`f` None):
/// `(operators, from_cache, cache_file or None)`, `operators` as [`to_py`] returns them.
/// With `cache_dir`, read from or stored in that folder (the library's cache).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (v, f, k_eig, cache_dir, dtype, normals, laplacian, grad_regularization, n_neighbors, tol))]
pub fn learning_operators<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'_, f64>,
    f: Option<PyReadonlyArray2<'_, i64>>,
    k_eig: usize,
    cache_dir: Option<PathBuf>,
    dtype: &str,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    laplacian: &str,
    grad_regularization: f64,
    n_neighbors: usize,
    tol: f64,
) -> PyResult<(Bound<'py, PyTuple>, bool, Option<String>)> {
    let fail = |e: Failure| e.into_pyerr(py);
    let dtype = BasisDtype::parse(dtype).map_err(|e| fail(Failure::Value(e)))?;
    let input = match &f {
        Some(f) => Input::Mesh(mesh_from(&v, f).map_err(fail)?),
        None => Input::Cloud(cloud_from(&v, None).map_err(fail)?),
    };
    // The normals' shape, count and finiteness are checked as a point cloud's normals are.
    let normals: Option<Vec<[f64; 3]>> = match &normals {
        Some(nr) => cloud_from(&v, Some(nr))
            .map_err(fail)?
            .normals()
            .map(<[[f64; 3]]>::to_vec),
        None => None,
    };
    let params = LearningParams {
        k_eig,
        laplacian: laplacian_of(laplacian).map_err(fail)?,
        grad_regularization,
        neighbors: n_neighbors,
        tolerance: tolerance_of(tol).map_err(fail)?,
    };
    let rows = Some(match &input {
        Input::Mesh(m) => m.n_vertices(),
        Input::Cloud(c) => c.positions().len(),
    });
    let (ops, hit, path) = run::run_heavy(py, rows, move |token| {
        let shape = match &input {
            Input::Mesh(m) => LearningShape::Mesh(m),
            Input::Cloud(c) => LearningShape::Cloud(c),
        };
        let nr = normals.as_deref();
        let mut quiet = |_| {};
        match cache_dir {
            Some(dir) => {
                let (ops, hit, path) =
                    learning::load_or_compute(&dir, shape, nr, &params, &mut quiet, token)?;
                Ok((ops, hit, Some(path.display().to_string())))
            }
            None => Ok((
                learning::compute_operators(shape, nr, &params, &mut quiet, token)?,
                false,
                None,
            )),
        }
    })?;
    Ok((to_py(py, ops, dtype)?, hit, path))
}

/// The library's defaults of the learning operators, for the Python signatures.
#[pyfunction]
pub fn learning_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let p = LearningParams::default();
    pyjson::to_py(
        py,
        &json!({
            "k_eig": p.k_eig,
            "laplacian": p.laplacian.name(),
            "grad_regularization": p.grad_regularization,
            "n_neighbors": p.neighbors,
            "tol": p.tolerance,
            "mass_eps": learning::MASS_EPS,
            "cache_format_version": learning::CACHE_FORMAT_VERSION,
        }),
    )
}
