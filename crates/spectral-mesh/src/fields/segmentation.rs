//! Segmentation into patches: the descending manifolds (watershed basins) of the maxima
//! of a scalar field, with persistence-based merging.
//!
//! Vertices are swept by descending value (ties: lower index first, a symbolic
//! perturbation). A vertex with no already-swept neighbour is a maximum and starts a region
//! born at its value. Otherwise it joins the region of its highest swept neighbour
//! (steepest ascent). When regions meet at a vertex `v`, each younger region (lower birth
//! value) whose persistence `birth - f(v)` is below `persistence * (max f - min f)` is
//! merged into the oldest one (the elder rule). Regions that survive their first meeting
//! are never merged later (later meetings happen at lower values).
//!
//! Patches are numbered by decreasing birth value (the highest maximum is patch 0), so the
//! labels are deterministic for a given input. The genus of each patch is that of the
//! sub-mesh made of the triangles whose three vertices share its label.

use crate::mesh::Mesh;
use crate::mesh::topology::{Topology, UnionFind};

/// Parameters of [`segment`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentParams {
    /// Merge threshold, relative to the range of the field: a region whose persistence
    /// is below `persistence * (max - min)` is merged into its elder neighbour.
    pub persistence: f64,
}

impl Default for SegmentParams {
    fn default() -> Self {
        Self { persistence: 0.05 }
    }
}

/// Errors of [`segment`].
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SegmentationError {
    /// The field length does not match the mesh.
    #[error("the field has {got} values but the mesh has {n} vertices")]
    LengthMismatch {
        /// Values given.
        got: usize,
        /// Vertices.
        n: usize,
    },
    /// A field value is not finite.
    #[error("the field value at vertex {0} is not finite")]
    NonFinite(usize),
    /// The persistence threshold is invalid.
    #[error("the persistence threshold must be finite and >= 0, got {0}")]
    InvalidPersistence(f64),
}

/// A segmentation into patches.
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    /// Patch of each vertex (`n` entries, each in `0..n_patches`).
    pub labels: Vec<usize>,
    /// Number of patches.
    pub n_patches: usize,
    /// Vertex of the maximum of each patch.
    pub maxima: Vec<usize>,
    /// Genus of each patch as a sub-mesh (triangles whose three vertices share the label):
    /// the sum of the genera of its connected pieces, or `None` when it has no triangle or
    /// a piece is not an orientable manifold.
    pub patch_genus: Vec<Option<i64>>,
}

