//! The experiments the page can run, as plain functions of a mesh, its operators and an
//! eigenbasis. Conventions follow the project's MATH.md: S positive semi-definite,
//! eigenvectors B-orthonormal, spectral weights `w = 1/phi`.

use serde::{Deserialize, Serialize};
use spectral_mesh::linalg::SparseCholesky;
use spectral_mesh::mesh::topology::{Topology, VertexTriangles};
use spectral_mesh::{Eigenbasis, Mesh, Operators};

use crate::expr::Expr;

/// Which field to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Experiment {
    /// Harmonic map with Dirichlet constraints (no basis needed).
    #[default]
    Harmonic,
    /// Heat kernel basis function `K_t e_i = X D_t X^T B e_i` at the source (anchor).
    Heat,
    /// wFEM diffusion distance (eq. 15) from the source at time `t`.
    Diffusion,
    /// Filtered spectral distance from the source with the chosen filter.
    Distance,
    /// Generalized spectral function `G(p,p)` with the chosen filter (HKS for diffusion).
    Signature,
    /// Spectral segmentation: k-means on the filtered spectral embedding.
    Segmentation,
    /// One coordinate of the filtered spectral embedding `sqrt(w(lambda_j)) x_j`.
    Embedding,
    /// One eigenfunction `x_j`.
    Eigenfunction,
}

impl Experiment {
    /// True when the experiment needs an eigenbasis.
    pub fn needs_basis(self) -> bool {
        !matches!(self, Experiment::Harmonic)
    }
    /// The name users type.
    pub fn name(self) -> &'static str {
        match self {
            Experiment::Harmonic => "harmonic",
            Experiment::Heat => "heat",
            Experiment::Diffusion => "diffusion",
            Experiment::Distance => "distance",
            Experiment::Signature => "signature",
            Experiment::Segmentation => "segmentation",
            Experiment::Embedding => "embedding",
            Experiment::Eigenfunction => "eigenfunction",
        }
    }
}

/// The spectral filter, given as the weight `w(s) = 1/phi(s)` (MATH.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Filter {
    /// `w(s) = exp(-t s)`.
    Diffusion,
    /// `w(s) = 1/s`.
    Commute,
    /// `w(s) = 1/s^2`.
    #[default]
    Biharmonic,
    /// `w(s) = (1-a) exp(-t s) + a/s^2`.
    Mix,
    /// A user expression in `s`, `t`, `a` (see [`crate::expr`]), read as `w` or `phi`.
    Custom,
}

/// Every parameter of a field request (flat, so that it also reads from a query string).
#[derive(Debug, Clone, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct FieldParams {
    /// The experiment.
    pub experiment: Experiment,
    /// Discretization name (`fem` by default).
    pub laplacian: Option<String>,
    /// Number of eigenpairs used.
    pub k: Option<usize>,
    /// Time `t > 0` (heat, diffusion, diffusion filter).
    pub t: Option<f64>,
    /// Mix parameter `a` in [0, 1].
    pub a: Option<f64>,
    /// Filter for distance, signature, embedding, segmentation.
    pub filter: Option<Filter>,
    /// The custom filter expression.
    pub custom: Option<String>,
    /// Whether `custom` is the weight `w` ("w", default) or `phi` ("phi").
    pub custom_kind: Option<String>,
    /// Source / anchor vertex.
    pub source: Option<usize>,
    /// Harmonic constraints: "2", "4", "6" (the paper's presets) or "v=x,v=x,...".
    pub constraints: Option<String>,
    /// Number of level sets (0..=100).
    pub levels: Option<usize>,
    /// Eigenfunction / embedding coordinate index (0-based).
    pub component: Option<usize>,
    /// Number of segments for segmentation (2..=32).
    pub segments: Option<usize>,
    /// Download format (only read by the download endpoint).
    pub format: Option<String>,
}

/// A request that cannot be served, with a message for the user.
#[derive(Debug, Clone, PartialEq)]
pub struct BadRequest(pub String);

impl<T: Into<String>> From<T> for BadRequest {
    fn from(s: T) -> Self {
        BadRequest(s.into())
    }
}

