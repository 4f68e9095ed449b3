//! One request type for every field a face can ask for, with the one set of defaults.
//!
//! A [`FieldRequest`] names the field and its parameters; [`super::Analysis::field`]
//! evaluates it. The CLI builds requests from its arguments, the web app from its JSON
//! bodies, the Python package from keyword arguments and experiment files from their
//! `[field]` table: all four read the same serde form (a table tagged by `kind`, unknown
//! keys refused), so a request saved by one face replays in another.
//!
//! Defaults are the executable paper's: `k = 100` pairs, heat time `t = 0.5` (for the shape
//! scaled to unit area, see [`super::AnalysisOptions::normalize`]), the bi-harmonic filter,
//! the source or anchor at the vertex of largest x (lowest index on ties), 2 harmonic
//! constraints (vertex of min x -> 0, of max x -> 1).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::fields::harmonic::{Constraint, ConstraintSpec};
use crate::spectral::filters::{Filter, FilterError};
use crate::spectral::heat::KernelKind;

/// Default number of eigenpairs (the paper's).
pub const DEFAULT_K: usize = 100;
/// Default heat time of the heat basis function and of diffusions (the paper's `t = 0.5`;
/// for the unit-area shape when the analysis normalizes).
pub const DEFAULT_HEAT_T: f64 = 0.5;
/// Default time of the heat kernel signature and the auto-diffusion function.
pub const DEFAULT_SIGNATURE_T: f64 = 0.1;
/// Default bandwidth of a wave kernel signature at one energy.
pub const DEFAULT_WKS_SIGMA: f64 = 0.5;
/// Default persistence threshold of segmentations (relative to the field's range).
pub const DEFAULT_PERSISTENCE: f64 = 0.05;
/// Default index of single eigenfunctions and embedding coordinates: the first pair after
/// the constant one.
pub const DEFAULT_COMPONENT: usize = 1;
/// Longest filter or signature text accepted (a bound on what a client can make us parse).
pub const MAX_SPEC_LEN: usize = 1000;

fn default_k() -> usize {
    DEFAULT_K
}
fn default_heat_t() -> f64 {
    DEFAULT_HEAT_T
}
fn default_signature_t() -> f64 {
    DEFAULT_SIGNATURE_T
}
fn default_wks_sigma() -> f64 {
    DEFAULT_WKS_SIGMA
}
fn default_persistence() -> f64 {
    DEFAULT_PERSISTENCE
}
fn default_component() -> usize {
    DEFAULT_COMPONENT
}
fn default_order() -> u32 {
    1
}

