//! Critical points of a piecewise-linear function (Banchoff's rule, Sect. 3 of the paper).
//!
//! For each vertex v the triangles around it are walked into their ordered link (the ring
//! of neighbours), and each neighbour u is marked *above* or *below* v. Ties are broken by
//! vertex index (symbolic perturbation), so every field is "general":
//!
//! ```text
//! u is above v  <=>  f(u) > f(v)  or  (f(u) == f(v) and u > v)
//! ```
//!
//! (a NaN value compares as a tie, so the index decides). Along a **closed** link (an
//! interior vertex) the number c of sign changes is even: c = 0 with every neighbour above
//! is a minimum, c = 0 with every neighbour below a maximum, c = 2 a regular point and
//! c = 2m + 2 a saddle of multiplicity m. For a closed surface
//! `minima - saddles (with multiplicity) + maxima = Euler characteristic`.
//!
//! ## Boundary vertices
//! The link of a boundary vertex is an open path. Two rules are offered ([`BoundaryRule`]):
//!
//! - [`BoundaryRule::Double`] (default): reflect the surface across its boundary (this is
//!   exactly what the natural, Neumann, boundary condition of a harmonic map means). The
//!   doubled link is the path followed by its mirror, so c changes along the open path
//!   become 2c around the doubled link: c = 0 is a minimum or maximum, c = 1 regular, c >= 2
//!   a saddle of multiplicity c - 1. The check is on the doubled surface, whose Euler
//!   characteristic is 2 chi: `2 (m_i - s_i + M_i) + (m_b - s_b + M_b) = 2 chi`, where `_i`
//!   counts interior and `_b` boundary critical points
//!   ([`CriticalPoints::euler_check_doubled`]).
//! - [`BoundaryRule::LowerLink`]: Morse theory of sublevel sets. A boundary vertex is a
//!   minimum when every neighbour is above; otherwise, with k runs of "below" neighbours
//!   along the path, it is regular for k = 1 (this includes a vertex with every neighbour
//!   below: a boundary maximum is *not* critical) and a saddle of multiplicity k - 1 for
//!   k >= 2. Then `m - s + M = chi` holds for bordered surfaces too
//!   ([`CriticalPoints::euler_check`]), at the price of an asymmetric rule.
//!
//! ## Non-manifold vertices
//! The triangles around a vertex are split into fans, joined through edges `(v, u)` that
//! exactly two of them share. A vertex with more than one fan (a pinch), or whose link is
//! not a simple path or cycle, is listed in [`CriticalPoints::non_manifold`] and classified
//! conservatively: minimum if every neighbour is above, maximum if every neighbour is
//! below, otherwise a saddle of multiplicity `k - 1` when its lower link (the link
//! restricted to the neighbours below) has k > 1 connected pieces, else regular. The Euler
//! checks are not guaranteed on such meshes.
//!
//! Vertices no triangle uses are never critical. Several components are handled
//! naturally: pass the total Euler characteristic (the sum over components) to the checks.
//!
//! ## Flat fields: plateaus
//! A connected component on which the field is constant up to rounding is one plateau,
//! not a pattern of critical points drawn by rounding noise (or by the index rule). The
//! rule, applied before any vertex is classified: with `scale = max |f|` over the finite
//! values of the whole field, a component whose values are all finite and lie within
//! `FLAT_RELATIVE_TOLERANCE * scale` of each other (`max - min <= 1e-10 * scale`) is a
//! [`Plateau`]: none of its vertices is critical, and the Euler checks leave it out
//! (see [`crate::analysis::CriticalReport`]). A field that is zero everywhere is flat. A
//! plateau that covers only part of a component is classified by the rules above (ties
//! broken by index): before classification the values are rounded to multiples of
//! `FLAT_RELATIVE_TOLERANCE * scale` above the field's minimum, so differences below the
//! tolerance are ties everywhere, not only on whole-component plateaus. Every face (CLI summaries, pictures, the web app) takes its critical
//! points from here, so all of them agree.

use rayon::prelude::*;

use crate::mesh::Mesh;
use crate::mesh::topology::{UnionFind, VertexTriangles};

/// Values of a connected component that lie within `FLAT_RELATIVE_TOLERANCE * max |f|` of
/// each other (`max |f|` over the whole field) make the component one [`Plateau`] without
/// critical points. Rounding noise of a field computed in f64 from a few hundred terms is
/// around `1e-14` of its largest value; a picture (8-bit colours, f32 values) cannot show
/// relative differences below about `1e-7`.
pub const FLAT_RELATIVE_TOLERANCE: f64 = 1e-10;

/// How boundary vertices are classified (see the module documentation).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryRule {
    /// Reflect the surface across its boundary (symmetric in min and max; the default).
    #[default]
    Double,
    /// Sublevel-set (lower link) rule: boundary maxima are not critical; `m - s + M = chi`.
    LowerLink,
}

/// Errors from [`critical_points`].
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CriticalPointsError {
    /// The field does not have one value per vertex.
    #[error("the field has {got} values but the mesh has {expected} vertices")]
    LengthMismatch {
        /// Number of vertices.
        expected: usize,
        /// Number of values.
        got: usize,
    },
}

