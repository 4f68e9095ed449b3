//! Geodesic distance by the heat method (Crane, Weischedel and Wardetzky, "Geodesics in
//! Heat", 2013, and "The Heat Method for Distance Computation", 2017).
//!
//! A [`GeodesicSolver`] factors its matrices once and then answers any number of source
//! sets; the formulas, signs and the boundary rule are in `docs/MATH.md` ("Geodesic distance"):
//!
//! 1. **Heat.** `(B + t S) u = delta`, `t = m h^2` with `h` the mean edge length and `m`
//!    [`GeodesicParams::time_factor`] (1 by default). `delta` is 1 at a source vertex (the
//!    barycentric weights at the corners of a face point), not divided by the mass.
//!    On a mesh with boundary the [`Convention::Crane`] rule averages the Neumann solution
//!    and the Dirichlet one (`u = 0` on the boundary): `u = (u_N + u_D) / 2`.
//! 2. **Direction.** In every triangle, `X = grad u / |grad u|` (zero where `grad u = 0`).
//!    This is minus the paper's `X`; the sign is taken back in step 3.
//! 3. **Poisson.** `S phi = div X` with the integrated divergence
//!    `(div X)_i = sum over triangles, over the two edges i -> j of the triangle, of
//!    w_ij (p_j - p_i) . X`, `w_ij` the half cotangent of the angle opposite the edge (the
//!    weights of S, so that `div grad u = -S u` exactly).
//! 4. **Shift.** `phi` is shifted so that its weighted mean over the sources is 0 (for a
//!    face point, the value expected at each corner is the straight distance inside the
//!    face). Each connected component is shifted on its own; a component with no source gets
//!    `f64::INFINITY` (the heat never reaches it).
//!
//! Which triangles carry the gradient: the input triangles for the cotangent Laplacians;
//! for [`Laplacian::Robust`] the intrinsic Delaunay triangulation of the tufted cover
//! ([`crate::operators::robust`]), so that gradient, divergence and S come from the same
//! triangles (this is what geometry-central's heat-method solver does with its robust
//! Laplacian).

mod cloud;
mod sampling;
mod triangles;

use rayon::prelude::*;

use crate::linalg::cholesky::CholeskyAnalysis;
use crate::linalg::{CholeskyError, SparseCholesky, SparseMatrix};
use crate::mesh::topology::UnionFind;
use crate::mesh::{Mesh, PointCloud};
use crate::operators::robust::{MollifyMean, RobustError, RobustParams, Soup, robust_with_faces};
use crate::operators::{Laplacian, Operators, PointCloudParams, point_cloud_laplacian};
use cloud::TangentGradient;
use triangles::FaceFrames;

pub use cloud::DEFAULT_GRADIENT_NEIGHBORS;
pub use sampling::farthest_point_sampling;

/// Source sets solved together as one block of right-hand sides (bounds the working
/// memory of many-source calls to about `3 n BLOCK` values).
pub const BLOCK: usize = 32;

/// Columns of the divergence on triangles computed together.
const LANES: usize = 8;

/// Which published variant of the heat method.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Convention {
    /// Crane, Weischedel and Wardetzky: on a mesh with boundary the heat is the average of
    /// the Neumann and the Dirichlet solutions; the Poisson problem is solved exactly (one
    /// vertex per component held at 0, then the shift); `h` is the mean length of the input
    /// edges.
    #[default]
    Crane,
    /// geometry-central's `HeatMethodDistanceSolver` (potpourri3d's
    /// `MeshHeatMethodDistanceSolver`): Neumann heat only; the Poisson matrix is its
    /// Laplacian plus `1e-6 I` (with the robust Laplacian, its Laplacian is that of the
    /// whole cover, `2 S`, so ours gets `0.5e-6 I`); with the robust Laplacian, `h` is the
    /// mean edge length of the intrinsic Delaunay cover and the cover is mollified from the
    /// cover's mean edge length. For comparisons with it.
    Potpourri3d,
}

crate::io::names::names_as_text!(
    Convention,
    names: [Crane => "crane", Potpourri3d => "potpourri3d"],
    aliases: [Crane => ["average"], Potpourri3d => ["geometry-central", "neumann"]],
    unknown: |s| format!("unknown heat-method convention '{s}': expected crane or potpourri3d"),
);

/// Parameters of the heat method. `Default`: `m = 1`, [`Convention::Crane`], the robust
/// Laplacian's default parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GeodesicParams {
    /// `m` in `t = m h^2` (potpourri3d's `t_coef`). Finite and `> 0`.
    pub time_factor: f64,
    /// Boundary rule and Poisson solve.
    pub convention: Convention,
    /// Parameters of the robust Laplacian (used with [`Laplacian::Robust`] only).
    pub robust: RobustParams,
}

