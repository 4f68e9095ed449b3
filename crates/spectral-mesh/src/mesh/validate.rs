//! Mesh checks ([`report`]) and repairs ([`repair`]).
//!
//! Definitions used by both:
//! - a *degenerate* (zero-area) triangle has area `<= DEGENERATE_AREA_FACTOR * d^2`, `d` the
//!   bounding-box diagonal of the mesh (all its vertices), i.e. `1e-14 d^2`: a triangle of
//!   that size is at the level of rounding noise of the coordinates;
//! - *duplicate* faces use the same three vertices, in any order or orientation; the first
//!   one in triangle order is the original, the later ones are duplicates;
//! - non-manifold edges and vertices, orientation and orientability are those of
//!   [`Topology`].

use std::collections::HashMap;

use super::topology::{Component, Topology, UnionFind, VertexTriangles};
use super::{Mesh, MeshError, cross, dot, norm, sorted_triangle, sub};

/// Triangles with area `<= DEGENERATE_AREA_FACTOR * diagonal^2` count as zero-area.
pub const DEGENERATE_AREA_FACTOR: f64 = 1e-14;

/// What [`report`] finds in a mesh. Vertex and triangle indices are 0-based.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MeshReport {
    /// Number of vertices (including unreferenced ones).
    pub vertices: usize,
    /// Number of distinct edges.
    pub edges: usize,
    /// Number of triangles.
    pub faces: usize,
    /// Number of connected components (through shared vertices).
    pub components: usize,
    /// Per-component counts, Euler characteristic and genus.
    pub component_details: Vec<Component>,
    /// Number of boundary loops.
    pub boundary_loops: usize,
    /// Number of boundary edges (edges with one triangle).
    pub boundary_edges: usize,
    /// Euler characteristic `V - E + F` over referenced vertices.
    pub euler_characteristic: i64,
    /// Genus of every closed component, in component order (`None` when the component is
    /// not an orientable manifold).
    pub closed_component_genus: Vec<Option<i64>>,
    /// True when every edge has two triangles and no vertex is pinched.
    pub closed_manifold: bool,
    /// Total area.
    pub area: f64,
    /// Bounding box corner with the smallest coordinates.
    pub bbox_min: [f64; 3],
    /// Bounding box corner with the largest coordinates.
    pub bbox_max: [f64; 3],
    /// Bounding-box diagonal.
    pub diagonal: f64,
    /// Smallest interior angle over all triangles, in degrees (0 for a triangle with a
    /// zero-length edge or collinear corners).
    pub smallest_angle_degrees: f64,
    /// Area threshold used for degenerate triangles (`1e-14 * diagonal^2`).
    pub degenerate_area_threshold: f64,
    /// Vertices no triangle uses.
    pub unreferenced_vertices: Vec<usize>,
    /// Triangles whose vertex set equals that of an earlier triangle.
    pub duplicate_faces: Vec<usize>,
    /// Zero-area triangles (see the module documentation).
    pub degenerate_faces: Vec<usize>,
    /// Edges with more than two triangles.
    pub non_manifold_edges: Vec<[usize; 2]>,
    /// Vertices whose triangles form more than one fan.
    pub non_manifold_vertices: Vec<usize>,
    /// Interior edges traversed in the same direction by both of their triangles.
    pub inconsistently_oriented_edges: usize,
    /// False when some component cannot be oriented consistently.
    pub orientable: bool,
}

impl MeshReport {
    /// One sentence per problem found (empty for a clean mesh). Boundaries, several
    /// components and skinny triangles are not problems.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        let mut add = |n: usize, what: &str| {
            if n > 0 {
                p.push(format!("{n} {what}"));
            }
        };
        add(self.unreferenced_vertices.len(), "unreferenced vertices");
        add(self.duplicate_faces.len(), "duplicate faces");
        add(
            self.degenerate_faces.len(),
            "zero-area (degenerate) triangles",
        );
        add(self.non_manifold_edges.len(), "non-manifold edges");
        add(self.non_manifold_vertices.len(), "non-manifold vertices");
        add(
            self.inconsistently_oriented_edges,
            "inconsistently oriented edges",
        );
        if !self.orientable {
            p.push("the mesh is not orientable".to_string());
        }
        p
    }

    /// True when [`MeshReport::problems`] is empty.
    pub fn is_clean(&self) -> bool {
        self.problems().is_empty()
    }
}