/// The parameters after validation.
#[derive(Debug, Clone)]
pub struct Checked {
    /// Time.
    pub t: f64,
    /// Mix parameter.
    pub a: f64,
    /// Source vertex.
    pub source: usize,
    /// Number of level sets.
    pub levels: usize,
    /// Component index.
    pub component: usize,
    /// Number of segments.
    pub segments: usize,
    /// The filter weight.
    pub weight: Weight,
}

/// A spectral weight function.
#[derive(Debug, Clone)]
pub enum Weight {
    /// A built-in filter.
    Builtin(Filter),
    /// A custom expression, as `w` (false) or `phi` (true).
    Custom(Expr, bool),
}

impl Weight {
    /// `w(s)` at `s` with the page's `t` and `a`.
    pub fn eval(&self, s: f64, t: f64, a: f64) -> f64 {
        match self {
            Weight::Builtin(Filter::Diffusion) => (-t * s).exp(),
            Weight::Builtin(Filter::Commute) => 1.0 / s,
            Weight::Builtin(Filter::Biharmonic) => 1.0 / (s * s),
            Weight::Builtin(Filter::Mix) => (1.0 - a) * (-t * s).exp() + a / (s * s),
            Weight::Builtin(Filter::Custom) => f64::NAN,
            Weight::Custom(e, false) => e.eval(s, t, a),
            Weight::Custom(e, true) => 1.0 / e.eval(s, t, a),
        }
    }
}

/// Validates the scalar parameters against a mesh of `n` vertices.
pub fn check(p: &FieldParams, n: usize) -> Result<Checked, BadRequest> {
    let t = p.t.unwrap_or(0.5);
    if !t.is_finite() || t <= 0.0 || t > 1e12 {
        return Err(format!("t must be a finite number > 0 (got {t})").into());
    }
    let a = p.a.unwrap_or(0.5);
    if !a.is_finite() || !(0.0..=1.0).contains(&a) {
        return Err(format!("a must be in [0, 1] (got {a})").into());
    }
    let source = p.source.unwrap_or(0);
    if source >= n {
        return Err(format!("vertex {source} is out of range: the mesh has {n} vertices").into());
    }
    let levels = p.levels.unwrap_or(10);
    if levels > 100 {
        return Err(format!("at most 100 level sets (got {levels})").into());
    }
    let segments = p.segments.unwrap_or(5);
    if !(2..=32).contains(&segments) {
        return Err(format!("segments must be in 2..=32 (got {segments})").into());
    }
    let filter = p.filter.unwrap_or_default();
    let weight = if filter == Filter::Custom {
        let text = p.custom.as_deref().unwrap_or("").trim();
        if text.is_empty() {
            return Err("the custom filter needs an expression in s (e.g. exp(-t*s))".into());
        }
        let e = Expr::parse(text).map_err(|m| format!("custom filter: {m}"))?;
        let as_phi = match p.custom_kind.as_deref().unwrap_or("w") {
            "w" | "weight" => false,
            "phi" => true,
            other => return Err(format!("custom_kind must be 'w' or 'phi' (got '{other}')").into()),
        };
        Weight::Custom(e, as_phi)
    } else {
        Weight::Builtin(filter)
    };
    Ok(Checked {
        t,
        a,
        source,
        levels,
        component: p.component.unwrap_or(1),
        segments,
        weight,
    })
}

/// The weights `w(lambda_j)` of the first `k` pairs; zero eigenvalues get weight 0.
/// Errors when the weight is not finite and strictly positive at some eigenvalue.
pub fn weights(values: &[f64], c: &Checked) -> Result<Vec<f64>, BadRequest> {
    let lmax = values.iter().copied().fold(1.0f64, f64::max);
    let tol = 1e-9 * lmax;
    let mut w = Vec::with_capacity(values.len());
    for &l in values {
        if l <= tol {
            w.push(0.0);
            continue;
        }
        let v = c.weight.eval(l, c.t, c.a);
        if !v.is_finite() || v <= 0.0 {
            return Err(format!(
                "the filter weight w(s) must be finite and > 0 at every eigenvalue; w({l:.6}) = {v}"
            )
            .into());
        }
        w.push(v);
    }
    Ok(w)
}

