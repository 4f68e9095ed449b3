//! Server state: the byte-bounded cache of meshes and analyses with the memory budget,
//! the eigenbasis jobs, and the counters of the limits.

use std::path::PathBuf;
use std::sync::Arc;

use spectral_mesh::analysis::{
    Analysis, AnalysisError, AnalysisInput, AnalysisOptions, DistanceSpec, FieldRequest,
};
use spectral_mesh::{Laplacian, Mesh};

use crate::ServeConfig;
use crate::cache::{ByteLru, Entry};
use crate::jobs::{Jobs, predicted_factor_len};
use crate::limits::InFlight;

/// What was loaded: a triangle mesh or a point cloud.
pub enum Loaded {
    /// A mesh, shared with its analyses (every discretization applies).
    Mesh(Arc<Mesh>),
    /// A point cloud, as the library's analysis input ([`AnalysisInput::Points`]: the
    /// points, their normals if any, and the parameters of its Laplacian). Its analyses
    /// are made by [`Analysis::from_input`]; only [`Laplacian::Robust`] (the point-cloud
    /// Laplacian of Sharp and Crane) applies.
    Points(AnalysisInput),
}

/// A mesh or point cloud the page has loaded.
pub struct MeshEntry {
    /// The first 16 hex digits of the content hash ([`Mesh::content_hash`], or
    /// [`spectral_mesh::PointCloud::content_hash`] for a cloud).
    pub id: String,
    /// The whole content hash (64 hex digits), as experiment files record it.
    pub hash: String,
    /// Shape spec or uploaded file name (what the experiment file records as `mesh`).
    pub source: String,
    /// The mesh or the point cloud.
    pub input: Loaded,
    /// The info panel's JSON.
    pub info: serde_json::Value,
}

impl MeshEntry {
    /// Vertices of the mesh, or points of the cloud.
    pub fn n(&self) -> usize {
        match &self.input {
            Loaded::Mesh(m) => m.n_vertices(),
            Loaded::Points(p) => p.n(),
        }
    }

    /// Triangles of the mesh (0 for a point cloud: its triangle union belongs to its
    /// analyses).
    pub fn n_triangles(&self) -> usize {
        match &self.input {
            Loaded::Mesh(m) => m.n_triangles(),
            Loaded::Points(_) => 0,
        }
    }

    /// The vertex or point positions, `n` entries.
    pub fn positions(&self) -> &[[f64; 3]] {
        match &self.input {
            Loaded::Mesh(m) => m.positions(),
            Loaded::Points(AnalysisInput::Points { cloud, .. }) => cloud.positions(),
            Loaded::Points(AnalysisInput::Mesh(m)) => m.positions(),
        }
    }

    /// The mesh, `None` for a point cloud.
    pub fn mesh(&self) -> Option<&Arc<Mesh>> {
        match &self.input {
            Loaded::Mesh(m) => Some(m),
            Loaded::Points(_) => None,
        }
    }

    /// True for a point cloud.
    pub fn is_points(&self) -> bool {
        matches!(self.input, Loaded::Points(_))
    }

    /// `"mesh"` or `"point cloud"`.
    pub fn kind(&self) -> &'static str {
        if self.is_points() {
            "point cloud"
        } else {
            "mesh"
        }
    }

    /// `"vertices"` or `"points"`, for messages.
    pub fn noun(&self) -> &'static str {
        if self.is_points() {
            "points"
        } else {
            "vertices"
        }
    }

    /// The discretizations that apply: all for a mesh, robust only for a point cloud.
    pub fn laplacians(&self) -> Vec<&'static str> {
        if self.is_points() {
            vec![Laplacian::Robust.name()]
        } else {
            [
                Laplacian::Fem,
                Laplacian::VoronoiCot,
                Laplacian::Cot,
                Laplacian::MixedVoronoi,
                Laplacian::Uniform,
                Laplacian::Robust,
            ]
            .iter()
            .map(|l| l.name())
            .collect()
        }
    }

    /// The discretization of a request: the one given, or the input's default (fem for
    /// a mesh, robust for a point cloud, as the CLI). A point cloud refuses any other
    /// than robust with a message saying why (the handlers answer 422).
    pub fn laplacian(&self, given: Option<Laplacian>) -> Result<Laplacian, String> {
        match (self.is_points(), given) {
            (false, g) => Ok(g.unwrap_or(Laplacian::Fem)),
            (true, None | Some(Laplacian::Robust)) => Ok(Laplacian::Robust),
            (true, Some(l)) => Err(format!(
                "laplacian: '{}' is a point cloud and the {} Laplacian needs triangles: a point cloud has only its point-cloud Laplacian (Sharp and Crane 2020), \"laplacian\": \"robust\" (the default for point clouds)",
                self.source,
                l.name()
            )),
        }
    }

    /// Bytes the entry takes (see [`mesh_bytes`]; a cloud: positions and normals).
    pub fn bytes(&self) -> usize {
        match &self.input {
            Loaded::Mesh(m) => mesh_bytes(m),
            Loaded::Points(p) => p.n() * 96,
        }
    }
}

