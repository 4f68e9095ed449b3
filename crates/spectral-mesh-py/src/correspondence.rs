//! Shape correspondence (the library's `correspondence` module): the functional map of two
//! eigenbases, ZoomOut, point maps. Bases come in as eigenvalues and the `(k, n)`
//! transpose of the eigenvectors, with the mesh whose mass matrix (of `kind`) they are
//! orthonormal in.

use std::path::PathBuf;

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use spectral_mesh::batch::{
    PairJob, PairParams, PairRecord, Pairing, plan_pairs, process_pair, resolve_inputs,
    write_pairs_summary,
};
use spectral_mesh::correspondence::{
    CorrespondenceError, FunctionalMap, MatchParams, Refined, ZoomoutDirection, fmap_to_p2p,
    fmap_to_p2p_12, match_shapes, zoomout,
};
use spectral_mesh::spectral::BasisView;
use spectral_mesh::{Mesh, Operators, SparseMatrix};

use crate::arrays::{Layout, columns, mesh_from, to_matrix, to_vector, values};
use crate::errors::Failure;
use crate::laplacian_of;
use crate::run::run;

impl From<CorrespondenceError> for Failure {
    fn from(e: CorrespondenceError) -> Self {
        match e {
            CorrespondenceError::Singular => Failure::Solver(e.to_string()),
            _ => Failure::Value(e.to_string()),
        }
    }
}

/// One shape: mesh, mass, eigenpairs (`n x k` column-major vectors).
struct Shape {
    mesh: Mesh,
    mass: SparseMatrix,
    values: Vec<f64>,
    vectors: Vec<f64>,
}

impl Shape {
    fn view(&self) -> BasisView<'_> {
        BasisView {
            laplacian: spectral_mesh::Laplacian::Fem,
            n: self.mesh.n_vertices(),
            values: &self.values,
            vectors: &self.vectors,
            mass: &self.mass,
        }
    }
}

/// One shape of a pair as the wrappers pass it: one tuple `(V, F, evals, evecs_t)`, the
/// eigenvalues `None` where the function needs none.
#[derive(FromPyObject)]
pub struct ShapeArgs<'py>(
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray2<'py, i64>,
    Option<PyReadonlyArray1<'py, f64>>,
    PyReadonlyArray2<'py, f64>,
);

/// The shape (`which`: 1 or 2, for the messages) with its mass for the discretization
/// `kind`, checked against its basis.
fn shape(args: &ShapeArgs<'_>, kind: &str, which: usize) -> Result<Shape, Failure> {
    let ShapeArgs(v, f, evals, evecs_t) = args;
    let mesh = mesh_from(v, f)?;
    let (n, k, vectors) = columns(evecs_t, &format!("evecs{which}"))?;
    if n != mesh.n_vertices() {
        return Err(Failure::value(format!(
            "evecs{which} has {n} rows but V{which} has {} vertices",
            mesh.n_vertices()
        )));
    }
    let values = match evals {
        Some(e) => values(e, &format!("evals{which}"))?,
        None => vec![0.0; k],
    };
    if values.len() != k {
        return Err(Failure::value(format!(
            "evals{which} has {} values but evecs{which} has {k} columns",
            values.len()
        )));
    }
    let lap = laplacian_of(kind)?;
    let mass = Operators::new(&mesh, lap).mass;
    Ok(Shape {
        mesh,
        mass,
        values,
        vectors,
    })
}

fn fmap_from(c: &PyReadonlyArray2<'_, f64>) -> Result<FunctionalMap, Failure> {
    // C arrives as its C-contiguous transpose (k1, k2): column-major k2 x k1.
    let (k2, k1, data) = columns(c, "C")?;
    Ok(FunctionalMap { k1, k2, c: data })
}

fn params_from(json: &str) -> Result<MatchParams, Failure> {
    serde_json::from_str(json).map_err(|e| Failure::value(format!("parameters: {e}")))
}

/// The library's defaults of the correspondence functions, as JSON.
#[pyfunction]
pub fn correspondence_defaults() -> PyResult<String> {
    serde_json::to_string(&MatchParams::default())
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
}

