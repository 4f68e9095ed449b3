//! An analysis: one shape, its operators for one discretization, the factorization, an
//! eigenbasis that grows with `k`, and the heat and harmonic solvers, answering any
//! [`FieldRequest`] (geometry-central's pattern: factor once, answer many queries).
//!
//! Every face (CLI, web app, Python, batch) builds an [`Analysis`] and asks it for fields;
//! no face computes a field itself, so they all give the same numbers for the same
//! parameters.
//!
//! # Scale normalisation
//!
//! With [`AnalysisOptions::normalize`] (the default) the shape is analysed as if scaled to
//! total mass 1 (unit area for the area-based masses; `n` for the identity mass of `cot`
//! and `uniform`): the operators are `(S, B / A)` with `A = 1^T B 1`, so eigenvalues are
//! `lambda * A`, eigenvectors `x * sqrt(A)`, and every time `t` is a time on the unit-area
//! shape. The cotangent stiffness is scale-invariant, so nothing else changes. Without it
//! the shape is used as given (what `eigs` saves, comparable to SciPy on the raw operators).
//!
//! # Point clouds
//!
//! [`Analysis::from_input`] takes a mesh or a point cloud ([`AnalysisInput`]). A cloud is
//! analysed with the point-cloud Laplacian ([`crate::operators::point_cloud`], the
//! discretization [`Laplacian::Robust`]); its [`Analysis::mesh`] is the triangle union of
//! that Laplacian (see [`points`] for why, and for what critical points mean on a cloud),
//! and [`Analysis::point_cloud`] gives the points back. Every field request works on both.
//!
//! # Threads
//!
//! An `Analysis` is `Send + Sync`: fields are computed from a snapshot of the held basis
//! without holding a lock, so a web server can answer field requests while a larger basis
//! is being computed.

mod eval;
pub mod hint;
pub mod memory;
pub mod points;
pub mod request;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock, RwLock};

pub use hint::{TRUNCATION_RATIO_WARNING, TruncationHint};
pub use points::AnalysisInput;
pub use request::{
    Constraints, DistanceSpec, FieldRequest, Kernel, RequestError, Signal, SignatureSpec,
};

use crate::cancel::CancelToken;
use crate::fields::critical_points::{
    BoundaryRule, CriticalPointFinder, CriticalPoints, CriticalPointsError, FLAT_RELATIVE_TOLERANCE,
};
use crate::fields::harmonic::{Constraint, FloatingComponent, HarmonicError, HarmonicSolver};
use crate::fields::persistence::{
    Persistence, PersistencePair, PersistenceThresholds, persistence,
};
use crate::fields::segmentation::SegmentationError;
use crate::geodesic::{GeodesicError, GeodesicParams, GeodesicSolver};
use crate::linalg::EigenProgress;
use crate::mesh::topology::{Topology, VertexComponents};
use crate::mesh::{Mesh, PointCloud};
use crate::operators::robust::RobustError;
use crate::operators::{Laplacian, Operators, PointCloudParams, point_cloud_laplacian};
use crate::spectral::Eigenbasis;
use crate::spectral::distances::DistanceError;
use crate::spectral::eigenbasis::{EigenError, EigenParams, EigenSolver};
use crate::spectral::heat::HeatError;
use crate::spectral::signatures::SignatureError;

crate::defaults::declare::with_defaults! {
    /// How an analysis is set up. `Default` is the paper's: linear FEM, unit-area times, the
    /// eigensolver's defaults.
    #[derive(Debug, Clone, PartialEq)]
    pub struct AnalysisOptions {
        /// The discretization (default fem).
        pub laplacian: Laplacian = Laplacian::Fem,
        /// Analyse the shape scaled to unit total mass (default `true`; see the module
        /// documentation).
        pub normalize: bool = crate::defaults::values::NORMALIZE,
        /// Eigensolver parameters (tolerance, seed, method, Dirichlet vertices); `k` is ignored
        /// (each request names its own).
        pub eigen: EigenParams = EigenParams::default(),
    }
}