/// Smallest interior angle of a triangle, radians (0 when an edge has zero length).
fn min_angle(c: [[f64; 3]; 3]) -> f64 {
    let mut m = f64::INFINITY;
    for k in 0..3 {
        let (a, b, d) = (c[k], c[(k + 1) % 3], c[(k + 2) % 3]);
        let (u, v) = (sub(b, a), sub(d, a));
        let ang = if norm(u) == 0.0 || norm(v) == 0.0 {
            0.0
        } else {
            norm(cross(u, v)).atan2(dot(u, v))
        };
        m = m.min(ang);
    }
    m
}

fn duplicate_faces(tris: &[[usize; 3]]) -> Vec<usize> {
    let mut seen: HashMap<[usize; 3], usize> = HashMap::with_capacity(tris.len());
    let mut dups = Vec::new();
    for (t, &tri) in tris.iter().enumerate() {
        if seen.insert(sorted_triangle(tri), t).is_some() {
            dups.push(t);
        }
    }
    dups
}

fn degenerate_faces(mesh: &Mesh, threshold: f64) -> Vec<usize> {
    mesh.triangle_areas()
        .iter()
        .enumerate()
        .filter(|(_, a)| **a <= threshold)
        .map(|(t, _)| t)
        .collect()
}

/// Checks `mesh`: counts, topology and every problem listed on [`MeshReport`].
pub fn report(mesh: &Mesh) -> MeshReport {
    let topo = Topology::new(mesh);
    let (lo, hi) = mesh.bounding_box();
    let diagonal = mesh.diagonal();
    let threshold = DEGENERATE_AREA_FACTOR * diagonal * diagonal;
    let smallest = (0..mesh.n_triangles())
        .map(|t| min_angle(mesh.corners(t)))
        .fold(f64::INFINITY, f64::min);
    MeshReport {
        vertices: mesh.n_vertices(),
        edges: topo.edges.len(),
        faces: mesh.n_triangles(),
        components: topo.n_components(),
        component_details: topo.components.clone(),
        boundary_loops: topo.boundary_loops.len(),
        boundary_edges: topo.edge_face_count.iter().filter(|&&c| c == 1).count(),
        euler_characteristic: topo.euler_characteristic(),
        closed_component_genus: topo
            .components
            .iter()
            .filter(|c| c.closed)
            .map(|c| c.genus)
            .collect(),
        closed_manifold: topo.is_closed_manifold(),
        area: mesh.area(),
        bbox_min: lo,
        bbox_max: hi,
        diagonal,
        smallest_angle_degrees: smallest.to_degrees(),
        degenerate_area_threshold: threshold,
        unreferenced_vertices: topo.unreferenced_vertices.clone(),
        duplicate_faces: duplicate_faces(mesh.triangles()),
        degenerate_faces: degenerate_faces(mesh, threshold),
        non_manifold_edges: topo.non_manifold_edges.clone(),
        non_manifold_vertices: topo.non_manifold_vertices.clone(),
        inconsistently_oriented_edges: topo.inconsistently_oriented_edges,
        orientable: topo.orientable,
    }
}

/// Which repairs [`repair`] runs. `Default` runs all of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RepairOptions {
    /// Remove triangles whose vertex set repeats an earlier triangle (the first is kept).
    pub remove_duplicate_faces: bool,
    /// Remove zero-area triangles (threshold as in [`report`], on the input's diagonal).
    pub remove_degenerate_faces: bool,
    /// Give each pinched vertex one copy per fan of triangles (the fan with the lowest
    /// triangle index keeps the original vertex; the copies are appended at the end, with
    /// the same position).
    pub split_non_manifold_vertices: bool,
    /// Flip triangles so every orientable component is consistently oriented; per
    /// component (through edges with exactly two triangles) the orientation that needs
    /// fewer flips wins. Non-orientable components are left as they are and logged.
    pub orient_consistently: bool,
    /// Finally drop vertices no triangle uses and renumber the rest in order.
    pub remove_unreferenced_vertices: bool,
}

impl Default for RepairOptions {
    fn default() -> Self {
        Self {
            remove_duplicate_faces: true,
            remove_degenerate_faces: true,
            split_non_manifold_vertices: true,
            orient_consistently: true,
            remove_unreferenced_vertices: true,
        }
    }
}

/// The result of [`repair`].
#[derive(Debug, Clone)]
pub struct Repaired {
    /// The repaired mesh.
    pub mesh: Mesh,
    /// For every input vertex, its index in the repaired mesh (`None` when removed). A split
    /// vertex maps to the copy that kept the original index's first fan.
    pub vertex_map: Vec<Option<usize>>,
    /// One line per step that changed something (and per problem left in place).
    pub log: Vec<String>,
}