/// The critical points of a field, each list ascending by vertex index.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct CriticalPoints {
    /// Local minima.
    pub minima: Vec<usize>,
    /// Local maxima.
    pub maxima: Vec<usize>,
    /// Saddles with their multiplicity (>= 1).
    pub saddles: Vec<(usize, usize)>,
    /// Critical points (of any kind) on the boundary, i.e. classified from an open link.
    pub on_boundary: Vec<usize>,
    /// Non-manifold vertices (classified conservatively; see the module documentation).
    pub non_manifold: Vec<usize>,
    /// The boundary rule used.
    pub boundary_rule: BoundaryRule,
    /// Connected components on which the field is constant within
    /// [`FLAT_RELATIVE_TOLERANCE`]: none of their vertices is critical. Ascending by
    /// their lowest vertex.
    pub plateaus: Vec<Plateau>,
}

/// A connected component on which the field is constant within
/// [`FLAT_RELATIVE_TOLERANCE`] of the field's largest magnitude (see the module
/// documentation).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Plateau {
    /// The component's lowest vertex (identifies it whatever the component numbering).
    pub first_vertex: usize,
    /// Vertices of the component.
    pub vertices: usize,
    /// The smallest value on it.
    pub min: f64,
    /// The largest value on it.
    pub max: f64,
}

impl CriticalPoints {
    /// Number of saddles counted with multiplicity.
    pub fn saddle_count(&self) -> usize {
        self.saddles.iter().map(|s| s.1).sum()
    }

    /// `(minima - saddles + maxima, chi)`: equal for a closed surface of Euler characteristic
    /// `chi` (and for bordered surfaces under [`BoundaryRule::LowerLink`]).
    pub fn euler_check(&self, chi: i64) -> (i64, i64) {
        let m = self.minima.len() as i64;
        let big_m = self.maxima.len() as i64;
        (m - self.saddle_count() as i64 + big_m, chi)
    }

    /// The count on the surface doubled across its boundary, `(2 (m_i - s_i + M_i) + (m_b -
    /// s_b + M_b), 2 chi)`: equal for any manifold surface, closed or bordered, under
    /// [`BoundaryRule::Double`] (`_i` interior, `_b` boundary critical points).
    pub fn euler_check_doubled(&self, chi: i64) -> (i64, i64) {
        let w = |v: usize| -> i64 {
            if self.on_boundary.binary_search(&v).is_ok() {
                1
            } else {
                2
            }
        };
        let mut sum = 0i64;
        sum += self.minima.iter().map(|&v| w(v)).sum::<i64>();
        sum += self.maxima.iter().map(|&v| w(v)).sum::<i64>();
        sum -= self
            .saddles
            .iter()
            .map(|&(v, k)| w(v) * k as i64)
            .sum::<i64>();
        (sum, 2 * chi)
    }
}

/// Critical points of `field` (one value per vertex) with the default boundary rule
/// ([`BoundaryRule::Double`]).
pub fn critical_points(mesh: &Mesh, field: &[f64]) -> Result<CriticalPoints, CriticalPointsError> {
    critical_points_with(mesh, field, BoundaryRule::default())
}

/// What one vertex is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Regular,
    Min,
    Max,
    Saddle(usize),
}

impl CriticalPoints {
    /// Files vertex `v` of kind `kind` (`open`: its link is open, `nonman`: it is
    /// non-manifold) in the lists it belongs to.
    fn record(&mut self, v: usize, kind: Kind, open: bool, nonman: bool) {
        if nonman {
            self.non_manifold.push(v);
        }
        if kind != Kind::Regular && open {
            self.on_boundary.push(v);
        }
        match kind {
            Kind::Regular => {}
            Kind::Min => self.minima.push(v),
            Kind::Max => self.maxima.push(v),
            Kind::Saddle(m) => self.saddles.push((v, m)),
        }
    }
}

/// Refuses a field whose length is not the `n` vertices.
pub(crate) fn check_length(field: &[f64], n: usize) -> Result<(), CriticalPointsError> {
    if field.len() != n {
        return Err(CriticalPointsError::LengthMismatch {
            expected: n,
            got: field.len(),
        });
    }
    Ok(())
}

/// Critical points of `field` with the given boundary rule.
pub fn critical_points_with(
    mesh: &Mesh,
    field: &[f64],
    rule: BoundaryRule,
) -> Result<CriticalPoints, CriticalPointsError> {
    CriticalPointFinder::new(mesh).find(field, rule)
}