/// Errors of an analysis, each saying what to change.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum AnalysisError {
    /// A request parameter is out of range.
    #[error(transparent)]
    Request(#[from] RequestError),
    /// A vertex index is out of range.
    #[error("{key} {vertex} is out of range: the mesh has {n} vertices")]
    VertexOutOfRange {
        /// The key naming it (`source`, `anchor`, `vertex`, ...).
        key: &'static str,
        /// The index given.
        vertex: usize,
        /// Vertices.
        n: usize,
    },
    /// More eigenpairs than vertices.
    #[error("k = {k} eigenpairs asked for, but the mesh has only {n} vertices")]
    TooManyPairs {
        /// Pairs asked for.
        k: usize,
        /// Vertices.
        n: usize,
    },
    /// A per-vertex input has the wrong length.
    #[error("{key} has {got} values but the mesh has {n} vertices")]
    LengthMismatch {
        /// The key.
        key: &'static str,
        /// Values given.
        got: usize,
        /// Vertices.
        n: usize,
    },
    /// The eigenbasis could not be computed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// A harmonic map could not be computed.
    #[error(transparent)]
    Harmonic(#[from] HarmonicError),
    /// A heat kernel quantity could not be computed.
    #[error(transparent)]
    Heat(#[from] HeatError),
    /// A distance or filter could not be computed.
    #[error(transparent)]
    Distance(#[from] DistanceError),
    /// A signature could not be computed.
    #[error(transparent)]
    Signature(#[from] SignatureError),
    /// A segmentation could not be computed.
    #[error(transparent)]
    Segmentation(#[from] SegmentationError),
    /// Critical points could not be classified.
    #[error(transparent)]
    CriticalPoints(#[from] CriticalPointsError),
    /// A geodesic distance could not be computed (a source on no triangle, a Laplacian
    /// without a gradient, a failed factorization).
    #[error("geodesic distance: {0}")]
    Geodesic(#[from] GeodesicError),
    /// The held basis has fewer pairs than the request uses.
    #[error("the request uses k = {k} eigenpairs but the basis holds {held}")]
    BasisTooSmall {
        /// Pairs the request uses.
        k: usize,
        /// Pairs held.
        held: usize,
    },
    /// A spectral request reached evaluation without a basis (an internal error).
    #[error("internal error: a spectral field was evaluated without an eigenbasis")]
    NoBasis,
    /// A discretization that needs triangles was asked for on a point cloud.
    #[error(
        "the {laplacian} Laplacian needs triangles and does not apply to a point cloud: use robust (the point-cloud Laplacian)"
    )]
    NotForPoints {
        /// The discretization asked for.
        laplacian: Laplacian,
    },
    /// The point-cloud Laplacian's parameters are out of range.
    #[error("point-cloud Laplacian: {0}")]
    PointCloud(#[from] RobustError),
    /// The local triangulations of a point cloud found no triangle.
    #[error(
        "the point cloud ({n} points) has no triangle in its local triangulations: its points are collinear or coincident"
    )]
    NoTriangles {
        /// Points.
        n: usize,
    },
    /// The field came out with non-finite values.
    #[error(
        "the {kind} field has non-finite values (at vertex {vertex}): try a larger t, fewer pairs or another filter"
    )]
    NonFinite {
        /// The request kind.
        kind: &'static str,
        /// First vertex with a non-finite value.
        vertex: usize,
    },
}

/// A computed field and what a face needs to show or save it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Field {
    /// One value per vertex (`n` values).
    pub values: Vec<f64>,
    /// The request with every default resolved (the source or anchor filled in): saving
    /// this replays the same field.
    pub request: FieldRequest,
    /// Vertices to mark: the source or anchor, or the constrained vertices.
    pub marks: Vec<usize>,
    /// The resolved constraints of a harmonic map (empty otherwise).
    pub constraints: Vec<Constraint>,
    /// Components of a harmonic map that hold no constraint (they hold the mean of the
    /// constraint values; see [`FloatingComponent`]).
    pub floating: Vec<FloatingComponent>,
    /// Patch labels of a segmentation (`n` entries), `None` otherwise.
    pub labels: Option<Vec<usize>>,
    /// Components (as in [`Topology::components`]; `usize::MAX` for vertices no triangle
    /// uses) that the sources of a geodesic distance cannot reach: the values there are
    /// `+inf`, and they have no critical points or level sets. Empty otherwise.
    pub unreachable: Vec<usize>,
    /// Vertices whose value is `+inf` (those of `unreachable`).
    pub unreachable_vertices: usize,
    /// Eigenpairs used (`None` when no basis was used).
    pub k: Option<usize>,
    /// Eigenpairs the basis held when the field was computed (the first `k` were used).
    pub basis_k: Option<usize>,
    /// True when the values are those of the shape scaled to unit area (never for a
    /// geodesic distance, which is in the mesh's units).
    pub normalized: bool,
}

impl Field {
    /// The smallest and largest finite values (`None` when no value is finite): the range
    /// of colour maps and level sets, leaving out a geodesic distance's `+inf`.
    pub fn finite_range(&self) -> Option<(f64, f64)> {
        self.values
            .iter()
            .filter(|v| v.is_finite())
            .fold(None, |r, &v| match r {
                None => Some((v, v)),
                Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
            })
    }

    /// What every face says of a field with unreachable vertices (`None` when every value
    /// is finite): how many vertices, on how many components, have an infinite distance.
    pub fn unreachable_message(&self) -> Option<String> {
        if self.unreachable_vertices == 0 {
            return None;
        }
        let comps = self
            .unreachable
            .iter()
            .filter(|&&c| c != usize::MAX)
            .count();
        let loose = self.unreachable.contains(&usize::MAX);
        Some(format!(
            "{} of {} vertices cannot be reached from the sources ({comps} component{} without a source{}): their geodesic distance is infinite (inf), with no level sets or critical points there",
            self.unreachable_vertices,
            self.values.len(),
            if comps == 1 { "" } else { "s" },
            if loose {
                ", and vertices in no triangle"
            } else {
                ""
            },
        ))
    }
}

/// An analysis (see the module documentation).
pub struct Analysis {
    /// The mesh, or the triangle union of a point cloud's Laplacian.
    mesh: Arc<Mesh>,
    /// The point cloud, when the input was one.
    cloud: Option<Arc<PointCloud>>,
    options: AnalysisOptions,
    /// `1^T B 1` of the operators as assembled (before normalisation).
    input_mass: f64,
    ops: Arc<Operators>,
    topology: OnceLock<Topology>,
    /// The vertex components (built on first use, see [`Analysis::components`]).
    components: OnceLock<VertexComponents>,
    /// The link edges of every vertex, for critical points (built on first use).
    critical: OnceLock<CriticalPointFinder>,
    solver: Mutex<EigenSolver>,
    held: RwLock<Option<Arc<Eigenbasis>>>,
    /// `B X` of the held basis, computed on first use by the wFEM distance.
    bx: Mutex<Option<BxCache>>,
    /// The last few harmonic solvers: (order, constrained vertices ascending, solver).
    harmonic: Mutex<Vec<HarmonicEntry>>,
    /// The last few heat-method solvers, by their parameters (each holds its factors).
    geodesic: Mutex<Vec<(GeodesicParams, Arc<GeodesicSolver>)>>,
    /// Values of the eigensolver's kept factorizations, as of its last solve (read
    /// without waiting for a running solve).
    factor_len: AtomicUsize,
}

/// The basis `B X` was computed from, and `B X`.
type BxCache = (Arc<Eigenbasis>, Arc<Vec<f64>>);
/// (order, constrained vertices ascending, solver).
type HarmonicEntry = (u32, Vec<usize>, Arc<HarmonicSolver>);

/// Harmonic solvers kept per analysis (each holds a factorization).
const HARMONIC_CACHE: usize = 4;
/// Heat-method solvers kept per analysis (each holds two or three factorizations).
const GEODESIC_CACHE: usize = 2;

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic elsewhere while holding the lock leaves plain data behind; keep serving.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl std::fmt::Debug for Analysis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Analysis")
            .field("n", &self.mesh.n_vertices())
            .field("options", &self.options)
            .field("held_k", &self.held_basis().map(|b| b.k()))
            .finish()
    }
}

