//! Connectivity: edges, boundary loops, connected components, Euler characteristic,
//! genus, manifoldness and orientation.
//!
//! Everything here is combinatorial: positions are never read.

use super::Mesh;

/// Union-find over `0..n` with path halving and union by size.
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<usize>,
    size: Vec<usize>,
}

impl UnionFind {
    /// `n` singletons.
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
            size: vec![1; n],
        }
    }

    /// `n` singletons again, keeping the allocation.
    pub fn reset(&mut self, n: usize) {
        self.parent.clear();
        self.parent.extend(0..n);
        self.size.clear();
        self.size.resize(n, 1);
    }

    /// Representative of `x`.
    pub fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }

    /// Merges the sets of `a` and `b`; returns false if they were already one.
    pub fn union(&mut self, a: usize, b: usize) -> bool {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return false;
        }
        if self.size[a] < self.size[b] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b] = a;
        self.size[a] += self.size[b];
        true
    }
}

/// Vertex-to-triangle incidence in compressed form.
#[derive(Debug, Clone)]
pub struct VertexTriangles {
    offsets: Vec<usize>,
    triangles: Vec<usize>,
}

impl VertexTriangles {
    /// Builds the incidence of `mesh`.
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.n_vertices();
        let mut offsets = vec![0usize; n + 1];
        for tri in mesh.triangles() {
            for &v in tri {
                offsets[v + 1] += 1;
            }
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut triangles = vec![0; offsets[n]];
        for (t, tri) in mesh.triangles().iter().enumerate() {
            for &v in tri {
                triangles[fill[v]] = t;
                fill[v] += 1;
            }
        }
        Self { offsets, triangles }
    }

    /// Triangles incident to vertex `v`, ascending.
    pub fn of(&self, v: usize) -> &[usize] {
        &self.triangles[self.offsets[v]..self.offsets[v + 1]]
    }
}

/// One connected component (of the triangles, through shared vertices).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Component {
    /// Referenced vertices in the component.
    pub vertices: usize,
    /// Distinct edges in the component.
    pub edges: usize,
    /// Triangles in the component.
    pub faces: usize,
    /// Boundary loops in the component.
    pub boundary_loops: usize,
    /// Euler characteristic V - E + F.
    pub euler_characteristic: i64,
    /// Genus `(2 - chi - b) / 2` when the component is an orientable manifold, else `None`.
    pub genus: Option<i64>,
    /// True when the component has no boundary.
    pub closed: bool,
}

/// The connected components of a mesh's vertices through its triangles: the part of
/// [`Topology`] that reports on eigenbases need (how many zero eigenvalues to expect),
/// in a few milliseconds where the whole topology takes tens (43 ms at 104k vertices).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VertexComponents {
    /// Component of each vertex (`usize::MAX` for a vertex no triangle uses), numbered in
    /// the order of their first vertex.
    pub of_vertex: Vec<usize>,
    /// Number of components.
    pub count: usize,
}

impl VertexComponents {
    /// The components of `mesh` (union-find over its triangles).
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.n_vertices();
        let tris = mesh.triangles();
        let mut uf = UnionFind::new(n);
        let mut used = vec![false; n];
        for tri in tris {
            uf.union(tri[0], tri[1]);
            uf.union(tri[0], tri[2]);
            for &v in tri {
                used[v] = true;
            }
        }
        let mut of_vertex = vec![usize::MAX; n];
        let mut of_root = vec![usize::MAX; n];
        let mut count = 0;
        for v in 0..n {
            if used[v] {
                let r = uf.find(v);
                if of_root[r] == usize::MAX {
                    of_root[r] = count;
                    count += 1;
                }
                of_vertex[v] = of_root[r];
            }
        }
        Self { of_vertex, count }
    }
}