/// The part of the classification that depends only on the mesh: the link edges of every
/// vertex and which links are one simple cycle. Build it once per mesh (O(n + m)) and
/// classify any number of fields with [`CriticalPointFinder::find`]: a field then costs
/// two comparisons per link edge, spread over the threads (100k vertices: about 1 ms).
#[derive(Debug, Clone)]
pub struct CriticalPointFinder {
    /// `edges[offsets[v]..offsets[v + 1]]`: the link edges of `v`, one per triangle
    /// around it (ascending triangle index), each the two other corners in the
    /// triangle's order.
    offsets: Vec<usize>,
    edges: Vec<(usize, usize)>,
    /// True when the link of the vertex is one simple cycle (every interior vertex of a
    /// manifold mesh): classified from the edges whose ends differ, without ordering.
    simple: Vec<bool>,
    /// Connected component of each vertex (through triangles), numbered by lowest vertex;
    /// `u32::MAX` for a vertex no triangle uses.
    component: Vec<u32>,
    /// `(lowest vertex, vertices)` of each component.
    components: Vec<(usize, usize)>,
    /// `neighbours[neighbour_offsets[v]..neighbour_offsets[v + 1]]`: the neighbours of `v`
    /// (the ends of its link edges), each once: around the cycle when the link is one
    /// simple cycle, else ascending. The persistence sweeps walk them (see
    /// [`crate::fields::persistence`]).
    neighbour_offsets: Vec<usize>,
    neighbours: Vec<u32>,
}

/// Vertices per parallel task of [`CriticalPointFinder::find`].
const FIND_CHUNK: usize = 4096;

impl CriticalPointFinder {
    /// The link edges of `mesh` and the simple-cycle test of every link.
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.n_vertices();
        let vt = VertexTriangles::new(mesh);
        let tris = mesh.triangles();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        let mut edges = Vec::with_capacity(3 * mesh.n_triangles());
        for v in 0..n {
            for &t in vt.of(v) {
                let tri = tris[t];
                let k = tri.iter().position(|&x| x == v).unwrap_or(0);
                edges.push((tri[(k + 1) % 3], tri[(k + 2) % 3]));
            }
            offsets.push(edges.len());
        }
        let simple: Vec<bool> = (0..n)
            .into_par_iter()
            .with_min_len(FIND_CHUNK)
            .map(|v| is_simple_cycle(&edges[offsets[v]..offsets[v + 1]]))
            .collect();
        let mut uf = UnionFind::new(n);
        for t in tris {
            uf.union(t[0], t[1]);
            uf.union(t[0], t[2]);
        }
        // Numbered in the order of their lowest vertex.
        let mut root_id: Vec<u32> = vec![u32::MAX; n];
        let mut component = vec![u32::MAX; n];
        let mut components: Vec<(usize, usize)> = Vec::new();
        for v in 0..n {
            if offsets[v] == offsets[v + 1] {
                continue;
            }
            let r = uf.find(v);
            if root_id[r] == u32::MAX {
                root_id[r] = components.len() as u32;
                components.push((v, 0));
            }
            component[v] = root_id[r];
            components[root_id[r] as usize].1 += 1;
        }
        let (neighbour_offsets, neighbours) = neighbour_lists(&offsets, &edges, &simple);
        Self {
            offsets,
            edges,
            simple,
            component,
            components,
            neighbour_offsets,
            neighbours,
        }
    }

    /// The components of `field` that are plateaus (see the module documentation), and
    /// for each vertex whether it lies on one.
    fn plateaus(&self, field: &[f64]) -> (Vec<Plateau>, Vec<bool>) {
        let scale = field
            .iter()
            .filter(|x| x.is_finite())
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let tol = FLAT_RELATIVE_TOLERANCE * scale;
        let nc = self.components.len();
        let mut lo = vec![f64::INFINITY; nc];
        let mut hi = vec![f64::NEG_INFINITY; nc];
        let mut finite = vec![true; nc];
        for (v, &c) in self.component.iter().enumerate() {
            if c == u32::MAX {
                continue;
            }
            let c = c as usize;
            let x = field[v];
            if x.is_finite() {
                lo[c] = lo[c].min(x);
                hi[c] = hi[c].max(x);
            } else {
                finite[c] = false;
            }
        }
        let flat: Vec<bool> = (0..nc).map(|c| finite[c] && hi[c] - lo[c] <= tol).collect();
        let plateaus = (0..nc)
            .filter(|&c| flat[c])
            .map(|c| Plateau {
                first_vertex: self.components[c].0,
                vertices: self.components[c].1,
                min: lo[c],
                max: hi[c],
            })
            .collect();
        let on = self
            .component
            .iter()
            .map(|&c| c != u32::MAX && flat[c as usize])
            .collect();
        (plateaus, on)
    }

    /// The link edges of `v` (one per triangle around it): their ends are its neighbours.
    #[cfg(test)]
    pub(crate) fn link_edges(&self, v: usize) -> &[(usize, usize)] {
        &self.edges[self.offsets[v]..self.offsets[v + 1]]
    }

    /// The neighbours of `v` (the ends of its link edges), each once, and whether they are
    /// in the order of the link cycle (the link is one simple cycle: consecutive
    /// neighbours, the last and the first included, share a triangle edge); else
    /// ascending.
    pub(crate) fn neighbours(&self, v: usize) -> (&[u32], bool) {
        (
            &self.neighbours[self.neighbour_offsets[v]..self.neighbour_offsets[v + 1]],
            self.simple[v],
        )
    }

    /// Connected component of `v` (through triangles, numbered by lowest vertex), `None`
    /// for a vertex no triangle uses.
    pub(crate) fn component_of(&self, v: usize) -> Option<usize> {
        let c = self.component[v];
        (c != u32::MAX).then_some(c as usize)
    }

    /// Number of connected components (through triangles).
    pub(crate) fn n_components(&self) -> usize {
        self.components.len()
    }

    /// Number of vertices of the mesh it was built for.
    pub fn n_vertices(&self) -> usize {
        self.simple.len()
    }

    /// The critical points of `field` (one value per vertex of the mesh the finder was
    /// built for) under `rule`; vertices are classified in parallel. The result is the
    /// same as [`critical_points_with`] on the mesh.
    pub fn find(
        &self,
        field: &[f64],
        rule: BoundaryRule,
    ) -> Result<CriticalPoints, CriticalPointsError> {
        self.find_impl(field, rule, true, true)
    }

    /// [`CriticalPointFinder::find`]; `parallel` spreads the vertices over the threads,
    /// `fast` takes the shortcut for simple-cycle links (both off only to test that every
    /// way agrees).
    fn find_impl(
        &self,
        field: &[f64],
        rule: BoundaryRule,
        parallel: bool,
        fast: bool,
    ) -> Result<CriticalPoints, CriticalPointsError> {
        let n = self.n_vertices();
        check_length(field, n)?;
        let (plateaus, on_plateau) = self.plateaus(field);
        let q = quantized(field);
        let field = &q[..];
        // (vertex, kind, open link, non-manifold) of every vertex that is critical or
        // non-manifold, ascending.
        let one = |v: usize| -> Option<(usize, Kind, bool, bool)> {
            let (kind, open, nonman) = self.classify_vertex(v, field, rule, fast)?;
            // A plateau has no critical points (its non-manifold vertices are listed).
            let kind = if on_plateau[v] { Kind::Regular } else { kind };
            (kind != Kind::Regular || nonman).then_some((v, kind, open, nonman))
        };
        let found: Vec<(usize, Kind, bool, bool)> = if parallel {
            (0..n)
                .into_par_iter()
                .with_min_len(FIND_CHUNK)
                .filter_map(one)
                .collect()
        } else {
            (0..n).filter_map(one).collect()
        };
        let mut out = CriticalPoints {
            boundary_rule: rule,
            plateaus,
            ..Default::default()
        };
        for (v, kind, open, nonman) in found {
            out.record(v, kind, open, nonman);
        }
        Ok(out)
    }

    /// (kind, link is open, non-manifold) of vertex `v`; `None` for a vertex no triangle
    /// uses.
    fn classify_vertex(
        &self,
        v: usize,
        field: &[f64],
        rule: BoundaryRule,
        fast: bool,
    ) -> Option<(Kind, bool, bool)> {
        let edges = &self.edges[self.offsets[v]..self.offsets[v + 1]];
        if edges.is_empty() {
            return None;
        }
        let fv = field[v];
        let above = |u: usize| -> bool {
            match field[u].partial_cmp(&fv) {
                Some(std::cmp::Ordering::Greater) => true,
                Some(std::cmp::Ordering::Less) => false,
                _ => u > v,
            }
        };
        if fast && self.simple[v] {
            let mut changes = 0;
            for &(a, b) in edges {
                changes += usize::from(above(a) != above(b));
            }
            return Some((closed_kind(changes, above(edges[0].0)), false, false));
        }
        Some(classify(edges, &above, rule))
    }
}