impl Default for GeodesicParams {
    fn default() -> Self {
        Self {
            time_factor: crate::defaults::values::DEFAULT_GEODESIC_TIME_FACTOR,
            convention: Convention::Crane,
            robust: RobustParams::default(),
        }
    }
}

/// A source of distance: a vertex, or a point inside a triangle.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Source {
    /// A vertex index.
    Vertex(usize),
    /// A point of triangle `face` with barycentric coordinates `bary` (for the triangle's
    /// vertices in order; `>= 0`, summing to 1; they are renormalized).
    FacePoint {
        /// Triangle index.
        face: usize,
        /// Barycentric coordinates.
        bary: [f64; 3],
    },
}

impl From<usize> for Source {
    fn from(v: usize) -> Self {
        Source::Vertex(v)
    }
}

/// Errors of the heat method, each saying what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeodesicError {
    /// A parameter is out of its range.
    #[error("{0}")]
    BadParameter(String),
    /// No source was given.
    #[error("no source given: name at least one vertex or face point")]
    NoSources,
    /// A source vertex does not exist.
    #[error("source vertex {vertex} is out of range: the mesh has {n} vertices")]
    VertexOutOfRange {
        /// The index given.
        vertex: usize,
        /// Vertices.
        n: usize,
    },
    /// A source vertex belongs to no triangle.
    #[error(
        "source vertex {vertex} belongs to no triangle: no distance along the surface starts there"
    )]
    IsolatedVertex {
        /// The vertex.
        vertex: usize,
    },
    /// A source triangle does not exist.
    #[error("source triangle {face} is out of range: the mesh has {m} triangles")]
    FaceOutOfRange {
        /// The index given.
        face: usize,
        /// Triangles.
        m: usize,
    },
    /// A face-point source given to a point cloud's solver.
    #[error(
        "a point cloud has no triangles: the face-point source in triangle {face} needs a mesh (name source points by index)"
    )]
    FacePointOnCloud {
        /// The triangle index given.
        face: usize,
    },
    /// Barycentric coordinates that are negative, not finite or sum to 0.
    #[error(
        "the barycentric coordinates {bary:?} of the source in triangle {face} must be finite, >= 0 and sum to 1"
    )]
    BadBarycentric {
        /// Triangle.
        face: usize,
        /// The coordinates given.
        bary: [f64; 3],
    },
    /// The chosen Laplacian has no gradient to go with it.
    #[error(
        "the heat method needs a cotangent Laplacian (voronoi-cot, fem, mixed-voronoi, cot or robust); '{0}' has no matching gradient"
    )]
    NotGeometric(Laplacian),
    /// A factorization failed.
    #[error("the heat method could not factor its matrix: {0}")]
    Factorization(#[from] CholeskyError),
    /// The robust Laplacian refused its parameters.
    #[error(transparent)]
    Robust(#[from] RobustError),
}

/// The carrier of the gradient and the divergence.
#[derive(Debug)]
enum Gradient {
    /// Triangles laid out in their planes (meshes).
    Triangles(FaceFrames),
    /// Least squares in each point's tangent plane (point clouds).
    Tangent(TangentGradient),
}

impl Gradient {
    fn memory_bytes(&self) -> usize {
        match self {
            Gradient::Triangles(f) => f.memory_bytes(),
            Gradient::Tangent(g) => g.memory_bytes(),
        }
    }
}

/// Parameters of the heat method on a point cloud. `Default`: the point-cloud Laplacian's
/// defaults, [`DEFAULT_GRADIENT_NEIGHBORS`] neighbours for the gradient.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CloudGeodesicParams {
    /// The point-cloud Laplacian (S, B) of the heat and Poisson solves; its `normals`
    /// also choose the tangent planes of the gradient.
    pub laplacian: PointCloudParams,
    /// Nearest neighbours of the least-squares gradient of each point (`>= 2`; fewer when
    /// the cloud has fewer points).
    pub gradient_neighbors: usize,
    /// The matrix of the Poisson solve.
    pub poisson: CloudPoisson,
}

impl Default for CloudGeodesicParams {
    fn default() -> Self {
        Self {
            laplacian: PointCloudParams::default(),
            gradient_neighbors: DEFAULT_GRADIENT_NEIGHBORS,
            poisson: CloudPoisson::default(),
        }
    }
}

/// The matrix of the Poisson solve on a point cloud.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum CloudPoisson {
    /// `G^T B G`, the energy of the least-squares gradient itself, so that `div grad` is
    /// exactly minus the Poisson matrix, as on meshes: `phi` is the function whose
    /// gradient fits the unit field best in the mass-weighted least-squares sense. A wider
    /// stencil than S (about 37 entries a row with 12 gradient neighbours against 7).
    /// Falls back to [`CloudPoisson::Laplacian`] where the neighbour graph splits a
    /// component of S.
    #[default]
    GradientEnergy,
    /// The point-cloud Laplacian S (inconsistent with the divergence: on the unit sphere
    /// the distances come out about 3% short).
    Laplacian,
}

