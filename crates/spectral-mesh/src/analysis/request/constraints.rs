//! Harmonic constraints of a request: presets or explicit pairs.

use serde::{Deserialize, Serialize};

use super::RequestError;
use crate::fields::harmonic::{Constraint, ConstraintSpec};

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
    pub(super) fn validate(&self) -> Result<(), RequestError> {
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