/// `(B x_j)_i` for every `j < k`: row `i` of `B X` (B is symmetric).
fn bx_row(basis: &Eigenbasis, k: usize, i: usize) -> Vec<f64> {
    let n = basis.n;
    let (rows, vals) = basis.mass.col(i);
    (0..k)
        .map(|j| {
            let x = &basis.vectors[j * n..(j + 1) * n];
            rows.iter().zip(vals).map(|(&r, &v)| v * x[r]).sum()
        })
        .collect()
}

/// `sum_j c_j x_j` over the first `coef.len()` eigenvectors.
fn combine(basis: &Eigenbasis, coef: &[f64]) -> Vec<f64> {
    let n = basis.n;
    let mut out = vec![0.0; n];
    for (j, &c) in coef.iter().enumerate() {
        if c == 0.0 {
            continue;
        }
        let x = &basis.vectors[j * n..(j + 1) * n];
        out.iter_mut().zip(x).for_each(|(o, v)| *o += c * v);
    }
    out
}

/// Computes a field that needs the first `k` pairs of `basis`.
pub fn spectral_field(
    exp: Experiment,
    basis: &Eigenbasis,
    k: usize,
    c: &Checked,
) -> Result<Vec<f64>, BadRequest> {
    let n = basis.n;
    let k = k.min(basis.k());
    let values = &basis.values[..k];
    let i = c.source;
    match exp {
        Experiment::Harmonic => Err("harmonic maps need no basis".into()),
        Experiment::Heat => {
            let bx = bx_row(basis, k, i);
            let coef: Vec<f64> = values
                .iter()
                .zip(&bx)
                .map(|(l, b)| (-l * c.t).exp() * b)
                .collect();
            Ok(combine(basis, &coef))
        }
        Experiment::Diffusion => {
            // d_t(i,j)^2 = sum_l exp(-lambda_l t) ((B x_l)_i - (B x_l)_j)^2.
            let bx: Vec<Vec<f64>> = (0..k)
                .map(|j| basis.mass.mul_vec(&basis.vectors[j * n..(j + 1) * n]))
                .collect();
            let mut d = vec![0.0; n];
            for (l, col) in values.iter().zip(&bx) {
                let w = (-l * c.t).exp();
                let ci = col[i];
                d.iter_mut()
                    .zip(col)
                    .for_each(|(o, v)| *o += w * (ci - v) * (ci - v));
            }
            Ok(d.into_iter().map(|v| v.max(0.0).sqrt()).collect())
        }
        Experiment::Distance => {
            let w = weights(values, c)?;
            let mut d = vec![0.0; n];
            for (j, &wj) in w.iter().enumerate() {
                if wj == 0.0 {
                    continue;
                }
                let x = &basis.vectors[j * n..(j + 1) * n];
                let xi = x[i];
                d.iter_mut()
                    .zip(x)
                    .for_each(|(o, v)| *o += wj * (xi - v) * (xi - v));
            }
            Ok(d.into_iter().map(|v| v.max(0.0).sqrt()).collect())
        }
        Experiment::Signature => {
            let w = weights(values, c)?;
            let mut g = vec![0.0; n];
            for (j, &wj) in w.iter().enumerate() {
                let x = &basis.vectors[j * n..(j + 1) * n];
                g.iter_mut().zip(x).for_each(|(o, v)| *o += wj * v * v);
            }
            Ok(g)
        }
        Experiment::Embedding | Experiment::Eigenfunction => {
            let j = c.component;
            if j >= k {
                return Err(format!(
                    "component {j} is out of range: the basis has k = {k} pairs (0-based)"
                )
                .into());
            }
            let x = &basis.vectors[j * n..(j + 1) * n];
            let s = if exp == Experiment::Embedding {
                weights(&values[j..=j], c)?[0].sqrt()
            } else {
                1.0
            };
            Ok(x.iter().map(|v| s * v).collect())
        }
        Experiment::Segmentation => {
            let w = weights(values, c)?;
            Ok(segment(basis, &w, c.segments))
        }
    }
}