/// The heat method on one mesh or point cloud: factored once, then any number of sources
/// (see the module docs).
#[derive(Debug)]
pub struct GeodesicSolver {
    n: usize,
    /// Input triangles (face-point sources) and positions (the shift); for a point cloud
    /// the triangle union of its Laplacian (pictures only).
    triangles: Vec<[usize; 3]>,
    positions: Vec<[f64; 3]>,
    /// Gradient and divergence.
    gradient: Gradient,
    /// Component of each vertex (`usize::MAX` for a vertex no triangle uses).
    component: Vec<usize>,
    n_components: usize,
    heat: SparseCholesky,
    /// Dirichlet heat on the interior vertices: (interior vertices, factor).
    dirichlet: Option<(Vec<usize>, SparseCholesky)>,
    poisson: SparseCholesky,
    /// Vertices whose Poisson right-hand side is set to 0: one held vertex per component
    /// (convention `crane`) and the vertices no triangle uses.
    zero_rhs: Vec<usize>,
    h: f64,
    t: f64,
    laplacian: Laplacian,
    params: GeodesicParams,
    point_cloud: bool,
    factor_len: usize,
}

/// The factored matrices shared by meshes and point clouds.
struct Factors {
    heat: SparseCholesky,
    dirichlet: Option<(Vec<usize>, SparseCholesky)>,
    poisson: SparseCholesky,
    zero_rhs: Vec<usize>,
    component: Vec<usize>,
    n_components: usize,
}

/// Components of the graph of `edges` over the vertices marked `used` (`usize::MAX` for
/// the others), and the first vertex of each component.
fn components(
    n: usize,
    used: &[bool],
    edges: impl Iterator<Item = (usize, usize)>,
) -> (Vec<usize>, Vec<usize>) {
    let mut uf = UnionFind::new(n);
    for (a, b) in edges {
        uf.union(a, b);
    }
    let mut root_id = vec![usize::MAX; n];
    let mut component = vec![usize::MAX; n];
    let mut pinned = Vec::new();
    for v in 0..n {
        if !used[v] {
            continue;
        }
        let r = uf.find(v);
        if root_id[r] == usize::MAX {
            root_id[r] = pinned.len();
            pinned.push(v);
        }
        component[v] = root_id[r];
    }
    (component, pinned)
}

/// Factors the heat matrix `B + t S` (1 on the diagonal of unused vertices), the
/// Dirichlet heat on the vertices not in `boundary` (when given and non-empty; Crane's
/// rule), and the Poisson matrix of `convention` (`gc_scale`: geometry-central's
/// Laplacian over ours, for its `1e-6 I` shift).
#[allow(clippy::too_many_arguments)]
fn factor(
    stiffness: &SparseMatrix,
    poisson_stiffness: Option<&SparseMatrix>,
    mass: &SparseMatrix,
    t: f64,
    used: &[bool],
    component: Vec<usize>,
    pinned: &[usize],
    boundary: Option<&[bool]>,
    convention: Convention,
    gc_scale: f64,
) -> Result<Factors, GeodesicError> {
    let n = used.len();
    let pp3d = convention == Convention::Potpourri3d;
    let n_components = pinned.len();
    // Heat: B + t S, 1 on the diagonal of unused vertices.
    let mut heat_m = mass.add_scaled(1.0, stiffness, t);
    if let Some(p) = poisson_stiffness {
        // The union of the two patterns (explicit zeros), shared by both factors.
        heat_m = heat_m.add_scaled(1.0, p, 0.0);
    }
    let poisson_s = poisson_stiffness.unwrap_or(stiffness);
    if used.iter().any(|&u| !u) {
        let unused_diag: Vec<f64> = used.iter().map(|&u| if u { 0.0 } else { 1.0 }).collect();
        heat_m = heat_m.add_scaled(1.0, &SparseMatrix::diagonal(&unused_diag), 1.0);
    }
    // Poisson, on the pattern of the heat matrix (explicit zeros where it has fewer
    // entries) so that the two share one ordering and symbolic analysis.
    let mut is_pinned = vec![false; n];
    if !pp3d {
        for &p in pinned {
            is_pinned[p] = true;
        }
    }
    let eps = 1e-6 / gc_scale;
    let mut values = vec![0.0; heat_m.nnz()];
    let col_ptr = heat_m.col_ptr();
    let row_idx = heat_m.row_idx();
    for c in 0..n {
        let (srows, svals) = poisson_s.col(c);
        let mut q = 0;
        for k in col_ptr[c]..col_ptr[c + 1] {
            let r = row_idx[k];
            while q < srows.len() && srows[q] < r {
                q += 1;
            }
            let s = if q < srows.len() && srows[q] == r {
                svals[q]
            } else {
                0.0
            };
            let held = |v: usize| is_pinned[v] || !used[v];
            values[k] = if held(r) || held(c) {
                if r == c { 1.0 } else { 0.0 }
            } else if pp3d && r == c {
                s + eps
            } else {
                s
            };
        }
    }
    let poisson_m = SparseMatrix::from_csc(n, n, col_ptr.to_vec(), row_idx.to_vec(), values)
        .ok_or_else(|| {
            GeodesicError::Factorization(CholeskyError::Internal(
                "the Poisson matrix has no valid pattern".to_string(),
            ))
        })?;
    let analysis = CholeskyAnalysis::new(&heat_m)?;
    // The Dirichlet heat (Crane's rule, meshes with boundary only).
    let interior: Option<Vec<usize>> = match boundary {
        Some(boundary) if !pp3d && boundary.iter().any(|&b| b) => {
            let interior: Vec<usize> = (0..n).filter(|&v| !boundary[v]).collect();
            (!interior.is_empty()).then_some(interior)
        }
        _ => None,
    };
    // The numeric factorizations side by side.
    let ((heat, poisson), dirichlet) = rayon::join(
        || rayon::join(|| analysis.factor(&heat_m), || analysis.factor(&poisson_m)),
        || {
            interior.map(|interior| {
                let sub = heat_m.submatrix(&interior, &interior);
                SparseCholesky::new(&sub).map(|f| (interior, f))
            })
        },
    );
    let (heat, poisson) = (heat?, poisson?);
    let dirichlet = dirichlet.transpose()?;
    let mut zero_rhs: Vec<usize> = (0..n).filter(|&v| !used[v]).collect();
    if !pp3d {
        zero_rhs.extend(pinned);
    }
    Ok(Factors {
        heat,
        dirichlet,
        poisson,
        zero_rhs,
        component,
        n_components,
    })
}