impl Analysis {
    /// Assembles the operators of `mesh` for `options` (cheap: O(n)); nothing is factored
    /// until a request needs it.
    pub fn new(mesh: impl Into<Arc<Mesh>>, options: AnalysisOptions) -> Self {
        let mesh = mesh.into();
        let ops = Operators::new(&mesh, options.laplacian);
        Self::with_operators(mesh, ops, options)
    }

    /// An analysis over operators built elsewhere (e.g. a robust or point-cloud Laplacian
    /// of the same vertices). `ops` must be `n x n` for the mesh's `n` vertices.
    pub fn with_operators(
        mesh: impl Into<Arc<Mesh>>,
        mut ops: Operators,
        options: AnalysisOptions,
    ) -> Self {
        let mesh = mesh.into();
        let input_mass = ops.normalize_mass(options.normalize);
        let ops = Arc::new(ops);
        let solver = EigenSolver::new(ops.clone(), options.eigen.clone());
        Self {
            mesh,
            cloud: None,
            options,
            input_mass,
            ops,
            topology: OnceLock::new(),
            components: OnceLock::new(),
            critical: OnceLock::new(),
            solver: Mutex::new(solver),
            held: RwLock::new(None),
            bx: Mutex::new(None),
            harmonic: Mutex::new(Vec::new()),
            geodesic: Mutex::new(Vec::new()),
            factor_len: AtomicUsize::new(0),
        }
    }

    /// An analysis of a mesh or a point cloud: [`Analysis::new`] for a mesh,
    /// [`Analysis::from_points`] for a cloud. The one constructor every face can use for
    /// whatever the user gave (`Analysis::from_input(io::read_input(path)?, options)`).
    pub fn from_input(
        input: impl Into<AnalysisInput>,
        options: AnalysisOptions,
    ) -> Result<Self, AnalysisError> {
        match input.into() {
            AnalysisInput::Mesh(m) => Ok(Self::new(m, options)),
            AnalysisInput::Points { cloud, params } => Self::from_points(cloud, &params, options),
        }
    }