/// What one analysis is of: mesh id, discretization, scale normalisation.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct AnalysisKey {
    /// Mesh id.
    pub id: String,
    /// Discretization.
    pub laplacian: Laplacian,
    /// Unit-area normalisation.
    pub normalize: bool,
}

/// Cache keys.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Key {
    /// A mesh, by id.
    Mesh(String),
    /// An analysis of a mesh.
    Analysis(AnalysisKey),
}

/// Cached values.
pub enum Item {
    /// A mesh.
    Mesh(Box<MeshEntry>),
    /// An analysis (operators, factorization, eigenbasis, solver caches).
    Analysis(Arc<Analysis>),
}

impl Entry<Key> for Item {
    fn in_use(self: &Arc<Self>) -> bool {
        Arc::strong_count(self) > 1
            || matches!(&**self, Item::Analysis(a) if Arc::strong_count(a) > 1)
    }

    fn dependents(&self, keys: &[Key]) -> Vec<Key> {
        match self {
            Item::Mesh(e) => keys
                .iter()
                .filter(|k| matches!(k, Key::Analysis(a) if a.id == e.id))
                .cloned()
                .collect(),
            Item::Analysis(_) => Vec::new(),
        }
    }
}

/// Memory reserved from the server's budget (released when dropped).
pub type Reservation = crate::cache::Reservation<Key, Item>;

/// Everything the handlers share.
pub struct AppState {
    /// The configuration.
    pub config: ServeConfig,
    /// Meshes and analyses, and the reservations of work in progress.
    pub cache: Arc<ByteLru<Key, Item>>,
    /// Eigenbasis jobs.
    pub jobs: Jobs,
    /// Requests in progress.
    pub in_flight: InFlight,
    /// Resolved `node_modules` folder.
    pub node_modules: PathBuf,
    /// Threads of the field requests' parallel work, apart from rayon's global pool where
    /// the eigensolver runs: a field is not queued behind a basis being computed, and its
    /// threads never ran the solver (threads that did, or were started from one that did,
    /// ran the field kernels 1.5-3x slower in our measurements; see BENCHMARKS.md). `None`
    /// when the threads could not be started (the global pool is used).
    pub fields: Option<rayon::ThreadPool>,
}