impl GeodesicSolver {
    /// Assembles the operators of `laplacian` on `mesh` (unscaled: distances are in the
    /// mesh's units) and factors the heat and Poisson matrices.
    pub fn new(
        mesh: &Mesh,
        laplacian: Laplacian,
        params: &GeodesicParams,
    ) -> Result<Self, GeodesicError> {
        check_time_factor(params)?;
        if !laplacian.is_cotangent() {
            return Err(GeodesicError::NotGeometric(laplacian));
        }
        let n = mesh.n_vertices();
        let pp3d = params.convention == Convention::Potpourri3d;
        // Operators, the triangles of the gradient, h, and the scale of gc's Laplacian.
        let (stiffness, mass, frames, h, gc_scale) = if laplacian == Laplacian::Robust {
            params.robust.validate()?;
            let mean = if pp3d {
                MollifyMean::Cover
            } else {
                MollifyMean::Distinct
            };
            let (r, faces) = robust_with_faces(Soup::of_mesh(mesh, &params.robust), mean, true);
            let faces = faces.unwrap_or_default();
            let h = if pp3d {
                faces.mean_edge_length
            } else {
                distinct_mean_edge_length(mesh)
            };
            let frames = FaceFrames::from_lengths(&faces.vertices, &faces.lengths, 0.5);
            (r.stiffness, r.mass, frames, h, 2.0)
        } else {
            let ops = Operators::new(mesh, laplacian);
            let frames = FaceFrames::from_mesh(mesh);
            (
                ops.stiffness,
                ops.mass,
                frames,
                distinct_mean_edge_length(mesh),
                1.0,
            )
        };
        let t = params.time_factor * h * h;

        // Components (through triangles) and vertices no triangle uses.
        let mut used = vec![false; n];
        for tri in mesh.triangles() {
            for &v in tri {
                used[v] = true;
            }
        }
        let (component, pinned) = components(
            n,
            &used,
            mesh.triangles()
                .iter()
                .flat_map(|t| [(t[0], t[1]), (t[1], t[2])]),
        );
        let boundary = boundary_vertices(mesh);
        let f = factor(
            &stiffness,
            None,
            &mass,
            t,
            &used,
            component,
            &pinned,
            Some(&boundary),
            params.convention,
            gc_scale,
        )?;
        Ok(Self::from_factors(
            f,
            mesh.triangles().to_vec(),
            mesh.positions().to_vec(),
            Gradient::Triangles(frames),
            h,
            t,
            laplacian,
            params,
            false,
        ))
    }