    /// An analysis of a point cloud with its point-cloud Laplacian (built now: O(n k log n)
    /// for `k` neighbours). `options.laplacian` must be [`Laplacian::Robust`]
    /// ([`AnalysisError::NotForPoints`] otherwise). The connectivity ([`Analysis::mesh`]) is
    /// the Laplacian's triangle union, oriented consistently (see [`points`]).
    pub fn from_points(
        cloud: impl Into<Arc<PointCloud>>,
        params: &PointCloudParams,
        options: AnalysisOptions,
    ) -> Result<Self, AnalysisError> {
        if options.laplacian != Laplacian::Robust {
            return Err(AnalysisError::NotForPoints {
                laplacian: options.laplacian,
            });
        }
        let cloud: Arc<PointCloud> = cloud.into();
        let r = point_cloud_laplacian(&cloud, params)?;
        let mesh =
            points::connectivity_mesh(&cloud, r.triangles).ok_or(AnalysisError::NoTriangles {
                n: cloud.n_points(),
            })?;
        let ops = Operators {
            laplacian: Laplacian::Robust,
            stiffness: r.stiffness,
            mass: r.mass,
        };
        let mut an = Self::with_operators(mesh, ops, options);
        an.cloud = Some(cloud);
        Ok(an)
    }

    /// The point cloud, when the analysis is of one.
    pub fn point_cloud(&self) -> Option<&PointCloud> {
        self.cloud.as_deref()
    }

    /// True when the analysis is of a point cloud.
    pub fn is_point_cloud(&self) -> bool {
        self.cloud.is_some()
    }

    /// The mean neighbour spacing of a point cloud (the mean edge length of its triangle
    /// union; pictures size their discs from it), `None` for a mesh.
    pub fn point_spacing(&self) -> Option<f64> {
        self.cloud.as_ref().map(|_| self.mesh.mean_edge_length())
    }

    /// The shape: the mesh, or for a point cloud the triangle union of its Laplacian (the
    /// points are its vertices, in the same order).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The shape, shared.
    pub fn mesh_arc(&self) -> &Arc<Mesh> {
        &self.mesh
    }

    /// The options.
    pub fn options(&self) -> &AnalysisOptions {
        &self.options
    }

    /// The operators in use: `(S, B)`, or `(S, B / A)` when normalizing.
    pub fn operators(&self) -> &Operators {
        &self.ops
    }

    /// `A = 1^T B 1` of the mass as assembled (the area for area-based masses): the
    /// factor of the normalisation.
    pub fn input_total_mass(&self) -> f64 {
        self.input_mass
    }

    /// Number of vertices.
    pub fn n(&self) -> usize {
        self.mesh.n_vertices()
    }

    /// The connectivity (computed on first use).
    pub fn topology(&self) -> &Topology {
        self.topology.get_or_init(|| Topology::new(&self.mesh))
    }

    /// The vertex components (computed on first use: from the topology when that exists,
    /// else on their own, which is much cheaper than the whole topology).
    pub fn components(&self) -> &VertexComponents {
        self.components.get_or_init(|| match self.topology.get() {
            Some(t) => VertexComponents {
                of_vertex: t.vertex_component.clone(),
                count: t.n_components(),
            },
            None => VertexComponents::new(&self.mesh),
        })
    }

    /// The default source or anchor: the vertex of largest x (lowest index on ties).
    pub fn default_source(&self) -> usize {
        self.mesh.vertex_of_largest_x()
    }

