//! What the server's cache holds: the inputs the page loaded ([`MeshEntry`]), the
//! analyses of them ([`AnalysisKey`]), the cache's keys and items, and the memory
//! reservations of work in progress.

use std::sync::Arc;

use spectral_mesh::Laplacian;
use spectral_mesh::Mesh;
use spectral_mesh::analysis::memory::{cloud_bytes, mesh_bytes};
use spectral_mesh::analysis::{Analysis, AnalysisInput};

use crate::cache::Entry;

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
        Laplacian::ALL
            .iter()
            .filter(|l| spectral_mesh::defaults::laplacian_for(Some(**l), self.is_points()).is_ok())
            .map(|l| l.name())
            .collect()
    }

    /// The discretization of a request: the one given, or the input's default (the
    /// library's [`spectral_mesh::defaults::laplacian_for`]: fem for a mesh, robust for
    /// a point cloud). A point cloud refuses any other than robust with a message saying
    /// why (the handlers answer 422).
    pub fn laplacian(&self, given: Option<Laplacian>) -> Result<Laplacian, String> {
        spectral_mesh::defaults::laplacian_for(given, self.is_points())
            .map_err(|e| format!("laplacian: '{}' is a point cloud: {e}", self.source))
    }

    /// Bytes the entry takes (the library's [`mesh_bytes`] and [`cloud_bytes`]).
    pub fn bytes(&self) -> usize {
        match &self.input {
            Loaded::Mesh(m) => mesh_bytes(m),
            Loaded::Points(p) => cloud_bytes(p.n()),
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