    /// The heat method on a point cloud: the heat and Poisson solves on the point-cloud
    /// Laplacian ([`point_cloud_laplacian`], unscaled), the gradient by least squares in
    /// each point's tangent plane over its nearest neighbours, and the divergence its
    /// adjoint with the mass (see `docs/MATH.md`). `h` is the mean edge length of the
    /// Laplacian's triangles. Sources are points ([`Source::Vertex`]); a point cloud has
    /// no boundary rule (Neumann heat only). `params.robust` is not used: the cloud's
    /// Laplacian has its own parameters in `cloud`.
    pub fn from_point_cloud(
        points: &PointCloud,
        cloud: &CloudGeodesicParams,
        params: &GeodesicParams,
    ) -> Result<Self, GeodesicError> {
        check_time_factor(params)?;
        if cloud.gradient_neighbors < 2 {
            return Err(GeodesicError::BadParameter(format!(
                "the gradient of a point cloud needs at least 2 neighbours, got {}",
                cloud.gradient_neighbors
            )));
        }
        let lap = point_cloud_laplacian(points, &cloud.laplacian)?;
        let n = points.n_points();
        let h = mean_edge_length_of(points.positions(), &lap.triangles);
        let h = if h > 0.0 {
            h
        } else {
            // No triangle at all (every neighbourhood collinear): the mean distance to
            // the nearest neighbour.
            mean_nearest_distance(points.positions())
        };
        let t = params.time_factor * h * h;
        let used = vec![true; n];
        let gradient = TangentGradient::new(
            points,
            cloud.gradient_neighbors,
            cloud.laplacian.neighbors,
            cloud.laplacian.normals,
            lap.mass.diag(),
        );
        let graph_edges = |m: &SparseMatrix| -> Vec<(usize, usize)> {
            (0..n)
                .flat_map(|c| {
                    let (rows, vals) = m.col(c);
                    rows.iter()
                        .zip(vals)
                        .filter(move |&(&r, &v)| r != c && v != 0.0)
                        .map(move |(&r, _)| (r, c))
                        .collect::<Vec<_>>()
                })
                .collect()
        };
        let s = &lap.stiffness;
        let s_edges = graph_edges(s);
        let energy = match cloud.poisson {
            CloudPoisson::GradientEnergy => {
                let e = gradient.energy();
                let e_edges = graph_edges(&e);
                // The energy's components must be those of the union (else a component
                // of the union would have more than one null vector).
                let (_, own) = components(n, &used, e_edges.iter().copied());
                let (_, union) = components(n, &used, e_edges.iter().chain(&s_edges).copied());
                (own.len() == union.len()).then_some(e)
            }
            CloudPoisson::Laplacian => None,
        };
        let (component, pinned) = match &energy {
            Some(e) => components(
                n,
                &used,
                graph_edges(e).into_iter().chain(s_edges.iter().copied()),
            ),
            None => components(n, &used, s_edges.iter().copied()),
        };
        let f = factor(
            s,
            energy.as_ref(),
            &lap.mass,
            t,
            &used,
            component,
            &pinned,
            None,
            params.convention,
            1.0,
        )?;
        Ok(Self::from_factors(
            f,
            lap.triangles,
            points.positions().to_vec(),
            Gradient::Tangent(gradient),
            h,
            t,
            Laplacian::Robust,
            params,
            true,
        ))
    }

    #[allow(clippy::too_many_arguments)]
    fn from_factors(
        f: Factors,
        triangles: Vec<[usize; 3]>,
        positions: Vec<[f64; 3]>,
        gradient: Gradient,
        h: f64,
        t: f64,
        laplacian: Laplacian,
        params: &GeodesicParams,
        point_cloud: bool,
    ) -> Self {
        let factor_len = f.heat.factor_len()
            + f.poisson.factor_len()
            + f.dirichlet.as_ref().map_or(0, |d| d.1.factor_len());
        Self {
            n: positions.len(),
            triangles,
            positions,
            gradient,
            component: f.component,
            n_components: f.n_components,
            heat: f.heat,
            dirichlet: f.dirichlet,
            poisson: f.poisson,
            zero_rhs: f.zero_rhs,
            h,
            t,
            laplacian,
            params: *params,
            point_cloud,
            factor_len,
        }
    }

    /// True for a solver built on a point cloud ([`GeodesicSolver::from_point_cloud`]).
    pub fn is_point_cloud(&self) -> bool {
        self.point_cloud
    }

    /// For a point cloud: its points with the triangle union of its Laplacian, oriented
    /// consistently (to draw a distance on); `None` for a mesh or a cloud without
    /// triangles.
    pub fn point_cloud_mesh(&self) -> Option<Mesh> {
        if !self.point_cloud {
            return None;
        }
        let cloud = PointCloud::new(self.positions.clone(), None).ok()?;
        crate::analysis::points::connectivity_mesh(&cloud, self.triangles.clone())
    }

    /// Number of vertices.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The mean edge length `h` in `t = m h^2`.
    pub fn mean_edge_length(&self) -> f64 {
        self.h
    }

