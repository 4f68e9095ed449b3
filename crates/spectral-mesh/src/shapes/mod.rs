//! Built-in procedural shapes with a resolution parameter, so that every command works
//! without a mesh file.
//!
//! A shape is named by a spec string ([`parse_shape`]): `NAME` or
//! `NAME:KEY=VALUE,...`, e.g. `3torus`, `sphere:res=4`, `torus:res=3,R=1,r=0.4`,
//! `irregular-sphere:res=3` (equivalently `sphere:res=3,irregular=1`). [`build`] turns a
//! spec into a [`Mesh`]; the same spec always gives a bit-identical mesh (nothing is
//! random). The default shape is [`DEFAULT_SHAPE`], the paper's 3-torus.
//!
//! Every shape is manifold, consistently oriented (outward normals for the closed ones,
//! +z for the disk, away from the axis for the cylinder) and free of zero-area triangles.
//!
//! | name | topology | vertices at res | default res: vertices |
//! | --- | --- | --- | --- |
//! | `3torus` | closed, genus 3, chi = -4 | 100 * 4^res - 4 | 3: 6 396 |
//! | `torus` | closed, genus 1, chi = 0 | 2k^2, k = 7 * 2^res | 3: 6 272 |
//! | `sphere` | closed, genus 0, chi = 2 | 10 * 4^res + 2 | 4: 2 562 |
//! | `uv-sphere` | closed, genus 0, chi = 2 | 2k(k - 1) + 2, k = 7 * 2^res | 3: 6 162 |
//! | `double-torus` | closed, genus 2, chi = -2 | 74 * 4^res - 2 | 3: 4 734 |
//! | `disk` | 1 boundary loop, chi = 1 | 3k(k + 1) + 1, k = 6 * 2^res | 3: 7 057 |
//! | `cylinder` | 2 boundary loops, chi = 0 | 2k(k + 1), k = 7 * 2^res | 3: 6 384 |
//! | `irregular-NAME` | same as `NAME` | data-dependent (below) | see below |
//!
//! Sizes for benchmarks: `res = 4, 5, 6` give about 25k, 100k and 400k vertices for every
//! family except `sphere`, whose `res` is the icosphere subdivision level
//! (`res = 5, 6, 7, 8`: 10 242, 40 962, 163 842, 655 362 vertices). Building the 400k
//! meshes takes under a second (`3torus:res=6`: 0.8 s, 409 596 vertices), the irregular
//! ones a few seconds (`irregular-3torus:res=6`: 3.3 s, 528 388 vertices).
//!
//! Construction:
//! - `3torus`, `double-torus`: a closed quad control mesh, a plate with 3 (2) holes in a
//!   row (`26g + 22` quads), Catmull-Clark subdivided `res` times; vertices are moved to
//!   their limit positions, so every level samples the same smooth limit surface; each quad
//!   is split along its shorter diagonal.
//! - `torus` (params `R`, `r`): the grid `(u, v)` of `2k x k` points on
//!   `((R + r cos v) cos u, (R + r cos v) sin u, r sin v)`.
//! - `sphere`: the icosahedron split 1-to-4 `res` times, every vertex normalised (radius 1
//!   to rounding).
//! - `uv-sphere`: `k` latitude bands, `2k` meridians, one vertex per pole.
//! - `disk`: `k` hexagonal rings of `6i` vertices at radius `i/k` (boundary exactly on the
//!   unit circle), near-equilateral triangles.
//! - `cylinder` (params `r`, `h`): `k + 1` rings of `2k` vertices, z in `[-h/2, h/2]`.
//! - `irregular-NAME`: the regular shape at `res - 2` (at least 0), then three nested
//!   (`res + 1` when `res < 2`) red-green refinements of the triangles whose centroid lies beyond 45%, 60% and 75%
//!   of the bounding box along x; new vertices go onto the exact surface (normalised,
//!   closest point on the torus, radial for the cylinder, on the circle for disk boundary
//!   edges) or, for the subdivision surfaces, onto curved (PN-triangle) edges from the
//!   vertex normals. Triangle areas then vary by a factor of about 100 across the
//!   surface, from coarse on the -x side to fine on the +x side, with a gradual
//!   transition; a bisected triangle is never bisected again, so the smallest angle stays
//!   above about half the base mesh's smallest angle.

mod parametric;
mod pretzel;
mod refine;
mod spec;