/// A field any face can ask for. Serialized as a table with a `kind` tag
/// (`kind = "distance"`, `source = 5`, ...); every other key is optional and takes the
/// default named in its documentation. `k` is the number of eigenpairs used (the analysis
/// may hold more: the first `k` are used).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum FieldRequest {
    /// Harmonic (`order = 1`, `S f = 0`) or bi-harmonic (`order = 2`, `S B^-1 S f = 0`,
    /// lumped B) map with Dirichlet constraints. No eigenbasis.
    Harmonic {
        /// The constraints (default: the paper's 2, min x -> 0 and max x -> 1).
        #[serde(default)]
        constraints: Constraints,
        /// 1 (default) or 2.
        #[serde(default = "default_order")]
        order: u32,
    },
    /// The heat kernel basis function `K_t e_anchor` (the paper's diffusion basis).
    Heat {
        /// Anchor vertex (default: the vertex of largest x).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        anchor: Option<usize>,
        /// Time `t >= 0` (default 0.5).
        #[serde(default = "default_heat_t")]
        t: f64,
        /// The kernel (default wfem: `X D_t X^T B`).
        #[serde(default)]
        kernel: Kernel,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// The diffusion `K_t f` of a signal `f`.
    Diffusion {
        /// The signal.
        signal: Signal,
        /// Time `t >= 0` (default 0.5).
        #[serde(default = "default_heat_t")]
        t: f64,
        /// The kernel (default wfem).
        #[serde(default)]
        kernel: Kernel,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// A filtered spectral distance from a source, or the wFEM diffusion distance of
    /// eq. 15 (`distance = "wfem-diffusion:t=0.5"`).
    Distance {
        /// Source vertex (default: the vertex of largest x).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        source: Option<usize>,
        /// The distance (default bi-harmonic).
        #[serde(default)]
        distance: DistanceSpec,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// The generalized spectral function `G(p,p) = sum w(lambda) x(p)^2` of a filter.
    SpectralFunction {
        /// The filter (default bi-harmonic).
        #[serde(default, with = "filter_text")]
        filter: Filter,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// The heat kernel signature at one time (pyFM's convention: all pairs).
    Hks {
        /// Time (default 0.1).
        #[serde(default = "default_signature_t")]
        t: f64,
        /// Divide by the heat trace.
        #[serde(default)]
        scaled: bool,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// The wave kernel signature at one energy (log-eigenvalue).
    Wks {
        /// Energy `e` (a log-eigenvalue).
        energy: f64,
        /// Bandwidth (default 0.5).
        #[serde(default = "default_wks_sigma")]
        sigma: f64,
        /// Divide by the normalization sum.
        #[serde(default)]
        scaled: bool,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// The auto-diffusion function (zero eigenvalues skipped).
    Adf {
        /// Time (default 0.1).
        #[serde(default = "default_signature_t")]
        t: f64,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// Segmentation into the watershed basins of the maxima of a signature, merged by
    /// persistence; the field holds the patch labels.
    Segmentation {
        /// The segmented field (default `hks:t=0.1`).
        #[serde(default)]
        signature: SignatureSpec,
        /// Merge threshold relative to the field's range (default 0.05).
        #[serde(default = "default_persistence")]
        persistence: f64,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// One coordinate `sqrt(w(lambda_j)) x_j` of the filtered spectral embedding.
    Embedding {
        /// The filter (default bi-harmonic).
        #[serde(default, with = "filter_text")]
        filter: Filter,
        /// The pair `j`, 0-based (default 1).
        #[serde(default = "default_component")]
        component: usize,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// One eigenfunction `x_j`.
    Eigenfunction {
        /// The pair `j`, 0-based (default 1, the first after the constant).
        #[serde(default = "default_component")]
        index: usize,
        /// Eigenpairs computed (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
    /// A row `G(source, .)` of the generalized Green kernel `X diag(w) X^T`.
    Green {
        /// Source vertex (default: the vertex of largest x).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        source: Option<usize>,
        /// The filter (default bi-harmonic).
        #[serde(default, with = "filter_text")]
        filter: Filter,
        /// Eigenpairs used (default 100).
        #[serde(default = "default_k")]
        k: usize,
    },
}

impl Default for FieldRequest {
    /// The paper's spectral-distance experiment: the bi-harmonic distance, k = 100, from
    /// the vertex of largest x.
    fn default() -> Self {
        FieldRequest::Distance {
            source: None,
            distance: DistanceSpec::default(),
            k: DEFAULT_K,
        }
    }
}

impl FieldRequest {
    /// The default distance request with `k` pairs.
    pub fn default_with_k(k: usize) -> Self {
        FieldRequest::Distance {
            source: None,
            distance: DistanceSpec::default(),
            k,
        }
    }
}

/// The names of the request kinds, as typed (`kind = "..."`).
pub const KINDS: [&str; 12] = [
    "harmonic",
    "heat",
    "diffusion",
    "distance",
    "spectral-function",
    "hks",
    "wks",
    "adf",
    "segmentation",
    "embedding",
    "eigenfunction",
    "green",
];

impl FieldRequest {
    /// The `kind` tag.
    pub fn kind(&self) -> &'static str {
        match self {
            FieldRequest::Harmonic { .. } => "harmonic",
            FieldRequest::Heat { .. } => "heat",
            FieldRequest::Diffusion { .. } => "diffusion",
            FieldRequest::Distance { .. } => "distance",
            FieldRequest::SpectralFunction { .. } => "spectral-function",
            FieldRequest::Hks { .. } => "hks",
            FieldRequest::Wks { .. } => "wks",
            FieldRequest::Adf { .. } => "adf",
            FieldRequest::Segmentation { .. } => "segmentation",
            FieldRequest::Embedding { .. } => "embedding",
            FieldRequest::Eigenfunction { .. } => "eigenfunction",
            FieldRequest::Green { .. } => "green",
        }
    }

    /// The number of eigenpairs the request uses, `None` when it needs no eigenbasis (a
    /// harmonic map, or a segmentation of a given field).
    pub fn eigenpairs(&self) -> Option<usize> {
        match self {
            FieldRequest::Harmonic { .. } => None,
            FieldRequest::Segmentation {
                signature: SignatureSpec::Values(_),
                ..
            } => None,
            FieldRequest::Heat { k, .. }
            | FieldRequest::Diffusion { k, .. }
            | FieldRequest::Distance { k, .. }
            | FieldRequest::SpectralFunction { k, .. }
            | FieldRequest::Hks { k, .. }
            | FieldRequest::Wks { k, .. }
            | FieldRequest::Adf { k, .. }
            | FieldRequest::Segmentation { k, .. }
            | FieldRequest::Embedding { k, .. }
            | FieldRequest::Eigenfunction { k, .. }
            | FieldRequest::Green { k, .. } => Some(*k),
        }
    }

    /// Sets the number of eigenpairs (no effect on requests that need no basis).
    pub fn set_eigenpairs(&mut self, new_k: usize) {
        match self {
            FieldRequest::Harmonic { .. } => {}
            FieldRequest::Heat { k, .. }
            | FieldRequest::Diffusion { k, .. }
            | FieldRequest::Distance { k, .. }
            | FieldRequest::SpectralFunction { k, .. }
            | FieldRequest::Hks { k, .. }
            | FieldRequest::Wks { k, .. }
            | FieldRequest::Adf { k, .. }
            | FieldRequest::Segmentation { k, .. }
            | FieldRequest::Embedding { k, .. }
            | FieldRequest::Eigenfunction { k, .. }
            | FieldRequest::Green { k, .. } => *k = new_k,
        }
    }

    /// The source or anchor vertex the request names, if it names one.
    pub fn source(&self) -> Option<usize> {
        match self {
            FieldRequest::Heat { anchor, .. } => *anchor,
            FieldRequest::Distance { source, .. } | FieldRequest::Green { source, .. } => *source,
            _ => None,
        }
    }

    /// True when the request is about a source or anchor vertex (which defaults to the
    /// vertex of largest x).
    pub fn uses_source(&self) -> bool {
        matches!(
            self,
            FieldRequest::Heat { .. } | FieldRequest::Distance { .. } | FieldRequest::Green { .. }
        )
    }

    /// Sets the source or anchor (no effect on requests without one).
    pub fn set_source(&mut self, v: Option<usize>) {
        match self {
            FieldRequest::Heat { anchor, .. } => *anchor = v,
            FieldRequest::Distance { source, .. } | FieldRequest::Green { source, .. } => {
                *source = v
            }
            _ => {}
        }
    }

    /// The heat or diffusion time the request uses, if any (for truncation guidance).
    pub fn time(&self) -> Option<f64> {
        match self {
            FieldRequest::Heat { t, .. }
            | FieldRequest::Diffusion { t, .. }
            | FieldRequest::Hks { t, .. }
            | FieldRequest::Adf { t, .. } => Some(*t),
            FieldRequest::Distance {
                distance: DistanceSpec::WfemDiffusion { t },
                ..
            } => Some(*t),
            FieldRequest::Distance {
                distance: DistanceSpec::Filter(Filter::Diffusion { t }),
                ..
            } => Some(*t),
            _ => None,
        }
    }

    /// Checks every parameter that does not depend on the mesh (times finite and
    /// non-negative, orders, filters' own parameters, lengths of texts); the analysis then
    /// checks vertices and `k` against the mesh.
    pub fn validate(&self) -> Result<(), RequestError> {
        let time = |name: &'static str, t: f64| {
            if t.is_finite() && t >= 0.0 {
                Ok(())
            } else {
                Err(RequestError::Invalid {
                    key: name,
                    message: format!("{t}: the time must be a finite number >= 0"),
                })
            }
        };
        let k_ok = |k: usize| {
            if k == 0 {
                Err(RequestError::Invalid {
                    key: "k",
                    message: "at least one eigenpair is needed".into(),
                })
            } else {
                Ok(())
            }
        };
        if let Some(k) = self.eigenpairs() {
            k_ok(k)?;
        }
        match self {
            FieldRequest::Harmonic { constraints, order } => {
                if !matches!(order, 1 | 2) {
                    return Err(RequestError::Invalid {
                        key: "order",
                        message: format!("{order}: must be 1 (harmonic) or 2 (bi-harmonic)"),
                    });
                }
                constraints.validate()?;
            }
            FieldRequest::Heat { t, .. } => time("t", *t)?,
            FieldRequest::Diffusion { t, signal, .. } => {
                time("t", *t)?;
                signal.validate()?;
            }
            FieldRequest::Distance { distance, .. } => distance.validate()?,
            FieldRequest::SpectralFunction { filter, .. }
            | FieldRequest::Embedding { filter, .. }
            | FieldRequest::Green { filter, .. } => {
                filter
                    .validate_parameters()
                    .map_err(|e| RequestError::Filter {
                        key: "filter",
                        source: e,
                    })?
            }
            FieldRequest::Hks { t, .. } | FieldRequest::Adf { t, .. } => {
                if !(t.is_finite() && *t > 0.0) {
                    return Err(RequestError::Invalid {
                        key: "t",
                        message: format!("{t}: the time must be a finite number > 0"),
                    });
                }
            }
            FieldRequest::Wks { energy, sigma, .. } => {
                if !energy.is_finite() {
                    return Err(RequestError::Invalid {
                        key: "energy",
                        message: format!("{energy}: must be finite"),
                    });
                }
                if !(sigma.is_finite() && *sigma > 0.0) {
                    return Err(RequestError::Invalid {
                        key: "sigma",
                        message: format!("{sigma}: must be a finite number > 0"),
                    });
                }
            }
            FieldRequest::Segmentation {
                signature,
                persistence,
                ..
            } => {
                signature.validate()?;
                if !(persistence.is_finite() && *persistence >= 0.0) {
                    return Err(RequestError::Invalid {
                        key: "persistence",
                        message: format!("{persistence}: must be a finite number >= 0"),
                    });
                }
            }
            FieldRequest::Eigenfunction { .. } => {}
        }
        if let FieldRequest::Embedding { component, k, .. }
        | FieldRequest::Eigenfunction {
            index: component,
            k,
        } = self
            && component >= k
        {
            return Err(RequestError::Invalid {
                key: if matches!(self, FieldRequest::Embedding { .. }) {
                    "component"
                } else {
                    "index"
                },
                message: format!("{component}: out of range for k = {k} pairs (0-based)"),
            });
        }
        Ok(())
    }
}

/// A request that cannot be served, naming the key at fault.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum RequestError {
    /// A parameter is out of its range.
    #[error("{key}: {message}")]
    Invalid {
        /// The key (as typed in files and JSON bodies).
        key: &'static str,
        /// What is wrong.
        message: String,
    },
    /// A filter is refused.
    #[error("{key}: {source}")]
    Filter {
        /// The key.
        key: &'static str,
        /// The filter's error.
        source: FilterError,
    },
}

/// A heat kernel discretization (see [`crate::spectral::heat`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kernel {
    /// `K_t = X D_t X^T B` (the paper's wFEM kernel; conserves the B-mass). Default.
    #[default]
    Wfem,
    /// `K*_t = X D_t X^T D`, D the lumped mass.
    VoronoiCot,
    /// `K~_t = X D_t X^T` (no mass; LaPy's and pyFM's kernel).
    Standard,
}

impl Kernel {
    /// Every kernel, in a stable order.
    pub const ALL: [Kernel; 3] = [Kernel::Wfem, Kernel::VoronoiCot, Kernel::Standard];

    /// The name typed.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Wfem => "wfem",
            Kernel::VoronoiCot => "voronoi-cot",
            Kernel::Standard => "standard",
        }
    }
}

impl From<Kernel> for KernelKind {
    fn from(k: Kernel) -> Self {
        match k {
            Kernel::Wfem => KernelKind::Wfem,
            Kernel::VoronoiCot => KernelKind::VoronoiCot,
            Kernel::Standard => KernelKind::Standard,
        }
    }
}

impl FromStr for Kernel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Kernel::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
            .ok_or_else(|| format!("unknown kernel '{s}': expected wfem, voronoi-cot or standard"))
    }
}

/// The signal a diffusion starts from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum Signal {
    /// One value per vertex.
    Values(Vec<f64>),
    /// The indicator of the Euclidean ball of `radius` (mesh units) around `vertex`.
    Ball {
        /// Centre vertex.
        vertex: usize,
        /// Radius, `>= 0`.
        radius: f64,
    },
    /// The unit impulse at a vertex (`e_vertex`; the same as the heat basis function).
    Impulse(usize),
}

