//! Distances and segmentation signatures named by text (`biharmonic`, `hks:t=0.1`, ...), with their serde forms.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::serde_text::{text_de, text_ser};
use super::{DEFAULT_HEAT_T, DEFAULT_SIGNATURE_T, DEFAULT_WKS_SIGMA, MAX_SPEC_LEN, RequestError};
use crate::spectral::filters::{Filter, FilterError};

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
    pub(super) fn validate(&self) -> Result<(), RequestError> {
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
    pub(super) fn validate(&self) -> Result<(), RequestError> {
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
