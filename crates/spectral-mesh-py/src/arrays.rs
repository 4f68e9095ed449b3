//! NumPy arrays in and out.
//!
//! The pure-Python layer normalizes what users pass (any float or integer dtype, C or
//! Fortran order, array-likes) to the few layouts accepted here: `V` as C-contiguous
//! `(n, 3)` float64, `F` as C-contiguous `(m, 3)` int64, per-vertex values as `(n,)`
//! float64, and `n x k` matrices as their C-contiguous `(k, n)` transpose (the library's
//! column-major layout, a free view of a Fortran-ordered `(n, k)` array). Everything is
//! still checked here, so the native module can be called directly without crashing.

use numpy::ndarray::{Array2, Ix2, ShapeBuilder, StrideShape};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use spectral_mesh::mesh::PointCloudError;
use spectral_mesh::{Mesh, PointCloud, SparseMatrix};

use crate::errors::Failure;

/// The slice of a C-contiguous array, or a `ValueError` naming it.
fn slice<'a, T: numpy::Element>(
    a: &'a numpy::PyReadonlyArray<'_, T, impl numpy::ndarray::Dimension>,
    name: &str,
) -> Result<&'a [T], Failure> {
    if !a.is_c_contiguous() {
        return Err(Failure::value(format!("{name} must be C-contiguous")));
    }
    a.as_slice()
        .map_err(|e| Failure::value(format!("{name}: {e}")))
}

/// Copies `V` (`(n, 3)` float64) and `F` (`(m, 3)` int64) into a [`Mesh`], checking shapes,
/// index ranges, finiteness and repeated vertices (errors name the row).
pub fn mesh_from(
    v: &PyReadonlyArray2<'_, f64>,
    f: &PyReadonlyArray2<'_, i64>,
) -> Result<Mesh, Failure> {
    let (vs, fs) = (v.shape(), f.shape());
    if vs[1] != 3 {
        return Err(Failure::value(format!(
            "V must have shape (n, 3), got ({}, {})",
            vs[0], vs[1]
        )));
    }
    if fs[1] != 3 {
        return Err(Failure::value(format!(
            "F must have shape (m, 3) (triangles), got ({}, {})",
            fs[0], fs[1]
        )));
    }
    let n = vs[0];
    let positions: Vec<[f64; 3]> = slice(v, "V")?
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let mut triangles = Vec::with_capacity(fs[0]);
    for (t, c) in slice(f, "F")?.chunks_exact(3).enumerate() {
        let mut tri = [0usize; 3];
        for (slot, &i) in tri.iter_mut().zip(c) {
            *slot = usize::try_from(i).ok().filter(|&i| i < n).ok_or_else(|| {
                Failure::value(format!(
                    "F[{t}] refers to vertex {i}, but V has {n} vertices (valid: 0 to {})",
                    n.saturating_sub(1)
                ))
            })?;
        }
        triangles.push(tri);
    }
    Mesh::new(positions, triangles).map_err(|e| match e {
        spectral_mesh::mesh::MeshError::NonFinite { vertex } => Failure::value(format!(
            "V[{vertex}] has a non-finite coordinate (NaN or inf)"
        )),
        spectral_mesh::mesh::MeshError::RepeatedVertex { triangle, index } => Failure::value(
            format!("F[{triangle}] uses vertex {index} twice (a degenerate triangle)"),
        ),
        other => other.into(),
    })
}

/// Copies a point cloud's `P` (`(n, 3)` float64) and optional normals (`(n, 3)` float64,
/// zero rows meaning "unknown") into a [`PointCloud`], checking shapes and finiteness
/// (errors name the row).
pub fn cloud_from(
    p: &PyReadonlyArray2<'_, f64>,
    normals: Option<&PyReadonlyArray2<'_, f64>>,
) -> Result<PointCloud, Failure> {
    let rows = |a: &PyReadonlyArray2<'_, f64>, name: &str| -> Result<Vec<[f64; 3]>, Failure> {
        let s = a.shape();
        if s[1] != 3 {
            return Err(Failure::value(format!(
                "{name} must have shape (n, 3), got ({}, {})",
                s[0], s[1]
            )));
        }
        Ok(slice(a, name)?
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect())
    };
    let positions = rows(p, "P")?;
    let normals = normals.map(|nr| rows(nr, "normals")).transpose()?;
    PointCloud::new(positions, normals).map_err(|e| match e {
        PointCloudError::NonFinite { point } => Failure::value(format!(
            "P[{point}] has a non-finite coordinate (NaN or inf)"
        )),
        PointCloudError::NonFiniteNormal { point } => Failure::value(format!(
            "normals[{point}] has a non-finite component (NaN or inf)"
        )),
        PointCloudError::NormalCount { normals, points } => Failure::value(format!(
            "normals has {normals} rows but P has {points} points"
        )),
        PointCloudError::Empty => Failure::value("P is empty: the cloud needs at least one point"),
    })
}

/// A per-vertex vector (`(len,)` float64), checked finite.
pub fn values(a: &PyReadonlyArray1<'_, f64>, name: &str) -> Result<Vec<f64>, Failure> {
    let s = a
        .as_slice()
        .map_err(|e| Failure::value(format!("{name}: {e}")))?;
    if let Some(i) = s.iter().position(|x| !x.is_finite()) {
        return Err(Failure::value(format!(
            "{name}[{i}] = {} is not finite",
            s[i]
        )));
    }
    Ok(s.to_vec())
}