/// The neighbour lists of every vertex from its link edges `edges[offsets[v]..offsets[v +
/// 1]]`, in compressed form: in the order of the cycle for a link that is one simple cycle
/// (`simple`; consecutive neighbours, the last and the first included, share a triangle
/// edge), else ascending without repeats.
fn neighbour_lists(
    offsets: &[usize],
    edges: &[(usize, usize)],
    simple: &[bool],
) -> (Vec<usize>, Vec<u32>) {
    let n = offsets.len() - 1;
    let mut nbr_offsets = Vec::with_capacity(n + 1);
    nbr_offsets.push(0);
    // Vertex ids fit in u32, as in the component numbering.
    let mut nbrs: Vec<u32> = Vec::with_capacity(edges.len() + edges.len() / 4);
    for v in 0..n {
        let link = &edges[offsets[v]..offsets[v + 1]];
        let start = nbrs.len();
        if simple[v] {
            // Walk the cycle (at most 64 edges: see `simple_cycle_changes`).
            let first = link[0].0;
            let mut cur = link[0].1;
            let mut used: u64 = 1;
            nbrs.push(first as u32);
            while cur != first {
                nbrs.push(cur as u32);
                let next = link
                    .iter()
                    .enumerate()
                    .find(|&(i, &(a, b))| used & (1 << i) == 0 && (a == cur || b == cur));
                let Some((i, &(a, b))) = next else { break };
                used |= 1 << i;
                cur = if a == cur { b } else { a };
            }
        } else {
            for &(a, b) in link {
                nbrs.push(a as u32);
                nbrs.push(b as u32);
            }
            nbrs[start..].sort_unstable();
            let mut kept = start;
            for i in start..nbrs.len() {
                if kept == start || nbrs[kept - 1] != nbrs[i] {
                    nbrs[kept] = nbrs[i];
                    kept += 1;
                }
            }
            nbrs.truncate(kept);
        }
        nbr_offsets.push(nbrs.len());
    }
    (nbr_offsets, nbrs)
}