    /// The time step `t = m h^2`.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The Laplacian the solver uses.
    pub fn laplacian(&self) -> Laplacian {
        self.laplacian
    }

    /// The parameters.
    pub fn params(&self) -> &GeodesicParams {
        &self.params
    }

    /// True when Crane's boundary rule is in use (a mesh with boundary, [`Convention::Crane`]).
    pub fn averages_boundary(&self) -> bool {
        self.dirichlet.is_some()
    }

    /// Number of connected components (through triangles).
    pub fn n_components(&self) -> usize {
        self.n_components
    }

    /// Values held by the factors (8 bytes each).
    pub fn factor_len(&self) -> usize {
        self.factor_len
    }

    /// Approximate memory held by the solver, in bytes.
    pub fn memory_bytes(&self) -> usize {
        8 * self.factor_len
            + self.gradient.memory_bytes()
            + self.triangles.len() * 24
            + self.positions.len() * 24
            + self.component.len() * 8
    }

    /// Vertices whose distance from `sources` is infinite: those on components without a
    /// source, and vertices no triangle uses. Checks the sources first.
    pub fn unreachable(&self, sources: &[Source]) -> Result<usize, GeodesicError> {
        let rhs = self.prepare(sources)?;
        Ok((0..self.n)
            .filter(|&v| {
                let c = self.component[v];
                c == usize::MAX || !rhs.has_component[c]
            })
            .count())
    }

    /// Distance from the set `sources` (the distance to the nearest of them) at every
    /// vertex; `f64::INFINITY` where no source can be reached.
    pub fn distance(&self, sources: &[Source]) -> Result<Vec<f64>, GeodesicError> {
        let rhs = self.prepare(sources)?;
        Ok(self
            .solve_block(std::slice::from_ref(&rhs))
            .pop()
            .unwrap_or_default())
    }

    /// Distance from one vertex.
    pub fn distance_from_vertex(&self, v: usize) -> Result<Vec<f64>, GeodesicError> {
        self.distance(&[Source::Vertex(v)])
    }

