//! Checks of a request that do not depend on the mesh, and the error naming the key at fault.

use super::FieldRequest;
use crate::spectral::filters::FilterError;

impl FieldRequest {
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
            FieldRequest::Geodesic { time_factor, .. } => {
                if !(time_factor.is_finite() && *time_factor > 0.0) {
                    return Err(RequestError::Invalid {
                        key: "time_factor",
                        message: format!(
                            "{time_factor}: m in the time step t = m h^2 must be a finite number > 0"
                        ),
                    });
                }
            }
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
