//! Perturbations that delete triangles: scattered missing triangles and a hole cut by a
//! ball.

use super::rng::Rng;
use super::{PerturbError, Perturbed, SurfaceMap, ball_radius};
use crate::mesh::topology::Topology;
use crate::mesh::{Mesh, norm, sub};

/// Keeps the triangles flagged `keep`, drops the vertices no kept triangle uses, and
/// returns the new mesh with the surviving original vertex indices.
fn keep_triangles(mesh: &Mesh, keep: &[bool]) -> Result<(Mesh, Vec<usize>), PerturbError> {
    let n = mesh.n_vertices();
    let kept: Vec<[usize; 3]> = mesh
        .triangles()
        .iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .map(|(t, _)| *t)
        .collect();
    if kept.is_empty() {
        return Err(PerturbError::EmptyResult);
    }
    let mut used = vec![false; n];
    for t in &kept {
        for &v in t {
            used[v] = true;
        }
    }
    // Survivors keep their original relative order.
    let old: Vec<usize> = (0..n).filter(|&v| used[v]).collect();
    let mut renum = vec![usize::MAX; n];
    for (i, &v) in old.iter().enumerate() {
        renum[v] = i;
    }
    let tris = kept
        .into_iter()
        .map(|t| [renum[t[0]], renum[t[1]], renum[t[2]]])
        .collect();
    let positions = old.iter().map(|&v| mesh.positions()[v]).collect();
    Ok((Mesh::new(positions, tris)?, old))
}

/// Deletes `count` random triangles, chosen so that no two of them share a vertex and
/// none has a vertex on the boundary: each deletion opens a separate small triangular
/// hole, every vertex stays used and no vertex becomes pinched (non-manifold). If fewer
/// than `count` triangles qualify, as many as possible are deleted and the description
/// says so. Vertices are kept, so the map is [`SurfaceMap::Identity`]. Deterministic in
/// `seed`.
pub fn missing_triangles(mesh: &Mesh, count: usize, seed: u64) -> Result<Perturbed, PerturbError> {
    let m = mesh.n_triangles();
    let topo = Topology::new(mesh);
    let mut blocked = vec![false; mesh.n_vertices()];
    for v in topo.boundary_vertices() {
        blocked[v] = true;
    }
    for &v in &topo.non_manifold_vertices {
        blocked[v] = true;
    }
    for e in &topo.non_manifold_edges {
        blocked[e[0]] = true;
        blocked[e[1]] = true;
    }
    // Vertex valence in triangles: a vertex with a single triangle would become unused.
    let mut tri_count = vec![0usize; mesh.n_vertices()];
    for tri in mesh.triangles() {
        for &v in tri {
            tri_count[v] += 1;
        }
    }
    let mut rng = Rng::new(seed);
    let mut order: Vec<usize> = (0..m).collect();
    rng.shuffle(&mut order);
    let mut keep = vec![true; m];
    let mut removed = 0;
    for t in order {
        if removed == count {
            break;
        }
        let tri = mesh.triangles()[t];
        if tri.iter().any(|&v| blocked[v] || tri_count[v] < 3) {
            continue;
        }
        keep[t] = false;
        removed += 1;
        for &v in &tri {
            blocked[v] = true;
        }
    }
    if removed == m {
        return Err(PerturbError::EmptyResult);
    }
    let positions = mesh.positions().to_vec();
    let tris = mesh
        .triangles()
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(t, _)| *t)
        .collect();
    let note = if removed < count {
        format!(
            " (only {removed} of the {count} requested could be removed without pinching vertices)"
        )
    } else {
        String::new()
    };
    Ok(Perturbed {
        mesh: Mesh::new(positions, tris)?,
        map: SurfaceMap::Identity,
        description: format!(
            "missing triangles: {removed} vertex-disjoint triangles deleted, seed {seed}{note}"
        ),
    })
}

/// Largest number of clean-up rounds [`hole`] makes to remove pinched vertices.
const MAX_CLEANUP_ROUNDS: usize = 32;

/// Cuts a hole: deletes every triangle whose centroid is within `radius` of `center`,
/// then (up to a few rounds) also the triangles around vertices that the cut left
/// pinched (non-manifold), so the hole has a clean boundary loop; finally drops the
/// vertices no triangle uses. The map is [`SurfaceMap::Vertices`] (survivors are
/// unmoved original vertices).
pub fn hole(mesh: &Mesh, center: [f64; 3], radius: f64) -> Result<Perturbed, PerturbError> {
    let radius = ball_radius("hole radius", center, radius)?;
    let mut keep: Vec<bool> = (0..mesh.n_triangles())
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            let g = [
                (a[0] + b[0] + c[0]) / 3.0,
                (a[1] + b[1] + c[1]) / 3.0,
                (a[2] + b[2] + c[2]) / 3.0,
            ];
            norm(sub(g, center)) > radius
        })
        .collect();
    let removed0 = keep.iter().filter(|k| !**k).count();
    // Pinched vertices that the cut created (not those the input already had).
    let before: std::collections::HashSet<usize> = Topology::new(mesh)
        .non_manifold_vertices
        .into_iter()
        .collect();
    for _ in 0..MAX_CLEANUP_ROUNDS {
        let (sub_mesh, old) = keep_triangles(mesh, &keep)?;
        let topo = Topology::new(&sub_mesh);
        let pinched: Vec<usize> = topo
            .non_manifold_vertices
            .iter()
            .map(|&v| old[v])
            .filter(|v| !before.contains(v))
            .collect();
        if pinched.is_empty() {
            break;
        }
        let mut is_pinched = vec![false; mesh.n_vertices()];
        for v in pinched {
            is_pinched[v] = true;
        }
        for (t, tri) in mesh.triangles().iter().enumerate() {
            if tri.iter().any(|&v| is_pinched[v]) {
                keep[t] = false;
            }
        }
    }
    let removed = keep.iter().filter(|k| !**k).count();
    let (out, old) = keep_triangles(mesh, &keep)?;
    Ok(Perturbed {
        description: format!(
            "hole of radius {radius} about ({}, {}, {}): {removed} triangles removed ({removed0} by the ball, {} to unpinch vertices), {} vertices dropped",
            center[0],
            center[1],
            center[2],
            removed - removed0,
            mesh.n_vertices() - out.n_vertices()
        ),
        mesh: out,
        map: SurfaceMap::Vertices(old),
    })
}
