//! Fill-reducing ordering for the sparse Cholesky factorization: nested dissection by
//! level-structure separators, with approximate minimum degree (faer's AMD) on the small
//! parts.
//!
//! A mesh Laplacian's graph is the mesh's edge graph. Minimum degree alone leaves a factor
//! whose fill grows faster than `n log n` on large surfaces (measured on Loop subdivisions
//! of a 6,475-vertex mesh, see BENCHMARKS.md); nested dissection splits the graph by a small
//! set of vertices (a separator), orders the two halves first and the separator last, and
//! recurses, so that the halves' eliminations never fill across the separator.
//!
//! The separator of a connected part is one level of a breadth-first search from a
//! pseudo-peripheral vertex (the level near the median, the smallest within a balance
//! window), thinned to the vertices that touch the next level; on a surface a level is a
//! closed ring of about `sqrt(n)` vertices. The level chosen has the least separator
//! per pair of vertices it separates (`|S| / (|A| |B|)`) among those leaving at least
//! [`BALANCE`] of the part on each side. Parts of at most [`LEAF`] vertices are ordered by
//! AMD on their own induced graph. Multilevel partitioners (METIS) find smaller
//! separators still: CHOLMOD with METIS stores about 0.63 of its AMD factor on the 414k
//! mesh, this ordering 0.80 of faer's AMD one.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

use super::SparseMatrix;

/// Parts of at most this many vertices are ordered by minimum degree instead of being
/// dissected further.
pub(crate) const LEAF: usize = 1024;

/// The least share of a part each side of a separator must hold.
const BALANCE: f64 = 0.2;

/// Below this many rows the matrix is ordered by AMD alone: on the Loop subdivisions of
/// fandisk, dissection gave 12% more factor values than AMD at 26k rows, 6% fewer at 104k
/// and 20% fewer at 414k.
pub(crate) const MIN_ROWS: usize = 50_000;

/// The symmetric graph of a square sparse matrix (both triangles of its pattern, no
/// diagonal), as compressed rows.
struct Graph {
    start: Vec<usize>,
    adj: Vec<u32>,
}

impl Graph {
    fn of(a: &SparseMatrix) -> Self {
        let n = a.nrows();
        let (cp, ri) = (a.col_ptr(), a.row_idx());
        let mut deg = vec![0usize; n + 1];
        for j in 0..n {
            for &i in &ri[cp[j]..cp[j + 1]] {
                if i != j {
                    deg[i] += 1;
                    deg[j] += 1;
                }
            }
        }
        let mut start = vec![0usize; n + 1];
        for v in 0..n {
            start[v + 1] = start[v] + deg[v];
        }
        let mut fill = start.clone();
        let mut adj = vec![0u32; start[n]];
        for j in 0..n {
            for &i in &ri[cp[j]..cp[j + 1]] {
                if i != j {
                    adj[fill[i]] = j as u32;
                    fill[i] += 1;
                    adj[fill[j]] = i as u32;
                    fill[j] += 1;
                }
            }
        }
        // Both triangles may be stored: sort and remove repeated neighbours.
        let mut out_start = vec![0usize; n + 1];
        let mut w = 0;
        for v in 0..n {
            let row = &mut adj[start[v]..start[v + 1]];
            row.sort_unstable();
            let mut last = u32::MAX;
            for r in start[v]..start[v + 1] {
                let u = adj[r];
                if u != last {
                    adj[w] = u;
                    w += 1;
                    last = u;
                }
            }
            out_start[v + 1] = w;
        }
        adj.truncate(w);
        Self {
            start: out_start,
            adj,
        }
    }

    fn neighbours(&self, v: usize) -> &[u32] {
        &self.adj[self.start[v]..self.start[v + 1]]
    }
}

/// Work arrays shared by every part: `part[v]` is the id of the part `v` currently
/// belongs to (`u32::MAX` once ordered), `level[v]` a breadth-first level, `queue` the
/// search queue.
struct Dissection<'g> {
    g: &'g Graph,
    part: Vec<u32>,
    level: Vec<u32>,
    next_part: u32,
    /// `order[p]` is the vertex eliminated at position `p`.
    order: Vec<usize>,
}