    /// Distances from several source sets at once (block right-hand sides, columns split
    /// over the rayon pool): one vector per set.
    pub fn distances(&self, sets: &[Vec<Source>]) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let rhs: Vec<Rhs> = sets
            .iter()
            .map(|s| self.prepare(s))
            .collect::<Result<_, _>>()?;
        let mut out = Vec::with_capacity(sets.len());
        for chunk in rhs.chunks(BLOCK) {
            out.extend(self.solve_block(chunk));
        }
        Ok(out)
    }

    /// Distances from each vertex of `vertices` on its own: one vector per vertex.
    pub fn distances_from_vertices(
        &self,
        vertices: &[usize],
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let sets: Vec<Vec<Source>> = vertices.iter().map(|&v| vec![Source::Vertex(v)]).collect();
        self.distances(&sets)
    }

    /// The `k x k` matrix of distances between the vertices `samples`: row `i` holds the
    /// distance from `samples[i]` at every sample. The heat method is not exactly
    /// symmetric; with `symmetric` the matrix is replaced by `(D + D^T) / 2`.
    pub fn distance_matrix(
        &self,
        samples: &[usize],
        symmetric: bool,
    ) -> Result<Vec<Vec<f64>>, GeodesicError> {
        let k = samples.len();
        let mut d = vec![vec![0.0; k]; k];
        for (c, chunk) in samples.chunks(BLOCK).enumerate() {
            let rows = self.distances_from_vertices(chunk)?;
            for (i, row) in rows.iter().enumerate() {
                for (j, &s) in samples.iter().enumerate() {
                    d[c * BLOCK + i][j] = row[s];
                }
            }
        }
        if symmetric {
            for i in 0..k {
                for j in 0..i {
                    let m = 0.5 * (d[i][j] + d[j][i]);
                    d[i][j] = m;
                    d[j][i] = m;
                }
            }
        }
        Ok(d)
    }

    /// Checks a source set and turns it into the heat right-hand side and the shift data.
    fn prepare(&self, sources: &[Source]) -> Result<Rhs, GeodesicError> {
        if sources.is_empty() {
            return Err(GeodesicError::NoSources);
        }
        let mut points = Vec::with_capacity(sources.len());
        let mut has_component = vec![false; self.n_components];
        for s in sources {
            let (verts, bary, lengths) = match *s {
                Source::Vertex(v) => {
                    if v >= self.n {
                        return Err(GeodesicError::VertexOutOfRange {
                            vertex: v,
                            n: self.n,
                        });
                    }
                    if self.component[v] == usize::MAX {
                        return Err(GeodesicError::IsolatedVertex { vertex: v });
                    }
                    ([v, v, v], [1.0, 0.0, 0.0], [0.0; 3])
                }
                Source::FacePoint { face, .. } if self.point_cloud => {
                    return Err(GeodesicError::FacePointOnCloud { face });
                }
                Source::FacePoint { face, bary } => {
                    let Some(&tri) = self.triangles.get(face) else {
                        return Err(GeodesicError::FaceOutOfRange {
                            face,
                            m: self.triangles.len(),
                        });
                    };
                    let sum: f64 = bary.iter().sum();
                    if bary.iter().any(|b| !b.is_finite() || *b < 0.0)
                        || !(sum > 0.0 && sum.is_finite())
                    {
                        return Err(GeodesicError::BadBarycentric { face, bary });
                    }
                    let b = bary.map(|x| x / sum);
                    let p = tri.map(|v| self.positions[v]);
                    let l = std::array::from_fn(|k| {
                        crate::mesh::norm(crate::mesh::sub(p[(k + 1) % 3], p[k]))
                    });
                    (tri, b, l)
                }
            };
            has_component[self.component[verts[0]]] = true;
            points.push(SourcePoint {
                verts,
                bary,
                lengths,
            });
        }
        Ok(Rhs {
            points,
            has_component,
        })
    }

    /// Heat, direction, Poisson and shift for up to [`BLOCK`] source sets.
    fn solve_block(&self, rhs: &[Rhs]) -> Vec<Vec<f64>> {
        let n = self.n;
        let k = rhs.len();
        let mut u = vec![0.0; n * k];
        for (c, r) in rhs.iter().enumerate() {
            for p in &r.points {
                for i in 0..3 {
                    u[c * n + p.verts[i]] += p.bary[i];
                }
            }
        }
        let delta = self.dirichlet.as_ref().map(|_| u.clone());
        self.heat.solve_many_in_place(&mut u, k);
        if let (Some((interior, chol)), Some(delta)) = (&self.dirichlet, delta) {
            let ni = interior.len();
            let mut ud = vec![0.0; ni * k];
            for c in 0..k {
                for (i, &v) in interior.iter().enumerate() {
                    ud[c * ni + i] = delta[c * n + v];
                }
            }
            chol.solve_many_in_place(&mut ud, k);
            u.par_chunks_mut(n)
                .zip(ud.par_chunks(ni))
                .for_each(|(col, d)| {
                    for x in col.iter_mut() {
                        *x *= 0.5;
                    }
                    for (i, &v) in interior.iter().enumerate() {
                        col[v] += 0.5 * d[i];
                    }
                });
        }
        // Direction field and its divergence, one column per task.
        let mut phi = vec![0.0; n * k];
        match &self.gradient {
            Gradient::Triangles(frames) => {
                // Groups of LANES columns, each group's triangles read once (by rows).
                phi.par_chunks_mut(n * LANES)
                    .zip(u.par_chunks(n * LANES))
                    .for_each(|(dcols, ucols)| {
                        let w = ucols.len() / n.max(1);
                        let mut ur = vec![[0.0; LANES]; n];
                        for c in 0..w {
                            for (i, r) in ur.iter_mut().enumerate() {
                                r[c] = ucols[c * n + i];
                            }
                        }
                        let mut dr = vec![[0.0; LANES]; n];
                        frames.normalized_divergence_rows(&ur, &mut dr);
                        for c in 0..w {
                            for (i, r) in dr.iter().enumerate() {
                                dcols[c * n + i] = r[c];
                            }
                        }
                    });
            }
            Gradient::Tangent(g) => {
                phi.par_chunks_mut(n)
                    .zip(u.par_chunks(n))
                    .for_each(|(div, col)| g.normalized_divergence(col, div));
            }
        }
        for div in phi.chunks_mut(n) {
            for &v in &self.zero_rhs {
                div[v] = 0.0;
            }
        }
        drop(u);
        self.poisson.solve_many_in_place(&mut phi, k);
        phi.par_chunks_mut(n)
            .zip(rhs.par_iter())
            .for_each(|(col, r)| self.shift(col, r));
        phi.chunks(n).map(|c| c.to_vec()).collect()
    }

    /// Shifts each component so that the weighted mean over its sources is 0; infinity on
    /// components without a source and on unused vertices.
    fn shift(&self, phi: &mut [f64], r: &Rhs) {
        let nc = self.n_components;
        let mut diff = vec![0.0; nc];
        let mut weight = vec![0.0; nc];
        let cloud = match &self.gradient {
            Gradient::Tangent(g) => Some(g),
            Gradient::Triangles(_) => None,
        };
        for p in &r.points {
            let c = self.component[p.verts[0]];
            if let Some(g) = cloud {
                // A point source: over its gradient stencil (the point and its gradient
                // neighbours), each expected at its straight distance from the source
                // (phi at the source alone can be off by a local oscillation).
                let v = p.verts[0];
                let pv = self.positions[v];
                for &j in std::iter::once(&v).chain(g.neighbors(v)) {
                    let expected = crate::mesh::norm(crate::mesh::sub(self.positions[j], pv));
                    diff[c] += phi[j] - expected;
                    weight[c] += 1.0;
                }
                continue;
            }
            for i in 0..3 {
                let w = p.bary[i];
                if w == 0.0 {
                    continue;
                }
                let mut corner = [0.0; 3];
                corner[i] = 1.0;
                let expected = bary_distance(p.bary, corner, p.lengths);
                diff[c] += w * (phi[p.verts[i]] - expected);
                weight[c] += w;
            }
        }
        for (v, x) in phi.iter_mut().enumerate() {
            let c = self.component[v];
            if c == usize::MAX || weight[c] == 0.0 {
                *x = f64::INFINITY;
            } else {
                *x -= diff[c] / weight[c];
                if cloud.is_some() {
                    // The stencil shift leaves values near the source slightly off 0.
                    *x = x.max(0.0);
                }
            }
        }
        if cloud.is_some() {
            for p in &r.points {
                phi[p.verts[0]] = 0.0;
            }
        }
    }
}