/// k-means (farthest-point seeds, 20 Lloyd steps) on the embedding `sqrt(w_j) x_j`.
fn segment(basis: &Eigenbasis, w: &[f64], segments: usize) -> Vec<f64> {
    let n = basis.n;
    let dims: Vec<usize> = (0..w.len()).filter(|&j| w[j] > 0.0).take(32).collect();
    if dims.is_empty() {
        return vec![0.0; n];
    }
    let d = dims.len();
    let mut pts = vec![0.0; n * d];
    for (c, &j) in dims.iter().enumerate() {
        let s = w[j].sqrt();
        for i in 0..n {
            pts[i * d + c] = s * basis.vectors[j * n + i];
        }
    }
    let dist2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>();
    let kk = segments.min(n);
    let mut centers: Vec<Vec<f64>> = vec![pts[0..d].to_vec()];
    let mut best = vec![f64::INFINITY; n];
    while centers.len() < kk {
        let last = centers[centers.len() - 1].clone();
        let mut far = 0;
        for i in 0..n {
            best[i] = best[i].min(dist2(&pts[i * d..(i + 1) * d], &last));
            if best[i] > best[far] {
                far = i;
            }
        }
        centers.push(pts[far * d..(far + 1) * d].to_vec());
    }
    let mut label = vec![0usize; n];
    for _ in 0..20 {
        for i in 0..n {
            let p = &pts[i * d..(i + 1) * d];
            let mut bi = 0;
            let mut bd = f64::INFINITY;
            for (ci, c) in centers.iter().enumerate() {
                let dd = dist2(p, c);
                if dd < bd {
                    bd = dd;
                    bi = ci;
                }
            }
            label[i] = bi;
        }
        let mut sums = vec![vec![0.0; d]; kk];
        let mut counts = vec![0usize; kk];
        for i in 0..n {
            counts[label[i]] += 1;
            for c in 0..d {
                sums[label[i]][c] += pts[i * d + c];
            }
        }
        for ci in 0..kk {
            if counts[ci] > 0 {
                centers[ci] = sums[ci].iter().map(|v| v / counts[ci] as f64).collect();
            }
        }
    }
    label.into_iter().map(|l| l as f64).collect()
}

/// Parses harmonic constraints: a preset "2", "4", "6" (vertex of min x -> 0, max x -> 1,
/// then y, then z) or explicit "v=x,v=x,...".
pub fn parse_constraints(spec: &str, mesh: &Mesh) -> Result<Vec<(usize, f64)>, BadRequest> {
    let n = mesh.n_vertices();
    let spec = spec.trim();
    if let Ok(count) = spec.parse::<usize>() {
        if !matches!(count, 2 | 4 | 6) {
            return Err(format!("constraint presets are 2, 4 or 6 (got {count})").into());
        }
        let p = mesh.positions();
        let mut out = Vec::new();
        for axis in 0..count / 2 {
            let mut lo = 0;
            let mut hi = 0;
            for i in 0..n {
                if p[i][axis] < p[lo][axis] {
                    lo = i;
                }
                if p[i][axis] > p[hi][axis] {
                    hi = i;
                }
            }
            out.push((lo, 0.0));
            out.push((hi, 1.0));
        }
        return Ok(dedup(out));
    }
    let mut out = Vec::new();
    for part in spec.split(',').filter(|s| !s.trim().is_empty()) {
        let (v, x) = part
            .split_once('=')
            .ok_or_else(|| format!("bad constraint '{part}': expected vertex=value"))?;
        let v: usize = v
            .trim()
            .parse()
            .map_err(|_| format!("bad vertex in constraint '{part}'"))?;
        let x: f64 = x
            .trim()
            .parse()
            .map_err(|_| format!("bad value in constraint '{part}'"))?;
        if v >= n {
            return Err(format!("vertex {v} is out of range: the mesh has {n} vertices").into());
        }
        if !x.is_finite() {
            return Err(format!("constraint value for vertex {v} is not finite").into());
        }
        out.push((v, x));
    }
    if out.len() < 2 {
        return Err("a harmonic map needs at least two constraints".into());
    }
    if out.len() > 10_000 {
        return Err("at most 10000 constraints".into());
    }
    Ok(dedup(out))
}

