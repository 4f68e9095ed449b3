//! The experiments the page can run, as plain functions of a mesh, its operators and an
//! eigenbasis. Conventions follow the project's MATH.md: S positive semi-definite,
//! eigenvectors B-orthonormal, spectral weights `w = 1/phi`.

use serde::{Deserialize, Serialize};
use spectral_mesh::Eigenbasis;
use spectral_mesh::fields::harmonic::{Constraint, ConstraintSpec};

use std::collections::BTreeMap;

use spectral_mesh::spectral::filters::{CustomKind, Filter as LibFilter};

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
    /// Colour map of picture downloads (hue, viridis, turbo, diverging, grey).
    pub colormap: Option<String>,
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
    /// The spectral filter (the library's, with `t` and `a` bound).
    pub filter: LibFilter,
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
    let filter = match p.filter.unwrap_or_default() {
        Filter::Diffusion => LibFilter::Diffusion { t },
        Filter::Commute => LibFilter::CommuteTime,
        Filter::Biharmonic => LibFilter::Biharmonic,
        Filter::Mix => LibFilter::Mix { a, t },
        Filter::Custom => {
            let text = p.custom.as_deref().unwrap_or("").trim();
            if text.is_empty() {
                return Err("the custom filter needs an expression in s (e.g. exp(-t*s))".into());
            }
            if text.len() > 500 {
                return Err("custom filter: the expression is longer than 500 characters".into());
            }
            let kind = match p.custom_kind.as_deref().unwrap_or("w") {
                "w" | "weight" => CustomKind::Weight,
                "phi" => CustomKind::Phi,
                other => {
                    return Err(format!("custom_kind must be 'w' or 'phi' (got '{other}')").into());
                }
            };
            let params = BTreeMap::from([("t".to_string(), t), ("a".to_string(), a)]);
            LibFilter::custom(text, params, kind).map_err(|e| format!("custom filter: {e}"))?
        }
    };
    Ok(Checked {
        t,
        a,
        source,
        levels,
        component: p.component.unwrap_or(1),
        segments,
        filter,
    })
}

/// The weights `w(lambda_j)` of the first `k` pairs (the library's rules: zero eigenvalues
/// get weight 0; every other weight must be finite and > 0).
pub fn weights(values: &[f64], c: &Checked) -> Result<Vec<f64>, BadRequest> {
    c.filter
        .weights(values)
        .map_err(|e| BadRequest(format!("filter: {e}")))
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
                weights(values, c)?[j].sqrt()
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
/// then y, then z; MATH.md) or explicit "v=x,v=x,...".
pub fn parse_constraints(spec: &str, n: usize) -> Result<ConstraintSpec, BadRequest> {
    let spec = spec.trim();
    if let Ok(count) = spec.parse::<usize>() {
        if !matches!(count, 2 | 4 | 6) {
            return Err(format!("constraint presets are 2, 4 or 6 (got {count})").into());
        }
        return Ok(ConstraintSpec::Extremes(count));
    }
    let mut out = Vec::new();
    for part in spec.split(',').filter(|s| !s.trim().is_empty()) {
        let (v, x) = part
            .split_once('=')
            .ok_or_else(|| format!("bad constraint '{part}': expected vertex=value"))?;
        let vertex: usize = v
            .trim()
            .parse()
            .map_err(|_| format!("bad vertex in constraint '{part}'"))?;
        let value: f64 = x
            .trim()
            .parse()
            .map_err(|_| format!("bad value in constraint '{part}'"))?;
        if vertex >= n {
            return Err(
                format!("vertex {vertex} is out of range: the mesh has {n} vertices").into(),
            );
        }
        if !value.is_finite() {
            return Err(format!("constraint value for vertex {vertex} is not finite").into());
        }
        out.push(Constraint { vertex, value });
    }
    if out.len() < 2 {
        return Err("a harmonic map needs at least two constraints (vertex=value, ...)".into());
    }
    if out.len() > 10_000 {
        return Err("at most 10000 constraints".into());
    }
    Ok(ConstraintSpec::Explicit(out))
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
    use spectral_mesh::shapes::build_str;
    use spectral_mesh::{Laplacian, Operators};

    #[test]
    fn heat_conserves_mass_with_full_basis() {
        let mesh = build_str("sphere:res=1").unwrap();
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
        let mesh = build_str("sphere:res=1").unwrap();
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
}