/// Removes the triangles `which` (ascending) and logs how many `what` went, if any.
fn remove_faces(tris: &mut Vec<[usize; 3]>, which: &[usize], what: &str, log: &mut Vec<String>) {
    if !which.is_empty() {
        remove_indices(tris, which);
        log.push(format!("removed {} {what}", which.len()));
    }
}

/// Repairs `mesh` in this order: duplicate faces, zero-area triangles, non-manifold
/// vertices, orientation, unreferenced vertices (each step switchable in `opts`).
///
/// Afterwards [`report`] shows no duplicate faces, no degenerate triangles, no
/// non-manifold vertices, no unreferenced vertices and no inconsistently oriented edges in
/// orientable components, for the steps switched on. Non-manifold edges are not repaired.
/// Fails with [`MeshError::Empty`] when every triangle was removed.
pub fn repair(mesh: &Mesh, opts: &RepairOptions) -> Result<Repaired, MeshError> {
    let n0 = mesh.n_vertices();
    let mut positions = mesh.positions().to_vec();
    let mut tris = mesh.triangles().to_vec();
    let mut log = Vec::new();

    if opts.remove_duplicate_faces {
        let dups = duplicate_faces(&tris);
        let what = "duplicate face(s) (same three vertices as an earlier face)";
        remove_faces(&mut tris, &dups, what, &mut log);
    }
    if opts.remove_degenerate_faces {
        let d = mesh.diagonal();
        let threshold = DEGENERATE_AREA_FACTOR * d * d;
        let current = Mesh::new(positions.clone(), tris.clone())?;
        let degen = degenerate_faces(&current, threshold);
        let what = format!("zero-area triangle(s) (area <= {threshold:e})");
        remove_faces(&mut tris, &degen, &what, &mut log);
    }
    if opts.split_non_manifold_vertices {
        let current = Mesh::new(positions.clone(), tris.clone())?;
        let (copies, split) = split_pinched(&current, &mut positions, &mut tris);
        if split > 0 {
            log.push(format!(
                "split {split} non-manifold vertex(es): {copies} copies added, one per extra fan"
            ));
        }
    }
    if opts.orient_consistently {
        let (flipped, comps_changed, non_orientable) = orient(&mut tris);
        if flipped > 0 {
            log.push(format!(
                "flipped {flipped} triangle(s) in {comps_changed} patch(es) to make the orientation consistent"
            ));
        }
        if non_orientable > 0 {
            log.push(format!(
                "{non_orientable} patch(es) are not orientable (e.g. a Moebius strip); left as they are"
            ));
        }
    }
    let n1 = positions.len();
    let mut vertex_map: Vec<Option<usize>> = (0..n0).map(Some).collect();
    if opts.remove_unreferenced_vertices {
        let mut used = vec![false; n1];
        for t in &tris {
            for &v in t {
                used[v] = true;
            }
        }
        let mut new_index = vec![usize::MAX; n1];
        let mut kept = Vec::with_capacity(n1);
        for v in 0..n1 {
            if used[v] {
                new_index[v] = kept.len();
                kept.push(positions[v]);
            }
        }
        let removed = n1 - kept.len();
        if removed > 0 {
            log.push(format!("removed {removed} unreferenced vertex(es)"));
        }
        for t in &mut tris {
            for v in t.iter_mut() {
                *v = new_index[*v];
            }
        }
        positions = kept;
        for (o, m) in vertex_map.iter_mut().enumerate() {
            *m = (new_index[o] != usize::MAX).then_some(new_index[o]);
        }
    }
    let mesh = Mesh::new(positions, tris)?;
    Ok(Repaired {
        mesh,
        vertex_map,
        log,
    })
}

/// Removes the triangles at the (ascending) indices `drop`.
fn remove_indices(tris: &mut Vec<[usize; 3]>, drop: &[usize]) {
    let mut k = 0;
    let mut t = 0;
    tris.retain(|_| {
        let remove = k < drop.len() && drop[k] == t;
        if remove {
            k += 1;
        }
        t += 1;
        !remove
    });
}

