//! Critical points simplified by persistence: which of the critical points of
//! [`crate::fields::critical_points`] are features and which are ripples (of a truncated
//! series, of rounding).
//!
//! ## Pairing
//! The vertices are swept up in the order of the classification (values rounded as there,
//! ties broken by vertex index), with a union-find over the mesh's vertex graph holding the
//! connected pieces of the sublevel set. A vertex with no lower neighbour starts a piece:
//! it is a minimum. A vertex whose lower neighbours lie in several pieces joins them: each
//! piece but the oldest (the one whose minimum is lowest, the *elder rule*) dies there, and
//! its minimum is paired with this vertex, a saddle, with persistence `f(saddle) -
//! f(minimum)`. The sweep down pairs maxima with saddles the same way (`f(maximum) -
//! f(saddle)`). The lowest minimum and the highest maximum of each connected component are
//! never paired (*essential*); their persistence is reported as the component's range. On
//! a closed surface every saddle (with multiplicity) is paired in exactly one sweep or is
//! one of the `2 g` essential saddles of the handles.
//!
//! ## Threshold and what is shown
//! With `R = max f - min f` and `S = max |f|` over the finite values, the threshold is
//!
//! ```text
//! threshold = max(PERSISTENCE_RELATIVE_THRESHOLD * R, PERSISTENCE_NOISE_FLOOR * S)
//! ```
//!
//! - A component whose range is below the threshold shows no critical point at all (the
//!   field is constant on it up to noise: it is left out of the Euler check like a
//!   plateau). This is what "no critical point" means for a constant field plus rounding
//!   noise: not even its global minimum and maximum, which the pairing can never cancel.
//! - Otherwise the essential points are shown, and the pairs are taken by ascending
//!   persistence: a pair below the threshold hides its extremum and one unit of its
//!   saddle's multiplicity. Hiding a pair removes one `+1` (extremum) and one `-1` (saddle)
//!   from `minima - saddles + maxima`, so the Euler characteristic holds for the shown set
//!   as for the raw one. On a bordered surface the check is doubled across the boundary
//!   (interior points count twice, boundary points once), so a pair is hidden only when
//!   its two ends weigh the same in that count (an interior extremum may use two units of
//!   a boundary saddle); a saddle whose units are used up is hidden.
//!
//! The raw set stays available ([`Persistence::raw`]) with its own check.

use rayon::prelude::*;

use crate::fields::critical_points::{
    BoundaryRule, CriticalPointFinder, CriticalPoints, CriticalPointsError, check_length, quantizer,
};

/// A pair whose persistence is below this fraction of the field's range (`max - min`) is
/// hidden. Truncation ripples of a heat kernel are many orders of magnitude below it; the
/// extrema and saddles of the paper's harmonic maps are tens of percent of it.
pub const PERSISTENCE_RELATIVE_THRESHOLD: f64 = 0.01;

/// Nothing below this fraction of the field's largest magnitude `max |f|` is significant
/// (a field of f32 values, as the pictures hold them, cannot tell apart relative
/// differences below about `1e-7`): a component whose range is below it shows no
/// critical point.
pub const PERSISTENCE_NOISE_FLOOR: f64 = 1e-6;

/// The kind of extremum a pair starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExtremumKind {
    /// Paired by the sweep up.
    Minimum,
    /// Paired by the sweep down.
    Maximum,
}

/// A critical point with its persistence.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PersistencePair {
    /// Minimum or maximum.
    pub kind: ExtremumKind,
    /// The extremum's vertex.
    pub extremum: usize,
    /// The saddle it dies at; `None` for an essential extremum (lowest minimum or highest
    /// maximum of its component).
    pub saddle: Option<usize>,
    /// `|f(saddle) - f(extremum)|`, or the component's range for an essential extremum
    /// (NaN when a value is not finite: never hidden).
    pub persistence: f64,
    /// True when the pair is hidden (below the threshold, or in a component whose range is
    /// below it).
    pub hidden: bool,
}

/// The threshold below which a persistence pair is hidden, and the two rules it comes
/// from. In JSON (as every report carries it): `persistence_threshold`,
/// `persistence_relative_threshold`, `persistence_noise_floor`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PersistenceThresholds {
    /// The absolute threshold, in the field's units (see the module documentation).
    #[serde(rename = "persistence_threshold")]
    pub threshold: f64,
    /// [`PERSISTENCE_RELATIVE_THRESHOLD`].
    #[serde(rename = "persistence_relative_threshold")]
    pub relative_threshold: f64,
    /// [`PERSISTENCE_NOISE_FLOOR`].
    #[serde(rename = "persistence_noise_floor")]
    pub noise_floor: f64,
}

