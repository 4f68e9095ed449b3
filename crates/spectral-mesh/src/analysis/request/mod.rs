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
//! constraints (vertex of min x -> 0, of max x -> 1), the heat method's time step
//! `t = m h^2` with `m = 1` ([`DEFAULT_GEODESIC_TIME_FACTOR`]).

use serde::{Deserialize, Serialize};

use crate::geodesic::Convention;
use crate::spectral::filters::Filter;

mod constraints;
mod serde_text;
mod signal;
mod spec;
mod validate;

pub use crate::spectral::heat::Kernel;
pub use constraints::Constraints;
pub use serde_text::filter_text;
pub use signal::Signal;
pub use spec::{DistanceSpec, SignatureSpec};
pub use validate::RequestError;

/// Declares each default as a public constant and as the function that serde's
/// `default = "..."` names (one declaration per default).
macro_rules! defaults {
    ($($(#[$doc:meta])* $name:ident, $function:ident: $ty:ty = $value:expr;)*) => {
        $(
            $(#[$doc])*
            pub const $name: $ty = $value;
            fn $function() -> $ty {
                $name
            }
        )*
    };
}

defaults! {
    /// Default number of eigenpairs (the paper's).
    DEFAULT_K, default_k: usize = 100;
    /// Default heat time of the heat basis function and of diffusions (the paper's `t = 0.5`;
    /// for the unit-area shape when the analysis normalizes).
    DEFAULT_HEAT_T, default_heat_t: f64 = 0.5;
    /// Default time of the heat kernel signature and the auto-diffusion function.
    DEFAULT_SIGNATURE_T, default_signature_t: f64 = 0.1;
    /// Default bandwidth of a wave kernel signature at one energy.
    DEFAULT_WKS_SIGMA, default_wks_sigma: f64 = 0.5;
    /// Default persistence threshold of segmentations (relative to the field's range).
    DEFAULT_PERSISTENCE, default_persistence: f64 = 0.05;
    /// Default index of single eigenfunctions and embedding coordinates: the first pair
    /// after the constant one.
    DEFAULT_COMPONENT, default_component: usize = 1;
    /// Default order of a harmonic map (1: harmonic; 2: bi-harmonic).
    DEFAULT_HARMONIC_ORDER, default_order: u32 = 1;
}
pub use crate::defaults::values::DEFAULT_GEODESIC_TIME_FACTOR;
/// Longest filter or signature text accepted (a bound on what a client can make us parse).
pub const MAX_SPEC_LEN: usize = 1000;

fn default_geodesic_time_factor() -> f64 {
    DEFAULT_GEODESIC_TIME_FACTOR
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
    /// Geodesic distance along the surface by the heat method ([`crate::geodesic`]), in
    /// the mesh's units (never scaled to unit area), from `source` and every vertex of
    /// `sources` (the distance to the nearest). No eigenbasis. Vertices the sources
    /// cannot reach (other components) get `+inf`, listed in [`super::Field::unreachable`].
    Geodesic {
        /// Source vertex (default: the vertex of largest x, when `sources` is empty too).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        source: Option<usize>,
        /// More source vertices (default none).
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        sources: Vec<usize>,
        /// `m` in the time step `t = m h^2` (default 1), finite and `> 0`.
        #[serde(default = "default_geodesic_time_factor")]
        time_factor: f64,
        /// The heat method's variant (default `crane`; `potpourri3d` to compare with it).
        #[serde(default)]
        convention: Convention,
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
pub const KINDS: [&str; 13] = [
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
    "geodesic",
];

/// The `k` field of a request, `None` for the kinds without one (a harmonic map, a geodesic
/// distance): a reference or a mutable one, as `$request` is.
macro_rules! eigenpairs_field {
    ($request:expr) => {
        match $request {
            FieldRequest::Harmonic { .. } | FieldRequest::Geodesic { .. } => None,
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
            | FieldRequest::Green { k, .. } => Some(k),
        }
    };
}

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
            FieldRequest::Geodesic { .. } => "geodesic",
        }
    }

    /// The number of eigenpairs the request uses, `None` when it needs no eigenbasis (a
    /// harmonic map, a geodesic distance, or a segmentation of a given field).
    pub fn eigenpairs(&self) -> Option<usize> {
        match self {
            FieldRequest::Segmentation {
                signature: SignatureSpec::Values(_),
                ..
            } => None,
            _ => eigenpairs_field!(self).copied(),
        }
    }

    /// Sets the number of eigenpairs (no effect on requests that need no basis).
    pub fn set_eigenpairs(&mut self, new_k: usize) {
        if let Some(k) = eigenpairs_field!(self) {
            *k = new_k;
        }
    }

    /// The source or anchor vertex the request names, if it names one (a geodesic
    /// distance: `source`, else the first of `sources`).
    pub fn source(&self) -> Option<usize> {
        match self {
            FieldRequest::Heat { anchor, .. } => *anchor,
            FieldRequest::Geodesic {
                source, sources, ..
            } => source.or_else(|| sources.first().copied()),
            FieldRequest::Distance { source, .. } | FieldRequest::Green { source, .. } => *source,
            _ => None,
        }
    }

    /// True when the request is about a source or anchor vertex (which defaults to the
    /// vertex of largest x).
    pub fn uses_source(&self) -> bool {
        matches!(
            self,
            FieldRequest::Heat { .. }
                | FieldRequest::Distance { .. }
                | FieldRequest::Green { .. }
                | FieldRequest::Geodesic { .. }
        )
    }

    /// Sets the source or anchor (no effect on requests without one; a geodesic
    /// distance keeps its further `sources`).
    pub fn set_source(&mut self, v: Option<usize>) {
        match self {
            FieldRequest::Heat { anchor, .. } => *anchor = v,
            FieldRequest::Distance { source, .. }
            | FieldRequest::Green { source, .. }
            | FieldRequest::Geodesic { source, .. } => *source = v,
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
}

#[cfg(test)]
mod tests;