/// Splits every pinched vertex; returns (copies added, vertices split).
fn split_pinched(
    mesh: &Mesh,
    positions: &mut Vec<[f64; 3]>,
    tris: &mut [[usize; 3]],
) -> (usize, usize) {
    let topo = Topology::new(mesh);
    let vt = VertexTriangles::new(mesh);
    let mut copies = 0;
    for &v in &topo.non_manifold_vertices {
        let ts = vt.of(v);
        let mut local = UnionFind::new(ts.len());
        let mut spokes: Vec<(usize, usize)> = Vec::with_capacity(2 * ts.len());
        for (k, &t) in ts.iter().enumerate() {
            for &u in &mesh.triangles()[t] {
                if u != v {
                    spokes.push((u, k));
                }
            }
        }
        spokes.sort_unstable();
        for w in spokes.windows(2) {
            if w[0].0 == w[1].0 {
                local.union(w[0].1, w[1].1);
            }
        }
        // `ts` is ascending, so the fan of ts[0] (lowest triangle) keeps `v`.
        let keep = local.find(0);
        let mut fan_vertex: HashMap<usize, usize> = HashMap::new();
        for (k, &t) in ts.iter().enumerate() {
            let r = local.find(k);
            if r == keep {
                continue;
            }
            let nv = *fan_vertex.entry(r).or_insert_with(|| {
                positions.push(positions[v]);
                copies += 1;
                positions.len() - 1
            });
            for x in tris[t].iter_mut() {
                if *x == v {
                    *x = nv;
                }
            }
        }
    }
    (copies, topo.non_manifold_vertices.len())
}