    /// The basis held, if any (no lock is held on return).
    pub fn held_basis(&self) -> Option<Arc<Eigenbasis>> {
        self.held.read().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// Eigenpairs held (0 when none).
    pub fn held_k(&self) -> usize {
        self.held_basis().map_or(0, |b| b.k())
    }

    /// How many times the shifted pencil was factored for eigenbases (a counter).
    pub fn factorizations(&self) -> usize {
        lock(&self.solver).factorizations()
    }

    /// A basis of at least `k` pairs: the held one when it has enough, else `k` pairs
    /// computed (reusing the factorization; see [`EigenSolver`]).
    pub fn basis(
        &self,
        k: usize,
        progress: &mut dyn FnMut(EigenProgress),
        cancel: &CancelToken,
    ) -> Result<Arc<Eigenbasis>, AnalysisError> {
        let n = self.n();
        if k == 0 {
            return Err(EigenError::Zero.into());
        }
        if k > n {
            return Err(AnalysisError::TooManyPairs { k, n });
        }
        if let Some(b) = self.held_basis()
            && b.k() >= k
        {
            return Ok(b);
        }
        let mut solver = lock(&self.solver);
        let solved = solver.solve(k, progress, cancel);
        // A factorization made before a cancellation or failure is kept too.
        self.factor_len
            .store(solver.factor_len(), Ordering::Relaxed);
        drop(solver);
        let b = solved?;
        *self.held.write().unwrap_or_else(|p| p.into_inner()) = Some(b.clone());
        Ok(b)
    }

    /// Installs a basis computed elsewhere (e.g. loaded from a saved `.npz` of the same
    /// mesh, discretization and normalisation). It must have `n` vertices.
    pub fn set_basis(&self, basis: Eigenbasis) -> Result<(), AnalysisError> {
        if basis.n != self.n() {
            return Err(AnalysisError::LengthMismatch {
                key: "basis",
                got: basis.n,
                n: self.n(),
            });
        }
        *self.held.write().unwrap_or_else(|p| p.into_inner()) = Some(Arc::new(basis));
        Ok(())
    }

    /// Values of the eigensolver's kept factorization (8 bytes each), as of its last
    /// solve: 0 before the first sparse solve (never waits for a running one).
    pub fn factor_len(&self) -> usize {
        self.factor_len.load(Ordering::Relaxed)
    }

    /// Bytes the analysis holds, counted from the lengths of its arrays (8 bytes per
    /// value, 8 per index): the operators, the eigensolver's kept factorization (its
    /// values only), the held basis (vectors `n x k` and its copy of the mass matrix), the
    /// `B X` cache of the wFEM distance, the kept harmonic solvers, and the connectivity
    /// and critical-point links once built. Allocator overhead and the factor's symbolic
    /// analysis are not counted. Never waits for a running eigenbasis computation (the
    /// factorization counted is the one of the last finished or cancelled solve).
    pub fn memory_bytes(&self) -> usize {
        let n = self.n();
        let m = self.mesh.n_triangles();
        let sparse = |a: &crate::linalg::sparse::SparseMatrix| a.nnz() * 16 + (a.ncols() + 1) * 8;
        let ops = sparse(&self.ops.stiffness) + sparse(&self.ops.mass);
        let factor = self.factor_len() * 8;
        let basis = self.held_basis().map_or(0, |b| {
            (b.vectors.len() + b.values.len() + b.residuals.len()) * 8 + sparse(&b.mass)
        });
        let bx = lock(&self.bx).as_ref().map_or(0, |(_, v)| v.len() * 8);
        let harmonic: usize = lock(&self.harmonic)
            .iter()
            .map(|(_, v, s)| v.len() * 8 + s.memory_bytes())
            .sum();
        let geodesic: usize = lock(&self.geodesic)
            .iter()
            .map(|(_, s)| s.memory_bytes())
            .sum();
        let topology = self.topology.get().map_or(0, |t| {
            t.edges.len() * 20
                + (t.vertex_component.len() + t.triangle_component.len()) * 8
                + t.boundary_loops
                    .iter()
                    .map(|l| l.len() * 8 + 24)
                    .sum::<usize>()
        });
        let components = self.components.get().map_or(0, |c| c.of_vertex.len() * 8);
        // Link edges: one per triangle corner (two indices each), offsets, flags.
        let critical = self
            .critical
            .get()
            .map_or(0, |_| 3 * m * 16 + (n + 1) * 8 + n);
        ops + factor + basis + bx + harmonic + geodesic + topology + components + critical
    }

    /// The field of `request`, computing the eigenbasis first when the held one is too
    /// small (no progress report; see [`Analysis::field_with`]).
    pub fn field(&self, request: &FieldRequest) -> Result<Field, AnalysisError> {
        self.field_with(request, &mut |_| {}, &CancelToken::new())
    }

    /// [`Analysis::field`] with progress and cancellation of the eigenbasis computation.
    pub fn field_with(
        &self,
        request: &FieldRequest,
        progress: &mut dyn FnMut(EigenProgress),
        cancel: &CancelToken,
    ) -> Result<Field, AnalysisError> {
        request.validate()?;
        let basis = match request.eigenpairs() {
            Some(k) => Some(self.basis(k, progress, cancel)?),
            None => None,
        };
        eval::evaluate(self, request, basis.as_deref())
    }

    /// The field of `request` from the held basis only: `Ok(None)` when the request needs
    /// more pairs than are held (the web app's fast path: it never waits for a solve).
    pub fn field_if_ready(&self, request: &FieldRequest) -> Result<Option<Field>, AnalysisError> {
        request.validate()?;
        let basis = match request.eigenpairs() {
            Some(k) => {
                if k > self.n() {
                    return Err(AnalysisError::TooManyPairs { k, n: self.n() });
                }
                match self.held_basis().filter(|b| b.k() >= k) {
                    Some(b) => Some(b),
                    None => return Ok(None),
                }
            }
            None => None,
        };
        eval::evaluate(self, request, basis.as_deref()).map(Some)
    }

    /// The values a diffusion of `signal` starts from (`n` entries): the given values, the
    /// ball's indicator or the impulse. Vertices and lengths are checked as by
    /// [`Analysis::field`].
    pub fn signal(&self, signal: &Signal) -> Result<Vec<f64>, AnalysisError> {
        eval::signal_values(self, signal).map(|(f, _)| f)
    }

    /// `1^T B f` with the analysis' mass (normalised when normalizing).
    pub fn mass_of(&self, f: &[f64]) -> f64 {
        self.ops.mass.mul_vec(f).iter().sum()
    }

    /// The critical points of per-vertex values on this mesh, with the Euler check of its
    /// topology.
    pub fn critical_points(&self, values: &[f64]) -> Result<CriticalReport, AnalysisError> {
        let p = self.find_critical_points(values)?;
        Ok(CriticalReport::new(p, self.topology(), &[]))
    }

    /// The critical points of a computed field: the components a harmonic map left
    /// unconstrained (their constant values have no critical points) and those a
    /// geodesic distance cannot reach (infinite there) are left out.
    pub fn field_critical_points(&self, field: &Field) -> Result<CriticalReport, AnalysisError> {
        let values = crate::fields::persistence::finite_for_critical(&field.values);
        let p = self.find_critical_points(&values)?;
        let mut excluded: Vec<usize> = field.floating.iter().map(|c| c.component).collect();
        excluded.extend(field.unreachable.iter().filter(|&&c| c != usize::MAX));
        Ok(CriticalReport::new(p, self.topology(), &excluded))
    }

    /// How much the truncation of a heat or diffusion field weighs (the time of the
    /// request against the held eigenvalues; see [`TruncationHint`]); `None` for fields
    /// without a time or a basis.
    pub fn truncation_hint(&self, field: &Field) -> Option<TruncationHint> {
        let t = field.request.time()?;
        let k = field.k?;
        let basis = self.held_basis()?;
        TruncationHint::new(&basis.values, k, t, self.n())
    }

    /// The critical points of `values` with their persistence, with the link edges built
    /// once per analysis.
    fn find_critical_points(&self, values: &[f64]) -> Result<Persistence, AnalysisError> {
        let finder = self
            .critical
            .get_or_init(|| CriticalPointFinder::new(&self.mesh));
        let raw = finder.find(values, BoundaryRule::default())?;
        Ok(persistence(finder, values, raw)?)
    }

    /// `B X` of `basis` (cached for the held basis).
    pub(crate) fn bx(&self, basis: &Eigenbasis) -> Arc<Vec<f64>> {
        let mut g = lock(&self.bx);
        if let Some((b, bx)) = &*g
            && std::ptr::eq(b.as_ref(), basis)
        {
            return bx.clone();
        }
        let bx = Arc::new(crate::spectral::distances::mass_times_vectors(basis));
        if let Some(held) = self.held_basis()
            && std::ptr::eq(held.as_ref(), basis)
        {
            *g = Some((held, bx.clone()));
        }
        bx
    }

    /// The heat-method solver of this analysis' Laplacian on its mesh with `params`
    /// (distances in the mesh's units), from the cache or factored now: one factoring
    /// answers every source.
    pub fn geodesic_solver(
        &self,
        params: &GeodesicParams,
    ) -> Result<Arc<GeodesicSolver>, AnalysisError> {
        {
            let mut g = lock(&self.geodesic);
            if let Some(i) = g.iter().position(|(p, _)| p == params) {
                let entry = g.remove(i);
                let s = entry.1.clone();
                g.push(entry);
                return Ok(s);
            }
        }
        let s = Arc::new(GeodesicSolver::new(
            &self.mesh,
            self.options.laplacian,
            params,
        )?);
        let mut g = lock(&self.geodesic);
        if g.len() >= GEODESIC_CACHE {
            g.remove(0);
        }
        g.push((*params, s.clone()));
        Ok(s)
    }

    /// A harmonic solver for the constrained vertices `vertices` (ascending, no repeats),
    /// from the cache or factored now.
    pub(crate) fn harmonic_solver(
        &self,
        order: u32,
        vertices: &[usize],
    ) -> Result<Arc<HarmonicSolver>, AnalysisError> {
        {
            let mut g = lock(&self.harmonic);
            if let Some(i) = g.iter().position(|(o, v, _)| *o == order && v == vertices) {
                let entry = g.remove(i);
                let s = entry.2.clone();
                g.push(entry);
                return Ok(s);
            }
        }
        let s = Arc::new(HarmonicSolver::with_operators(
            &self.mesh, &self.ops, vertices, order,
        )?);
        let mut g = lock(&self.harmonic);
        if g.len() >= HARMONIC_CACHE {
            g.remove(0);
        }
        g.push((order, vertices.to_vec(), s.clone()));
        Ok(s)
    }
}

/// Critical points with the Euler characteristic check, as every face reports them.
///
/// The points are the ones shown: the raw critical points simplified by persistence
/// ([`crate::fields::persistence`]: the pairs below the threshold hidden, components whose
/// range is below it quiet); the raw counts and their check are in `raw`, the number hidden
/// in `hidden`, every pair with its persistence in `pairs`.
///
/// Components left out (those of a harmonic map that hold no constraint, see
/// [`crate::fields::harmonic::FloatingComponent`], and plateaus: components on which the
/// field is constant within [`FLAT_RELATIVE_TOLERANCE`] of its largest magnitude, see
/// [`crate::fields::critical_points`]) contribute neither critical points nor Euler
/// characteristic; every other component is checked on its own as well (quiet components
/// are left out of the check of the shown points only). A field that is flat on every
/// component reports no critical points and `flat = true`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CriticalReport {
    /// The critical points shown (those of left-out components removed).
    pub points: CriticalPoints,
    /// How many are shown.
    #[serde(flatten)]
    pub counts: CriticalCounts,
    /// Euler characteristic of the components counted.
    pub chi: i64,
    /// True when the check is doubled across the boundary (bordered surfaces).
    pub doubled: bool,
    /// The check of the shown points (`m - s + M`, or its doubled form, against `chi` or
    /// `2 chi`); it holds when it holds on every component counted as well.
    #[serde(flatten)]
    pub check: CheckSides,
    /// The check in words.
    pub formula: &'static str,
    /// The check on each component counted.
    pub components: Vec<ComponentCheck>,
    /// The components left out of the counts.
    #[serde(flatten)]
    pub left_out: LeftOut,
    /// The raw critical points' counts and their check (before simplification).
    pub raw: RawCritical,
    /// How many raw critical points are not shown.
    pub hidden: CriticalCounts,
    /// The thresholds of the simplification.
    #[serde(flatten)]
    pub persistence: PersistenceThresholds,
    /// Components (as in `Topology::components`) whose range is below the threshold: no
    /// critical point shown.
    pub quiet_components: Vec<usize>,
    /// Every extremum of the counted components with its persistence (see
    /// [`PersistencePair`]).
    pub pairs: Vec<PersistencePair>,
}