/// `field` rounded to multiples of `FLAT_RELATIVE_TOLERANCE * max |f|` above its minimum
/// (differences below the tolerance become ties); unchanged when that step is zero (a
/// field of zeros or without finite values).
pub(crate) fn quantized(field: &[f64]) -> Vec<f64> {
    let q = quantizer(field);
    field.iter().map(|&x| q(x)).collect()
}

/// The rounding of [`quantized`] as a function of one value of `field`.
pub(crate) fn quantizer(field: &[f64]) -> impl Fn(f64) -> f64 + Copy + Sync {
    let (mut lo, mut scale) = (f64::INFINITY, 0.0f64);
    for &x in field.iter().filter(|x| x.is_finite()) {
        lo = lo.min(x);
        scale = scale.max(x.abs());
    }
    let tol = FLAT_RELATIVE_TOLERANCE * scale;
    let rounds = tol > 0.0 && tol.is_finite();
    move |x: f64| {
        if rounds { ((x - lo) / tol).round() } else { x }
    }
}

/// True when the link edges form one simple cycle (see [`simple_cycle_changes`]).
fn is_simple_cycle(edges: &[(usize, usize)]) -> bool {
    simple_cycle_changes(edges, &|_| true).is_some()
}

/// [`critical_points_with`] without the finder: `fast` takes the shortcut of
/// [`simple_cycle_changes`] for links that are one simple cycle (off only to test that
/// both ways agree). The reference the finder is tested against.
#[cfg(test)]
fn classify_all(
    mesh: &Mesh,
    field: &[f64],
    rule: BoundaryRule,
    fast: bool,
) -> Result<CriticalPoints, CriticalPointsError> {
    let n = mesh.n_vertices();
    check_length(field, n)?;
    let vt = VertexTriangles::new(mesh);
    let tris = mesh.triangles();
    let mut out = CriticalPoints {
        boundary_rule: rule,
        ..Default::default()
    };
    let mut edges: Vec<(usize, usize)> = Vec::new();
    for v in 0..n {
        let ts = vt.of(v);
        if ts.is_empty() {
            continue;
        }
        edges.clear();
        for &t in ts {
            let tri = tris[t];
            let k = tri.iter().position(|&x| x == v).unwrap_or(0);
            edges.push((tri[(k + 1) % 3], tri[(k + 2) % 3]));
        }
        let above = |u: usize| -> bool {
            match field[u].partial_cmp(&field[v]) {
                Some(std::cmp::Ordering::Greater) => true,
                Some(std::cmp::Ordering::Less) => false,
                _ => u > v,
            }
        };
        let cycle = if fast {
            simple_cycle_changes(&edges, &above)
        } else {
            None
        };
        let (kind, open, nonman) = match cycle {
            Some(c) => (closed_kind(c, above(edges[0].0)), false, false),
            None => classify(&edges, &above, rule),
        };
        out.record(v, kind, open, nonman);
    }
    Ok(out)
}

/// The number of sign changes of `above` around the link when the link is one simple
/// cycle (every interior vertex of a manifold mesh), else `None`. Consecutive vertices
/// of the cycle are exactly the two ends of a link edge, so the changes are the edges
/// whose ends differ, and the cycle need not be ordered. The check walks the edges from
/// the first one, taking at each vertex its only unused edge, and must use them all
/// before it comes back: a vertex met by more than two edges, several cycles or an open
/// path all fail it. No allocation: links of more than 64 edges go the general way.
/// (The general way built the ordered link with several small vectors per vertex:
/// 100-160 ms for the critical points of a 100k-vertex mesh.)
fn simple_cycle_changes(edges: &[(usize, usize)], above: &dyn Fn(usize) -> bool) -> Option<usize> {
    let d = edges.len();
    if !(3..=64).contains(&d) {
        return None;
    }
    let start = edges[0].0;
    let mut cur = edges[0].1;
    let mut used: u64 = 1;
    let mut steps = 1;
    while cur != start {
        let mut next = None;
        for (i, &(a, b)) in edges.iter().enumerate() {
            if used & (1 << i) == 0 && (a == cur || b == cur) {
                if next.is_some() {
                    return None;
                }
                next = Some((i, if a == cur { b } else { a }));
            }
        }
        let (i, w) = next?;
        used |= 1 << i;
        cur = w;
        steps += 1;
    }
    if steps != d {
        return None;
    }
    Some(edges.iter().filter(|&&(a, b)| above(a) != above(b)).count())
}

/// The kind of a vertex whose link is closed, from the sign changes around it and
/// whether its neighbours are above it (when there are no changes).
fn closed_kind(changes: usize, above: bool) -> Kind {
    match changes {
        0 if above => Kind::Min,
        0 => Kind::Max,
        2 => Kind::Regular,
        c => Kind::Saddle(c / 2 - 1),
    }
}

/// The link of one vertex, split into fans; each fan walked into an ordered sequence.
struct Link {
    /// Ordered neighbour sequences, with `true` for a closed (cyclic) one.
    fans: Vec<(Vec<usize>, bool)>,
    /// True when the link is not a single simple cycle or path.
    non_manifold: bool,
}