/// The critical points of a field with their persistence pairs, and the simplified set.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Persistence {
    /// Every critical point (as classified by [`crate::fields::critical_points`]).
    pub raw: CriticalPoints,
    /// The critical points shown: the raw ones minus the hidden pairs (a saddle's
    /// multiplicity lowered by the pairs that used it).
    pub shown: CriticalPoints,
    /// The pairs whose extremum is a raw critical point, ascending by extremum kind and
    /// vertex.
    pub pairs: Vec<PersistencePair>,
    /// The thresholds the pairs were hidden by.
    #[serde(flatten)]
    pub thresholds: PersistenceThresholds,
    /// Components (identified by their lowest vertex) whose range is below the threshold:
    /// no critical point shown.
    pub quiet_components: Vec<usize>,
}

impl Persistence {
    /// Minima hidden.
    pub fn hidden_minima(&self) -> usize {
        self.raw.minima.len() - self.shown.minima.len()
    }

    /// Maxima hidden.
    pub fn hidden_maxima(&self) -> usize {
        self.raw.maxima.len() - self.shown.maxima.len()
    }

    /// Saddles hidden, counted with multiplicity.
    pub fn hidden_saddles(&self) -> usize {
        self.raw.saddle_count() - self.shown.saddle_count()
    }

    /// The persistence of critical point `v` when it is an extremum (`None` for a saddle or
    /// a regular vertex).
    pub fn of(&self, v: usize) -> Option<f64> {
        self.pairs
            .iter()
            .find(|p| p.extremum == v)
            .map(|p| p.persistence)
    }
}

/// The persistence of the critical points `raw` of `field` (found by `finder` with
/// [`CriticalPointFinder::find`]) and the simplified set under the default threshold.
pub fn persistence(
    finder: &CriticalPointFinder,
    field: &[f64],
    raw: CriticalPoints,
) -> Result<Persistence, CriticalPointsError> {
    check_length(field, finder.n_vertices())?;
    // The classification's order: rounded values, ties by index. Both sweeps at once.
    let keys = sort_keys(field);
    let local = local_order(finder, &keys);
    // Range and scale over finite values, per component as well, meanwhile.
    let ((up, down), ranges) = rayon::join(
        || {
            rayon::join(
                || sweep(finder, &keys, &local, false),
                || sweep(finder, &keys, &local, true),
            )
        },
        || component_ranges(finder, field),
    );
    Ok(assemble(finder, field, raw, ranges, up, down))
}

/// Per connected component: the least and largest finite values, whether every value is
/// finite, and the first vertex.
pub(super) struct ComponentRanges {
    lo: Vec<f64>,
    hi: Vec<f64>,
    finite: Vec<bool>,
    first: Vec<usize>,
}

/// The [`ComponentRanges`] of `field`.
pub(super) fn component_ranges(finder: &CriticalPointFinder, field: &[f64]) -> ComponentRanges {
    let nc = finder.n_components();
    let mut r = ComponentRanges {
        lo: vec![f64::INFINITY; nc],
        hi: vec![f64::NEG_INFINITY; nc],
        finite: vec![true; nc],
        first: vec![usize::MAX; nc],
    };
    for (v, &x) in field.iter().enumerate().take(finder.n_vertices()) {
        let Some(c) = finder.component_of(v) else {
            continue;
        };
        r.first[c] = r.first[c].min(v);
        if x.is_finite() {
            r.lo[c] = r.lo[c].min(x);
            r.hi[c] = r.hi[c].max(x);
        } else {
            r.finite[c] = false;
        }
    }
    r
}