impl Signal {
    fn validate(&self) -> Result<(), RequestError> {
        match self {
            Signal::Values(v) => {
                if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                    return Err(RequestError::Invalid {
                        key: "signal",
                        message: format!("value {i} is not finite ({})", v[i]),
                    });
                }
            }
            Signal::Ball { radius, .. } => {
                if !(radius.is_finite() && *radius >= 0.0) {
                    return Err(RequestError::Invalid {
                        key: "signal",
                        message: format!("ball radius {radius}: must be a finite number >= 0"),
                    });
                }
            }
            Signal::Impulse(_) => {}
        }
        Ok(())
    }
}

/// Harmonic constraints: the paper's presets or explicit `(vertex, value)` pairs.
/// Serialized as a count (`2`, `4`, `6`) or a list of `{vertex, value}` tables.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Constraints {
    /// The paper's presets: 2 = min x -> 0 and max x -> 1; 4 adds y; 6 adds z.
    Preset(usize),
    /// Explicit constraints.
    List(Vec<Constraint>),
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints::Preset(2)
    }
}

impl Constraints {
    fn validate(&self) -> Result<(), RequestError> {
        match self {
            Constraints::Preset(c) if !matches!(c, 2 | 4 | 6) => Err(RequestError::Invalid {
                key: "constraints",
                message: format!("{c}: the presets are 2, 4 or 6"),
            }),
            Constraints::List(l) if l.is_empty() => Err(RequestError::Invalid {
                key: "constraints",
                message: "the list is empty".into(),
            }),
            Constraints::List(l) => {
                if let Some(c) = l.iter().find(|c| !c.value.is_finite()) {
                    return Err(RequestError::Invalid {
                        key: "constraints",
                        message: format!("the value at vertex {} is not finite", c.vertex),
                    });
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// As the library's constraint specification.
    pub fn spec(&self) -> ConstraintSpec {
        match self {
            Constraints::Preset(c) => ConstraintSpec::Extremes(*c),
            Constraints::List(l) => ConstraintSpec::Explicit(l.clone()),
        }
    }
}

/// A distance: a filter `w(lambda)` or the wFEM diffusion distance of eq. 15. Text form:
/// the filter syntax of [`crate::spectral::filters`], or `wfem-diffusion:t=T` (default
/// `t = 0.5`).
#[derive(Debug, Clone, PartialEq)]
pub enum DistanceSpec {
    /// `d^2 = sum_{lambda > 0} w(lambda) (x(p) - x(q))^2`.
    Filter(Filter),
    /// `d_t(i,j)^2 = (e_i - e_j)^T B X D_t X^T B (e_i - e_j)` over all pairs (eq. 15).
    WfemDiffusion {
        /// Time `t >= 0`.
        t: f64,
    },
}

impl Default for DistanceSpec {
    /// The paper's default: bi-harmonic.
    fn default() -> Self {
        DistanceSpec::Filter(Filter::Biharmonic)
    }
}

impl DistanceSpec {
    fn validate(&self) -> Result<(), RequestError> {
        match self {
            DistanceSpec::Filter(f) => f.validate_parameters().map_err(|e| RequestError::Filter {
                key: "distance",
                source: e,
            }),
            DistanceSpec::WfemDiffusion { t } if !(t.is_finite() && *t >= 0.0) => {
                Err(RequestError::Invalid {
                    key: "distance",
                    message: format!("wfem-diffusion: t = {t} must be a finite number >= 0"),
                })
            }
            DistanceSpec::WfemDiffusion { .. } => Ok(()),
        }
    }
}

impl fmt::Display for DistanceSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DistanceSpec::Filter(x) => write!(f, "{x}"),
            DistanceSpec::WfemDiffusion { t } => write!(f, "wfem-diffusion:t={t}"),
        }
    }
}

impl FromStr for DistanceSpec {
    type Err = FilterError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let text = s.trim();
        if text.len() > MAX_SPEC_LEN {
            return Err(FilterError::Syntax {
                text: text.chars().take(40).collect::<String>() + "...",
                message: format!("longer than {MAX_SPEC_LEN} characters"),
            });
        }
        if let Some(rest) = text.strip_prefix("wfem-diffusion") {
            let rest = rest.trim_start_matches(':').trim();
            let t = match rest.strip_prefix("t=").map(str::trim) {
                _ if rest.is_empty() => DEFAULT_HEAT_T,
                Some(v) => v.parse::<f64>().map_err(|_| FilterError::Syntax {
                    text: text.to_string(),
                    message: format!("bad time '{v}'"),
                })?,
                None => {
                    return Err(FilterError::Syntax {
                        text: text.to_string(),
                        message: "expected wfem-diffusion or wfem-diffusion:t=T".into(),
                    });
                }
            };
            if !(t.is_finite() && t >= 0.0) {
                return Err(FilterError::InvalidParameter(format!(
                    "wfem-diffusion: t = {t} must be a finite number >= 0"
                )));
            }
            return Ok(DistanceSpec::WfemDiffusion { t });
        }
        Ok(DistanceSpec::Filter(text.parse()?))
    }
}