/// The functional map `C` (`(k2, k1)`) of the energy and its value.
#[pyfunction]
#[pyo3(signature = (shape1, shape2, kind, params, landmarks))]
pub fn functional_map<'py>(
    py: Python<'py>,
    shape1: ShapeArgs<'_>,
    shape2: ShapeArgs<'_>,
    kind: &str,
    params: &str,
    landmarks: Vec<(usize, usize)>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, f64)> {
    let prep = || -> Result<(Shape, Shape, MatchParams), Failure> {
        let s1 = shape(&shape1, kind, 1)?;
        let s2 = shape(&shape2, kind, 2)?;
        let mut p = params_from(params)?;
        p.zoomout_k = 0;
        Ok((s1, s2, p))
    };
    let (s1, s2, p) = prep().map_err(|e| e.into_pyerr(py))?;
    let (c, energy) = run(py, move |_| {
        let k = p.k;
        let res = match_shapes(
            &s1.mesh,
            truncated(s1.view(), k),
            &s2.mesh,
            truncated(s2.view(), k),
            &landmarks,
            &p,
        )?;
        Ok((res.initial, res.energy))
    })?;
    Ok((
        to_matrix(py, Layout::Rows, c.k2, c.k1, c.row_major())?,
        energy,
    ))
}

fn truncated(b: BasisView<'_>, k: usize) -> BasisView<'_> {
    let k = k.min(b.k());
    BasisView {
        values: &b.values[..k],
        vectors: &b.vectors[..k * b.n],
        ..b
    }
}

/// A refined map and its point map, when that direction was asked for.
type Refinement<'py> = Option<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<usize>>)>;

fn refinement<'py>(py: Python<'py>, r: Option<Refined>) -> PyResult<Refinement<'py>> {
    r.map(|r| {
        Ok((
            to_matrix(py, Layout::Rows, r.fmap.k2, r.fmap.k1, r.fmap.row_major())?,
            to_vector(py, r.p2p),
        ))
    })
    .transpose()
}

/// ZoomOut from `C` to `k_final` in the `direction` (`forward`, `reverse`, `both`):
/// `(forward, reverse)`, each `(refined map, point map)` or `None` (forward: `C` and
/// `p2p_21`; reverse: `C_12` and `p2p_12`).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (shape1, shape2, kind, c, k_final, step, direction))]
pub fn zoomout_refine<'py>(
    py: Python<'py>,
    shape1: ShapeArgs<'_>,
    shape2: ShapeArgs<'_>,
    kind: &str,
    c: PyReadonlyArray2<'_, f64>,
    k_final: usize,
    step: usize,
    direction: &str,
) -> PyResult<(Refinement<'py>, Refinement<'py>)> {
    let prep = || -> Result<(Shape, Shape, FunctionalMap, ZoomoutDirection), Failure> {
        Ok((
            shape(&shape1, kind, 1)?,
            shape(&shape2, kind, 2)?,
            fmap_from(&c)?,
            direction
                .parse()
                .map_err(|e: String| Failure::value(format!("direction: {e}")))?,
        ))
    };
    let (s1, s2, c, direction) = prep().map_err(|e| e.into_pyerr(py))?;
    let zoomed = run(py, move |_| {
        Ok(zoomout(&c, s1.view(), s2.view(), k_final, step, direction)?)
    })?;
    Ok((
        refinement(py, zoomed.forward)?,
        refinement(py, zoomed.reverse)?,
    ))
}

/// The point map of `C`: `p2p_21` (or `p2p_12` with `to_second`).
#[pyfunction]
#[pyo3(signature = (c, evecs1_t, evecs2_t, adjoint, to_second))]
pub fn point_map<'py>(
    py: Python<'py>,
    c: PyReadonlyArray2<'_, f64>,
    evecs1_t: PyReadonlyArray2<'_, f64>,
    evecs2_t: PyReadonlyArray2<'_, f64>,
    adjoint: bool,
    to_second: bool,
) -> PyResult<Bound<'py, PyArray1<usize>>> {
    let prep = || -> Result<_, Failure> {
        let (n1, k1, x1) = columns(&evecs1_t, "evecs1")?;
        let (n2, k2, x2) = columns(&evecs2_t, "evecs2")?;
        Ok((fmap_from(&c)?, n1, k1, x1, n2, k2, x2))
    };
    let (c, n1, k1, x1, n2, k2, x2) = prep().map_err(|e| e.into_pyerr(py))?;
    let p2p = run(py, move |_| {
        // No mass is needed: nearest neighbours of the embeddings only.
        let m1 = SparseMatrix::identity(0);
        let (e1, e2) = (vec![0.0; k1], vec![0.0; k2]);
        let b1 = BasisView {
            laplacian: spectral_mesh::Laplacian::Fem,
            n: n1,
            values: &e1,
            vectors: &x1,
            mass: &m1,
        };
        let b2 = BasisView {
            n: n2,
            values: &e2,
            vectors: &x2,
            ..b1
        };
        Ok(if to_second {
            fmap_to_p2p_12(&c, b1, b2)?
        } else {
            fmap_to_p2p(&c, b1, b2, adjoint)?
        })
    })?;
    Ok(to_vector(py, p2p))
}