/// The persistence result from the two sweeps' pairs and essential extrema (`up`:
/// minima, `down`: maxima): each pair's persistence, the pairs hidden under the default
/// threshold (within each raw saddle's share of the Euler count), and the shown set.
pub(super) fn assemble(
    finder: &CriticalPointFinder,
    field: &[f64],
    raw: CriticalPoints,
    ranges: ComponentRanges,
    (up_pairs, up_essential): (Vec<(usize, usize)>, Vec<usize>),
    (down_pairs, down_essential): (Vec<(usize, usize)>, Vec<usize>),
) -> Persistence {
    let n = finder.n_vertices();
    let nc = finder.n_components();
    let ComponentRanges {
        lo,
        hi,
        finite,
        first,
    } = ranges;
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
    let mut hidden_vertex = vec![false; n];
    for p in &pairs {
        if p.hidden {
            hidden_vertex[p.extremum] = true;
        }
    }
    let hidden_extremum = |v: usize| hidden_vertex[v];
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
    Persistence {
        raw,
        shown,
        pairs,
        thresholds: PersistenceThresholds {
            threshold,
            relative_threshold: PERSISTENCE_RELATIVE_THRESHOLD,
            noise_floor: PERSISTENCE_NOISE_FLOOR,
        },
        quiet_components,
    }
}

/// The critical points of `field` on `mesh` (default boundary rule) with their
/// persistence and the simplified set.
pub fn simplified_critical_points(
    mesh: &crate::mesh::Mesh,
    field: &[f64],
) -> Result<Persistence, CriticalPointsError> {
    let field = finite_for_critical(field);
    let finder = CriticalPointFinder::new(mesh);
    let raw = finder.find(&field, BoundaryRule::default())?;
    persistence(&finder, &field, raw)
}

/// `field` with every `+inf` (a geodesic distance where its sources cannot reach: whole
/// components) replaced by 0, so that such a component is one plateau, with no critical
/// point; borrowed unchanged when no value is `+inf`.
pub fn finite_for_critical(field: &[f64]) -> std::borrow::Cow<'_, [f64]> {
    if field.contains(&f64::INFINITY) {
        field
            .iter()
            .map(|&v| if v == f64::INFINITY { 0.0 } else { v })
            .collect::<Vec<f64>>()
            .into()
    } else {
        field.into()
    }
}

/// The bits of every value of `field` as the classification rounds it, ordered as
/// [`f64::total_cmp`] orders the rounded values: the sweeps' order is that of
/// `(key, vertex)`.
fn sort_keys(field: &[f64]) -> Vec<u64> {
    let q = quantizer(field);
    field
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&x| {
            let b = q(x).to_bits();
            if b >> 63 == 1 { !b } else { b | (1 << 63) }
        })
        .collect()
}

/// Vertices per parallel task of the sweeps.
const CHUNK: usize = 4096;

/// No vertex (a vertex no triangle uses; a basin not yet known).
const NONE: u32 = u32::MAX;

/// What the sweeps need of one vertex's neighbourhood.
#[derive(Debug, Clone, Copy)]
struct Local {
    /// The lowest neighbour when it is below the vertex, else the vertex itself (a
    /// minimum); [`NONE`] for a vertex no triangle uses.
    low: u32,
    /// The highest neighbour when it is above the vertex, else the vertex (a maximum).
    high: u32,
    /// Bit 0: the vertex may join pieces in the sweep up; bit 1: in the sweep down.
    may_join: u8,
}

/// [`Local`] of every vertex, in one parallel pass over the neighbours in the order of
/// `(keys[v], v)`. A vertex whose link is one simple cycle can join pieces only when its
/// lower neighbours form two arcs or more around the cycle (four changes or more between
/// lower and upper): consecutive lower neighbours share a triangle edge, below the vertex,
/// so one arc is already one piece. Any other vertex may join pieces when two of its
/// neighbours are below it (above it, going down).
fn local_order(finder: &CriticalPointFinder, keys: &[u64]) -> Vec<Local> {
    (0..finder.n_vertices() as u32)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|v| {
            let (nbrs, cyclic) = finder.neighbours(v as usize);
            let Some(&last) = nbrs.last() else {
                return Local {
                    low: NONE,
                    high: NONE,
                    may_join: 0,
                };
            };
            let kv = (keys[v as usize], v);
            let (mut lo, mut hi) = (kv, kv);
            let mut prev = (keys[last as usize], last) < kv;
            let (mut below, mut changes) = (0usize, 0usize);
            for &u in nbrs {
                let ku = (keys[u as usize], u);
                let is_below = ku < kv;
                lo = lo.min(ku);
                hi = hi.max(ku);
                below += usize::from(is_below);
                changes += usize::from(is_below != prev);
                prev = is_below;
            }
            let may_join = if cyclic {
                if changes >= 4 { 3 } else { 0 }
            } else {
                u8::from(below >= 2) | (u8::from(nbrs.len() - below >= 2) << 1)
            };
            Local {
                low: lo.1,
                high: hi.1,
                may_join,
            }
        })
        .collect()
}