/// The field a segmentation divides. Text form: `hks:t=0.1` (default), `adf:t=0.1`,
/// `wks:e=E,sigma=0.5`, `biharmonic-function`, `commute-function`,
/// `spectral-function:FILTER`; or, in serde form only, a list of values.
#[derive(Debug, Clone, PartialEq)]
pub enum SignatureSpec {
    /// Heat kernel signature at time `t`.
    Hks {
        /// Time.
        t: f64,
    },
    /// Auto-diffusion function at time `t`.
    Adf {
        /// Time.
        t: f64,
    },
    /// Wave kernel signature at energy `e` with bandwidth `sigma`.
    Wks {
        /// Energy (log-eigenvalue).
        e: f64,
        /// Bandwidth.
        sigma: f64,
    },
    /// The generalized spectral function of a filter.
    Spectral(Filter),
    /// A given field (one value per vertex): no eigenbasis needed.
    Values(Vec<f64>),
}

impl Default for SignatureSpec {
    fn default() -> Self {
        SignatureSpec::Hks {
            t: DEFAULT_SIGNATURE_T,
        }
    }
}

impl SignatureSpec {
    fn validate(&self) -> Result<(), RequestError> {
        let bad = |message: String| {
            Err(RequestError::Invalid {
                key: "signature",
                message,
            })
        };
        match self {
            SignatureSpec::Hks { t } | SignatureSpec::Adf { t } if !(t.is_finite() && *t > 0.0) => {
                bad(format!("t = {t} must be a finite number > 0"))
            }
            SignatureSpec::Wks { e, sigma }
                if !(e.is_finite() && sigma.is_finite() && *sigma > 0.0) =>
            {
                bad(format!(
                    "wks: e = {e} must be finite and sigma = {sigma} > 0"
                ))
            }
            SignatureSpec::Spectral(f) => {
                f.validate_parameters().map_err(|e| RequestError::Filter {
                    key: "signature",
                    source: e,
                })
            }
            SignatureSpec::Values(v) => match v.iter().position(|x| !x.is_finite()) {
                Some(i) => bad(format!("value {i} is not finite")),
                None => Ok(()),
            },
            _ => Ok(()),
        }
    }
}