/// An `n x k` column-major matrix from its C-contiguous `(k, n)` transpose.
pub fn columns(
    a: &PyReadonlyArray2<'_, f64>,
    name: &str,
) -> Result<(usize, usize, Vec<f64>), Failure> {
    let s = a.shape();
    let (k, n) = (s[0], s[1]);
    let data = slice(a, name)?;
    if let Some(i) = data.iter().position(|x| !x.is_finite()) {
        return Err(Failure::value(format!(
            "{name}[{}, {}] is not finite",
            i % n.max(1),
            i / n.max(1)
        )));
    }
    Ok((n, k, data.to_vec()))
}

/// Eigenpairs given as arrays: eigenvalues `(k,)` and the eigenvectors' `(k, n)`
/// transpose, as `(n, values, vectors column-major)` (the counts checked to agree).
pub fn pairs(
    evals: &PyReadonlyArray1<'_, f64>,
    evecs_t: &PyReadonlyArray2<'_, f64>,
) -> Result<(usize, Vec<f64>, Vec<f64>), Failure> {
    let values = values(evals, "evals")?;
    let (n, k, vectors) = columns(evecs_t, "evecs")?;
    if k != values.len() {
        return Err(Failure::value(format!(
            "evecs has {k} columns but evals has {} values",
            values.len()
        )));
    }
    Ok((n, values, vectors))
}

/// How a matrix's data are laid out.
#[derive(Debug, Clone, Copy)]
pub enum Layout {
    /// Row-major: a C-ordered array.
    Rows,
    /// Column-major: a Fortran-ordered array.
    Columns,
}

/// A `(rows, cols)` array owning `data` (laid out as `layout` says), without a copy.
pub fn to_matrix<'py, T: numpy::Element>(
    py: Python<'py>,
    layout: Layout,
    rows: usize,
    cols: usize,
    data: Vec<T>,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let shape: StrideShape<Ix2> = match layout {
        Layout::Rows => (rows, cols).into(),
        Layout::Columns => (rows, cols).f().into(),
    };
    let a = Array2::from_shape_vec(shape, data)
        .map_err(|e| Failure::Internal(format!("array shape: {e}")).into_pyerr(py))?;
    Ok(PyArray2::from_owned_array(py, a))
}

/// A vector as a NumPy array, without a copy.
pub fn to_vector<'py, T: numpy::Element>(py: Python<'py>, data: Vec<T>) -> Bound<'py, PyArray1<T>> {
    PyArray1::from_vec(py, data)
}

/// `V` and `F` of a mesh as owned row-major data.
pub fn mesh_arrays(mesh: &Mesh) -> (Vec<f64>, Vec<i64>) {
    let v = mesh.positions().iter().flatten().copied().collect();
    let f = mesh
        .triangles()
        .iter()
        .flatten()
        .map(|&i| i as i64)
        .collect();
    (v, f)
}

/// A sparse matrix's CSC arrays `(data, indices, indptr)` with int64 indices; for a
/// symmetric matrix they are also its CSR arrays.
pub type Csc = (Vec<f64>, Vec<i64>, Vec<i64>);

/// The CSC arrays of `m`.
pub fn csc_parts(m: &SparseMatrix) -> Csc {
    (
        m.values().to_vec(),
        m.row_idx().iter().map(|&i| i as i64).collect(),
        m.col_ptr().iter().map(|&i| i as i64).collect(),
    )
}

/// The CSC arrays as NumPy arrays `(data, indices, indptr)`.
pub fn csc_to_py<'py>(py: Python<'py>, c: Csc) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
    let (d, i, p) = c;
    pyo3::types::PyTuple::new(
        py,
        [
            to_vector(py, d).into_any(),
            to_vector(py, i).into_any(),
            to_vector(py, p).into_any(),
        ],
    )
}

/// A square `n x n` matrix from CSC arrays (indices sorted within columns, no duplicates).
pub fn csc_from(
    name: &str,
    n: usize,
    data: &PyReadonlyArray1<'_, f64>,
    indices: &PyReadonlyArray1<'_, i64>,
    indptr: &PyReadonlyArray1<'_, i64>,
) -> Result<SparseMatrix, Failure> {
    let bad = |m: String| Failure::value(format!("{name}: {m}"));
    let d = data.as_slice().map_err(|e| bad(e.to_string()))?;
    if let Some(i) = d.iter().position(|x| !x.is_finite()) {
        return Err(bad(format!("stored entry {i} is not finite ({})", d[i])));
    }
    let to_usize = |a: &PyReadonlyArray1<'_, i64>, what: &str| -> Result<Vec<usize>, Failure> {
        a.as_slice()
            .map_err(|e| bad(e.to_string()))?
            .iter()
            .map(|&x| usize::try_from(x).map_err(|_| bad(format!("negative entry {x} in {what}"))))
            .collect()
    };
    let rows = to_usize(indices, "indices")?;
    let ptr = to_usize(indptr, "indptr")?;
    SparseMatrix::from_csc(n, n, ptr, rows, d.to_vec()).ok_or_else(|| {
        bad("the CSC arrays are inconsistent (indptr, unsorted or repeated indices, or indices out of range)".into())
    })
}

/// `(evals (k,), evecs (n, k))` as NumPy arrays.
pub type Pairs<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);
/// `(V (n, 3), F (m, 3))` as NumPy arrays.
pub type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);
/// A field's `(values, labels, info)`.
pub type FieldOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    Option<Bound<'py, PyArray1<i64>>>,
    Bound<'py, PyAny>,
);
/// A basis archive's `(evals, evecs, mass CSC arrays, meta)`.
pub type Archive<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, pyo3::types::PyTuple>,
    Bound<'py, PyAny>,
);
