//! Server state: the byte-bounded cache of meshes and analyses ([`crate::entries`]) with
//! the memory budget, the eigenbasis jobs, and the counters of the limits.

use std::path::PathBuf;
use std::sync::Arc;

use spectral_mesh::analysis::{Analysis, AnalysisError, AnalysisOptions};

use crate::cache::{ByteLru, Shortfall};
use crate::config::ServeConfig;
use crate::entries::{AnalysisKey, Item, Key, Loaded, MeshEntry, Reservation};
use crate::jobs::{self, Jobs};
use crate::limits::InFlight;

/// The state as the handlers extract it.
pub type St = axum::extract::State<Arc<AppState>>;

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
    /// cloud with `k` neighbours: reserve the library's
    /// [`spectral_mesh::analysis::memory::creation_bytes`] first; nothing
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
        let bytes = a.cached_bytes();
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

impl jobs::Host for AppState {
    fn jobs(&self) -> &Jobs {
        &self.jobs
    }

    fn max_jobs(&self) -> usize {
        self.config.limits.max_jobs
    }

    fn try_reserve(&self, bytes: usize) -> Result<Reservation, Shortfall> {
        self.cache.try_reserve(bytes)
    }

    fn remember(&self, key: &AnalysisKey, a: &Arc<Analysis>) {
        AppState::remember(self, key, a);
    }
}
