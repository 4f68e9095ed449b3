//! Shape specs: names, parameters, parsing and printing.

use std::fmt;
use std::str::FromStr;

use thiserror::Error;

use crate::mesh::MeshError;

/// Range of every shape parameter (`R`, `r`, `h`): beyond it, squared lengths and areas
/// overflow or underflow `f64`.
pub const PARAM_RANGE: (f64, f64) = (1e-100, 1e100);

/// Largest ratio `R / r` of the torus and `h / r`, `r / h` of the cylinder: beyond it the
/// finest resolutions have triangles at the rounding level of the mesh size (zero-area).
pub const MAX_ASPECT: f64 = 1e6;

/// Errors raised when a shape spec is parsed, validated or built.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ShapeError {
    /// The spec string is empty.
    #[error("empty shape spec; valid shapes: {valid}")]
    Empty {
        /// Comma-separated list of valid shape names.
        valid: String,
    },
    /// The name before `:` is not a built-in shape.
    #[error("unknown shape `{name}`; valid shapes: {valid}")]
    UnknownShape {
        /// The offending name.
        name: String,
        /// Comma-separated list of valid shape names.
        valid: String,
    },
    /// A parameter name that the shape does not have.
    #[error("shape `{shape}` has no parameter `{param}`; valid parameters: {valid}")]
    UnknownParam {
        /// Shape name.
        shape: String,
        /// The offending parameter name.
        param: String,
        /// Comma-separated list of the shape's parameters.
        valid: String,
    },
    /// A parameter token that is not of the form `NAME=VALUE`.
    #[error("malformed parameter `{token}` in shape spec (expected NAME=VALUE)")]
    Malformed {
        /// The offending token.
        token: String,
    },
    /// The same parameter given twice.
    #[error("parameter `{param}` given twice in shape spec")]
    Duplicate {
        /// The repeated parameter name.
        param: String,
    },
    /// A parameter value that cannot be parsed or is out of range.
    #[error("bad value `{value}` for parameter `{param}`: {reason}")]
    BadValue {
        /// Parameter name.
        param: String,
        /// The offending value as written.
        value: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The mesh would have more vertices than the caller's budget
    /// ([`super::build_limited`]).
    #[error(
        "shape `{spec}` would have {vertices} vertices, more than the limit of {limit}; lower res"
    )]
    TooLarge {
        /// The spec, in canonical form.
        spec: String,
        /// Its vertex count (an upper bound for the irregular variants).
        vertices: usize,
        /// The budget it exceeds.
        limit: usize,
    },
    /// The generated arrays were rejected by [`crate::Mesh::new`] (a bug: please report).
    #[error("internal error while building a shape: {0}")]
    Mesh(#[from] MeshError),
}

/// The families of built-in shapes. Each can be built regular or irregularly sampled
/// (see [`ShapeSpec::irregular`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ShapeKind {
    /// Smooth closed genus-3 surface (the paper's default shape).
    ThreeTorus,
    /// Smooth closed genus-2 surface.
    DoubleTorus,
    /// Parametric ring torus, genus 1.
    Torus,
    /// Icosphere of radius 1.
    Sphere,
    /// Latitude/longitude sphere with two poles.
    UvSphere,
    /// Unit disk in the plane z = 0.
    Disk,
    /// Open tube without caps.
    Cylinder,
}

/// One numeric parameter of a shape: name, default and meaning.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ParamInfo {
    /// Name as typed in a spec (`res`, `R`, ...). Case-sensitive.
    pub name: &'static str,
    /// Default value.
    pub default: f64,
    /// One-line meaning.
    pub meaning: &'static str,
}

/// Expected topology of a shape (the same for its irregular variant).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ExpectedTopology {
    /// Euler characteristic V - E + F.
    pub euler_characteristic: i64,
    /// Genus.
    pub genus: i64,
    /// Number of boundary loops (0 for a closed surface).
    pub boundary_loops: usize,
}

const TORUS_PARAMS: &[ParamInfo] = &[
    ParamInfo {
        name: "R",
        default: 1.0,
        meaning: "major radius (centre of the tube to the axis)",
    },
    ParamInfo {
        name: "r",
        default: 0.4,
        meaning: "minor radius (of the tube), R / 1e6 <= r < R",
    },
];

const CYLINDER_PARAMS: &[ParamInfo] = &[
    ParamInfo {
        name: "r",
        default: 1.0,
        meaning: "radius",
    },
    ParamInfo {
        name: "h",
        default: 2.0,
        meaning: "height (the tube spans z in [-h/2, h/2]), r / 1e6 <= h <= r * 1e6",
    },
];