/// The connectivity of a mesh, computed once.
#[derive(Debug, Clone)]
pub struct Topology {
    /// Distinct undirected edges `(i, j)`, `i < j`, sorted.
    pub edges: Vec<[usize; 2]>,
    /// Number of triangles on each edge (1 = boundary, 2 = interior, more = non-manifold).
    pub edge_face_count: Vec<u32>,
    /// Boundary loops as vertex cycles, following the triangles' orientation.
    pub boundary_loops: Vec<Vec<usize>>,
    /// Component of each vertex (`usize::MAX` for a vertex no triangle uses).
    pub vertex_component: Vec<usize>,
    /// Component of each triangle.
    pub triangle_component: Vec<usize>,
    /// Per-component counts.
    pub components: Vec<Component>,
    /// Vertices no triangle uses.
    pub unreferenced_vertices: Vec<usize>,
    /// Edges shared by more than two triangles.
    pub non_manifold_edges: Vec<[usize; 2]>,
    /// Vertices whose triangles do not form one fan (a "pinch" or bow-tie).
    pub non_manifold_vertices: Vec<usize>,
    /// Interior edges traversed in the same direction by both of their triangles.
    pub inconsistently_oriented_edges: usize,
    /// False when some component cannot be oriented consistently (e.g. a Möbius strip).
    pub orientable: bool,
}

