//! The pairing as first written (commit 832c158), kept as the reference the fast one is
//! tested against: a comparison sort of the vertices, one sweep after the other, a
//! union-find over the whole mesh, the lower neighbours of each vertex gathered from its
//! link edges and all joined at once to the oldest piece.

use crate::fields::critical_points::{
    CriticalPointFinder, CriticalPoints, CriticalPointsError, check_length, quantized,
};
use crate::fields::persistence::{Persistence, assemble, component_ranges};
use crate::mesh::topology::UnionFind;

/// The classification's order (rounded values, ties by index) of the vertices a triangle
/// uses.
pub(super) fn order(finder: &CriticalPointFinder, field: &[f64]) -> Vec<usize> {
    let n = finder.n_vertices();
    let q = quantized(field);
    let mut order: Vec<usize> = (0..n)
        .filter(|&v| finder.component_of(v).is_some())
        .collect();
    order.sort_unstable_by(|&a, &b| q[a].total_cmp(&q[b]).then(a.cmp(&b)));
    order
}

/// The persistence of the critical points `raw` of `field` (found by `finder` with
/// [`CriticalPointFinder::find`]) and the simplified set under the default threshold.
pub(super) fn persistence(
    finder: &CriticalPointFinder,
    field: &[f64],
    raw: CriticalPoints,
) -> Result<Persistence, CriticalPointsError> {
    let n = finder.n_vertices();
    check_length(field, n)?;
    let mut order = order(finder, field);
    let (up_pairs, up_essential) = sweep(finder, &order, n);
    order.reverse();
    let (down_pairs, down_essential) = sweep(finder, &order, n);

    // What follows the pairing is the one assembly.
    Ok(assemble(
        finder,
        field,
        raw,
        component_ranges(finder, field),
        (up_pairs, up_essential),
        (down_pairs, down_essential),
    ))
}

/// One sweep over `order` (every vertex a triangle uses): the pairs `(extremum, saddle)`
/// of the pieces that die, and the extremum of each piece left at the end (one per
/// connected component).
pub(super) fn sweep(
    finder: &CriticalPointFinder,
    order: &[usize],
    n: usize,
) -> (Vec<(usize, usize)>, Vec<usize>) {
    let mut rank = vec![usize::MAX; n];
    for (i, &v) in order.iter().enumerate() {
        rank[v] = i;
    }
    let mut uf = UnionFind::new(n);
    // The extremum (oldest vertex) of the piece whose root this is.
    let mut birth = vec![usize::MAX; n];
    let mut pairs = Vec::new();
    let mut roots: Vec<usize> = Vec::new();
    for &v in order {
        roots.clear();
        for &(a, b) in finder.link_edges(v) {
            for u in [a, b] {
                if rank[u] < rank[v] {
                    let r = uf.find(u);
                    if !roots.contains(&r) {
                        roots.push(r);
                    }
                }
            }
        }
        let Some(&elder) = roots.iter().min_by_key(|&&r| rank[birth[r]]) else {
            birth[v] = v;
            continue;
        };
        let oldest = birth[elder];
        for &r in &roots {
            if r != elder {
                pairs.push((birth[r], v));
            }
            uf.union(r, v);
        }
        let root = uf.find(v);
        birth[root] = oldest;
    }
    let mut essential: Vec<usize> = order
        .iter()
        .filter(|&&v| uf.find(v) == v)
        .map(|&v| birth[v])
        .collect();
    essential.sort_unstable();
    (pairs, essential)
}
