//! Server state: the byte-bounded cache of meshes and analyses with the memory budget,
//! the eigenbasis jobs, and the counters of the limits.

use std::path::PathBuf;
use std::sync::Arc;

use spectral_mesh::analysis::{Analysis, AnalysisOptions, DistanceSpec, FieldRequest};
use spectral_mesh::{Laplacian, Mesh};

use crate::ServeConfig;
use crate::cache::{ByteLru, Entry};
use crate::jobs::{Jobs, predicted_factor_len};
use crate::limits::InFlight;

/// A mesh the page has loaded.
pub struct MeshEntry {
    /// The first 16 hex digits of [`Mesh::content_hash`].
    pub id: String,
    /// The whole content hash (64 hex digits), as experiment files record it.
    pub hash: String,
    /// Shape spec or uploaded file name (what the experiment file records as `mesh`).
    pub source: String,
    /// The mesh, shared with its analyses.
    pub mesh: Arc<Mesh>,
    /// The info panel's JSON.
    pub info: serde_json::Value,
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
    /// assembled now, O(n): reserve [`analysis_creation_bytes`] first; nothing factored
    /// yet).
    pub fn analysis(&self, entry: &MeshEntry, key: &AnalysisKey) -> Arc<Analysis> {
        if let Some(a) = self.existing_analysis(key) {
            return a;
        }
        let a = Arc::new(Analysis::new(
            entry.mesh.clone(),
            AnalysisOptions {
                laplacian: key.laplacian,
                normalize: key.normalize,
                ..AnalysisOptions::default()
            },
        ));
        self.remember(key, &a);
        a
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
/// tenth for allocator overhead and the factor's symbolic analysis.
pub fn analysis_bytes(a: &Analysis) -> usize {
    let b = a.memory_bytes();
    b + b / 10
}

/// Bytes an eigenbasis of `k` pairs on `n` vertices takes.
pub fn basis_bytes(n: usize, k: usize) -> usize {
    n * k * 8 + k * 16
}

/// Peak bytes of assembling the operators of a new analysis on `n` vertices (triplets
/// and the two sparse matrices; the robust Laplacian builds an intrinsic mesh first).
pub fn analysis_creation_bytes(n: usize, laplacian: Laplacian) -> usize {
    match laplacian {
        Laplacian::Robust => 3000 * n,
        _ => 1000 * n,
    }
}

/// Peak bytes of a field request on `n` vertices beyond what the analysis holds: the
/// values, the reply, critical points and level sets (400 per vertex), plus a harmonic
/// map's factorization (when not kept from an earlier request) or the wFEM distance's
/// `B X` (`n x k`, computed once).
pub fn field_bytes(n: usize, request: &FieldRequest) -> usize {
    let base = 400 * n;
    match request {
        FieldRequest::Harmonic { .. } => base + predicted_factor_len(n) * 13,
        FieldRequest::Distance {
            distance: DistanceSpec::WfemDiffusion { .. },
            k,
            ..
        } => base + 8 * n * k,
        _ => base,
    }
}