impl Topology {
    /// Computes the connectivity of `mesh` in O(m log m).
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.n_vertices();
        let tris = mesh.triangles();
        // Half-edges keyed by undirected edge, sorted: grouped by their smaller vertex (a
        // counting sort), then each group sorted on its own, which gives the order of one
        // sort of them all in linear time plus small sorts.
        let mut start = vec![0usize; n + 1];
        for tri in tris {
            for k in 0..3 {
                start[tri[k].min(tri[(k + 1) % 3]) + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut half: Vec<([usize; 2], usize, bool)> = vec![([0, 0], 0, false); 3 * tris.len()];
        for (t, tri) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let lo = a.min(b);
                half[fill[lo]] = ([lo, a.max(b)], t, a < b);
                fill[lo] += 1;
            }
        }
        for v in 0..n {
            half[start[v]..start[v + 1]].sort_unstable();
        }
        let mut edges = Vec::new();
        let mut edge_face_count = Vec::new();
        let mut non_manifold_edges = Vec::new();
        let mut inconsistent = 0usize;
        // Orientation parity graph: for each interior manifold edge, relation between faces.
        let mut same_dir_pairs: Vec<(usize, usize, bool)> = Vec::new();
        let mut boundary_half: Vec<(usize, usize)> = Vec::new();
        let mut i = 0;
        while i < half.len() {
            let mut j = i;
            while j < half.len() && half[j].0 == half[i].0 {
                j += 1;
            }
            let e = half[i].0;
            edges.push(e);
            edge_face_count.push((j - i) as u32);
            match j - i {
                1 => {
                    let (t, fwd) = (half[i].1, half[i].2);
                    let _ = t;
                    if fwd {
                        boundary_half.push((e[0], e[1]));
                    } else {
                        boundary_half.push((e[1], e[0]));
                    }
                }
                2 => {
                    let same = half[i].2 == half[i + 1].2;
                    if same {
                        inconsistent += 1;
                    }
                    same_dir_pairs.push((half[i].1, half[i + 1].1, same));
                }
                _ => non_manifold_edges.push(e),
            }
            i = j;
        }
        let VertexComponents {
            of_vertex: comp_id,
            count: nc,
        } = VertexComponents::new(mesh);
        let triangle_component: Vec<usize> = tris.iter().map(|t| comp_id[t[0]]).collect();
        // A vertex no triangle uses has no component.
        let unreferenced_vertices: Vec<usize> =
            (0..n).filter(|&v| comp_id[v] == usize::MAX).collect();

        // Orientability: 2-colouring of faces by flip parity.
        let mut parity_uf = UnionFind::new(2 * tris.len());
        let mut orientable = true;
        for &(a, b, same) in &same_dir_pairs {
            // same direction -> faces need opposite flip states.
            if same {
                parity_uf.union(2 * a, 2 * b + 1);
                parity_uf.union(2 * a + 1, 2 * b);
            } else {
                parity_uf.union(2 * a, 2 * b);
                parity_uf.union(2 * a + 1, 2 * b + 1);
            }
        }
        for t in 0..tris.len() {
            if parity_uf.find(2 * t) == parity_uf.find(2 * t + 1) {
                orientable = false;
                break;
            }
        }
        let mut comp_orientable = vec![true; nc];
        if !orientable {
            for t in 0..tris.len() {
                if parity_uf.find(2 * t) == parity_uf.find(2 * t + 1) {
                    comp_orientable[triangle_component[t]] = false;
                }
            }
        }

        let boundary_loops = trace_loops(&boundary_half);

        // Non-manifold vertices: the link of the vertex is not one fan.
        let vt = VertexTriangles::new(mesh);
        let mut non_manifold_vertices = Vec::new();
        // Reused for every vertex.
        let mut local = UnionFind::new(0);
        let mut spokes: Vec<(usize, usize)> = Vec::new();
        for v in 0..n {
            let ts = vt.of(v);
            if ts.len() < 2 {
                continue;
            }
            // Local union-find over the triangles of v, merged across shared edges at v.
            local.reset(ts.len());
            spokes.clear();
            for (k, &t) in ts.iter().enumerate() {
                for &u in &tris[t] {
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
            let root = local.find(0);
            if (1..ts.len()).any(|k| local.find(k) != root) {
                non_manifold_vertices.push(v);
            }
        }

        let mut components = vec![
            Component {
                vertices: 0,
                edges: 0,
                faces: 0,
                boundary_loops: 0,
                euler_characteristic: 0,
                genus: None,
                closed: true,
            };
            nc
        ];
        for v in 0..n {
            if comp_id[v] != usize::MAX {
                components[comp_id[v]].vertices += 1;
            }
        }
        for e in &edges {
            components[comp_id[e[0]]].edges += 1;
        }
        for &c in &triangle_component {
            components[c].faces += 1;
        }
        for l in &boundary_loops {
            components[comp_id[l[0]]].boundary_loops += 1;
        }
        let mut comp_manifold = vec![true; nc];
        for e in &non_manifold_edges {
            comp_manifold[comp_id[e[0]]] = false;
        }
        for &v in &non_manifold_vertices {
            comp_manifold[comp_id[v]] = false;
        }
        for (c, comp) in components.iter_mut().enumerate() {
            comp.euler_characteristic =
                comp.vertices as i64 - comp.edges as i64 + comp.faces as i64;
            comp.closed = comp.boundary_loops == 0;
            let twice = 2 - comp.euler_characteristic - comp.boundary_loops as i64;
            if comp_manifold[c] && comp_orientable[c] && twice >= 0 && twice % 2 == 0 {
                comp.genus = Some(twice / 2);
            }
        }
        Self {
            edges,
            edge_face_count,
            boundary_loops,
            vertex_component: comp_id,
            triangle_component,
            components,
            unreferenced_vertices,
            non_manifold_edges,
            non_manifold_vertices,
            inconsistently_oriented_edges: inconsistent,
            orientable,
        }
    }

    /// Number of connected components.
    pub fn n_components(&self) -> usize {
        self.components.len()
    }

    /// Euler characteristic of the whole mesh (referenced vertices only).
    pub fn euler_characteristic(&self) -> i64 {
        self.components.iter().map(|c| c.euler_characteristic).sum()
    }

    /// Vertices on some boundary edge, ascending.
    pub fn boundary_vertices(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.boundary_loops.iter().flatten().copied().collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// True when every edge has exactly two triangles and no vertex is pinched.
    pub fn is_closed_manifold(&self) -> bool {
        self.edge_face_count.iter().all(|&c| c == 2) && self.non_manifold_vertices.is_empty()
    }
}

/// Follows boundary edges into loops. Each edge is used once; the first edge of a loop
/// is walked in its triangle's direction, the rest follow adjacency, so a flipped
/// triangle or a pinched boundary vertex never breaks a loop apart.
fn trace_loops(boundary: &[(usize, usize)]) -> Vec<Vec<usize>> {
    // Undirected incidence: (vertex, edge index).
    let mut inc: Vec<(usize, usize)> = Vec::with_capacity(2 * boundary.len());
    for (e, &(a, b)) in boundary.iter().enumerate() {
        inc.push((a, e));
        inc.push((b, e));
    }
    inc.sort_unstable();
    let mut used = vec![false; boundary.len()];
    let mut loops = Vec::new();
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let (first, mut cur) = boundary[start];
        let mut lp = vec![first];
        while cur != first {
            lp.push(cur);
            let lo = inc.partition_point(|h| h.0 < cur);
            match (lo..inc.len())
                .take_while(|&k| inc[k].0 == cur)
                .map(|k| inc[k].1)
                .find(|&e| !used[e])
            {
                Some(e) => {
                    used[e] = true;
                    let (a, b) = boundary[e];
                    cur = if a == cur { b } else { a };
                }
                None => break,
            }
        }
        loops.push(lp);
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bow_tie, tetra};

    #[test]
    fn edges_are_every_triangle_side_once_sorted_with_their_face_counts() {
        // A grid with a fold (an edge of three triangles), a pinched vertex and a triangle
        // listed twice: the bucketed sort must give the order of one sort of all sides.
        let mut tris = crate::test_support::grid(6, |i, j| [i as f64, j as f64, 0.0])
            .triangles()
            .to_vec();
        tris.push([0, 1, 40]);
        tris.push([7, 45, 48]);
        tris.push(tris[3]);
        let n = 49;
        let positions: Vec<[f64; 3]> = (0..n).map(|v| [v as f64, (v * v) as f64, 1.0]).collect();
        let mesh = Mesh::new(positions, tris.clone()).unwrap();
        let t = Topology::new(&mesh);
        let mut sides: Vec<[usize; 2]> = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
            .collect();
        sides.sort_unstable();
        let mut expected: Vec<([usize; 2], u32)> = Vec::new();
        for e in sides {
            match expected.last_mut() {
                Some((last, c)) if *last == e => *c += 1,
                _ => expected.push((e, 1)),
            }
        }
        let got: Vec<([usize; 2], u32)> = t
            .edges
            .iter()
            .copied()
            .zip(t.edge_face_count.iter().copied())
            .collect();
        assert_eq!(got, expected);
        let folds: Vec<[usize; 2]> = expected
            .iter()
            .filter(|(_, c)| *c > 2)
            .map(|(e, _)| *e)
            .collect();
        assert!(!folds.is_empty());
        assert_eq!(t.non_manifold_edges, folds);
    }

    #[test]
    fn tetrahedron_is_a_closed_sphere() {
        let t = Topology::new(&tetra());
        assert_eq!(t.edges.len(), 6);
        assert_eq!(t.n_components(), 1);
        assert_eq!(t.euler_characteristic(), 2);
        assert_eq!(t.components[0].genus, Some(0));
        assert!(t.is_closed_manifold());
        assert_eq!(t.inconsistently_oriented_edges, 0);
        assert!(t.boundary_loops.is_empty());
    }

    #[test]
    fn open_fan_has_one_boundary_loop_and_flip_is_detected() {
        let mut m = tetra().into_parts();
        m.1.pop();
        m.1[0] = [0, 1, 2];
        let t = Topology::new(&Mesh::new(m.0, m.1).unwrap());
        assert_eq!(t.boundary_loops.len(), 1);
        assert_eq!(t.boundary_loops[0].len(), 3);
        assert!(t.inconsistently_oriented_edges > 0);
        assert!(t.orientable);
    }

    #[test]
    fn vertex_components_number_components_by_first_vertex() {
        // Three pieces listed out of order (the triangle 6-7-8 first), and vertex 5 in no
        // triangle.
        let positions: Vec<[f64; 3]> = (0..12).map(|v| [v as f64, (v * v) as f64, 1.0]).collect();
        let tris = vec![[6, 7, 8], [9, 10, 11], [0, 1, 2], [2, 3, 4], [8, 6, 9]];
        let mesh = Mesh::new(positions, tris).unwrap();
        let c = VertexComponents::new(&mesh);
        let m = usize::MAX;
        assert_eq!(c.count, 2);
        assert_eq!(c.of_vertex, vec![0, 0, 0, 0, 0, m, 1, 1, 1, 1, 1, 1]);
        let t = Topology::new(&mesh);
        assert_eq!(t.vertex_component, c.of_vertex);
        assert_eq!(t.n_components(), c.count);
        assert_eq!(t.unreferenced_vertices, vec![5]);
    }

    #[test]
    fn bow_tie_vertex_is_non_manifold() {
        let m = bow_tie();
        let t = Topology::new(&m);
        assert_eq!(t.non_manifold_vertices, vec![0]);
        assert_eq!(t.n_components(), 1);
        assert_eq!(t.components[0].genus, None);
    }
}