/// A part waiting to be ordered into the positions `lo..lo + verts.len()`.
struct Pending {
    id: u32,
    verts: Vec<u32>,
    lo: usize,
}

const DONE: u32 = u32::MAX;
const UNSEEN: u32 = u32::MAX;

impl Dissection<'_> {
    /// Breadth-first search from `root` within part `id`; `queue` receives the vertices
    /// in visiting order, `level` their distances. Returns the number of levels.
    fn bfs(&mut self, root: u32, id: u32, queue: &mut Vec<u32>) -> usize {
        queue.clear();
        queue.push(root);
        self.level[root as usize] = 0;
        let mut head = 0;
        let mut depth = 0;
        while head < queue.len() {
            let v = queue[head] as usize;
            head += 1;
            let lv = self.level[v];
            depth = depth.max(lv as usize + 1);
            for &u in self.g.neighbours(v) {
                let u = u as usize;
                if self.part[u] == id && self.level[u] == UNSEEN {
                    self.level[u] = lv + 1;
                    queue.push(u as u32);
                }
            }
        }
        depth
    }

    fn reset_levels(&mut self, verts: &[u32]) {
        for &v in verts {
            self.level[v as usize] = UNSEEN;
        }
    }

    /// Splits the vertices of part `id` into connected components (each a new part id).
    fn components(&mut self, verts: &[u32], id: u32) -> Vec<(u32, Vec<u32>)> {
        let mut out = Vec::new();
        let mut queue = Vec::new();
        for &s in verts {
            if self.part[s as usize] != id {
                continue;
            }
            let cid = self.next_part;
            self.next_part += 1;
            self.part[s as usize] = cid;
            queue.clear();
            queue.push(s);
            let mut head = 0;
            while head < queue.len() {
                let v = queue[head] as usize;
                head += 1;
                for &u in self.g.neighbours(v) {
                    if self.part[u as usize] == id {
                        self.part[u as usize] = cid;
                        queue.push(u);
                    }
                }
            }
            out.push((cid, std::mem::take(&mut queue)));
        }
        out
    }

    /// Orders a small part by AMD on its induced graph.
    fn order_leaf(&mut self, p: &Pending) {
        let m = p.verts.len();
        if m == 1 {
            self.order[p.lo] = p.verts[0] as usize;
            self.part[p.verts[0] as usize] = DONE;
            return;
        }
        // Local numbering through `level` (free between searches).
        for (i, &v) in p.verts.iter().enumerate() {
            self.level[v as usize] = i as u32;
        }
        let mut col_ptr = Vec::with_capacity(m + 1);
        let mut rows = Vec::new();
        col_ptr.push(0usize);
        for &v in &p.verts {
            let first = rows.len();
            for &u in self.g.neighbours(v as usize) {
                if self.part[u as usize] == p.id {
                    rows.push(self.level[u as usize] as usize);
                }
            }
            rows[first..].sort_unstable();
            col_ptr.push(rows.len());
        }
        let mut perm = vec![0usize; m];
        let mut perm_inv = vec![0usize; m];
        let pattern = SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &rows);
        let ordered = MemBuffer::try_new(amd::order_scratch::<usize>(m, rows.len()))
            .ok()
            .and_then(|mut mem| {
                amd::order(
                    &mut perm,
                    &mut perm_inv,
                    pattern,
                    Default::default(),
                    MemStack::new(&mut mem),
                )
                .ok()
            })
            .is_some();
        for (i, slot) in self.order[p.lo..p.lo + m].iter_mut().enumerate() {
            let local = if ordered { perm[i] } else { i };
            *slot = p.verts[local] as usize;
        }
        for &v in &p.verts {
            self.level[v as usize] = UNSEEN;
            self.part[v as usize] = DONE;
        }
    }

    /// Dissects one connected part: returns its two sides as pending parts (each split
    /// into connected components), after placing its separator at the end of its range.
    /// `None` when no level splits it (it is then ordered as a leaf).
    fn dissect(&mut self, p: &Pending) -> Option<Vec<Pending>> {
        let n = p.verts.len();
        let mut queue = Vec::with_capacity(n);
        // A pseudo-peripheral root: repeat searches from the last vertex reached (the one
        // of least degree in the last level) while the depth grows.
        let mut root = p.verts[0];
        let mut depth = self.bfs(root, p.id, &mut queue);
        for _ in 0..4 {
            let last = self.level[*queue.last()? as usize];
            let candidate = queue
                .iter()
                .rev()
                .take_while(|&&v| self.level[v as usize] == last)
                .copied()
                .min_by_key(|&v| self.g.neighbours(v as usize).len())?;
            self.reset_levels(&p.verts);
            let d = self.bfs(candidate, p.id, &mut queue);
            if d <= depth {
                // Keep `candidate`'s levels: as good a root as the last.
                root = candidate;
                depth = d;
                break;
            }
            root = candidate;
            depth = d;
        }
        let _ = root;
        if depth < 3 || queue.len() != n {
            self.reset_levels(&p.verts);
            return None;
        }
        let mut count = vec![0usize; depth];
        for &v in &queue {
            count[self.level[v as usize] as usize] += 1;
        }
        // Per level, the vertices that touch the next level: the level's separator.
        let mut thin = vec![0usize; depth];
        for &v in &queue {
            let lv = self.level[v as usize];
            if self
                .g
                .neighbours(v as usize)
                .iter()
                .any(|&u| self.part[u as usize] == p.id && self.level[u as usize] == lv + 1)
            {
                thin[lv as usize] += 1;
            }
        }
        // The separating level: the least separator per pair of vertices it separates
        // (`|S| / (|A| |B|)`) among the levels with a share of the part on each side,
        // else the median level.
        let balance = BALANCE;
        let mut before = 0usize;
        let mut best: Option<(usize, f64)> = None;
        let mut median = depth / 2;
        let mut median_found = false;
        for (j, &c) in count.iter().enumerate() {
            let after = n - before - c;
            if !median_found && 2 * (before + c) >= n {
                median = j;
                median_found = true;
            }
            let a_len = before + c - thin[j];
            if j > 0
                && j + 1 < depth
                && a_len as f64 >= balance * n as f64
                && after as f64 >= balance * n as f64
            {
                let score = thin[j] as f64 / (a_len as f64 * after as f64);
                match best {
                    Some((_, bs)) if bs <= score => {}
                    _ => best = Some((j, score)),
                }
            }
            before += c;
        }
        let sep_level = best.map_or(median, |(j, _)| j).clamp(1, depth - 2) as u32;
        // Separator: the vertices of that level with a neighbour one level further.
        let a_id = self.next_part;
        let b_id = self.next_part + 1;
        self.next_part += 2;
        let mut separator = Vec::new();
        let mut a = Vec::new();
        let mut b = Vec::new();
        for &v in &p.verts {
            let lv = self.level[v as usize];
            if lv < sep_level {
                a.push(v);
            } else if lv > sep_level {
                b.push(v);
            } else if self
                .g
                .neighbours(v as usize)
                .iter()
                .any(|&u| self.part[u as usize] == p.id && self.level[u as usize] == lv + 1)
            {
                separator.push(v);
            } else {
                a.push(v);
            }
        }
        self.reset_levels(&p.verts);
        for &v in &a {
            self.part[v as usize] = a_id;
        }
        for &v in &b {
            self.part[v as usize] = b_id;
        }
        // The separator is eliminated last, in its search order (a ring: a thin band).
        let hi = p.lo + n;
        for (slot, &v) in self.order[hi - separator.len()..hi]
            .iter_mut()
            .zip(&separator)
        {
            *slot = v as usize;
            self.part[v as usize] = DONE;
        }
        let mut out = Vec::new();
        let mut lo = p.lo;
        for (side, id) in [(a, a_id), (b, b_id)] {
            for (cid, verts) in self.components(&side, id) {
                let len = verts.len();
                out.push(Pending { id: cid, verts, lo });
                lo += len;
            }
        }
        Some(out)
    }
}