/// One sweep (up, or down when `down`) in the order of `(keys[v], v)` over the vertices a
/// triangle uses: the pairs `(extremum, saddle)` of the pieces that die, and the extremum
/// of each piece left at the end (one per connected component), ascending.
///
/// The pieces of the sublevel set (superlevel set when `down`) are found without sweeping
/// every vertex through a union-find:
///
/// 1. Each vertex points to its steepest earlier neighbour (the lowest one going up),
///    an extremum to itself ([`local_order`]).
/// 2. Following the pointers gives each vertex the *basin* of its extremum. When a vertex
///    is reached, the path to its extremum runs through earlier vertices, so it lies in
///    the same piece as its extremum.
/// 3. Only the vertices [`local_order`] marks can join pieces (about the saddles); any
///    other vertex joins the one piece its earlier neighbours lie in.
/// 4. The marked vertices, sorted, run through a union-find over the basins: where pieces
///    meet the younger dies (the elder rule) and its extremum is paired with the vertex.
///
/// This pairs exactly as a union-find sweep over every vertex in sorted order (kept in the
/// tests as the reference and compared with this one), in O(n) besides the sort of the
/// marked vertices, without per-vertex allocation.
fn sweep(
    finder: &CriticalPointFinder,
    keys: &[u64],
    local: &[Local],
    down: bool,
) -> (Vec<(usize, usize)>, Vec<usize>) {
    let n = finder.n_vertices();
    // u comes before v in this sweep.
    let before = |u: u32, v: u32| -> bool {
        let (a, b) = ((keys[u as usize], u), (keys[v as usize], v));
        if down { a > b } else { a < b }
    };
    let to = |v: u32| -> u32 {
        let l = local[v as usize];
        if down { l.high } else { l.low }
    };
    // 2. Basins: each path is walked once, then every vertex on it gets its basin.
    let mut basin = vec![NONE; n];
    let mut extrema: Vec<u32> = Vec::new();
    let mut path: Vec<u32> = Vec::new();
    for v in 0..n as u32 {
        if to(v) == NONE || basin[v as usize] != NONE {
            continue;
        }
        path.clear();
        let mut x = v;
        while basin[x as usize] == NONE && to(x) != x {
            path.push(x);
            x = to(x);
        }
        let b = if basin[x as usize] == NONE {
            let b = extrema.len() as u32;
            extrema.push(x);
            basin[x as usize] = b;
            b
        } else {
            basin[x as usize]
        };
        for &y in &path {
            basin[y as usize] = b;
        }
    }
    // 3. The vertices that may join pieces, in the order of the sweep.
    let bit = if down { 2 } else { 1 };
    let mut joins: Vec<u32> = (0..n as u32)
        .filter(|&v| local[v as usize].may_join & bit != 0)
        .collect();
    joins.sort_unstable_by_key(|&v| (keys[v as usize], v));
    if down {
        joins.reverse();
    }
    // 4. A union-find over the basins; each root keeps its piece's extremum (the oldest).
    let mut parent: Vec<u32> = (0..extrema.len() as u32).collect();
    let oldest = extrema;
    let find = |parent: &mut [u32], mut x: u32| -> u32 {
        while parent[x as usize] != x {
            let up = parent[parent[x as usize] as usize];
            parent[x as usize] = up;
            x = up;
        }
        x
    };
    let mut pairs = Vec::new();
    for v in joins {
        let mut root = NONE;
        for &u in finder.neighbours(v as usize).0 {
            if !before(u, v) {
                continue;
            }
            let r = find(&mut parent, basin[u as usize]);
            if root == NONE {
                root = r;
                continue;
            }
            if r == root {
                continue;
            }
            let (elder, younger) = if before(oldest[r as usize], oldest[root as usize]) {
                (r, root)
            } else {
                (root, r)
            };
            pairs.push((oldest[younger as usize] as usize, v as usize));
            parent[younger as usize] = elder;
            root = elder;
        }
    }
    let mut essential: Vec<usize> = (0..parent.len() as u32)
        .filter(|&r| parent[r as usize] == r)
        .map(|r| oldest[r as usize] as usize)
        .collect();
    essential.sort_unstable();
    (pairs, essential)
}

#[cfg(test)]
mod tests;