pub use spec::{
    ExpectedTopology, MAX_ASPECT, PARAM_RANGE, ParamInfo, ShapeError, ShapeKind, ShapeSpec,
    parse_shape,
};

use crate::mesh::Mesh;
use refine::{Refiner, Surface};

/// The default shape (the paper's): the smooth genus-3 surface.
pub const DEFAULT_SHAPE: &str = "3torus";

/// Fractions of the bounding box along x beyond which the irregular variants refine,
/// one entry per nested refinement level.
pub const IRREGULAR_THRESHOLDS: [f64; 3] = [0.45, 0.6, 0.75];

/// How many levels below `res` the irregular variants start from.
pub const IRREGULAR_COARSENING: u32 = 2;

/// Description of one built-in shape name, for `spectral-mesh shapes`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ShapeInfo {
    /// The stable name, e.g. `torus` or `irregular-torus`.
    pub name: String,
    /// One-line description.
    pub description: String,
    /// Topology (the same for the irregular variant).
    pub topology: ExpectedTopology,
    /// Parameters: `res`, then the shape's own, then `irregular`.
    pub params: Vec<ParamInfo>,
    /// Vertex count at the default resolution (`None` for irregular variants: it is only
    /// known after building).
    pub default_vertices: Option<usize>,
    /// Vertex-count formula in terms of `res`.
    pub vertex_formula: &'static str,
}

fn formula(kind: ShapeKind) -> &'static str {
    match kind {
        ShapeKind::ThreeTorus => "100 * 4^res - 4",
        ShapeKind::DoubleTorus => "74 * 4^res - 2",
        ShapeKind::Torus => "2 k^2, k = 7 * 2^res",
        ShapeKind::Sphere => "10 * 4^res + 2",
        ShapeKind::UvSphere => "2 k (k - 1) + 2, k = 7 * 2^res",
        ShapeKind::Disk => "3 k (k + 1) + 1, k = 6 * 2^res",
        ShapeKind::Cylinder => "2 k (k + 1), k = 7 * 2^res",
    }
}

/// Every built-in name: the seven families, then their `irregular-` variants.
pub fn shape_names() -> Vec<ShapeInfo> {
    let mut out = Vec::new();
    for irregular in [false, true] {
        for kind in ShapeKind::ALL {
            let mut params = vec![ParamInfo {
                name: "res",
                default: f64::from(kind.default_res()),
                meaning: "resolution level (see the vertex-count formula)",
            }];
            params.extend_from_slice(kind.params());
            params.push(ParamInfo {
                name: "irregular",
                default: if irregular { 1.0 } else { 0.0 },
                meaning: "1: strongly irregular sampling of the same surface",
            });
            let spec = ShapeSpec::new(kind).with_irregular(irregular);
            let (description, vertex_formula) = if irregular {
                (
                    format!(
                        "irregularly sampled {}: coarse (res - 2) on -x, 3 levels finer on +x",
                        kind.name()
                    ),
                    "data-dependent (adaptive refinement)",
                )
            } else {
                (kind.description().to_string(), formula(kind))
            };
            out.push(ShapeInfo {
                name: spec.name(),
                description,
                topology: kind.expected_topology(),
                params,
                default_vertices: spec.vertex_count(),
                vertex_formula,
            });
        }
    }
    out
}

/// True when `s` names a built-in shape rather than a file: no path separator, no mesh
/// file extension (`.off`, `.obj`, `.ply`, `.stl`), and the part before `:` is a known
/// name. The parameters are not checked here: [`parse_shape`] reports their errors.
pub fn is_shape_spec(s: &str) -> bool {
    let s = s.trim();
    if s.is_empty() || s.contains('/') || s.contains('\\') {
        return false;
    }
    let lower = s.to_ascii_lowercase();
    if [".off", ".obj", ".ply", ".stl"]
        .iter()
        .any(|e| lower.ends_with(e))
    {
        return false;
    }
    let name = s.split(':').next().unwrap_or(s);
    spec::lookup_name(name).is_some()
}

/// Raw arrays of the regular shape.
fn regular(kind: ShapeKind, res: u32, values: &[f64]) -> parametric::Arrays {
    let v = |i: usize| values.get(i).copied().unwrap_or(kind.params()[i].default);
    match kind {
        ShapeKind::ThreeTorus => pretzel::pretzel(3, res),
        ShapeKind::DoubleTorus => pretzel::pretzel(2, res),
        ShapeKind::Torus => parametric::torus(res, v(0), v(1)),
        ShapeKind::Sphere => parametric::icosphere(res),
        ShapeKind::UvSphere => parametric::uv_sphere(res),
        ShapeKind::Disk => parametric::disk(res),
        ShapeKind::Cylinder => parametric::cylinder(res, v(0), v(1)),
    }
}