/// Counts of critical points: shown, raw, or hidden by the simplification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CriticalCounts {
    /// Minima.
    pub minima: usize,
    /// Maxima.
    pub maxima: usize,
    /// Saddles, counted with multiplicity.
    pub saddles: usize,
}

impl CriticalCounts {
    /// The counts of `cp`.
    fn of(cp: &CriticalPoints) -> Self {
        Self {
            minima: cp.minima.len(),
            maxima: cp.maxima.len(),
            saddles: cp.saddle_count(),
        }
    }
}

/// Both sides of an Euler check and whether they agree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CheckSides {
    /// Left side: the critical points counted (`m - s + M`, or its doubled form).
    pub lhs: i64,
    /// Right side (`chi` or `2 chi`).
    pub rhs: i64,
    /// `lhs == rhs` (and, for a sum over components, the check of each).
    pub holds: bool,
}

/// The components a report leaves out of its counts and checks.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LeftOut {
    /// Components the caller excluded (a harmonic map's unconstrained components).
    pub excluded_components: Vec<usize>,
    /// Components on which the field is constant within `flat_tolerance` (plateaus, no
    /// critical points).
    pub plateau_components: Vec<usize>,
    /// The relative tolerance of plateaus: values within `flat_tolerance * max |f|` of
    /// each other on a component are one plateau ([`FLAT_RELATIVE_TOLERANCE`]).
    pub flat_tolerance: f64,
    /// True when every component is a plateau or left out, and at least one is a
    /// plateau: the field is constant (up to rounding), with no critical points.
    pub flat: bool,
}