/// JSON text of a value.
fn json<T: serde::Serialize>(v: &T) -> Result<String, Failure> {
    serde_json::to_string(v).map_err(|e| Failure::Internal(e.to_string()))
}

/// Matching over pairs of a collection (the library's `batch::pairs`): the inputs
/// resolved, the pairs planned and the parameters checked. `pairing` and `params` are
/// JSON (`Pairing` and `PairParams` in their serde forms); returns the jobs (JSON text
/// each, plain data for a Dask task) and the canonical parameters.
#[pyfunction]
pub fn pairs_plan(
    py: Python<'_>,
    specs: Vec<String>,
    pairing: &str,
    params: &str,
) -> PyResult<(Vec<String>, String)> {
    let parse = || -> Result<(Pairing, PairParams), Failure> {
        let pairing =
            serde_json::from_str(pairing).map_err(|e| Failure::value(format!("pairs: {e}")))?;
        let params: PairParams =
            serde_json::from_str(params).map_err(|e| Failure::value(format!("parameters: {e}")))?;
        params
            .validate()
            .map_err(|e| Failure::value(e.to_string()))?;
        Ok((pairing, params))
    };
    let (pairing, params) = parse().map_err(|e| e.into_pyerr(py))?;
    run(py, move |_| {
        let inputs = resolve_inputs(&specs).map_err(|e| Failure::value(e.to_string()))?;
        let jobs = plan_pairs(&inputs, &pairing).map_err(|e| Failure::value(e.to_string()))?;
        Ok((
            jobs.iter().map(json).collect::<Result<_, _>>()?,
            json(&params)?,
        ))
    })
}

/// One pair: its record as JSON text (`process_pair`), in the shared pool of `threads`
/// threads (0: the global pool); never raises for a bad mesh (its record says why).
#[pyfunction]
pub fn match_pair(
    py: Python<'_>,
    job: &str,
    params: &str,
    out: PathBuf,
    threads: usize,
) -> PyResult<String> {
    let parse = || -> Result<(PairJob, PairParams), Failure> {
        Ok((
            serde_json::from_str(job).map_err(|e| Failure::value(format!("job: {e}")))?,
            serde_json::from_str(params).map_err(|e| Failure::value(format!("parameters: {e}")))?,
        ))
    };
    let (job, params) = parse().map_err(|e| e.into_pyerr(py))?;
    run(py, move |token| {
        let work = || process_pair(&job, &params, &out, token);
        let record = if threads > 0 {
            crate::batch::pool(threads)?.install(work)
        } else {
            work()
        };
        json(&record)
    })
}

/// A failed record of `job` with `message` (a Dask task that failed), as JSON text.
#[pyfunction]
pub fn pair_failed(py: Python<'_>, job: &str, params: &str, message: &str) -> PyResult<String> {
    let make = || -> Result<String, Failure> {
        let job: PairJob =
            serde_json::from_str(job).map_err(|e| Failure::value(format!("job: {e}")))?;
        let params: PairParams =
            serde_json::from_str(params).map_err(|e| Failure::value(format!("parameters: {e}")))?;
        json(&PairRecord::failed(&job, &params, message))
    };
    make().map_err(|e| e.into_pyerr(py))
}

/// Writes `out/pairs.csv` from the records (JSON text each); returns its path.
#[pyfunction]
pub fn pairs_summary(py: Python<'_>, out: PathBuf, records: Vec<String>) -> PyResult<String> {
    run(py, move |_| {
        let records: Vec<PairRecord> = records
            .iter()
            .map(|r| serde_json::from_str(r).map_err(|e| Failure::value(format!("record: {e}"))))
            .collect::<Result<_, _>>()?;
        let path =
            write_pairs_summary(&out, &records).map_err(|e| Failure::value(e.to_string()))?;
        Ok(path.display().to_string())
    })
}