impl AppState {
    /// A fresh state.
    pub fn new(config: ServeConfig) -> Self {
        let node_modules = config
            .node_modules
            .clone()
            .or_else(|| std::env::var_os("SPECTRAL_MESH_WEB_NODE_MODULES").map(PathBuf::from))
            .unwrap_or_else(|| {
                PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../web/node_modules")
            });
        let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
        let fields = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("spectral-mesh-field-{i}"))
            .build()
            .ok();
        let limits = &config.limits;
        Self {
            fields,
            cache: Arc::new(ByteLru::new(limits.cache_bytes, limits.memory_bytes)),
            jobs: Jobs::default(),
            in_flight: InFlight::default(),
            config,
            node_modules,
        }
    }

    /// Runs `f` (a field request's work) on the field threads.
    pub fn on_field_threads<T: Send>(&self, f: impl FnOnce() -> T + Send) -> T {
        match &self.fields {
            Some(pool) => pool.install(f),
            None => f(),
        }
    }

    /// The mesh `id`, if still cached.
    pub fn mesh(&self, id: &str) -> Option<Arc<Item>> {
        self.cache.get(&Key::Mesh(id.to_string()))
    }

    /// The analysis of `key` if one exists: the cached one or the one a job holds.
    pub fn existing_analysis(&self, key: &AnalysisKey) -> Option<Arc<Analysis>> {
        if let Some(item) = self.cache.get(&Key::Analysis(key.clone()))
            && let Item::Analysis(a) = &*item
        {
            return Some(a.clone());
        }
        let a = self.jobs.analysis_of(key)?;
        self.remember(key, &a);
        Some(a)
    }

    /// The analysis of `entry` for `key`: an existing one, or a new one (operators
    /// assembled now, O(n) for a mesh, O(n k log n) for the point-cloud Laplacian of a
    /// cloud with `k` neighbours: reserve [`analysis_creation_bytes`] first; nothing
    /// factored yet). A mesh shares its `Arc` with the analysis ([`Analysis::new`], what
    /// [`Analysis::from_input`] does with a mesh, without a copy); a point cloud goes
    /// through [`Analysis::from_input`], which refuses a discretization other than
    /// robust and a cloud without a triangle in its local triangulations.
    pub fn analysis(
        &self,
        entry: &MeshEntry,
        key: &AnalysisKey,
    ) -> Result<Arc<Analysis>, AnalysisError> {
        if let Some(a) = self.existing_analysis(key) {
            return Ok(a);
        }
        let options = AnalysisOptions {
            laplacian: key.laplacian,
            normalize: key.normalize,
            ..AnalysisOptions::default()
        };
        let a = Arc::new(match &entry.input {
            Loaded::Mesh(m) => Analysis::new(m.clone(), options),
            Loaded::Points(input) => Analysis::from_input(input.clone(), options)?,
        });
        self.remember(key, &a);
        Ok(a)
    }

    /// (Re-)enters an analysis into the cache with its current size, if its mesh is
    /// still loaded. When it does not fit, it is left out (it is freed when its last
    /// user lets go; a field request then answers 409 and the basis is asked again).
    pub fn remember(&self, key: &AnalysisKey, a: &Arc<Analysis>) {
        if self.cache.peek(&Key::Mesh(key.id.clone())).is_none() {
            return;
        }
        let k = Key::Analysis(key.clone());
        let bytes = analysis_bytes(a);
        match self.cache.peek(&k) {
            Some(item) if matches!(&*item, Item::Analysis(held) if Arc::ptr_eq(held, a)) => {
                drop(item);
                self.cache.resize(&k, bytes);
            }
            _ => {
                let _ = self
                    .cache
                    .insert(k, Arc::new(Item::Analysis(a.clone())), bytes);
            }
        }
    }
}

/// Bytes a mesh entry takes: positions and triangles (24 bytes each), the connectivity
/// the info panel was computed from is not kept; 64 + 96 per vertex and triangle leaves
/// room for the info JSON and allocator overhead.
pub fn mesh_bytes(m: &Mesh) -> usize {
    m.n_vertices() * 64 + m.n_triangles() * 96
}

/// Bytes an analysis takes: [`Analysis::memory_bytes`] (counted from its arrays) plus a
/// tenth for allocator overhead and the factor's symbolic analysis; the analysis of a
/// point cloud also holds its points and the triangle union of its Laplacian.
pub fn analysis_bytes(a: &Analysis) -> usize {
    let mut b = a.memory_bytes();
    if a.is_point_cloud() {
        b += mesh_bytes(a.mesh()) + 48 * a.n();
    }
    b + b / 10
}

/// Bytes an eigenbasis of `k` pairs on `n` vertices takes.
pub fn basis_bytes(n: usize, k: usize) -> usize {
    n * k * 8 + k * 16
}

/// Peak bytes of assembling the operators of a new analysis on `n` vertices (triplets
/// and the two sparse matrices; the robust Laplacian builds an intrinsic mesh first; the
/// point-cloud Laplacian of a cloud of `n` points also its neighbour lists, local
/// triangulations and their union: an estimate of twice the robust figure).
pub fn analysis_creation_bytes(n: usize, laplacian: Laplacian, points: bool) -> usize {
    match (laplacian, points) {
        (_, true) => 6000 * n,
        (Laplacian::Robust, false) => 3000 * n,
        _ => 1000 * n,
    }
}

/// Peak bytes of a field request on `n` vertices beyond what the analysis holds: the
/// values, the reply, critical points and level sets (400 per vertex), plus a harmonic
/// map's factorization (when not kept from an earlier request), a geodesic distance's
/// heat-method factors, or the wFEM distance's `B X` (`n x k`, computed once).
pub fn field_bytes(n: usize, request: &FieldRequest) -> usize {
    let base = 400 * n;
    match request {
        FieldRequest::Harmonic { .. } => base + predicted_factor_len(n) * 13,
        // The heat method factors up to three matrices (heat, Dirichlet heat, Poisson).
        FieldRequest::Geodesic { .. } => base + 3 * predicted_factor_len(n) * 13,
        FieldRequest::Distance {
            distance: DistanceSpec::WfemDiffusion { .. },
            k,
            ..
        } => base + 8 * n * k,
        _ => base,
    }
}