/// Segments `mesh` by the descending manifolds of the maxima of `field` (see the module
/// documentation).
pub fn segment(
    mesh: &Mesh,
    field: &[f64],
    params: SegmentParams,
) -> Result<Segmentation, SegmentationError> {
    let n = mesh.n_vertices();
    if field.len() != n {
        return Err(SegmentationError::LengthMismatch {
            got: field.len(),
            n,
        });
    }
    if let Some(i) = field.iter().position(|v| !v.is_finite()) {
        return Err(SegmentationError::NonFinite(i));
    }
    if !(params.persistence.is_finite() && params.persistence >= 0.0) {
        return Err(SegmentationError::InvalidPersistence(params.persistence));
    }
    let topo = Topology::new(mesh);
    // Adjacency in CSR form.
    let mut deg = vec![0usize; n + 1];
    for e in &topo.edges {
        deg[e[0] + 1] += 1;
        deg[e[1] + 1] += 1;
    }
    for i in 0..n {
        deg[i + 1] += deg[i];
    }
    let mut fill = deg.clone();
    let mut adj = vec![0usize; deg[n]];
    for e in &topo.edges {
        adj[fill[e[0]]] = e[1];
        fill[e[0]] += 1;
        adj[fill[e[1]]] = e[0];
        fill[e[1]] += 1;
    }
    let (lo, hi) = field
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let threshold = params.persistence * (hi - lo);

    // Sweep order: descending value, ties by ascending index.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| field[b].total_cmp(&field[a]).then(a.cmp(&b)));
    let mut rank = vec![0usize; n];
    for (r, &v) in order.iter().enumerate() {
        rank[v] = r;
    }
    let mut uf = UnionFind::new(n);
    // For each union-find root: the vertex of its maximum (the oldest).
    let mut peak = vec![usize::MAX; n];
    let mut assigned = vec![false; n];
    let mut roots: Vec<usize> = Vec::new();
    for &v in &order {
        // Swept neighbours (those earlier in the order).
        let nb = &adj[deg[v]..deg[v + 1]];
        let mut best: Option<usize> = None;
        for &u in nb {
            if assigned[u] && best.is_none_or(|b| rank[u] < rank[b]) {
                best = Some(u);
            }
        }
        let Some(b) = best else {
            // A maximum: a new region.
            assigned[v] = true;
            peak[v] = v;
            continue;
        };
        let rb = uf.find(b);
        let pb = peak[rb];
        uf.union(v, rb);
        let r = uf.find(v);
        peak[r] = pb;
        assigned[v] = true;
        // Regions meeting at v.
        roots.clear();
        for &u in nb {
            if assigned[u] && u != v {
                roots.push(uf.find(u));
            }
        }
        roots.sort_unstable();
        roots.dedup();
        if roots.len() < 2 {
            continue;
        }
        // The oldest region: the one whose peak comes first in the sweep.
        let mut eldest = roots[0];
        for &q in &roots {
            if rank[peak[q]] < rank[peak[eldest]] {
                eldest = q;
            }
        }
        let elder_peak = peak[eldest];
        for &q in &roots {
            if q == eldest {
                continue;
            }
            let pers = field[peak[q]] - field[v];
            if pers < threshold {
                let e = uf.find(eldest);
                let q = uf.find(q);
                uf.union(e, q);
                let r = uf.find(e);
                peak[r] = elder_peak;
            }
        }
    }
    // Compact labels by decreasing birth (sweep rank of the peak).
    let mut rep: Vec<usize> = (0..n).map(|v| uf.find(v)).collect();
    let mut peaks: Vec<usize> = rep.iter().map(|&r| peak[r]).collect();
    peaks.sort_unstable_by_key(|&p| rank[p]);
    peaks.dedup();
    let mut label_of_peak = vec![usize::MAX; n];
    for (l, &p) in peaks.iter().enumerate() {
        label_of_peak[p] = l;
    }
    let labels: Vec<usize> = rep.iter_mut().map(|r| label_of_peak[peak[*r]]).collect();
    let n_patches = peaks.len();

    let patch_genus = patch_genera(mesh, &labels, n_patches);
    Ok(Segmentation {
        labels,
        n_patches,
        maxima: peaks,
        patch_genus,
    })
}

/// The genus of each of the `n_patches` patches of a labelling (`labels[v] < n_patches`,
/// one per vertex), as in [`Segmentation::patch_genus`]: each patch is the sub-mesh of the
/// triangles whose three vertices share its label. Labels out of range are ignored.
pub fn patch_genera(mesh: &Mesh, labels: &[usize], n_patches: usize) -> Vec<Option<i64>> {
    let mut tris_of: Vec<Vec<[usize; 3]>> = vec![Vec::new(); n_patches];
    for tri in mesh.triangles() {
        let Some(&l) = labels.get(tri[0]) else {
            continue;
        };
        if labels.get(tri[1]) == Some(&l) && labels.get(tri[2]) == Some(&l) && l < n_patches {
            tris_of[l].push(*tri);
        }
    }
    tris_of.iter().map(|tris| patch_genus(mesh, tris)).collect()
}

fn patch_genus(mesh: &Mesh, tris: &[[usize; 3]]) -> Option<i64> {
    if tris.is_empty() {
        return None;
    }
    let mut map = std::collections::HashMap::new();
    let mut pos = Vec::new();
    let local: Vec<[usize; 3]> = tris
        .iter()
        .map(|t| {
            t.map(|v| {
                *map.entry(v).or_insert_with(|| {
                    pos.push(mesh.positions()[v]);
                    pos.len() - 1
                })
            })
        })
        .collect();
    let sub = Mesh::new(pos, local).ok()?;
    let topo = Topology::new(&sub);
    topo.components.iter().map(|c| c.genus).sum()
}