fn build_link(edges: &[(usize, usize)]) -> Link {
    // Link vertices and how many link edges touch each.
    let mut verts: Vec<usize> = edges.iter().flat_map(|&(a, b)| [a, b]).collect();
    verts.sort_unstable();
    let mut deg: Vec<(usize, usize)> = Vec::new();
    for &u in &verts {
        match deg.last_mut() {
            Some((w, c)) if *w == u => *c += 1,
            _ => deg.push((u, 1)),
        }
    }
    // Join edges through link vertices of degree exactly 2 (manifold edges (v, u)).
    let mut uf = UnionFind::new(edges.len());
    for &(u, d) in &deg {
        if d == 2 {
            let mut it = edges
                .iter()
                .enumerate()
                .filter(|(_, e)| e.0 == u || e.1 == u)
                .map(|(i, _)| i);
            if let (Some(a), Some(b)) = (it.next(), it.next()) {
                uf.union(a, b);
            }
        }
    }
    let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
    for i in 0..edges.len() {
        let r = uf.find(i);
        match groups.iter_mut().find(|g| g.0 == r) {
            Some(g) => g.1.push(i),
            None => groups.push((r, vec![i])),
        }
    }
    let mut non_manifold = groups.len() > 1 || deg.iter().any(|d| d.1 > 2);
    let mut fans = Vec::with_capacity(groups.len());
    for (_, group) in &groups {
        // Degrees within the fan.
        let fan_deg = |u: usize| {
            group
                .iter()
                .filter(|&&i| edges[i].0 == u || edges[i].1 == u)
                .count()
        };
        if group
            .iter()
            .any(|&i| fan_deg(edges[i].0) > 2 || fan_deg(edges[i].1) > 2)
        {
            non_manifold = true;
        }
        // Start at an end of a path (fan degree 1) if there is one.
        let start = group
            .iter()
            .flat_map(|&i| [edges[i].0, edges[i].1])
            .find(|&u| fan_deg(u) == 1);
        let closed = start.is_none();
        let mut cur = start.unwrap_or(edges[group[0]].0);
        let mut used = vec![false; group.len()];
        let mut seq = vec![cur];
        loop {
            let next = group
                .iter()
                .enumerate()
                .find(|&(k, &i)| !used[k] && (edges[i].0 == cur || edges[i].1 == cur));
            let Some((k, &i)) = next else { break };
            used[k] = true;
            cur = if edges[i].0 == cur {
                edges[i].1
            } else {
                edges[i].0
            };
            seq.push(cur);
        }
        if used.iter().any(|&u| !u) {
            non_manifold = true;
        }
        if closed && seq.len() > 1 && seq.first() == seq.last() {
            seq.pop();
        }
        fans.push((seq, closed));
    }
    Link { fans, non_manifold }
}

fn changes(s: &[bool], closed: bool) -> usize {
    let mut c = s.windows(2).filter(|w| w[0] != w[1]).count();
    if closed && s.len() > 1 && s[0] != s[s.len() - 1] {
        c += 1;
    }
    c
}

/// Lower-link rule for non-manifold vertices: min/max when all neighbours are on one side,
/// otherwise saddle of multiplicity (pieces of the lower link - 1).
fn conservative(edges: &[(usize, usize)], above: &dyn Fn(usize) -> bool) -> Kind {
    let mut nb: Vec<usize> = edges.iter().flat_map(|&(a, b)| [a, b]).collect();
    nb.sort_unstable();
    nb.dedup();
    let below: Vec<usize> = nb.iter().copied().filter(|&u| !above(u)).collect();
    if below.is_empty() {
        return Kind::Min;
    }
    if below.len() == nb.len() {
        return Kind::Max;
    }
    let mut uf = UnionFind::new(below.len());
    for &(a, b) in edges {
        if let (Ok(i), Ok(j)) = (below.binary_search(&a), below.binary_search(&b)) {
            uf.union(i, j);
        }
    }
    let pieces = (0..below.len()).filter(|&i| uf.find(i) == i).count();
    if pieces > 1 {
        Kind::Saddle(pieces - 1)
    } else {
        Kind::Regular
    }
}

