//! Level sets (iso-lines) of a piecewise-linear per-vertex field.
//!
//! A per-vertex field `f` is linear on every triangle, so the set `{f = c}` inside a
//! triangle is a straight segment joining two points on the triangle's edges. This
//! module finds those segments for a list of values and chains them across triangles
//! into polylines.
//!
//! # Values exactly at a vertex
//!
//! A vertex whose value equals `c` exactly is treated as lying *above* `c`
//! (symbolic perturbation: `f(v) == c` behaves like `f(v) = c + ε`). An edge is crossed
//! when exactly one of its ends is below `c`, so the crossing point is well defined
//! (the two end values differ) and lies on the closed edge. Where this would give a
//! zero-length segment (a triangle whose only "above" corner sits exactly on `c`) the
//! segment is dropped, and segments that coincide exactly (both ends at vertices with the
//! value `c`, e.g. along a ridge of vertices at the value) are kept once. Crossing points
//! that fall exactly on a vertex are identified with that vertex, so a polyline never
//! repeats a point.
//!
//! Non-finite field values: a triangle with a NaN or infinite corner value is skipped.

use crate::mesh::Mesh;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// `count` evenly spaced values strictly inside `[min, max]`: the centres of `count`
/// equal bins, `min + (i + 0.5) (max - min) / count` for `i = 0..count`.
///
/// Returns an empty vector when `count == 0` or a bound is not finite. When
/// `max <= min` every value equals `min` (a degenerate range has one level).
pub fn level_values(min: f64, max: f64, count: usize) -> Vec<f64> {
    if count == 0 || !min.is_finite() || !max.is_finite() {
        return Vec::new();
    }
    if max <= min {
        return vec![min; count.min(1)];
    }
    let step = (max - min) / count as f64;
    (0..count).map(|i| min + (i as f64 + 0.5) * step).collect()
}

/// One chained piece of a level set: a sequence of points on mesh edges.
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    /// The points, in order along the curve. A closed polyline does not repeat its first
    /// point at the end.
    pub points: Vec<[f64; 3]>,
    /// For each point, the mesh edge it lies on, as `[a, b]` with `a < b`.
    pub edges: Vec<[usize; 2]>,
    /// For each point, its parameter on its edge: `point = (1 - t) p[a] + t p[b]`, `t` in `[0, 1]`.
    pub t: Vec<f64>,
    /// Whether the last point connects back to the first.
    pub closed: bool,
}

impl Polyline {
    /// Length of the polyline (including the closing segment when closed).
    pub fn length(&self) -> f64 {
        let n = self.points.len();
        if n < 2 {
            return 0.0;
        }
        let mut s: f64 = self.points.windows(2).map(|w| dist(w[0], w[1])).sum();
        if self.closed {
            s += dist(self.points[n - 1], self.points[0]);
        }
        s
    }
}

/// The level set `{f = value}` of a field.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelSet {
    /// The iso-value.
    pub value: f64,
    /// Every segment, one per crossed triangle, unordered (no zero-length segments).
    pub segments: Vec<[[f64; 3]; 2]>,
    /// The segments chained across triangles.
    pub polylines: Vec<Polyline>,
}