impl ShapeKind {
    /// Every kind, in the order of the documentation table.
    pub const ALL: [ShapeKind; 7] = [
        ShapeKind::ThreeTorus,
        ShapeKind::Torus,
        ShapeKind::Sphere,
        ShapeKind::UvSphere,
        ShapeKind::DoubleTorus,
        ShapeKind::Disk,
        ShapeKind::Cylinder,
    ];

    /// The canonical (stable) name.
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::ThreeTorus => "3torus",
            ShapeKind::DoubleTorus => "double-torus",
            ShapeKind::Torus => "torus",
            ShapeKind::Sphere => "sphere",
            ShapeKind::UvSphere => "uv-sphere",
            ShapeKind::Disk => "disk",
            ShapeKind::Cylinder => "cylinder",
        }
    }

    /// Accepted alternative spellings (lower case).
    pub fn aliases(self) -> &'static [&'static str] {
        match self {
            ShapeKind::ThreeTorus => &["3-torus", "triple-torus"],
            ShapeKind::DoubleTorus => &["2torus", "2-torus"],
            ShapeKind::Torus => &[],
            ShapeKind::Sphere => &["icosphere"],
            ShapeKind::UvSphere => &["uvsphere"],
            ShapeKind::Disk => &["disc"],
            ShapeKind::Cylinder => &["tube"],
        }
    }

    /// Looks a kind up by canonical name or alias (case-insensitive).
    pub fn from_name(name: &str) -> Option<ShapeKind> {
        let n = name.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|k| k.name() == n || k.aliases().contains(&n.as_str()))
    }

    /// One-line description.
    pub fn description(self) -> &'static str {
        match self {
            ShapeKind::ThreeTorus => {
                "smooth genus-3 surface: a plate with three holes in a row, Catmull-Clark subdivided"
            }
            ShapeKind::DoubleTorus => {
                "smooth genus-2 surface: a plate with two holes in a row, Catmull-Clark subdivided"
            }
            ShapeKind::Torus => "parametric ring torus around the z axis",
            ShapeKind::Sphere => "icosphere of radius 1 (every vertex at distance 1 from 0)",
            ShapeKind::UvSphere => "latitude/longitude sphere of radius 1 with two poles",
            ShapeKind::Disk => "unit disk in the plane z = 0, hexagonal rings",
            ShapeKind::Cylinder => "open tube around the z axis, no caps",
        }
    }

    /// Topology of the shape (and of its irregular variant).
    pub fn expected_topology(self) -> ExpectedTopology {
        let (chi, genus, b) = match self {
            ShapeKind::ThreeTorus => (-4, 3, 0),
            ShapeKind::DoubleTorus => (-2, 2, 0),
            ShapeKind::Torus => (0, 1, 0),
            ShapeKind::Sphere | ShapeKind::UvSphere => (2, 0, 0),
            ShapeKind::Disk => (1, 0, 1),
            ShapeKind::Cylinder => (0, 0, 2),
        };
        ExpectedTopology {
            euler_characteristic: chi,
            genus,
            boundary_loops: b,
        }
    }

    /// Default resolution.
    pub fn default_res(self) -> u32 {
        match self {
            ShapeKind::Sphere => 4,
            _ => 3,
        }
    }

    /// Largest accepted resolution (a few million vertices).
    pub fn max_res(self) -> u32 {
        match self {
            ShapeKind::ThreeTorus | ShapeKind::DoubleTorus => 7,
            ShapeKind::Sphere => 9,
            _ => 8,
        }
    }

    /// The shape's numeric parameters other than `res` and `irregular`.
    pub fn params(self) -> &'static [ParamInfo] {
        match self {
            ShapeKind::Torus => TORUS_PARAMS,
            ShapeKind::Cylinder => CYLINDER_PARAMS,
            _ => &[],
        }
    }

    /// Vertex count of the regular shape at resolution `res` (`None` when `res > max_res`).
    ///
    /// | kind | formula |
    /// | --- | --- |
    /// | 3torus | 100 * 4^res - 4 |
    /// | double-torus | 74 * 4^res - 2 |
    /// | torus | 2 k^2, k = 7 * 2^res |
    /// | sphere | 10 * 4^res + 2 |
    /// | uv-sphere | 2 k (k - 1) + 2, k = 7 * 2^res |
    /// | disk | 3 k (k + 1) + 1, k = 6 * 2^res |
    /// | cylinder | 2 k (k + 1), k = 7 * 2^res |
    pub fn vertex_count(self, res: u32) -> Option<usize> {
        if res > self.max_res() {
            return None;
        }
        let p4 = 1usize << (2 * res);
        let p2 = 1usize << res;
        Some(match self {
            ShapeKind::ThreeTorus => 100 * p4 - 4,
            ShapeKind::DoubleTorus => 74 * p4 - 2,
            ShapeKind::Torus => {
                let k = 7 * p2;
                2 * k * k
            }
            ShapeKind::Sphere => 10 * p4 + 2,
            ShapeKind::UvSphere => {
                let k = 7 * p2;
                2 * k * (k - 1) + 2
            }
            ShapeKind::Disk => {
                let k = 6 * p2;
                3 * k * (k + 1) + 1
            }
            ShapeKind::Cylinder => {
                let k = 7 * p2;
                2 * k * (k + 1)
            }
        })
    }
}

