//! The pairing as first written (commit 832c158), kept as the reference the fast one is
//! tested against: a comparison sort of the vertices, one sweep after the other, a
//! union-find over the whole mesh, the lower neighbours of each vertex gathered from its
//! link edges and all joined at once to the oldest piece.

use crate::fields::critical_points::{
    BoundaryRule, CriticalPointFinder, CriticalPoints, CriticalPointsError, quantized,
};
use crate::fields::persistence::{
    ExtremumKind, PERSISTENCE_NOISE_FLOOR, PERSISTENCE_RELATIVE_THRESHOLD, Persistence,
    PersistencePair,
};
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
    if field.len() != n {
        return Err(CriticalPointsError::LengthMismatch {
            expected: n,
            got: field.len(),
        });
    }
    let mut order = order(finder, field);
    let (up_pairs, up_essential) = sweep(finder, &order, n);
    order.reverse();
    let (down_pairs, down_essential) = sweep(finder, &order, n);

    // Range and scale over finite values; per component as well.
    let nc = finder.n_components();
    let mut lo = vec![f64::INFINITY; nc];
    let mut hi = vec![f64::NEG_INFINITY; nc];
    let mut finite = vec![true; nc];
    let mut first = vec![usize::MAX; nc];
    for v in 0..n {
        let Some(c) = finder.component_of(v) else {
            continue;
        };
        first[c] = first[c].min(v);
        let x = field[v];
        if x.is_finite() {
            lo[c] = lo[c].min(x);
            hi[c] = hi[c].max(x);
        } else {
            finite[c] = false;
        }
    }
    let (glo, ghi) = (0..nc).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
        (a.min(lo[c]), b.max(hi[c]))
    });
    let (scale, range) = if ghi >= glo {
        (glo.abs().max(ghi.abs()), ghi - glo)
    } else {
        (0.0, 0.0) // no finite value
    };
    let threshold = (PERSISTENCE_RELATIVE_THRESHOLD * range).max(PERSISTENCE_NOISE_FLOOR * scale);
    let comp_range = |c: usize| {
        if hi[c] >= lo[c] && finite[c] {
            hi[c] - lo[c]
        } else {
            f64::NAN
        }
    };
    // A component is quiet when its (finite) range is below the threshold.
    let quiet: Vec<bool> = (0..nc).map(|c| comp_range(c) < threshold).collect();
    let is_quiet = |v: usize| finder.component_of(v).is_some_and(|c| quiet[c]);

    // Weights of the Euler count: doubled across the boundary under the Double rule.
    let on_boundary = |v: usize| raw.on_boundary.binary_search(&v).is_ok();
    let weight = |v: usize| -> usize {
        match raw.boundary_rule {
            BoundaryRule::Double if !on_boundary(v) => 2,
            _ => 1,
        }
    };
    let is_min = |v: usize| raw.minima.binary_search(&v).is_ok();
    let is_max = |v: usize| raw.maxima.binary_search(&v).is_ok();
    let saddle_index = |v: usize| raw.saddles.binary_search_by_key(&v, |s| s.0).ok();

    let mut pairs: Vec<PersistencePair> = Vec::new();
    let value_gap = |a: usize, b: usize| {
        let d = (field[a] - field[b]).abs();
        if d.is_finite() { d } else { f64::NAN }
    };
    for (kind, list, essential, is_kind) in [
        (
            ExtremumKind::Minimum,
            &up_pairs,
            &up_essential,
            &is_min as &dyn Fn(usize) -> bool,
        ),
        (ExtremumKind::Maximum, &down_pairs, &down_essential, &is_max),
    ] {
        for &(e, s) in list.iter() {
            if is_kind(e) {
                pairs.push(PersistencePair {
                    kind,
                    extremum: e,
                    saddle: Some(s),
                    persistence: value_gap(e, s),
                    hidden: false,
                });
            }
        }
        for &e in essential.iter() {
            if is_kind(e) {
                let c = finder.component_of(e).unwrap_or(0);
                pairs.push(PersistencePair {
                    kind,
                    extremum: e,
                    saddle: None,
                    persistence: comp_range(c),
                    hidden: false,
                });
            }
        }
    }
    pairs.sort_by_key(|p| (p.kind == ExtremumKind::Maximum, p.extremum));

    // Units of each raw saddle still shown, in the weights of the Euler count.
    let mut budget: Vec<usize> = raw.saddles.iter().map(|&(v, m)| weight(v) * m).collect();
    let mut by_persistence: Vec<usize> = (0..pairs.len())
        .filter(|&i| pairs[i].saddle.is_some() && pairs[i].persistence < threshold)
        .collect();
    by_persistence.sort_by(|&a, &b| {
        pairs[a]
            .persistence
            .total_cmp(&pairs[b].persistence)
            .then(pairs[a].extremum.cmp(&pairs[b].extremum))
    });
    for i in by_persistence {
        let p = pairs[i];
        let Some(s) = p.saddle else { continue };
        if is_quiet(p.extremum) {
            continue;
        }
        let Some(k) = saddle_index(s) else { continue };
        let (we, ws) = (weight(p.extremum), weight(s));
        if we % ws == 0 && budget[k] >= we {
            budget[k] -= we;
            pairs[i].hidden = true;
        }
    }
    for p in &mut pairs {
        if is_quiet(p.extremum) {
            p.hidden = true;
        }
    }
    let hidden_extremum = |v: usize| pairs.iter().any(|p| p.extremum == v && p.hidden);
    let mut shown = raw.clone();
    shown
        .minima
        .retain(|&v| !is_quiet(v) && !hidden_extremum(v));
    shown
        .maxima
        .retain(|&v| !is_quiet(v) && !hidden_extremum(v));
    shown.saddles = raw
        .saddles
        .iter()
        .zip(&budget)
        .filter(|&(&(v, _), &b)| b > 0 && !is_quiet(v))
        .map(|(&(v, _), &b)| (v, b / weight(v)))
        .collect();
    let kept = |v: usize| {
        shown.minima.binary_search(&v).is_ok()
            || shown.maxima.binary_search(&v).is_ok()
            || shown.saddles.binary_search_by_key(&v, |s| s.0).is_ok()
    };
    shown.on_boundary = raw
        .on_boundary
        .iter()
        .copied()
        .filter(|&v| kept(v))
        .collect();
    let quiet_components = (0..nc).filter(|&c| quiet[c]).map(|c| first[c]).collect();
    Ok(Persistence {
        raw,
        shown,
        pairs,
        threshold,
        relative_threshold: PERSISTENCE_RELATIVE_THRESHOLD,
        noise_floor: PERSISTENCE_NOISE_FLOOR,
        quiet_components,
    })
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
