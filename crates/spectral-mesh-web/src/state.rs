//! Server state: the byte-bounded cache of meshes, operators and eigenbases, and the
//! eigenbasis jobs in flight.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use serde::Serialize;
use spectral_mesh::mesh::topology::{Topology, VertexTriangles};
use spectral_mesh::{Eigenbasis, Laplacian, Mesh, Operators};

use crate::ServeConfig;
use crate::cache::ByteLru;

/// A mesh the page has loaded, with what every request needs of it.
pub struct MeshEntry {
    /// Content hash (16 hex digits).
    pub id: String,
    /// Shape spec or uploaded file name (what the experiment file records).
    pub source: String,
    /// The mesh.
    pub mesh: Mesh,
    /// Its connectivity.
    pub topo: Topology,
    /// Triangles around each vertex.
    pub vt: VertexTriangles,
    /// The info panel's JSON.
    pub info: serde_json::Value,
}

/// Cache keys.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Key {
    /// A mesh.
    Mesh(String),
    /// Operators of a mesh.
    Ops(String, Laplacian),
    /// An eigenbasis of a mesh: (id, discretization, k).
    Basis(String, Laplacian, usize),
}

/// Cached values.
pub enum Item {
    /// A mesh.
    Mesh(Box<MeshEntry>),
    /// Operators.
    Ops(Operators),
    /// An eigenbasis.
    Basis(Eigenbasis),
}

/// State of the eigenbasis computation of one mesh.
#[derive(Debug, Clone, Serialize)]
pub struct Job {
    /// "running", "done" or "error".
    pub state: String,
    /// Discretization.
    pub laplacian: String,
    /// Pairs asked for.
    pub k: usize,
    /// 0..=1.
    pub progress: f64,
    /// Last progress or error message.
    pub message: String,
    /// Seconds since start (or total when finished).
    pub seconds: f64,
}

/// Everything the handlers share.
pub struct AppState {
    /// The configuration.
    pub config: ServeConfig,
    /// Meshes, operators and bases.
    pub cache: ByteLru<Key, Item>,
    /// Basis jobs per mesh id.
    pub jobs: Mutex<HashMap<String, Job>>,
    /// Resolved `node_modules` folder.
    pub node_modules: PathBuf,
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
        Self {
            cache: ByteLru::new(config.cache_bytes),
            jobs: Mutex::new(HashMap::new()),
            config,
            node_modules,
        }
    }

    /// The jobs map (poisoning ignored: entries are plain data).
    pub fn jobs(&self) -> std::sync::MutexGuard<'_, HashMap<String, Job>> {
        self.jobs.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The mesh `id`, if still cached.
    pub fn mesh(&self, id: &str) -> Option<Arc<Item>> {
        self.cache.get(&Key::Mesh(id.to_string()))
    }

    /// Operators of mesh `id` (assembled and cached on first use).
    pub fn ops(&self, entry: &MeshEntry, lap: Laplacian) -> Arc<Item> {
        let key = Key::Ops(entry.id.clone(), lap);
        if let Some(v) = self.cache.get(&key) {
            return v;
        }
        let ops = Operators::new(&entry.mesh, lap);
        let bytes = (ops.stiffness.nnz() + ops.mass.nnz()) * 16 + ops.n() * 16;
        let item = Arc::new(Item::Ops(ops));
        self.cache.insert(key, item.clone(), bytes);
        item
    }

    /// A cached basis of mesh `id` with discretization `lap` and at least `k` pairs
    /// (the smallest such).
    pub fn basis(&self, id: &str, lap: Laplacian, k: usize) -> Option<Arc<Item>> {
        let mut keys = self
            .cache
            .keys(|key| matches!(key, Key::Basis(i, l, kk) if i == id && *l == lap && *kk >= k));
        keys.sort_by_key(|key| match key {
            Key::Basis(_, _, kk) => *kk,
            _ => usize::MAX,
        });
        keys.into_iter().find_map(|key| self.cache.get(&key))
    }
}

/// Bytes a mesh entry takes, roughly.
pub fn mesh_bytes(m: &Mesh) -> usize {
    m.n_vertices() * 64 + m.n_triangles() * 96
}

/// Bytes an eigenbasis takes, roughly.
pub fn basis_bytes(n: usize, k: usize, mass_nnz: usize) -> usize {
    n * k * 8 + k * 16 + mass_nnz * 16
}