/// Classifies one vertex from its link edges; returns (kind, link is open, non-manifold).
fn classify(
    edges: &[(usize, usize)],
    above: &dyn Fn(usize) -> bool,
    rule: BoundaryRule,
) -> (Kind, bool, bool) {
    let link = build_link(edges);
    if link.non_manifold || link.fans.len() != 1 {
        let open = link.fans.iter().any(|f| !f.1);
        return (conservative(edges, above), open, true);
    }
    let (seq, closed) = &link.fans[0];
    let s: Vec<bool> = seq.iter().map(|&u| above(u)).collect();
    let c = changes(&s, *closed);
    let kind = if *closed {
        closed_kind(c, s.iter().all(|&a| a))
    } else {
        match rule {
            BoundaryRule::Double => match c {
                0 if s.iter().all(|&a| a) => Kind::Min,
                0 => Kind::Max,
                1 => Kind::Regular,
                _ => Kind::Saddle(c - 1),
            },
            BoundaryRule::LowerLink => {
                // Runs of "below" neighbours along the open path.
                let runs = s
                    .iter()
                    .enumerate()
                    .filter(|&(i, &a)| !a && (i == 0 || s[i - 1]))
                    .count();
                match runs {
                    0 => Kind::Min,
                    1 => Kind::Regular,
                    k => Kind::Saddle(k - 1),
                }
            }
        }
    };
    (kind, !*closed, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan of `k` triangles around vertex 0 at the origin (closed when `closed`).
    fn fan(k: usize, closed: bool) -> Mesh {
        let mut p = vec![[0.0, 0.0, 0.0]];
        let m = if closed { k } else { k + 1 };
        for i in 0..m {
            let a = i as f64 * std::f64::consts::TAU / k as f64 * if closed { 1.0 } else { 0.5 };
            p.push([a.cos(), a.sin(), 0.0]);
        }
        let t: Vec<[usize; 3]> = (0..k).map(|i| [0, 1 + i, 1 + (i + 1) % m]).collect();
        Mesh::new(p, t).unwrap()
    }

    #[test]
    fn interior_vertex_kinds() {
        let m = fan(8, true);
        let kind_of_center = |f: Vec<f64>| {
            let cp = critical_points(&m, &f).unwrap();
            if cp.minima.contains(&0) {
                "min".to_string()
            } else if cp.maxima.contains(&0) {
                "max".to_string()
            } else if let Some(s) = cp.saddles.iter().find(|s| s.0 == 0) {
                format!("saddle{}", s.1)
            } else {
                "regular".to_string()
            }
        };
        let ring = |g: &dyn Fn(usize) -> f64| -> Vec<f64> {
            std::iter::once(0.0).chain((0..8).map(g)).collect()
        };
        assert_eq!(kind_of_center(ring(&|_| 1.0)), "min");
        assert_eq!(kind_of_center(ring(&|_| -1.0)), "max");
        assert_eq!(
            kind_of_center(ring(&|i| if i < 4 { 1.0 } else { -1.0 })),
            "regular"
        );
        // x^2 - y^2: four sign changes -> simple saddle.
        assert_eq!(
            kind_of_center(ring(
                &|i| (i as f64 * std::f64::consts::FRAC_PI_4 * 2.0).cos()
            )),
            "saddle1"
        );
        // Eight sign changes: a saddle of multiplicity 3.
        assert_eq!(
            kind_of_center(ring(&|i| if i % 2 == 0 && i < 6 {
                1.0
            } else if i < 6 {
                -1.0
            } else if i == 6 {
                1.0
            } else {
                -1.0
            })),
            "saddle3"
        );
        // Ties broken by index: neighbours equal to the centre (index 0) are above.
        assert_eq!(
            kind_of_center(ring(&|i| if i == 3 { 1.0 } else { 0.0 })),
            "min"
        );
        // A constant field is one plateau: nothing is critical.
        assert_eq!(kind_of_center(ring(&|_| 0.0)), "regular");
    }

    #[test]
    fn boundary_rules() {
        let m = fan(4, false); // open fan: path 1..5
        // x^2 - y^2 restricted to the half plane y >= 0: above, below, above -> c = 2.
        let f = vec![0.0, 1.0, 0.5, -1.0, 0.5, 1.0];
        let cp = critical_points(&m, &f).unwrap();
        assert_eq!(cp.saddles, vec![(0, 1)]);
        assert_eq!(cp.on_boundary.first(), Some(&0));
        // All below: a boundary maximum under Double, regular under LowerLink.
        let g = vec![0.0, -1.0, -1.0, -1.0, -1.0, -1.0];
        assert!(critical_points(&m, &g).unwrap().maxima.contains(&0));
        let ll = critical_points_with(&m, &g, BoundaryRule::LowerLink).unwrap();
        assert!(!ll.maxima.contains(&0) && !ll.saddles.iter().any(|s| s.0 == 0));
        assert!(critical_points(&m, &[0.0]).is_err());
    }

    /// Rounding noise on a constant is one plateau; a component is judged against the
    /// largest magnitude of the whole field; a range just above the tolerance is classified.
    #[test]
    fn flat_components_are_plateaus_without_critical_points() {
        let sphere = crate::shapes::build_str("sphere:res=3").unwrap();
        let n = sphere.n_vertices();
        // 1 + noise of a few ulps, as a heat kernel at a very large time.
        let noisy: Vec<f64> = (0..n)
            .map(|i| 1.0 + ((i * 7919) % 13) as f64 * 1e-16)
            .collect();
        for f in [noisy.clone(), vec![0.0; n]] {
            let cp = critical_points(&sphere, &f).unwrap();
            assert!(cp.minima.is_empty() && cp.maxima.is_empty() && cp.saddles.is_empty());
            assert_eq!(cp.plateaus.len(), 1);
            assert_eq!(
                (cp.plateaus[0].first_vertex, cp.plateaus[0].vertices),
                (0, n)
            );
        }
        // Without the rule the noise makes many critical points: what the rule removes.
        let without = classify_all(&sphere, &noisy, BoundaryRule::Double, true).unwrap();
        assert!(without.minima.len() + without.maxima.len() > 10);
        // A relative range of 1e-8 is above the tolerance: a real (if faint) field.
        let faint: Vec<f64> = sphere
            .positions()
            .iter()
            .map(|p| 1.0 + 1e-8 * p[2])
            .collect();
        let cp = critical_points(&sphere, &faint).unwrap();
        assert!(cp.plateaus.is_empty());
        assert_eq!(
            (cp.minima.len(), cp.maxima.len(), cp.saddle_count()),
            (1, 1, 0)
        );
        // Two components: the second holds 1e-12 (flat against the first's values of
        // order 1), the first varies.
        let a = crate::shapes::build_str("sphere:res=2").unwrap();
        let b = a.map_positions(|p| [p[0] + 5.0, p[1], p[2]]).unwrap();
        let na = a.n_vertices();
        let mut p = a.positions().to_vec();
        p.extend(b.positions());
        let mut t = a.triangles().to_vec();
        t.extend(b.triangles().iter().map(|tri| tri.map(|v| v + na)));
        let two = Mesh::new(p, t).unwrap();
        let f: Vec<f64> = (0..two.n_vertices())
            .map(|v| {
                if v < na {
                    two.positions()[v][2]
                } else {
                    1e-12 * (v % 3) as f64
                }
            })
            .collect();
        let cp = critical_points(&two, &f).unwrap();
        assert_eq!(cp.plateaus.len(), 1);
        assert_eq!(cp.plateaus[0].first_vertex, na);
        assert_eq!(
            (cp.minima.len(), cp.maxima.len(), cp.saddle_count()),
            (1, 1, 0)
        );
        assert!(cp.minima[0] < na && cp.maxima[0] < na);
        // Non-finite values: never a plateau.
        let mut g = vec![1.0; n];
        g[5] = f64::NAN;
        assert!(critical_points(&sphere, &g).unwrap().plateaus.is_empty());
    }

    /// The shortcut for simple-cycle links gives exactly what ordering every link gives,
    /// on closed and bordered meshes, a non-manifold one, and fields with many ties.
    #[test]
    fn the_simple_cycle_shortcut_agrees_with_the_ordered_links() {
        let two_fans = {
            let (p, t) = crate::test_support::two_fans();
            Mesh::new(p, t).unwrap()
        };
        let meshes = [
            crate::shapes::build_str("irregular-torus:res=3").unwrap(),
            crate::shapes::build_str("sphere:res=3").unwrap(),
            crate::shapes::build_str("disk:res=3").unwrap(),
            // More vertices than one parallel task takes.
            crate::shapes::build_str("sphere:res=5").unwrap(),
            fan(7, false),
            two_fans,
        ];
        let mut next = crate::test_support::lcg(12345);
        let mut shortcut_taken = 0;
        for m in &meshes {
            let n = m.n_vertices();
            let finder = CriticalPointFinder::new(m);
            assert_eq!(finder.n_vertices(), n);
            assert!(
                finder
                    .find(&vec![0.0; n + 1], BoundaryRule::Double)
                    .is_err()
            );
            for round in 0..5 {
                // Rounds 2 and 3 take values from a few levels only: many ties; round 4
                // has NaNs (ties broken by index).
                let f: Vec<f64> = (0..n)
                    .map(|_| {
                        let r = next();
                        match round {
                            2 | 3 => (r * 3.0).floor(),
                            4 if r < 0.2 => f64::NAN,
                            _ => r,
                        }
                    })
                    .collect();
                for rule in [BoundaryRule::Double, BoundaryRule::LowerLink] {
                    let fast = classify_all(m, &f, rule, true).unwrap();
                    let slow = classify_all(m, &f, rule, false).unwrap();
                    assert_eq!(fast.minima, slow.minima);
                    assert_eq!(fast.maxima, slow.maxima);
                    assert_eq!(fast.saddles, slow.saddles);
                    assert_eq!(fast.on_boundary, slow.on_boundary);
                    assert_eq!(fast.non_manifold, slow.non_manifold);
                    shortcut_taken += fast.minima.len() + fast.maxima.len() + fast.saddles.len();
                    // The finder, in parallel and serially, with and without the shortcut.
                    for parallel in [true, false] {
                        for shortcut in [true, false] {
                            let got = finder.find_impl(&f, rule, parallel, shortcut).unwrap();
                            assert_eq!(got, slow, "parallel {parallel} shortcut {shortcut}");
                        }
                    }
                    assert_eq!(finder.find(&f, rule).unwrap(), slow);
                    assert_eq!(critical_points_with(m, &f, rule).unwrap(), slow);
                }
            }
        }
        assert!(shortcut_taken > 0);
        // The shortcut refuses what is not one simple cycle.
        let above = |_: usize| true;
        assert_eq!(
            simple_cycle_changes(&[(1, 2), (2, 3), (3, 1)], &above),
            Some(0)
        );
        assert_eq!(simple_cycle_changes(&[(1, 2), (2, 3)], &above), None);
        assert_eq!(
            simple_cycle_changes(&[(1, 2), (2, 3), (3, 1), (1, 4), (4, 5), (5, 1)], &above),
            None
        );
        assert_eq!(
            simple_cycle_changes(&[(1, 2), (2, 3), (3, 4), (4, 5)], &above),
            None
        );
    }
}
