//! Geodesic distance by the heat method: a solver object that keeps its factors
//! ([`spectral_mesh::geodesic::GeodesicSolver`]).

use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use spectral_mesh::geodesic::{
    CloudGeodesicParams, Convention, GeodesicError, GeodesicParams, GeodesicSolver, Source,
    farthest_point_sampling,
};

use crate::arrays::{Layout, mesh_from, to_matrix, to_vector};
use crate::errors::Failure;
use crate::run::{run, run_heavy};
use crate::{PointsArgs, laplacian_of};

impl From<GeodesicError> for Failure {
    fn from(e: GeodesicError) -> Self {
        match e {
            GeodesicError::Factorization(_) => Failure::Solver(e.to_string()),
            _ => Failure::Value(e.to_string()),
        }
    }
}

/// The sources: vertices, then face points `(face, b0, b1, b2)`.
fn sources(vertices: Vec<usize>, points: Vec<(usize, f64, f64, f64)>) -> Vec<Source> {
    let mut s: Vec<Source> = vertices.into_iter().map(Source::Vertex).collect();
    s.extend(points.into_iter().map(|(face, a, b, c)| Source::FacePoint {
        face,
        bary: [a, b, c],
    }));
    s
}

/// The heat-method parameters from the Python keywords (`None`: the library's default).
fn geodesic_params(
    py: Python<'_>,
    time_factor: Option<f64>,
    convention: Option<&str>,
) -> PyResult<GeodesicParams> {
    let d = GeodesicParams::default();
    let convention: Convention = match convention {
        Some(c) => c
            .parse()
            .map_err(|e: String| Failure::Value(e).into_pyerr(py))?,
        None => d.convention,
    };
    Ok(GeodesicParams {
        time_factor: time_factor.unwrap_or(d.time_factor),
        convention,
        ..d
    })
}

/// The heat-method solver of one mesh or point cloud (factored once).
#[pyclass(frozen, name = "GeodesicSolver", module = "spectral_mesh._native")]
pub struct PyGeodesicSolver {
    solver: Arc<GeodesicSolver>,
    /// The time step `t = m h^2`.
    #[pyo3(get)]
    t: f64,
    /// The mean edge length `h`.
    #[pyo3(get)]
    h: f64,
    /// Number of vertices.
    #[pyo3(get)]
    n: usize,
}

impl PyGeodesicSolver {
    /// The Python object of a factored solver.
    fn wrap(solver: GeodesicSolver) -> Self {
        Self {
            t: solver.time(),
            h: solver.mean_edge_length(),
            n: solver.n(),
            solver: Arc::new(solver),
        }
    }
}

#[pymethods]
impl PyGeodesicSolver {
    /// Builds and factors the solver; `None` takes the library's default.
    #[new]
    #[pyo3(signature = (v, f, kind, time_factor=None, convention=None))]
    fn new(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        kind: &str,
        time_factor: Option<f64>,
        convention: Option<&str>,
    ) -> PyResult<Self> {
        let mesh = mesh_from(&v, &f).map_err(|e| e.into_pyerr(py))?;
        let lap = laplacian_of(kind).map_err(|e| e.into_pyerr(py))?;
        let params = geodesic_params(py, time_factor, convention)?;
        let rows = Some(mesh.n_vertices());
        let solver = run_heavy(py, rows, move |_| {
            Ok(GeodesicSolver::new(&mesh, lap, &params)?)
        })?;
        Ok(Self::wrap(solver))
    }

    /// Builds and factors the solver of a point cloud (point-cloud Laplacian, gradient in
    /// each point's tangent plane); `None` takes the library's default.
    #[staticmethod]
    #[pyo3(signature = (points, gradient_neighbors=None, time_factor=None, convention=None))]
    fn from_points(
        py: Python<'_>,
        points: PointsArgs<'_>,
        gradient_neighbors: Option<usize>,
        time_factor: Option<f64>,
        convention: Option<&str>,
    ) -> PyResult<Self> {
        let (cloud, laplacian) = points.build().map_err(|e| e.into_pyerr(py))?;
        let params = geodesic_params(py, time_factor, convention)?;
        let d = CloudGeodesicParams::default();
        let cp = CloudGeodesicParams {
            laplacian,
            gradient_neighbors: gradient_neighbors.unwrap_or(d.gradient_neighbors),
            ..d
        };
        let rows = Some(cloud.positions().len());
        let solver = run_heavy(py, rows, move |_| {
            Ok(GeodesicSolver::from_point_cloud(&cloud, &cp, &params)?)
        })?;
        Ok(Self::wrap(solver))
    }

    /// Distance from the set of vertices and face points.
    fn distance<'py>(
        &self,
        py: Python<'py>,
        vertices: Vec<usize>,
        points: Vec<(usize, f64, f64, f64)>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let s = self.solver.clone();
        let src = sources(vertices, points);
        let d = run(py, move |_| Ok(s.distance(&src)?))?;
        Ok(to_vector(py, d))
    }

    /// Distances from each vertex on its own, `(k, n)`.
    fn distances<'py>(
        &self,
        py: Python<'py>,
        vertices: Vec<usize>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let s = self.solver.clone();
        let k = vertices.len();
        let n = s.n();
        let d = run(py, move |_| Ok(s.distances_from_vertices(&vertices)?))?;
        to_matrix(py, Layout::Rows, k, n, d.concat())
    }

    /// The `k x k` distance matrix between sample vertices.
    fn distance_matrix<'py>(
        &self,
        py: Python<'py>,
        samples: Vec<usize>,
        symmetric: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let s = self.solver.clone();
        let k = samples.len();
        let d = run(py, move |_| Ok(s.distance_matrix(&samples, symmetric)?))?;
        to_matrix(py, Layout::Rows, k, k, d.concat())
    }

    /// Farthest-point sampling of `k` vertices from `start`.
    fn farthest_point_sampling(
        &self,
        py: Python<'_>,
        k: usize,
        start: usize,
    ) -> PyResult<Vec<usize>> {
        let s = self.solver.clone();
        run(py, move |_| Ok(farthest_point_sampling(&s, k, start)?))
    }
}