/// A nested-dissection ordering of the symmetric pattern of `a` (both triangles are read;
/// the diagonal is ignored): `order[p]` is the row eliminated at position `p`. Every
/// connected component is dissected on its own.
pub(crate) fn nested_dissection(a: &SparseMatrix) -> Vec<usize> {
    let n = a.nrows();
    let g = Graph::of(a);
    let mut d = Dissection {
        g: &g,
        part: vec![0; n],
        level: vec![UNSEEN; n],
        next_part: 1,
        order: vec![0; n],
    };
    let all: Vec<u32> = (0..n as u32).collect();
    let mut stack: Vec<Pending> = Vec::new();
    let mut lo = 0;
    for (id, verts) in d.components(&all, 0) {
        let len = verts.len();
        stack.push(Pending { id, verts, lo });
        lo += len;
    }
    while let Some(p) = stack.pop() {
        if p.verts.len() <= LEAF {
            d.order_leaf(&p);
            continue;
        }
        match d.dissect(&p) {
            Some(parts) => stack.extend(parts),
            None => d.order_leaf(&p),
        }
    }
    postorder(&g, d.order)
}

/// The same elimination order renumbered in a postorder of its elimination tree (children
/// in increasing order, each subtree a range of positions). The fill and the tree's shape
/// do not change; the factor's supernodes then number every subtree as a range, which the
/// two-thread triangular solves rely on (`supernodal.rs`), and siblings sit side by side.
fn postorder(g: &Graph, order: Vec<usize>) -> Vec<usize> {
    const NONE: usize = usize::MAX;
    let n = order.len();
    let mut inv = vec![0usize; n];
    for (p, &v) in order.iter().enumerate() {
        inv[v] = p;
    }
    // The elimination tree by ancestor links with path compression: for every entry
    // (j, k) with k < j, the root of k's current tree becomes a child of j.
    let mut parent = vec![NONE; n];
    let mut ancestor = vec![NONE; n];
    for (j, &v) in order.iter().enumerate() {
        for &u in g.neighbours(v) {
            let mut i = inv[u as usize];
            while i != NONE && i < j {
                let next = ancestor[i];
                ancestor[i] = j;
                if next == NONE {
                    parent[i] = j;
                }
                i = next;
            }
        }
    }
    // Children lists (increasing, as compressed rows), then a depth-first postorder.
    let mut start = vec![0usize; n + 1];
    for &p in &parent {
        if p != NONE {
            start[p + 1] += 1;
        }
    }
    for j in 0..n {
        start[j + 1] += start[j];
    }
    let mut fill = start.clone();
    let mut children = vec![0usize; start[n]];
    for (i, &p) in parent.iter().enumerate() {
        if p != NONE {
            children[fill[p]] = i;
            fill[p] += 1;
        }
    }
    let mut out = Vec::with_capacity(n);
    let mut stack: Vec<(usize, usize)> = Vec::new();
    for root in (0..n).filter(|&i| parent[i] == NONE) {
        stack.push((root, start[root]));
        while let Some((node, next)) = stack.last_mut() {
            if *next < start[*node + 1] {
                let child = children[*next];
                *next += 1;
                stack.push((child, start[child]));
            } else {
                out.push(order[*node]);
                stack.pop();
            }
        }
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The 5-point Laplacian of an `m x m` grid plus the identity.
    fn grid(m: usize) -> SparseMatrix {
        grid_matrix(m, 5.0)
    }

    /// The `m x m` grid matrix with `diagonal` on the diagonal and -1 between grid
    /// neighbours (vertex `i m + j` at row `i`, column `j`).
    pub(crate) fn grid_matrix(m: usize, diagonal: f64) -> SparseMatrix {
        let id = |i: usize, j: usize| i * m + j;
        let mut t = Vec::new();
        for i in 0..m {
            for j in 0..m {
                t.push((id(i, j), id(i, j), diagonal));
                if i + 1 < m {
                    t.push((id(i + 1, j), id(i, j), -1.0));
                    t.push((id(i, j), id(i + 1, j), -1.0));
                }
                if j + 1 < m {
                    t.push((id(i, j + 1), id(i, j), -1.0));
                    t.push((id(i, j), id(i, j + 1), -1.0));
                }
            }
        }
        SparseMatrix::from_triplets(m * m, m * m, &t)
    }

    #[test]
    fn the_order_is_a_permutation_of_every_component() {
        // Two grids side by side (two components) and an isolated vertex.
        let (g1, g2) = (grid(90), grid(40));
        let (n1, n2) = (g1.nrows(), g2.nrows());
        let mut t = Vec::new();
        for (off, g) in [(0, &g1), (n1, &g2)] {
            for j in 0..g.nrows() {
                for r in g.col_ptr()[j]..g.col_ptr()[j + 1] {
                    t.push((g.row_idx()[r] + off, j + off, 1.0));
                }
            }
        }
        let n = n1 + n2 + 1;
        t.push((n - 1, n - 1, 1.0));
        let a = SparseMatrix::from_triplets(n, n, &t);
        let order = nested_dissection(&a);
        let mut seen = vec![false; n];
        for &v in &order {
            assert!(!seen[v], "vertex {v} ordered twice");
            seen[v] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn a_separator_is_eliminated_after_both_sides_it_separates() {
        // On a 100 x 100 grid the last positions hold the top separator: removing the
        // vertices ordered last must disconnect what was ordered first from the rest.
        let m = 100;
        let a = grid(m);
        let order = nested_dissection(&a);
        let mut pos = vec![0; m * m];
        for (p, &v) in order.iter().enumerate() {
            pos[v] = p;
        }
        // The top separator: a trailing run of at most 2m vertices whose removal splits
        // the rest; find it as the smallest tail that does.
        let g = Graph::of(&a);
        let splits = |tail: usize| {
            let cut = m * m - tail;
            let mut comp = vec![usize::MAX; cut];
            let mut count = 0;
            for s in 0..m * m {
                if pos[s] >= cut || comp[pos[s]] != usize::MAX {
                    continue;
                }
                let mut q = vec![s];
                comp[pos[s]] = count;
                while let Some(v) = q.pop() {
                    for &u in g.neighbours(v) {
                        let u = u as usize;
                        if pos[u] < cut && comp[pos[u]] == usize::MAX {
                            comp[pos[u]] = count;
                            q.push(u);
                        }
                    }
                }
                count += 1;
            }
            count >= 2
        };
        let tail = (1..=2 * m).find(|&t| splits(t));
        let tail = tail.expect("the last 2m vertices of the order separate the grid");
        assert!(
            tail <= 2 * m,
            "separator of {tail} vertices on a {m} x {m} grid"
        );
    }

    #[test]
    fn dissection_fills_less_than_minimum_degree_on_a_large_grid() {
        use faer::sparse::linalg::cholesky::{
            CholeskySymbolicParams, SymmetricOrdering, factorize_symbolic_cholesky,
        };
        use faer::{Side, perm::PermRef};
        let a = grid(300);
        let n = a.nrows();
        let view = SymbolicSparseColMatRef::new_checked(n, n, a.col_ptr(), None, a.row_idx());
        let nnz = |ord: SymmetricOrdering<'_, usize>| {
            factorize_symbolic_cholesky(view, Side::Lower, ord, CholeskySymbolicParams::default())
                .unwrap()
                .len_val()
        };
        let order = nested_dissection(&a);
        let mut inv = vec![0; n];
        for (p, &v) in order.iter().enumerate() {
            inv[v] = p;
        }
        let perm = PermRef::new_checked(&order, &inv, n);
        let amd = nnz(SymmetricOrdering::Amd);
        let nd = nnz(SymmetricOrdering::Custom(perm));
        assert!(
            (nd as f64) < 0.95 * amd as f64,
            "nested dissection {nd} values against AMD's {amd}"
        );
    }
}