impl LevelSet {
    /// Total length of all segments.
    pub fn length(&self) -> f64 {
        self.segments.iter().map(|s| dist(s[0], s[1])).sum()
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Identity of a crossing point: a vertex (when the point falls exactly on it) or the
/// interior of an edge `(a, b)`, `a < b`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Key {
    Vertex(usize),
    Edge(usize, usize),
}

#[derive(Debug, Clone, Copy)]
struct Crossing {
    key: Key,
    edge: [usize; 2],
    t: f64,
    point: [f64; 3],
}

/// Crossing of edge `(u, w)` (one end below `value`, the other not).
fn crossing(mesh: &Mesh, field: &[f64], u: usize, w: usize, value: f64) -> Crossing {
    let (a, b) = if u < w { (u, w) } else { (w, u) };
    let (fa, fb) = (field[a], field[b]);
    // The ends are on opposite sides, so fa != fb.
    let t = ((value - fa) / (fb - fa)).clamp(0.0, 1.0);
    let pa = mesh.positions()[a];
    let pb = mesh.positions()[b];
    if t == 0.0 {
        return Crossing {
            key: Key::Vertex(a),
            edge: [a, b],
            t,
            point: pa,
        };
    }
    if t == 1.0 {
        return Crossing {
            key: Key::Vertex(b),
            edge: [a, b],
            t,
            point: pb,
        };
    }
    let point = [
        pa[0] + t * (pb[0] - pa[0]),
        pa[1] + t * (pb[1] - pa[1]),
        pa[2] + t * (pb[2] - pa[2]),
    ];
    Crossing {
        key: Key::Edge(a, b),
        edge: [a, b],
        t,
        point,
    }
}

/// Extracts the level sets of `field` (one value per vertex) for every entry of `values`.
///
/// Returns one [`LevelSet`] per value, in the same order. If `field.len()` differs from
/// the number of vertices, every returned level set is empty.
pub fn extract_level_sets(mesh: &Mesh, field: &[f64], values: &[f64]) -> Vec<LevelSet> {
    values
        .iter()
        .map(|&value| {
            if field.len() != mesh.n_vertices() || !value.is_finite() {
                return LevelSet {
                    value,
                    segments: Vec::new(),
                    polylines: Vec::new(),
                };
            }
            extract_one(mesh, field, value)
        })
        .collect()
}

/// The segments of the level sets of `field` for every entry of `values`, without
/// chaining them: exactly the `segments` of [`extract_level_sets`] (same points, same
/// order, same duplicates dropped), in one pass over the triangles for all values,
/// spread over the threads. What a viewer draws; O(m + segments).
///
/// Returns one list per value, in the order of `values`. If `field.len()` differs from
/// the number of vertices, every list is empty.
pub fn level_set_segments(mesh: &Mesh, field: &[f64], values: &[f64]) -> Vec<Vec<[[f64; 3]; 2]>> {
    level_set_segments_impl(mesh, field, values, true)
}

/// Triangles per parallel task of [`level_set_segments`].
const SEGMENT_CHUNK: usize = 8192;

/// A segment: its two end points.
type Segment = [[f64; 3]; 2];

/// A segment found in one triangle: (index into `values`, the keys of its two crossings,
/// the segment).
type Found = (usize, (Key, Key), Segment);

fn level_set_segments_impl(
    mesh: &Mesh,
    field: &[f64],
    values: &[f64],
    parallel: bool,
) -> Vec<Vec<[[f64; 3]; 2]>> {
    let mut out = vec![Vec::new(); values.len()];
    if field.len() != mesh.n_vertices() {
        return out;
    }
    // Finite values in ascending order, so that each triangle finds the values it
    // crosses by two binary searches.
    let mut order: Vec<usize> = (0..values.len())
        .filter(|&i| values[i].is_finite())
        .collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let sorted: Vec<f64> = order.iter().map(|&i| values[i]).collect();
    // Per vertex, how many of the sorted values are <= its value (u32::MAX when not
    // finite): a triangle crosses the values c with lo < c <= hi, which are those from
    // the smallest of its corners' counts to the largest.
    let count = |f: &f64| -> u32 {
        if f.is_finite() {
            sorted.partition_point(|&c| c <= *f) as u32
        } else {
            u32::MAX
        }
    };
    let counts: Vec<u32> = if parallel {
        field
            .par_iter()
            .with_min_len(SEGMENT_CHUNK)
            .map(count)
            .collect()
    } else {
        field.iter().map(count).collect()
    };
    let scan = |tris: &[[usize; 3]]| -> Vec<Found> {
        let mut found = Vec::new();
        for tri in tris {
            let c = [counts[tri[0]], counts[tri[1]], counts[tri[2]]];
            let first = c[0].min(c[1]).min(c[2]);
            let last = c[0].max(c[1]).max(c[2]);
            if first == last || last == u32::MAX {
                continue;
            }
            let fv = [field[tri[0]], field[tri[1]], field[tri[2]]];
            let (first, last) = (first as usize, last as usize);
            for (&level, &value) in order[first..last].iter().zip(&sorted[first..last]) {
                if let Some((keys, seg)) = triangle_segment(mesh, field, tri, fv, value) {
                    found.push((level, keys, seg));
                }
            }
        }
        found
    };
    let tris = mesh.triangles();
    let pieces: Vec<Vec<Found>> = if parallel {
        tris.par_chunks(SEGMENT_CHUNK).map(scan).collect()
    } else {
        vec![scan(tris)]
    };
    // In triangle order per value, keeping the first of segments that join the same two
    // crossings (as [`extract_level_sets`] does).
    let mut seen: Vec<HashSet<(Key, Key)>> = vec![HashSet::new(); values.len()];
    for (level, keys, seg) in pieces.into_iter().flatten() {
        if seen[level].insert(keys) {
            out[level].push(seg);
        }
    }
    out
}

/// The segment of level `value` in triangle `tri` (corner values `fv`), with the keys of
/// its two crossings (ascending), or `None` when the triangle has none (or only a
/// zero-length one).
fn triangle_segment(
    mesh: &Mesh,
    field: &[f64],
    tri: &[usize; 3],
    fv: [f64; 3],
    value: f64,
) -> Option<((Key, Key), Segment)> {
    let above = [fv[0] >= value, fv[1] >= value, fv[2] >= value];
    let mut ends: [Option<Crossing>; 2] = [None, None];
    let mut k = 0;
    for i in 0..3 {
        let j = (i + 1) % 3;
        if above[i] != above[j] && k < 2 {
            ends[k] = Some(crossing(mesh, field, tri[i], tri[j], value));
            k += 1;
        }
    }
    let (a, b) = (ends[0]?, ends[1]?);
    if a.key == b.key {
        return None;
    }
    let keys = if a.key < b.key {
        (a.key, b.key)
    } else {
        (b.key, a.key)
    };
    Some((keys, [a.point, b.point]))
}

fn extract_one(mesh: &Mesh, field: &[f64], value: f64) -> LevelSet {
    let mut nodes: Vec<Crossing> = Vec::new();
    let mut node_of: HashMap<Key, usize> = HashMap::new();
    let mut seg_nodes: Vec<[usize; 2]> = Vec::new();
    let mut seen: HashMap<(usize, usize), ()> = HashMap::new();

    for tri in mesh.triangles() {
        let fv = [field[tri[0]], field[tri[1]], field[tri[2]]];
        if fv.iter().any(|x| !x.is_finite()) {
            continue;
        }
        let above = [fv[0] >= value, fv[1] >= value, fv[2] >= value];
        let n_above = above.iter().filter(|&&x| x).count();
        if n_above == 0 || n_above == 3 {
            continue;
        }
        let mut ends = [0usize; 2];
        let mut k = 0;
        for i in 0..3 {
            let j = (i + 1) % 3;
            if above[i] != above[j] && k < 2 {
                let c = crossing(mesh, field, tri[i], tri[j], value);
                let id = *node_of.entry(c.key).or_insert_with(|| {
                    nodes.push(c);
                    nodes.len() - 1
                });
                ends[k] = id;
                k += 1;
            }
        }
        if k != 2 || ends[0] == ends[1] {
            continue;
        }
        let pair = (ends[0].min(ends[1]), ends[0].max(ends[1]));
        if seen.insert(pair, ()).is_some() {
            continue;
        }
        seg_nodes.push(ends);
    }

    let segments = seg_nodes
        .iter()
        .map(|&[a, b]| [nodes[a].point, nodes[b].point])
        .collect();
    let polylines = chain(&nodes, &seg_nodes);
    LevelSet {
        value,
        segments,
        polylines,
    }
}

/// Chains segments (pairs of node ids) into polylines: open chains start and end at nodes
/// whose degree is not 2; what is left are cycles.
fn chain(nodes: &[Crossing], segs: &[[usize; 2]]) -> Vec<Polyline> {
    let n = nodes.len();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (s, &[a, b]) in segs.iter().enumerate() {
        adj[a].push(s);
        adj[b].push(s);
    }
    let mut used = vec![false; segs.len()];
    let mut out = Vec::new();

    let walk = |start: usize, first_seg: usize, used: &mut Vec<bool>| -> (Vec<usize>, bool) {
        let mut path = vec![start];
        let mut cur = start;
        let mut seg = first_seg;
        loop {
            used[seg] = true;
            let [a, b] = segs[seg];
            let next = if a == cur { b } else { a };
            if next == start {
                return (path, true);
            }
            path.push(next);
            cur = next;
            if adj[cur].len() != 2 {
                return (path, false);
            }
            match adj[cur].iter().copied().find(|&s| !used[s]) {
                Some(s) => seg = s,
                None => return (path, false),
            }
        }
    };

    // Open chains (and branches at junctions) first, in a deterministic order.
    for (v, inc) in adj.iter().enumerate() {
        if inc.len() == 2 {
            continue;
        }
        for &s in inc {
            if used[s] {
                continue;
            }
            let (path, closed) = walk(v, s, &mut used);
            out.push(make_polyline(nodes, &path, closed));
        }
    }
    // Remaining segments form cycles through degree-2 nodes.
    for s in 0..segs.len() {
        if used[s] {
            continue;
        }
        let start = segs[s][0];
        let (path, closed) = walk(start, s, &mut used);
        out.push(make_polyline(nodes, &path, closed));
    }
    out
}

fn make_polyline(nodes: &[Crossing], path: &[usize], closed: bool) -> Polyline {
    Polyline {
        points: path.iter().map(|&i| nodes[i].point).collect(),
        edges: path.iter().map(|&i| nodes[i].edge).collect(),
        t: path.iter().map(|&i| nodes[i].t).collect(),
        closed: closed && path.len() >= 3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// UV sphere of radius `r` with `rings` latitude bands (even => an equator ring at z = 0).
    fn uv_sphere(r: f64, rings: usize, segs: usize) -> Mesh {
        let mut p = vec![[0.0, 0.0, r]];
        for i in 1..rings {
            let th = std::f64::consts::PI * i as f64 / rings as f64;
            for j in 0..segs {
                let ph = 2.0 * std::f64::consts::PI * j as f64 / segs as f64;
                let z = if 2 * i == rings { 0.0 } else { r * th.cos() };
                p.push([r * th.sin() * ph.cos(), r * th.sin() * ph.sin(), z]);
            }
        }
        p.push([0.0, 0.0, -r]);
        let south = p.len() - 1;
        let ring = |i: usize, j: usize| 1 + (i - 1) * segs + (j % segs);
        let mut t = Vec::new();
        for j in 0..segs {
            t.push([0, ring(1, j), ring(1, j + 1)]);
            t.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
        }
        for i in 1..rings - 1 {
            for j in 0..segs {
                t.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                t.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        Mesh::new(p, t).unwrap()
    }

    /// Icosphere (subdivided icosahedron projected on the sphere of radius `r`).
    fn icosphere(r: f64, levels: usize) -> Mesh {
        crate::shapes::build_str(&format!("sphere:res={levels}"))
            .unwrap()
            .map_positions(|p| [p[0] * r, p[1] * r, p[2] * r])
            .unwrap()
    }

    fn check_points(mesh: &Mesh, field: &[f64], ls: &LevelSet) {
        for pl in &ls.polylines {
            assert_eq!(pl.points.len(), pl.edges.len());
            assert_eq!(pl.points.len(), pl.t.len());
            for k in 0..pl.points.len() {
                let [a, b] = pl.edges[k];
                assert!(a < b);
                let t = pl.t[k];
                assert!((0.0..=1.0).contains(&t));
                let (pa, pb) = (mesh.positions()[a], mesh.positions()[b]);
                // The point is on segment [pa, pb] at parameter t.
                let q = pl.points[k];
                let len = dist(pa, pb);
                let expect = [
                    pa[0] + t * (pb[0] - pa[0]),
                    pa[1] + t * (pb[1] - pa[1]),
                    pa[2] + t * (pb[2] - pa[2]),
                ];
                assert!(dist(q, expect) <= 1e-12 * (1.0 + len));
                assert!((dist(pa, q) + dist(q, pb) - len).abs() <= 1e-12 * (1.0 + len));
                let f = (1.0 - t) * field[a] + t * field[b];
                let scale = ls
                    .value
                    .abs()
                    .max(field[a].abs())
                    .max(field[b].abs())
                    .max(1e-300);
                assert!(
                    (f - ls.value).abs() <= 1e-9 * scale,
                    "f {f} value {}",
                    ls.value
                );
            }
            // No repeated consecutive points, no zero-length pieces.
            let n = pl.points.len();
            for k in 0..n {
                if k + 1 < n || pl.closed {
                    assert!(dist(pl.points[k], pl.points[(k + 1) % n]) > 0.0);
                }
            }
        }
        for s in &ls.segments {
            assert!(dist(s[0], s[1]) > 0.0);
        }
    }

    #[test]
    fn level_values_are_bin_centres() {
        let v = level_values(0.0, 1.0, 4);
        assert_eq!(v, vec![0.125, 0.375, 0.625, 0.875]);
        assert!(level_values(0.0, 1.0, 0).is_empty());
        assert_eq!(level_values(2.0, 2.0, 5), vec![2.0]);
        assert!(level_values(f64::NAN, 1.0, 3).is_empty());
        for &x in &level_values(-3.0, 5.0, 7) {
            assert!(x > -3.0 && x < 5.0);
        }
    }

    #[test]
    fn icosphere_equator_length_converges() {
        let r = 2.0;
        let mut prev_err = f64::INFINITY;
        for levels in [1, 2, 3, 4] {
            let mesh = icosphere(r, levels);
            let field: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
            let ls = extract_level_sets(&mesh, &field, &[0.0]).remove(0);
            check_points(&mesh, &field, &ls);
            assert_eq!(ls.polylines.len(), 1, "levels {levels}");
            let pl = &ls.polylines[0];
            assert!(pl.closed);
            let err = (pl.length() - 2.0 * std::f64::consts::PI * r).abs();
            assert!((pl.length() - ls.length()).abs() < 1e-9);
            assert!(err < prev_err, "error must shrink: {err} >= {prev_err}");
            prev_err = err;
        }
        assert!(prev_err / (2.0 * std::f64::consts::PI * r) < 0.01);
    }

    #[test]
    fn equator_through_vertices_is_the_ring_polygon() {
        let r = 1.5;
        let segs = 48;
        let mesh = uv_sphere(r, 16, segs);
        let field: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
        let ls = extract_level_sets(&mesh, &field, &[0.0]).remove(0);
        check_points(&mesh, &field, &ls);
        assert_eq!(ls.polylines.len(), 1);
        let pl = &ls.polylines[0];
        assert!(pl.closed);
        assert_eq!(pl.points.len(), segs);
        assert_eq!(ls.segments.len(), segs);
        let n = segs as f64;
        let expect = 2.0 * n * r * (std::f64::consts::PI / n).sin();
        assert!((pl.length() - expect).abs() < 1e-9);
        for q in &pl.points {
            assert_eq!(q[2], 0.0);
        }
    }

    #[test]
    fn several_levels_on_sphere_are_circles() {
        let r = 1.0;
        let mesh = icosphere(r, 4);
        let field: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
        let vals = level_values(-1.0, 1.0, 5);
        let sets = extract_level_sets(&mesh, &field, &vals);
        assert_eq!(sets.len(), 5);
        for ls in &sets {
            check_points(&mesh, &field, ls);
            assert_eq!(ls.polylines.len(), 1);
            let circ = 2.0 * std::f64::consts::PI * (r * r - ls.value * ls.value).sqrt();
            let rel = (ls.polylines[0].length() - circ).abs() / circ;
            assert!(rel < 0.02, "value {} rel {rel}", ls.value);
        }
    }

    #[test]
    fn open_mesh_gives_open_polyline() {
        // A 4x4 grid of squares; field x; level through the interior.
        let mesh = crate::test_support::grid(5, |i, j| [i as f64, j as f64, 0.0]);
        let field: Vec<f64> = mesh.positions().iter().map(|q| q[0] + 0.1 * q[1]).collect();
        // Value exactly at vertex values (x = 2 on row 0) and in between.
        for v in [2.0, 1.7, 0.35, 3.95] {
            let ls = extract_level_sets(&mesh, &field, &[v]).remove(0);
            check_points(&mesh, &field, &ls);
            assert_eq!(ls.polylines.len(), 1, "value {v}");
            assert!(!ls.polylines[0].closed);
            assert_eq!(ls.polylines[0].points.len(), ls.segments.len() + 1);
        }
        // Outside the range: nothing.
        let ls = extract_level_sets(&mesh, &field, &[10.0]).remove(0);
        assert!(ls.segments.is_empty() && ls.polylines.is_empty());
        // Mismatched field length: empty, no panic.
        let ls = extract_level_sets(&mesh, &field[1..], &[1.0]).remove(0);
        assert!(ls.segments.is_empty());
    }

    #[test]
    fn ridge_at_the_value_is_not_duplicated() {
        // Two triangles sharing edge (0,1) whose ends are both exactly at the value.
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
        ];
        let mesh = Mesh::new(p, vec![[0, 1, 2], [1, 0, 3]]).unwrap();
        let field = [1.0, 1.0, 0.0, 0.0];
        let ls = extract_level_sets(&mesh, &field, &[1.0]).remove(0);
        assert_eq!(ls.segments.len(), 1);
        assert_eq!(ls.polylines.len(), 1);
        assert_eq!(ls.polylines[0].points.len(), 2);
        check_points(&mesh, &field, &ls);
        // A single vertex exactly at the value as a local maximum: no segment.
        let field = [1.0, 0.0, 0.0, 0.0];
        let ls = extract_level_sets(&mesh, &field, &[1.0]).remove(0);
        assert!(ls.segments.is_empty());
    }

    /// The one-pass segments, in parallel and serially, are exactly the segments of the
    /// chained extraction: closed, bordered and duplicated-triangle meshes, fields with
    /// ties and NaNs, values at vertex values, unsorted and non-finite values.
    #[test]
    fn one_pass_segments_equal_the_chained_extraction() {
        let dup = {
            // Two triangles on the same three vertices, plus a neighbour.
            let p = vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
            ];
            Mesh::new(p, vec![[0, 1, 2], [0, 2, 1], [1, 3, 2]]).unwrap()
        };
        let meshes = [
            crate::shapes::build_str("sphere:res=5").unwrap(), // > one parallel task
            crate::shapes::build_str("disk:res=3").unwrap(),
            crate::shapes::build_str("irregular-torus:res=2").unwrap(),
            uv_sphere(1.0, 16, 24),
            dup,
        ];
        let mut next = crate::test_support::lcg(99);
        let mut total = 0;
        for m in &meshes {
            let n = m.n_vertices();
            for round in 0..4 {
                let field: Vec<f64> = match round {
                    0 => m.positions().iter().map(|p| p[2]).collect(),
                    1 => (0..n).map(|_| (next() * 4.0).floor()).collect(), // ties
                    2 => (0..n)
                        .map(|_| if next() < 0.1 { f64::NAN } else { next() })
                        .collect(),
                    _ => (0..n).map(|_| next() - 0.5).collect(),
                };
                let mut values = level_values(-1.0, 1.0, 9);
                values.extend([0.0, 1.0, 2.0, f64::NAN, 0.25, -0.5, 1.0]);
                let chained = extract_level_sets(m, &field, &values);
                for parallel in [true, false] {
                    let got = level_set_segments_impl(m, &field, &values, parallel);
                    assert_eq!(got.len(), values.len());
                    for (g, ls) in got.iter().zip(&chained) {
                        assert_eq!(g, &ls.segments, "value {} round {round}", ls.value);
                        total += g.len();
                    }
                }
            }
        }
        assert!(total > 1000);
        let m = &meshes[3];
        assert!(
            level_set_segments(m, &[0.0; 3], &[0.5])
                .iter()
                .all(|s| s.is_empty())
        );
    }

    #[test]
    fn saddle_exactly_at_the_value() {
        // Grid on [-2, 2]^2 with f = x y: every axis vertex is exactly at 0, the origin a saddle.
        let n = 4;
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push([i as f64 - 2.0, j as f64 - 2.0, 0.0]);
            }
        }
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let a = j * (n + 1) + i;
                t.push([a, a + 1, a + n + 2]);
                t.push([a, a + n + 2, a + n + 1]);
            }
        }
        let mesh = Mesh::new(p, t).unwrap();
        let field: Vec<f64> = mesh.positions().iter().map(|q| q[0] * q[1]).collect();
        let ls = extract_level_sets(&mesh, &field, &[0.0]).remove(0);
        check_points(&mesh, &field, &ls);
        assert_eq!(ls.polylines.len(), 2);
        let on_boundary = |q: [f64; 3]| q[0].abs() == 2.0 || q[1].abs() == 2.0;
        let mut n_seg = 0;
        for pl in &ls.polylines {
            assert!(!pl.closed);
            assert!(on_boundary(pl.points[0]));
            assert!(on_boundary(*pl.points.last().unwrap()));
            n_seg += pl.points.len() - 1;
        }
        assert_eq!(n_seg, ls.segments.len());
    }
}