/// One source point: its corners, barycentric weights and the triangle's edge lengths
/// `[|v0 v1|, |v1 v2|, |v2 v0|]` (a vertex source: weight 1 at corner 0).
#[derive(Debug, Clone)]
struct SourcePoint {
    verts: [usize; 3],
    bary: [f64; 3],
    lengths: [f64; 3],
}

/// A checked source set.
#[derive(Debug, Clone)]
struct Rhs {
    points: Vec<SourcePoint>,
    has_component: Vec<bool>,
}

/// Distance between two points of a triangle given by barycentric coordinates:
/// `|P - Q|^2 = -sum over edges (i, j) of l_ij^2 d_i d_j`, `d = b2 - b1`.
fn bary_distance(b1: [f64; 3], b2: [f64; 3], l: [f64; 3]) -> f64 {
    let d: [f64; 3] = std::array::from_fn(|i| b2[i] - b1[i]);
    let mut s = 0.0;
    for i in 0..3 {
        s += l[i] * l[i] * d[i] * d[(i + 1) % 3];
    }
    if s <= 0.0 { (-s).sqrt() } else { 0.0 }
}

/// Refuses a time factor that is not finite and `> 0`.
fn check_time_factor(params: &GeodesicParams) -> Result<(), GeodesicError> {
    if params.time_factor.is_finite() && params.time_factor > 0.0 {
        Ok(())
    } else {
        Err(GeodesicError::BadParameter(format!(
            "the heat-method time factor m (t = m h^2) must be a finite number > 0, got {}",
            params.time_factor
        )))
    }
}

/// Mean length of the distinct edges of `triangles` over `positions` (0 without edges).
fn mean_edge_length_of(positions: &[[f64; 3]], triangles: &[[usize; 3]]) -> f64 {
    let mut e = crate::mesh::sorted_edges(triangles);
    e.dedup();
    let s: f64 = e
        .iter()
        .map(|&(a, b)| crate::mesh::norm(crate::mesh::sub(positions[a], positions[b])))
        .sum();
    if e.is_empty() {
        0.0
    } else {
        s / e.len() as f64
    }
}

/// Mean distance of each point to its nearest other point (0 for a single point).
fn mean_nearest_distance(positions: &[[f64; 3]]) -> f64 {
    let nb = crate::operators::point_cloud::nearest_neighbors(positions, 1);
    let d: Vec<f64> = nb
        .iter()
        .enumerate()
        .filter_map(|(i, j)| {
            j.first()
                .map(|&j| crate::mesh::norm(crate::mesh::sub(positions[i], positions[j])))
        })
        .collect();
    if d.is_empty() {
        0.0
    } else {
        d.iter().sum::<f64>() / d.len() as f64
    }
}

/// Mean length of the distinct edges of `mesh` (geometry-central's mean over the mesh's
/// edges).
pub fn distinct_mean_edge_length(mesh: &Mesh) -> f64 {
    mean_edge_length_of(mesh.positions(), mesh.triangles())
}

/// `true` for the vertices of edges with exactly one triangle.
fn boundary_vertices(mesh: &Mesh) -> Vec<bool> {
    let e = crate::mesh::sorted_edges(mesh.triangles());
    let mut out = vec![false; mesh.n_vertices()];
    let mut i = 0;
    while i < e.len() {
        let mut j = i + 1;
        while j < e.len() && e[j] == e[i] {
            j += 1;
        }
        if j - i == 1 {
            out[e[i].0] = true;
            out[e[i].1] = true;
        }
        i = j;
    }
    out
}
