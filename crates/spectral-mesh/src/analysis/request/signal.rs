//! The signal a diffusion starts from.

use serde::{Deserialize, Serialize};

use super::RequestError;

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
    pub(super) fn validate(&self) -> Result<(), RequestError> {
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