/// The raw critical points' counts and Euler check.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RawCritical {
    /// The counts.
    #[serde(flatten)]
    pub counts: CriticalCounts,
    /// Their check, on every component counted.
    #[serde(flatten)]
    pub check: CheckSides,
}

/// The Euler check on one connected component.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ComponentCheck {
    /// Component index (as in `Topology::components`).
    pub component: usize,
    /// Its Euler characteristic.
    pub chi: i64,
    /// The check.
    #[serde(flatten)]
    pub check: CheckSides,
}

/// The Euler check of `cp` over the components `included`.
struct Check {
    components: Vec<ComponentCheck>,
    chi: i64,
    doubled: bool,
    sides: CheckSides,
}

impl Check {
    fn new(cp: &CriticalPoints, topo: &Topology, included: &[usize]) -> Self {
        let nc = topo.n_components();
        let doubled = included.iter().any(|&c| !topo.components[c].closed);
        // Doubled across the boundary: interior points count twice, boundary ones once.
        let weight = |v: usize| -> i64 {
            if doubled && cp.on_boundary.binary_search(&v).is_err() {
                2
            } else {
                1
            }
        };
        let mut lhs_c = vec![0i64; nc];
        for &v in cp.minima.iter().chain(&cp.maxima) {
            lhs_c[topo.vertex_component[v]] += weight(v);
        }
        for &(v, m) in &cp.saddles {
            lhs_c[topo.vertex_component[v]] -= weight(v) * m as i64;
        }
        let factor = if doubled { 2 } else { 1 };
        let components: Vec<ComponentCheck> = included
            .iter()
            .map(|&c| {
                let chi = topo.components[c].euler_characteristic;
                ComponentCheck {
                    component: c,
                    chi,
                    check: CheckSides {
                        lhs: lhs_c[c],
                        rhs: factor * chi,
                        holds: lhs_c[c] == factor * chi,
                    },
                }
            })
            .collect();
        let chi: i64 = components.iter().map(|c| c.chi).sum();
        let lhs: i64 = components.iter().map(|c| c.check.lhs).sum();
        let rhs = factor * chi;
        Self {
            sides: CheckSides {
                lhs,
                rhs,
                holds: lhs == rhs && components.iter().all(|c| c.check.holds),
            },
            components,
            chi,
            doubled,
        }
    }
}