/// Makes orientation consistent across edges with exactly two triangles.
/// Returns (triangles flipped, patches changed, non-orientable patches).
fn orient(tris: &mut [[usize; 3]]) -> (usize, usize, usize) {
    let m = tris.len();
    // Half-edges keyed by undirected edge: (edge, triangle, forward?).
    let mut half: Vec<([usize; 2], usize, bool)> = Vec::with_capacity(3 * m);
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            half.push(([a.min(b), a.max(b)], t, a < b));
        }
    }
    half.sort_unstable();
    // Adjacency: (neighbour, same_direction).
    let mut adj: Vec<Vec<(usize, bool)>> = vec![Vec::new(); m];
    let mut i = 0;
    while i < half.len() {
        let mut j = i;
        while j < half.len() && half[j].0 == half[i].0 {
            j += 1;
        }
        if j - i == 2 {
            let (t1, f1) = (half[i].1, half[i].2);
            let (t2, f2) = (half[i + 1].1, half[i + 1].2);
            if t1 != t2 {
                adj[t1].push((t2, f1 == f2));
                adj[t2].push((t1, f1 == f2));
            }
        }
        i = j;
    }
    let mut flip: Vec<Option<bool>> = vec![None; m];
    let mut flipped = 0;
    let mut changed = 0;
    let mut bad = 0;
    let mut queue = std::collections::VecDeque::new();
    for s in 0..m {
        if flip[s].is_some() {
            continue;
        }
        flip[s] = Some(false);
        queue.push_back(s);
        let mut patch = vec![s];
        let mut ok = true;
        while let Some(t) = queue.pop_front() {
            let ft = flip[t].unwrap_or(false);
            for &(u, same) in &adj[t] {
                // Same direction on the shared edge: exactly one of the two must flip.
                let want = ft ^ same;
                match flip[u] {
                    None => {
                        flip[u] = Some(want);
                        patch.push(u);
                        queue.push_back(u);
                    }
                    Some(f) if f != want => ok = false,
                    Some(_) => {}
                }
            }
        }
        if !ok {
            bad += 1;
            continue;
        }
        let n_flip = patch.iter().filter(|&&t| flip[t] == Some(true)).count();
        // Flip the minority.
        let flip_true = 2 * n_flip <= patch.len();
        let count = if flip_true {
            n_flip
        } else {
            patch.len() - n_flip
        };
        if count == 0 {
            continue;
        }
        changed += 1;
        flipped += count;
        for &t in &patch {
            if flip[t] == Some(flip_true) {
                tris[t].swap(1, 2);
            }
        }
    }
    (flipped, changed, bad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bow_tie, tetra};

    #[test]
    fn clean_tetrahedron_reports_nothing() {
        let r = report(&tetra());
        assert!(r.is_clean(), "{:?}", r.problems());
        assert_eq!((r.vertices, r.edges, r.faces), (4, 6, 4));
        assert_eq!(r.euler_characteristic, 2);
        assert_eq!(r.closed_component_genus, vec![Some(0)]);
        assert!(r.closed_manifold);
        // The tetrahedron's smallest angle is 45 degrees.
        assert!((r.smallest_angle_degrees - 45.0).abs() < 1e-9);
        let rep = repair(&tetra(), &RepairOptions::default()).unwrap();
        assert_eq!(rep.mesh, tetra());
        assert!(rep.log.is_empty());
        assert_eq!(rep.vertex_map, vec![Some(0), Some(1), Some(2), Some(3)]);
    }

    #[test]
    fn every_problem_is_found_and_repaired() {
        let (mut p, mut t) = tetra().into_parts();
        // Flip one face, duplicate one, add an unreferenced vertex and a zero-area triangle.
        t[1] = [0, 3, 1];
        t.push([2, 1, 3]);
        p.push([5.0, 5.0, 5.0]); // 4: unreferenced
        p.push([0.5, 0.0, 0.0]); // 5: on edge 0-1
        t.push([0, 5, 1]);
        let m = Mesh::new(p, t).unwrap();
        let r = report(&m);
        assert_eq!(r.unreferenced_vertices, vec![4]);
        assert_eq!(r.duplicate_faces, vec![4]);
        assert_eq!(r.degenerate_faces, vec![5]);
        assert!(r.inconsistently_oriented_edges > 0);
        assert_eq!(r.smallest_angle_degrees, 0.0);
        let rep = repair(&m, &RepairOptions::default()).unwrap();
        let r2 = report(&rep.mesh);
        assert!(r2.is_clean(), "{:?} / log {:?}", r2.problems(), rep.log);
        assert_eq!(rep.mesh.n_triangles(), 4);
        assert_eq!(rep.mesh.n_vertices(), 4);
        assert_eq!(rep.vertex_map[4], None);
        assert_eq!(rep.vertex_map[5], None);
        assert_eq!(rep.vertex_map[3], Some(3));
        // Majority orientation (the original, outward one) wins: 3 of 4 faces agree.
        let orig = tetra();
        for tri in rep.mesh.triangles() {
            let s = sorted_triangle(*tri);
            let o = orig
                .triangles()
                .iter()
                .find(|x| sorted_triangle(**x) == s)
                .unwrap();
            let rot = |x: [usize; 3]| [[x[0], x[1], x[2]], [x[1], x[2], x[0]], [x[2], x[0], x[1]]];
            assert!(rot(*o).contains(tri), "{tri:?} vs {o:?}");
        }
    }

    #[test]
    fn bow_tie_is_split_into_two_manifold_fans() {
        let m = bow_tie();
        assert_eq!(report(&m).non_manifold_vertices, vec![0]);
        let rep = repair(&m, &RepairOptions::default()).unwrap();
        let r = report(&rep.mesh);
        assert!(r.is_clean(), "{:?}", r.problems());
        assert_eq!(rep.mesh.n_vertices(), 6);
        assert_eq!(r.components, 2);
        assert_eq!(rep.mesh.positions()[5], [0.0, 0.0, 0.0]);
        assert_eq!(rep.mesh.triangles()[1], [5, 3, 4]);
        // Switched off: the pinch stays.
        let opts = RepairOptions {
            split_non_manifold_vertices: false,
            ..RepairOptions::default()
        };
        let rep = repair(&m, &opts).unwrap();
        assert_eq!(report(&rep.mesh).non_manifold_vertices, vec![0]);
    }

    #[test]
    fn all_degenerate_mesh_cannot_be_repaired() {
        let m = Mesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert_eq!(report(&m).degenerate_faces, vec![0]);
        assert!(matches!(
            repair(&m, &RepairOptions::default()),
            Err(MeshError::Empty { .. })
        ));
    }

    #[test]
    fn moebius_strip_is_reported_not_orientable_and_left_alone() {
        // A Moebius strip from 5 quads split into triangles over a twisted band.
        let k = 5;
        let mut p = Vec::new();
        for i in 0..k {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            let tw = a / 2.0;
            let (c, s) = (a.cos(), a.sin());
            for w in [-0.3, 0.3] {
                let r = 1.0 + w * tw.cos();
                p.push([r * c, r * s, w * tw.sin()]);
            }
        }
        let mut t = Vec::new();
        for i in 0..k {
            let (a0, a1) = (2 * i, 2 * i + 1);
            let (b0, b1) = if i + 1 < k {
                (2 * i + 2, 2 * i + 3)
            } else {
                (1, 0)
            };
            t.push([a0, b0, a1]);
            t.push([a1, b0, b1]);
        }
        let m = Mesh::new(p, t).unwrap();
        let r = report(&m);
        assert!(!r.orientable);
        let rep = repair(&m, &RepairOptions::default()).unwrap();
        assert_eq!(rep.mesh, m);
        assert!(rep.log.iter().any(|l| l.contains("not orientable")));
    }
}