fn dedup(mut c: Vec<(usize, f64)>) -> Vec<(usize, f64)> {
    let mut seen = std::collections::HashSet::new();
    c.retain(|(v, _)| seen.insert(*v));
    c
}

/// Solves the Dirichlet problem `S_FF f_F = -S_FI f_I` (MATH.md, harmonic maps).
pub fn harmonic(
    ops: &Operators,
    topo: &Topology,
    constraints: &[(usize, f64)],
) -> Result<Vec<f64>, BadRequest> {
    let n = ops.n();
    let mut fixed = vec![None; n];
    for &(v, x) in constraints {
        fixed[v] = Some(x);
    }
    let mut has = vec![false; topo.components.len()];
    for &(v, _) in constraints {
        if let Some(c) = topo.vertex_component.get(v).copied()
            && c < has.len()
        {
            has[c] = true;
        }
    }
    if let Some(c) = has.iter().position(|h| !h) {
        return Err(format!(
            "component {c} has no constraint: every connected component needs one"
        )
        .into());
    }
    let free: Vec<usize> = (0..n)
        .filter(|&i| fixed[i].is_none() && topo.vertex_component[i] != usize::MAX)
        .collect();
    let fixed_idx: Vec<usize> = (0..n).filter(|&i| fixed[i].is_some()).collect();
    let mut f = vec![0.0; n];
    for &i in &fixed_idx {
        f[i] = fixed[i].unwrap_or(0.0);
    }
    if free.is_empty() {
        return Ok(f);
    }
    let sff = ops.stiffness.submatrix(&free, &free);
    let sfi = ops.stiffness.submatrix(&free, &fixed_idx);
    let fi: Vec<f64> = fixed_idx.iter().map(|&i| f[i]).collect();
    let rhs: Vec<f64> = sfi.mul_vec(&fi).into_iter().map(|v| -v).collect();
    let chol = SparseCholesky::new(&sff)
        .map_err(|e| format!("the harmonic system could not be factored: {e}"))?;
    let sol = chol.solve(&rhs);
    for (&i, v) in free.iter().zip(sol) {
        f[i] = v;
    }
    if f.iter().any(|v| !v.is_finite()) {
        return Err("the harmonic solve produced non-finite values".into());
    }
    Ok(f)
}

/// Critical points of a piecewise-linear function (Banchoff), ties broken by index.
#[derive(Debug, Clone, Serialize, Default)]
pub struct CriticalPoints {
    /// Minima.
    pub minima: Vec<usize>,
    /// Maxima.
    pub maxima: Vec<usize>,
    /// Saddles as (vertex, multiplicity).
    pub saddles: Vec<(usize, usize)>,
    /// Boundary vertices (not classified).
    pub boundary_skipped: usize,
    /// minima - saddles (with multiplicity) + maxima.
    pub euler_found: i64,
    /// The mesh's Euler characteristic.
    pub euler_expected: i64,
    /// True when the surface is closed and the check holds.
    pub euler_ok: bool,
}