impl fmt::Display for SignatureSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SignatureSpec::Hks { t } => write!(f, "hks:t={t}"),
            SignatureSpec::Adf { t } => write!(f, "adf:t={t}"),
            SignatureSpec::Wks { e, sigma } => write!(f, "wks:e={e},sigma={sigma}"),
            SignatureSpec::Spectral(x) => write!(f, "spectral-function:{x}"),
            SignatureSpec::Values(v) => write!(f, "values ({} entries)", v.len()),
        }
    }
}

impl FromStr for SignatureSpec {
    type Err = FilterError;
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let t = text.trim();
        let syntax = |m: String| FilterError::Syntax {
            text: text.to_string(),
            message: m,
        };
        if t.len() > MAX_SPEC_LEN {
            return Err(syntax(format!("longer than {MAX_SPEC_LEN} characters")));
        }
        let (name, rest) = t.split_once(':').unwrap_or((t, ""));
        let params = |allowed: &[&str]| -> Result<Vec<(String, f64)>, FilterError> {
            let mut out: Vec<(String, f64)> = Vec::new();
            for item in rest.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                let (k, v) = item
                    .split_once('=')
                    .ok_or_else(|| syntax(format!("'{item}' should be name=value")))?;
                let k = k.trim();
                if !allowed.contains(&k) {
                    return Err(syntax(format!(
                        "unknown parameter '{k}' (expected {})",
                        allowed.join(", ")
                    )));
                }
                let v: f64 = v
                    .trim()
                    .parse()
                    .map_err(|_| syntax(format!("'{}' is not a number", v.trim())))?;
                if out.iter().any(|(n, _)| n == k) {
                    return Err(syntax(format!("parameter '{k}' given twice")));
                }
                out.push((k.to_string(), v));
            }
            Ok(out)
        };
        let get = |p: &[(String, f64)], k: &str| p.iter().find(|(n, _)| n == k).map(|x| x.1);
        let spec = match name.trim().to_ascii_lowercase().as_str() {
            "hks" => SignatureSpec::Hks {
                t: get(&params(&["t"])?, "t").unwrap_or(DEFAULT_SIGNATURE_T),
            },
            "adf" => SignatureSpec::Adf {
                t: get(&params(&["t"])?, "t").unwrap_or(DEFAULT_SIGNATURE_T),
            },
            "wks" => {
                let p = params(&["e", "sigma"])?;
                SignatureSpec::Wks {
                    e: get(&p, "e")
                        .ok_or_else(|| syntax("wks needs e=ENERGY (and sigma=)".into()))?,
                    sigma: get(&p, "sigma").unwrap_or(DEFAULT_WKS_SIGMA),
                }
            }
            "biharmonic-function" | "biharmonic" => SignatureSpec::Spectral(Filter::Biharmonic),
            "commute-function" | "commute" => SignatureSpec::Spectral(Filter::CommuteTime),
            "spectral-function" => SignatureSpec::Spectral(rest.parse()?),
            other => {
                return Err(syntax(format!(
                    "unknown signature '{other}' (expected hks, adf, wks, biharmonic-function, commute-function or spectral-function:FILTER)"
                )));
            }
        };
        spec.validate().map_err(|e| match e {
            RequestError::Filter { source, .. } => source,
            RequestError::Invalid { message, .. } => FilterError::InvalidParameter(message),
        })?;
        Ok(spec)
    }
}