impl CriticalReport {
    /// The report of `p` (raw points, persistence, simplified set) on a mesh of topology
    /// `topo`, leaving out the components `excluded`.
    pub fn new(p: Persistence, topo: &Topology, excluded: &[usize]) -> Self {
        let nc = topo.n_components();
        let comp_of = |v: usize| topo.vertex_component.get(v).copied().filter(|&c| c < nc);
        let mut plateau_components: Vec<usize> = p
            .raw
            .plateaus
            .iter()
            .filter_map(|pl| comp_of(pl.first_vertex))
            .filter(|c| !excluded.contains(c))
            .collect();
        plateau_components.sort_unstable();
        plateau_components.dedup();
        let mut quiet_components: Vec<usize> = p
            .quiet_components
            .iter()
            .filter_map(|&v| comp_of(v))
            .filter(|c| !excluded.contains(c) && !plateau_components.contains(c))
            .collect();
        quiet_components.sort_unstable();
        quiet_components.dedup();
        let left_out = |c: usize| excluded.contains(&c) || plateau_components.contains(&c);
        let counted = |v: usize| comp_of(v).is_some_and(|c| !left_out(c));
        let restrict = |mut cp: CriticalPoints| {
            cp.minima.retain(|&v| counted(v));
            cp.maxima.retain(|&v| counted(v));
            cp.saddles.retain(|&(v, _)| counted(v));
            cp.on_boundary.retain(|&v| counted(v));
            cp.non_manifold.retain(|&v| counted(v));
            cp
        };
        let raw = restrict(p.raw);
        let shown = restrict(p.shown);
        let pairs: Vec<PersistencePair> = p
            .pairs
            .into_iter()
            .filter(|q| counted(q.extremum))
            .collect();
        let included: Vec<usize> = (0..nc).filter(|&c| !left_out(c)).collect();
        let included_shown: Vec<usize> = included
            .iter()
            .copied()
            .filter(|c| !quiet_components.contains(c))
            .collect();
        let raw_check = Check::new(&raw, topo, &included);
        let check = Check::new(&shown, topo, &included_shown);
        let (shown_counts, raw_counts) = (CriticalCounts::of(&shown), CriticalCounts::of(&raw));
        Self {
            counts: shown_counts,
            points: shown,
            chi: check.chi,
            doubled: check.doubled,
            check: check.sides,
            formula: if check.doubled {
                "doubled across the boundary: 2(m_i - s_i + M_i) + (m_b - s_b + M_b) = 2 chi"
            } else {
                "m - s + M = chi"
            },
            components: check.components,
            left_out: LeftOut {
                flat: included.is_empty() && !plateau_components.is_empty(),
                excluded_components: excluded.to_vec(),
                plateau_components,
                flat_tolerance: FLAT_RELATIVE_TOLERANCE,
            },
            raw: RawCritical {
                counts: raw_counts,
                check: raw_check.sides,
            },
            hidden: CriticalCounts {
                minima: raw_counts.minima - shown_counts.minima,
                maxima: raw_counts.maxima - shown_counts.maxima,
                saddles: raw_counts.saddles - shown_counts.saddles,
            },
            persistence: p.thresholds,
            quiet_components,
            pairs,
        }
    }
}

#[cfg(test)]
mod tests;