/// Classifies every interior vertex of `mesh` for the field `f`.
pub fn critical_points(
    mesh: &Mesh,
    topo: &Topology,
    vt: &VertexTriangles,
    f: &[f64],
) -> CriticalPoints {
    let n = mesh.n_vertices();
    let mut on_boundary = vec![false; n];
    for l in &topo.boundary_loops {
        for &v in l {
            on_boundary[v] = true;
        }
    }
    for e in &topo.non_manifold_edges {
        on_boundary[e[0]] = true;
        on_boundary[e[1]] = true;
    }
    for &v in &topo.non_manifold_vertices {
        on_boundary[v] = true;
    }
    let above = |u: usize, v: usize| f[u] > f[v] || (f[u] == f[v] && u > v);
    let mut cp = CriticalPoints::default();
    let tris = mesh.triangles();
    for v in 0..n {
        let star = vt.of(v);
        if star.is_empty() {
            continue;
        }
        if on_boundary[v] {
            cp.boundary_skipped += 1;
            continue;
        }
        let mut changes = 0usize;
        let mut any_above = false;
        let mut any_below = false;
        for &t in star {
            let tri = tris[t];
            let others: Vec<usize> = tri.iter().copied().filter(|&u| u != v).collect();
            if others.len() != 2 {
                continue;
            }
            let (a, b) = (above(others[0], v), above(others[1], v));
            if a != b {
                changes += 1;
            }
            any_above |= a || b;
            any_below |= !a || !b;
        }
        if changes == 0 {
            if any_above && !any_below {
                cp.minima.push(v);
            } else if any_below && !any_above {
                cp.maxima.push(v);
            }
        } else if changes >= 4 {
            cp.saddles.push((v, changes / 2 - 1));
        }
    }
    let saddle_mult: usize = cp.saddles.iter().map(|s| s.1).sum();
    cp.euler_found = cp.minima.len() as i64 - saddle_mult as i64 + cp.maxima.len() as i64;
    cp.euler_expected = topo.euler_characteristic();
    cp.euler_ok = cp.boundary_skipped == 0 && cp.euler_found == cp.euler_expected;
    cp
}

/// Level sets: `levels` iso-values evenly spaced strictly inside (min, max); returns the
/// iso-values, the segment count per level and the segments as `x1 y1 z1 x2 y2 z2` floats.
pub fn level_sets(mesh: &Mesh, f: &[f64], levels: usize) -> (Vec<f64>, Vec<u32>, Vec<f32>) {
    let (lo, hi) = min_max(f);
    let mut isos = Vec::new();
    let mut counts = Vec::new();
    let mut segs = Vec::new();
    if levels == 0 || hi <= lo {
        return (isos, counts, segs);
    }
    let p = mesh.positions();
    for l in 1..=levels {
        let c = lo + (hi - lo) * l as f64 / (levels + 1) as f64;
        isos.push(c);
        let before = segs.len();
        for tri in mesh.triangles() {
            let mut pts = [[0.0f64; 3]; 2];
            let mut np = 0;
            for e in 0..3 {
                let (i, j) = (tri[e], tri[(e + 1) % 3]);
                let (fi, fj) = (f[i] - c, f[j] - c);
                if (fi >= 0.0) != (fj >= 0.0) && np < 2 {
                    let s = fi / (fi - fj);
                    pts[np] = [
                        p[i][0] + s * (p[j][0] - p[i][0]),
                        p[i][1] + s * (p[j][1] - p[i][1]),
                        p[i][2] + s * (p[j][2] - p[i][2]),
                    ];
                    np += 1;
                }
            }
            if np == 2 {
                for q in pts {
                    segs.extend(q.iter().map(|&x| x as f32));
                }
            }
        }
        counts.push(((segs.len() - before) / 6) as u32);
    }
    (isos, counts, segs)
}

