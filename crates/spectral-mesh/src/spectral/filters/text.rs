//! The text form of a filter: `Display` and `FromStr` (syntax in the module documentation).

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use super::{CustomKind, Filter, FilterError};

impl fmt::Display for Filter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Filter::Diffusion { t } => write!(f, "diffusion:t={t}"),
            Filter::CommuteTime => f.write_str("commute"),
            Filter::Biharmonic => f.write_str("biharmonic"),
            Filter::Mix { a, t } => write!(f, "mix:a={a},t={t}"),
            Filter::Polynomial { p } => write!(f, "poly:p={p}"),
            Filter::BandSuppression { indices } => {
                let v: Vec<String> = indices.iter().map(|i| i.to_string()).collect();
                write!(f, "band:{}", v.join(","))
            }
            Filter::Custom { expr, params, kind } => {
                let k = match kind {
                    CustomKind::Weight => "custom-w",
                    CustomKind::Phi => "custom-phi",
                };
                write!(f, "{k}:{expr}")?;
                if !params.is_empty() {
                    let v: Vec<String> = params.iter().map(|(n, x)| format!("{n}={x}")).collect();
                    write!(f, ";{}", v.join(","))?;
                }
                Ok(())
            }
        }
    }
}

fn parse_params(text: &str, list: &str) -> Result<BTreeMap<String, f64>, FilterError> {
    let mut m = BTreeMap::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (k, v) = item.split_once('=').ok_or_else(|| FilterError::Syntax {
            text: text.to_string(),
            message: format!("parameter '{item}' is not of the form name=value"),
        })?;
        let k = k.trim();
        let valid = k
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid || k == "s" || k == "pi" {
            return Err(FilterError::Syntax {
                text: text.to_string(),
                message: format!("'{k}' is not a valid parameter name"),
            });
        }
        let x: f64 = v.trim().parse().map_err(|_| FilterError::Syntax {
            text: text.to_string(),
            message: format!("value of '{k}' is not a number: '{}'", v.trim()),
        })?;
        if m.insert(k.to_string(), x).is_some() {
            return Err(FilterError::Syntax {
                text: text.to_string(),
                message: format!("parameter '{k}' given twice"),
            });
        }
    }
    Ok(m)
}

impl FromStr for Filter {
    type Err = FilterError;

    /// Parses the syntax of the module documentation.
    fn from_str(text: &str) -> Result<Self, FilterError> {
        let t = text.trim();
        let (name, rest) = match t.split_once(':') {
            Some((a, b)) => (a.trim().to_ascii_lowercase(), b.trim()),
            None => (t.to_ascii_lowercase(), ""),
        };
        let syntax = |m: String| FilterError::Syntax {
            text: text.to_string(),
            message: m,
        };
        let named = |allowed: &[&str]| -> Result<BTreeMap<String, f64>, FilterError> {
            let p = parse_params(text, rest)?;
            if let Some(k) = p.keys().find(|k| !allowed.contains(&k.as_str())) {
                return Err(syntax(format!(
                    "unknown parameter '{k}' for '{name}' (expected: {})",
                    if allowed.is_empty() {
                        "none".to_string()
                    } else {
                        allowed.join(", ")
                    }
                )));
            }
            Ok(p)
        };
        let f = match name.as_str() {
            "diffusion" | "heat" => {
                let p = named(&["t"])?;
                Filter::Diffusion {
                    t: p.get("t").copied().unwrap_or(0.5),
                }
            }
            "commute" | "commute-time" | "commute_time" => {
                named(&[])?;
                Filter::CommuteTime
            }
            "biharmonic" | "bi-harmonic" => {
                named(&[])?;
                Filter::Biharmonic
            }
            "mix" => {
                let p = named(&["a", "t"])?;
                Filter::Mix {
                    a: p.get("a").copied().unwrap_or(0.5),
                    t: p.get("t").copied().unwrap_or(0.5),
                }
            }
            "poly" | "polynomial" => {
                let p = named(&["p"])?;
                Filter::Polynomial {
                    p: *p
                        .get("p")
                        .ok_or_else(|| syntax("poly needs p, e.g. poly:p=2".into()))?,
                }
            }
            "band" | "band-suppression" => {
                let mut indices = Vec::new();
                for item in rest.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                    indices.push(item.parse::<usize>().map_err(|_| {
                        syntax(format!("band index '{item}' is not a non-negative integer"))
                    })?);
                }
                if indices.is_empty() {
                    return Err(syntax("band needs indices, e.g. band:1,2".into()));
                }
                Filter::BandSuppression { indices }
            }
            "custom-w" | "custom-phi" => {
                let (expr, plist) = match rest.split_once(';') {
                    Some((e, p)) => (e.trim(), p),
                    None => (rest, ""),
                };
                if expr.is_empty() {
                    return Err(syntax(format!("{name} needs an expression after ':'")));
                }
                let params = parse_params(text, plist)?;
                let kind = if name == "custom-w" {
                    CustomKind::Weight
                } else {
                    CustomKind::Phi
                };
                Filter::custom(expr, params, kind)?
            }
            _ => {
                return Err(syntax(format!(
                    "unknown filter '{name}': expected diffusion, commute, biharmonic, mix, poly, band, custom-w or custom-phi"
                )));
            }
        };
        f.validate_parameters()?;
        Ok(f)
    }
}