/// A parsed, validated description of a built-in shape, e.g. `torus:res=3,R=1,r=0.4`.
///
/// [`fmt::Display`] prints the canonical spec with every parameter, and parsing that string
/// gives back an equal spec (floats print in shortest round-trip form).
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeSpec {
    /// Which family.
    pub kind: ShapeKind,
    /// Resolution level; see [`ShapeKind::vertex_count`].
    pub res: u32,
    /// Build the strongly irregularly sampled variant (name prefix `irregular-`).
    pub irregular: bool,
    /// Values of [`ShapeKind::params`], in that order.
    pub values: Vec<f64>,
}

impl ShapeSpec {
    /// The regular shape of this kind with default resolution and parameters.
    pub fn new(kind: ShapeKind) -> Self {
        Self {
            kind,
            res: kind.default_res(),
            irregular: false,
            values: kind.params().iter().map(|p| p.default).collect(),
        }
    }

    /// Same spec with another resolution.
    pub fn with_res(mut self, res: u32) -> Self {
        self.res = res;
        self
    }

    /// Same spec, irregular or not.
    pub fn with_irregular(mut self, irregular: bool) -> Self {
        self.irregular = irregular;
        self
    }

    /// The name as typed: `sphere` or `irregular-sphere`.
    pub fn name(&self) -> String {
        if self.irregular {
            format!("irregular-{}", self.kind.name())
        } else {
            self.kind.name().to_string()
        }
    }

    /// Value of the numeric parameter `name` (`res` included), if the shape has it.
    pub fn param(&self, name: &str) -> Option<f64> {
        if name == "res" {
            return Some(f64::from(self.res));
        }
        self.kind
            .params()
            .iter()
            .position(|p| p.name == name)
            .and_then(|i| self.values.get(i).copied())
    }

    /// Sets a parameter from its text value (`res`, `irregular` or one of [`ShapeKind::params`]).
    pub fn set_param(&mut self, name: &str, value: &str) -> Result<(), ShapeError> {
        let bad = |reason: &str| ShapeError::BadValue {
            param: name.to_string(),
            value: value.to_string(),
            reason: reason.to_string(),
        };
        match name {
            "res" => {
                let r: u32 = value
                    .trim()
                    .parse()
                    .map_err(|_| bad("expected a non-negative integer"))?;
                self.res = r;
            }
            "irregular" => {
                self.irregular = match value.trim() {
                    "1" | "true" | "yes" => true,
                    "0" | "false" | "no" => false,
                    _ => return Err(bad("expected 0 or 1")),
                };
            }
            _ => {
                let Some(i) = self.kind.params().iter().position(|p| p.name == name) else {
                    let mut valid = vec!["res", "irregular"];
                    valid.extend(self.kind.params().iter().map(|p| p.name));
                    return Err(ShapeError::UnknownParam {
                        shape: self.kind.name().to_string(),
                        param: name.to_string(),
                        valid: valid.join(", "),
                    });
                };
                let v: f64 = value.trim().parse().map_err(|_| bad("expected a number"))?;
                if !v.is_finite() {
                    return Err(bad("must be finite"));
                }
                self.values.resize(self.kind.params().len(), 0.0);
                self.values[i] = v;
            }
        }
        Ok(())
    }