/// Minimum and maximum of the finite entries.
pub fn min_max(f: &[f64]) -> (f64, f64) {
    f.iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fallback::{icosphere, torus};
    use spectral_mesh::Laplacian;

    #[test]
    fn critical_points_of_height_satisfy_euler() {
        for (mesh, chi) in [(icosphere(2), 2), (torus(24, 12, 1.0, 0.4), 0)] {
            let topo = Topology::new(&mesh);
            let vt = VertexTriangles::new(&mesh);
            let f: Vec<f64> = mesh
                .positions()
                .iter()
                .map(|p| p[0] + 0.3 * p[1] + 0.1 * p[2])
                .collect();
            let cp = critical_points(&mesh, &topo, &vt, &f);
            assert_eq!(cp.euler_expected, chi);
            assert!(cp.euler_ok, "{cp:?}");
            assert_eq!(cp.minima.len(), 1);
            assert_eq!(cp.maxima.len(), 1);
        }
    }

    #[test]
    fn harmonic_meets_constraints_and_max_principle() {
        let mesh = icosphere(2);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let topo = Topology::new(&mesh);
        let c = parse_constraints("2", &mesh).unwrap();
        let f = harmonic(&ops, &topo, &c).unwrap();
        for &(v, x) in &c {
            assert_eq!(f[v], x);
        }
        let (lo, hi) = min_max(&f);
        assert!(lo >= -1e-9 && hi <= 1.0 + 1e-9);
        // S f = 0 at free vertices.
        let sf = ops.stiffness.mul_vec(&f);
        for (i, v) in sf.iter().enumerate() {
            if c.iter().all(|&(w, _)| w != i) {
                assert!(v.abs() < 1e-9, "residual {v} at {i}");
            }
        }
    }

    #[test]
    fn heat_conserves_mass_with_full_basis() {
        let mesh = icosphere(1);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let n = mesh.n_vertices();
        let basis = Eigenbasis::dense(&ops, n).unwrap();
        let p = FieldParams {
            t: Some(0.1),
            source: Some(3),
            ..Default::default()
        };
        let c = check(&p, n).unwrap();
        let u = spectral_field(Experiment::Heat, &basis, n, &c).unwrap();
        // 1^T B K_t e_i = 1^T B e_i.
        let bu = ops.mass.mul_vec(&u);
        let ones = vec![1.0; n];
        let be = ops.mass.mul_vec(&{
            let mut e = vec![0.0; n];
            e[3] = 1.0;
            e
        });
        let total: f64 = bu.iter().sum();
        let want: f64 = be.iter().zip(&ones).map(|(a, b)| a * b).sum();
        assert!((total - want).abs() < 1e-9 * want.abs().max(1.0));
    }

    #[test]
    fn distance_is_zero_at_source_and_positive_elsewhere() {
        let mesh = icosphere(1);
        let ops = Operators::new(&mesh, Laplacian::Fem);
        let basis = Eigenbasis::dense(&ops, 20).unwrap();
        let p = FieldParams {
            source: Some(5),
            ..Default::default()
        };
        let c = check(&p, mesh.n_vertices()).unwrap();
        let d = spectral_field(Experiment::Distance, &basis, 20, &c).unwrap();
        assert_eq!(d[5], 0.0);
        assert!(d.iter().enumerate().all(|(i, &v)| i == 5 || v > 0.0));
    }

    #[test]
    fn bad_parameters_are_rejected() {
        let bad = [
            FieldParams {
                t: Some(f64::NAN),
                ..Default::default()
            },
            FieldParams {
                t: Some(-1.0),
                ..Default::default()
            },
            FieldParams {
                source: Some(100),
                ..Default::default()
            },
            FieldParams {
                filter: Some(Filter::Custom),
                custom: Some("exp(".into()),
                ..Default::default()
            },
        ];
        for p in bad {
            assert!(check(&p, 10).is_err(), "{p:?}");
        }
        let p = FieldParams {
            filter: Some(Filter::Custom),
            custom: Some("s - 100".into()),
            ..Default::default()
        };
        let c = check(&p, 10).unwrap();
        assert!(weights(&[0.0, 1.0, 2.0], &c).is_err());
    }

    #[test]
    fn level_sets_lie_on_the_surface() {
        let mesh = icosphere(2);
        let f: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
        let (isos, counts, segs) = level_sets(&mesh, &f, 5);
        assert_eq!(isos.len(), 5);
        assert!(counts.iter().all(|&c| c > 0));
        assert_eq!(segs.len(), 6 * counts.iter().sum::<u32>() as usize);
        // Every segment end point has z close to its iso-value (linear on triangles).
        let mut off = 0;
        for (l, &c) in counts.iter().enumerate() {
            for s in 0..c as usize {
                let z1 = segs[off + 6 * s + 2] as f64;
                let z2 = segs[off + 6 * s + 5] as f64;
                assert!((z1 - isos[l]).abs() < 1e-5 && (z2 - isos[l]).abs() < 1e-5);
            }
            off += 6 * c as usize;
        }
    }
}