/// Serde through the text form, for types with `Display` and `FromStr`.
fn text_ser<T: fmt::Display, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
}

fn text_de<'de, T, D>(d: D) -> Result<T, D::Error>
where
    T: FromStr,
    T::Err: fmt::Display,
    D: Deserializer<'de>,
{
    let s = String::deserialize(d)?;
    s.parse().map_err(serde::de::Error::custom)
}

/// Serde of a [`Filter`] as its text (`"biharmonic"`, `"diffusion:t=0.5"`, ...).
pub mod filter_text {
    use super::*;

    /// Writes the filter's text form.
    pub fn serialize<S: Serializer>(f: &Filter, s: S) -> Result<S::Ok, S::Error> {
        text_ser(f, s)
    }

    /// Parses the filter's text form.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Filter, D::Error> {
        text_de(d)
    }
}

impl Serialize for DistanceSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        text_ser(self, s)
    }
}

impl<'de> Deserialize<'de> for DistanceSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        text_de(d)
    }
}

impl Serialize for SignatureSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            SignatureSpec::Values(v) => v.serialize(s),
            other => text_ser(other, s),
        }
    }
}

impl<'de> Deserialize<'de> for SignatureSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Form {
            Text(String),
            Values(Vec<f64>),
        }
        match Form::deserialize(d)? {
            Form::Text(t) => t.parse().map_err(serde::de::Error::custom),
            Form::Values(v) => Ok(SignatureSpec::Values(v)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn json(v: &str) -> Result<FieldRequest, String> {
        serde_json::from_str(v).map_err(|e| e.to_string())
    }

    #[test]
    fn defaults_fill_every_missing_key() {
        assert_eq!(
            json(r#"{"kind": "distance"}"#).unwrap(),
            FieldRequest::default()
        );
        assert_eq!(
            json(r#"{"kind": "heat"}"#).unwrap(),
            FieldRequest::Heat {
                anchor: None,
                t: 0.5,
                kernel: Kernel::Wfem,
                k: 100
            }
        );
        assert_eq!(
            json(r#"{"kind": "harmonic"}"#).unwrap(),
            FieldRequest::Harmonic {
                constraints: Constraints::Preset(2),
                order: 1
            }
        );
    }

    #[test]
    fn unknown_keys_and_kinds_are_refused_by_name() {
        let e = json(r#"{"kind": "distance", "filter": "biharmonic"}"#).unwrap_err();
        assert!(e.contains("filter"), "{e}");
        let e = json(r#"{"kind": "geodesic"}"#).unwrap_err();
        assert!(e.contains("geodesic"), "{e}");
        let e = json(r#"{"kind": "distance", "distance": "diffusion:t=-1"}"#).unwrap_err();
        assert!(e.contains("t"), "{e}");
    }

    #[test]
    fn every_kind_round_trips_through_json_and_toml() {
        let reqs = vec![
            FieldRequest::Harmonic {
                constraints: Constraints::List(vec![
                    Constraint {
                        vertex: 3,
                        value: 0.25,
                    },
                    Constraint {
                        vertex: 9,
                        value: -1.0,
                    },
                ]),
                order: 2,
            },
            FieldRequest::Heat {
                anchor: Some(4),
                t: 0.01,
                kernel: Kernel::Standard,
                k: 30,
            },
            FieldRequest::Diffusion {
                signal: Signal::Ball {
                    vertex: 2,
                    radius: 0.3,
                },
                t: 0.1,
                kernel: Kernel::VoronoiCot,
                k: 20,
            },
            FieldRequest::Diffusion {
                signal: Signal::Values(vec![1.0, 0.5, 1e-300]),
                t: 0.1,
                kernel: Kernel::Wfem,
                k: 20,
            },
            FieldRequest::Distance {
                source: Some(1),
                distance: "wfem-diffusion:t=0.125".parse().unwrap(),
                k: 50,
            },
            FieldRequest::Distance {
                source: None,
                distance: "custom-w:exp(-t*s)/s;t=0.1".parse().unwrap(),
                k: 50,
            },
            FieldRequest::SpectralFunction {
                filter: "mix:a=0.3,t=0.7".parse().unwrap(),
                k: 10,
            },
            FieldRequest::Hks {
                t: 0.3,
                scaled: true,
                k: 10,
            },
            FieldRequest::Wks {
                energy: 2.5,
                sigma: 0.25,
                scaled: false,
                k: 10,
            },
            FieldRequest::Adf { t: 0.2, k: 10 },
            FieldRequest::Segmentation {
                signature: "wks:e=2,sigma=0.5".parse().unwrap(),
                persistence: 0.1,
                k: 10,
            },
            FieldRequest::Segmentation {
                signature: SignatureSpec::Values(vec![0.0, 1.0, 2.0]),
                persistence: 0.1,
                k: 10,
            },
            FieldRequest::Embedding {
                filter: Filter::CommuteTime,
                component: 3,
                k: 10,
            },
            FieldRequest::Eigenfunction { index: 2, k: 10 },
            FieldRequest::Green {
                source: Some(7),
                filter: "band:1,2".parse().unwrap(),
                k: 10,
            },
        ];
        for r in reqs {
            r.validate().unwrap();
            let j = serde_json::to_string(&r).unwrap();
            assert_eq!(json(&j).unwrap(), r, "{j}");
            let t = toml::to_string(&r).unwrap();
            let back: FieldRequest = toml::from_str(&t).unwrap();
            assert_eq!(back, r, "{t}");
        }
    }

    #[test]
    fn validation_names_the_key() {
        let cases = [
            (r#"{"kind": "heat", "t": -1}"#, "t"),
            (r#"{"kind": "heat", "k": 0}"#, "k"),
            (r#"{"kind": "harmonic", "order": 3}"#, "order"),
            (r#"{"kind": "harmonic", "constraints": 5}"#, "constraints"),
            (r#"{"kind": "harmonic", "constraints": []}"#, "constraints"),
            (r#"{"kind": "hks", "t": 0}"#, "t"),
            (r#"{"kind": "wks", "energy": 1, "sigma": 0}"#, "sigma"),
            (
                r#"{"kind": "eigenfunction", "index": 10, "k": 10}"#,
                "index",
            ),
            (
                r#"{"kind": "embedding", "component": 10, "k": 10}"#,
                "component",
            ),
            (
                r#"{"kind": "segmentation", "persistence": -1}"#,
                "persistence",
            ),
        ];
        for (text, key) in cases {
            let e = json(text).unwrap().validate().unwrap_err();
            assert!(e.to_string().starts_with(key), "{text}: {e}");
        }
    }

    #[test]
    fn distance_texts() {
        assert_eq!(
            "wfem-diffusion".parse::<DistanceSpec>().unwrap(),
            DistanceSpec::WfemDiffusion { t: 0.5 }
        );
        assert_eq!(
            "wfem-diffusion:t=0".parse::<DistanceSpec>().unwrap(),
            DistanceSpec::WfemDiffusion { t: 0.0 }
        );
        assert!("wfem-diffusion:t=-2".parse::<DistanceSpec>().is_err());
        assert!("wfem-diffusion:x".parse::<DistanceSpec>().is_err());
        assert!("x".repeat(2000).parse::<DistanceSpec>().is_err());
        for s in ["biharmonic", "diffusion:t=0.25", "wfem-diffusion:t=0.1"] {
            let d: DistanceSpec = s.parse().unwrap();
            assert_eq!(d.to_string(), s);
        }
        assert!("wks:e=1,e=2".parse::<SignatureSpec>().is_err());
        assert!("wks:sigma=1".parse::<SignatureSpec>().is_err());
        assert!("hks:t=-1".parse::<SignatureSpec>().is_err());
    }
}
