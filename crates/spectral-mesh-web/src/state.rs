//! Server state: the byte-bounded cache of meshes and analyses, and the eigenbasis jobs
//! in flight.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use serde::Serialize;
use spectral_mesh::analysis::{Analysis, AnalysisOptions};
use spectral_mesh::cancel::CancelToken;
use spectral_mesh::{Laplacian, Mesh};

use crate::ServeConfig;
use crate::cache::ByteLru;

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

/// State of the eigenbasis computation of one mesh, as the status endpoint reports it.
#[derive(Debug, Clone, Serialize)]
pub struct Job {
    /// "running", "done", "error" or "cancelled".
    pub state: String,
    /// Discretization.
    pub laplacian: String,
    /// Unit-area normalisation.
    pub normalize: bool,
    /// Pairs asked for.
    pub k: usize,
    /// Pairs the analysis holds now (at least `k` once done).
    pub held_k: usize,
    /// 0..=1.
    pub progress: f64,
    /// Last progress or error message.
    pub message: String,
    /// Seconds since start (or total when finished).
    pub seconds: f64,
}

/// A job and what the server needs to control it.
pub struct JobSlot {
    /// What the status endpoint shows.
    pub job: Job,
    /// Which start this is (a finished or cancelled computation only updates its own).
    pub serial: u64,
    /// Set to stop the computation.
    pub cancel: CancelToken,
    /// The analysis being computed, held while running (so that field requests find it
    /// even if the cache evicted it), dropped when done.
    pub analysis: Option<Arc<Analysis>>,
    /// Its key.
    pub key: AnalysisKey,
}

/// Everything the handlers share.
pub struct AppState {
    /// The configuration.
    pub config: ServeConfig,
    /// Meshes and analyses.
    pub cache: ByteLru<Key, Item>,
    /// Basis jobs per mesh id.
    pub jobs: Mutex<HashMap<String, JobSlot>>,
    /// Serial numbers of jobs.
    pub next_serial: Mutex<u64>,
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
        Self {
            fields,
            cache: ByteLru::new(config.cache_bytes),
            jobs: Mutex::new(HashMap::new()),
            next_serial: Mutex::new(0),
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

    /// The jobs map (poisoning ignored: entries are plain data).
    pub fn jobs(&self) -> MutexGuard<'_, HashMap<String, JobSlot>> {
        self.jobs.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A new job serial number.
    pub fn serial(&self) -> u64 {
        let mut s = self.next_serial.lock().unwrap_or_else(|p| p.into_inner());
        *s += 1;
        *s
    }

    /// The mesh `id`, if still cached.
    pub fn mesh(&self, id: &str) -> Option<Arc<Item>> {
        self.cache.get(&Key::Mesh(id.to_string()))
    }

    /// The analysis of `entry` for `key`: the cached one, the one a running job holds, or
    /// a new one (operators assembled now, O(n); nothing factored yet).
    pub fn analysis(&self, entry: &MeshEntry, key: &AnalysisKey) -> Arc<Analysis> {
        let ck = Key::Analysis(key.clone());
        if let Some(item) = self.cache.get(&ck)
            && let Item::Analysis(a) = &*item
        {
            return a.clone();
        }
        let running = self
            .jobs()
            .get(&key.id)
            .filter(|slot| &slot.key == key)
            .and_then(|slot| slot.analysis.clone());
        if let Some(a) = running {
            self.remember(key, &a);
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

    /// (Re-)inserts an analysis into the cache with its current size.
    pub fn remember(&self, key: &AnalysisKey, a: &Arc<Analysis>) {
        self.cache.insert(
            Key::Analysis(key.clone()),
            Arc::new(Item::Analysis(a.clone())),
            analysis_bytes(a),
        );
    }
}

/// Bytes a mesh entry takes, roughly.
pub fn mesh_bytes(m: &Mesh) -> usize {
    m.n_vertices() * 64 + m.n_triangles() * 96
}

/// Bytes an analysis takes, roughly: operators, the factorization kept for larger bases
/// (estimated at 20 non-zeros per vertex), the held basis (twice: `B X` is cached for
/// the wFEM distance), the connectivity and link edges.
pub fn analysis_bytes(a: &Analysis) -> usize {
    let n = a.n();
    let ops = a.operators();
    let ops_bytes = (ops.stiffness.nnz() + ops.mass.nnz()) * 16 + n * 16;
    let factor = n * 20 * 16;
    let topo = a.mesh().n_triangles() * 96 + n * 32;
    ops_bytes + factor + topo + 2 * basis_bytes(n, a.held_k())
}

/// Bytes an eigenbasis of `k` pairs on `n` vertices takes.
pub fn basis_bytes(n: usize, k: usize) -> usize {
    n * k * 8 + k * 16
}