/// Builds the mesh of a spec (validated first). Deterministic: the same spec gives a
/// bit-identical mesh. The size is bounded only by [`ShapeKind::max_res`] (up to about
/// 7 million vertices and 4 GB); a server or anything else that builds specs typed by
/// others should call [`build_limited`] instead.
pub fn build(spec: &ShapeSpec) -> Result<Mesh, ShapeError> {
    build_limited(spec, usize::MAX)
}

/// [`build`] with a vertex budget: a spec whose mesh would have more than `max_vertices`
/// vertices is refused with [`ShapeError::TooLarge`] before the large arrays are
/// allocated. A regular shape is checked against its vertex-count formula; an irregular
/// one builds its coarse base (`res - 2`, a sixteenth of the size) and, before every
/// refinement level, checks the bound "current vertices + current edges" (a refinement
/// adds at most one vertex per edge).
pub fn build_limited(spec: &ShapeSpec, max_vertices: usize) -> Result<Mesh, ShapeError> {
    spec.validate()?;
    let kind = spec.kind;
    let too_large = |vertices: usize| ShapeError::TooLarge {
        spec: spec.to_string(),
        vertices,
        limit: max_vertices,
    };
    if !spec.irregular {
        let count = kind.vertex_count(spec.res).unwrap_or(usize::MAX);
        if count > max_vertices {
            return Err(too_large(count));
        }
        let (p, t) = regular(kind, spec.res, &spec.values);
        return Ok(Mesh::new(p, t)?);
    }
    let base = spec.res.saturating_sub(IRREGULAR_COARSENING);
    let base_count = kind.vertex_count(base).unwrap_or(usize::MAX);
    if base_count > max_vertices {
        return Err(too_large(base_count));
    }
    // The finest triangles are always about level res + 1: fewer levels at res < 2.
    let levels = (spec.res + 1).min(IRREGULAR_THRESHOLDS.len() as u32) as usize;
    let (p, t) = regular(kind, base, &spec.values);
    let surface = match kind {
        ShapeKind::Sphere | ShapeKind::UvSphere => Surface::UnitSphere,
        ShapeKind::Torus => Surface::Torus {
            big_r: spec.values[0],
            small_r: spec.values[1],
        },
        ShapeKind::Cylinder => Surface::Cylinder {
            radius: spec.values[0],
        },
        ShapeKind::Disk => Surface::UnitDisk,
        ShapeKind::ThreeTorus | ShapeKind::DoubleTorus => Surface::Smooth,
    };
    let base_mesh = Mesh::new(p, t)?;
    let normals = (surface == Surface::Smooth).then(|| base_mesh.vertex_normals());
    let (lo, hi) = base_mesh.bounding_box();
    let (p, t) = base_mesh.into_parts();
    let mut r = Refiner::new(p, t, surface, normals);
    let extent = (hi[0] - lo[0]).max(f64::MIN_POSITIVE);
    for &thr in &IRREGULAR_THRESHOLDS[..levels] {
        if max_vertices != usize::MAX {
            let bound = r.positions.len().saturating_add(edge_count(&r.triangles));
            if bound > max_vertices {
                return Err(too_large(bound));
            }
        }
        let marked: Vec<bool> = r
            .triangles
            .iter()
            .map(|t| {
                let cx = (r.positions[t[0]][0] + r.positions[t[1]][0] + r.positions[t[2]][0]) / 3.0;
                (cx - lo[0]) / extent > thr
            })
            .collect();
        r.refine(marked);
    }
    Ok(Mesh::new(r.positions, r.triangles)?)
}

/// Number of distinct edges of a triangle list.
fn edge_count(triangles: &[[usize; 3]]) -> usize {
    let mut e: Vec<(usize, usize)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    e.sort_unstable();
    e.dedup();
    e.len()
}

/// Parses and builds in one step.
pub fn build_str(spec: &str) -> Result<Mesh, ShapeError> {
    build(&parse_shape(spec)?)
}

/// The default shape ([`DEFAULT_SHAPE`] at its default resolution).
pub fn default_shape() -> Result<Mesh, ShapeError> {
    build(&ShapeSpec::default())
}