    /// Checks the resolution range and the parameter constraints.
    pub fn validate(&self) -> Result<(), ShapeError> {
        let bad = |param: &str, value: String, reason: String| ShapeError::BadValue {
            param: param.to_string(),
            value,
            reason,
        };
        if self.res > self.kind.max_res() {
            return Err(bad(
                "res",
                self.res.to_string(),
                format!(
                    "must be at most {} for {}",
                    self.kind.max_res(),
                    self.kind.name()
                ),
            ));
        }
        if self.values.len() != self.kind.params().len() {
            return Err(bad(
                "values",
                format!("{:?}", self.values),
                format!(
                    "{} expects {} parameter values",
                    self.kind.name(),
                    self.kind.params().len()
                ),
            ));
        }
        for (p, &v) in self.kind.params().iter().zip(&self.values) {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(p.name, v.to_string(), "must be positive".into()));
            }
            if !(PARAM_RANGE.0..=PARAM_RANGE.1).contains(&v) {
                return Err(bad(
                    p.name,
                    v.to_string(),
                    format!(
                        "must be between {:e} and {:e}",
                        PARAM_RANGE.0, PARAM_RANGE.1
                    ),
                ));
            }
        }
        if self.kind == ShapeKind::Torus {
            let (big, small) = (self.values[0], self.values[1]);
            if small >= big {
                return Err(bad(
                    "r",
                    small.to_string(),
                    format!("must be smaller than R = {big}"),
                ));
            }
            if small < big / MAX_ASPECT {
                return Err(bad(
                    "r",
                    small.to_string(),
                    format!(
                        "must be at least R / {MAX_ASPECT:e} = {} (a thinner tube has zero-area triangles)",
                        big / MAX_ASPECT
                    ),
                ));
            }
        }
        if self.kind == ShapeKind::Cylinder {
            let (r, h) = (self.values[0], self.values[1]);
            if !(r / MAX_ASPECT..=r * MAX_ASPECT).contains(&h) {
                return Err(bad(
                    "h",
                    h.to_string(),
                    format!(
                        "must be between r / {MAX_ASPECT:e} and r * {MAX_ASPECT:e} (r = {r}; a flatter or longer tube has zero-area triangles)"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Vertex count from the documented formula (`None` for irregular variants, whose
    /// count depends on the adaptive refinement, or when `res` is out of range).
    pub fn vertex_count(&self) -> Option<usize> {
        if self.irregular {
            None
        } else {
            self.kind.vertex_count(self.res)
        }
    }
}

impl Default for ShapeSpec {
    /// The paper's default shape, `3torus` at its default resolution.
    fn default() -> Self {
        Self::new(ShapeKind::ThreeTorus)
    }
}

impl fmt::Display for ShapeSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:res={}", self.name(), self.res)?;
        for (p, v) in self.kind.params().iter().zip(&self.values) {
            write!(f, ",{}={}", p.name, v)?;
        }
        Ok(())
    }
}

impl FromStr for ShapeSpec {
    type Err = ShapeError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        parse_shape(s)
    }
}

/// All valid names (regular and irregular), comma-separated, for error messages.
pub(crate) fn valid_names() -> String {
    let mut v: Vec<String> = ShapeKind::ALL
        .iter()
        .map(|k| k.name().to_string())
        .collect();
    v.extend(
        ShapeKind::ALL
            .iter()
            .map(|k| format!("irregular-{}", k.name())),
    );
    v.join(", ")
}

/// Splits a name into `(kind, irregular)`; accepts `irregular-NAME` and aliases.
pub(crate) fn lookup_name(name: &str) -> Option<(ShapeKind, bool)> {
    let n = name.trim().to_ascii_lowercase();
    if let Some(k) = ShapeKind::from_name(&n) {
        return Some((k, false));
    }
    n.strip_prefix("irregular-")
        .and_then(ShapeKind::from_name)
        .map(|k| (k, true))
}

/// Parses a shape spec: `NAME` or `NAME:KEY=VALUE,KEY=VALUE,...`.
///
/// `NAME` is a canonical name or alias (case-insensitive), optionally prefixed with
/// `irregular-`; keys are `res`, `irregular` (0/1) and the shape's own parameters
/// (case-sensitive: the torus has both `R` and `r`). Missing parameters take their
/// defaults. Unknown names or keys give an error naming the token and listing the valid
/// choices; the result is validated ([`ShapeSpec::validate`]).
pub fn parse_shape(spec: &str) -> Result<ShapeSpec, ShapeError> {
    let spec = spec.trim();
    if spec.is_empty() {
        return Err(ShapeError::Empty {
            valid: valid_names(),
        });
    }
    let (name, rest) = match spec.split_once(':') {
        Some((n, r)) => (n.trim(), Some(r)),
        None => (spec, None),
    };
    let Some((kind, irregular)) = lookup_name(name) else {
        return Err(ShapeError::UnknownShape {
            name: name.to_string(),
            valid: valid_names(),
        });
    };
    let mut out = ShapeSpec::new(kind).with_irregular(irregular);
    let mut seen: Vec<String> = Vec::new();
    for token in rest.unwrap_or("").split(',') {
        let token = token.trim();
        if token.is_empty() {
            continue;
        }
        let Some((key, value)) = token.split_once('=') else {
            return Err(ShapeError::Malformed {
                token: token.to_string(),
            });
        };
        let key = key.trim();
        if key.is_empty() {
            return Err(ShapeError::Malformed {
                token: token.to_string(),
            });
        }
        if seen.iter().any(|s| s == key) {
            return Err(ShapeError::Duplicate {
                param: key.to_string(),
            });
        }
        seen.push(key.to_string());
        out.set_param(key, value)?;
    }
    out.validate()?;
    Ok(out)
}
