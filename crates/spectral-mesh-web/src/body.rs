//! The JSON body of field and download requests: the library's [`FieldRequest`] in its
//! serde form (tag `kind`, unknown keys refused), with the analysis keys and the picture
//! keys beside it in the same object.

use serde_json::{Map, Value};
use spectral_mesh::Laplacian;
use spectral_mesh::analysis::FieldRequest;
use spectral_mesh::experiments::file::FigureFile;
use spectral_mesh_render::figure::FigureOptions;

/// Keys of a body that are not the request's.
pub const FACE_KEYS: [&str; 10] = [
    "laplacian",
    "normalize",
    "levels",
    "colormap",
    "view",
    "size",
    "transparent",
    "critical_points",
    "colorbar",
    "format",
];

/// Default number of level sets the page draws.
pub const DEFAULT_LEVELS: usize = 10;
/// Most level sets a request may ask for (as experiment files).
pub const MAX_LEVELS: usize = 1000;
/// Largest picture the server draws, in pixels per side.
pub const MAX_PICTURE: u32 = 4096;

/// A parsed field or download body.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldBody {
    /// The field.
    pub request: FieldRequest,
    /// Discretization (default fem).
    pub laplacian: Laplacian,
    /// Unit-area normalisation (default true).
    pub normalize: bool,
    /// Level sets drawn (default 10).
    pub levels: usize,
    /// Picture options of downloads (`levels` included); the page colours the binary
    /// field itself.
    pub figure: FigureFile,
    /// Download format (download endpoint only).
    pub format: Option<String>,
}

/// Why a body was refused (a 400 or 422 for the client).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyError(pub String);

fn bad(msg: impl Into<String>) -> BodyError {
    BodyError(msg.into())
}

fn take_str(m: &mut Map<String, Value>, key: &str) -> Result<Option<String>, BodyError> {
    match m.remove(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::String(s)) => Ok(Some(s)),
        Some(other) => Err(bad(format!("{key}: expected a string, got {other}"))),
    }
}

fn take_bool(m: &mut Map<String, Value>, key: &str) -> Result<Option<bool>, BodyError> {
    match m.remove(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Bool(b)) => Ok(Some(b)),
        Some(other) => Err(bad(format!("{key}: expected true or false, got {other}"))),
    }
}

fn take_uint(m: &mut Map<String, Value>, key: &str, max: u64) -> Result<Option<u64>, BodyError> {
    match m.remove(key) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => match v.as_u64() {
            Some(x) if x <= max => Ok(Some(x)),
            _ => Err(bad(format!(
                "{key}: expected an integer from 0 to {max}, got {v}"
            ))),
        },
    }
}

impl FieldBody {
    /// Parses a body: a JSON object with `kind` and the request's keys, plus any of
    /// [`FACE_KEYS`].
    pub fn from_value(v: Value) -> Result<Self, BodyError> {
        let Value::Object(mut m) = v else {
            return Err(bad(
                "the body must be a JSON object with a \"kind\" (e.g. {\"kind\": \"heat\", \"t\": 0.01})",
            ));
        };
        let laplacian = match take_str(&mut m, "laplacian")? {
            None => Laplacian::Fem,
            Some(s) => s
                .parse::<Laplacian>()
                .map_err(|e| bad(format!("laplacian: {e}")))?,
        };
        let normalize = take_bool(&mut m, "normalize")?.unwrap_or(true);
        let levels =
            take_uint(&mut m, "levels", MAX_LEVELS as u64)?.map_or(DEFAULT_LEVELS, |l| l as usize);
        let size = take_uint(&mut m, "size", MAX_PICTURE as u64)?.map(|s| s as u32);
        if let Some(s) = size
            && s < 16
        {
            return Err(bad(format!("size: {s}: at least 16 pixels")));
        }
        let figure = FigureFile {
            levels: Some(levels),
            colormap: take_str(&mut m, "colormap")?,
            view: take_str(&mut m, "view")?,
            size,
            transparent: take_bool(&mut m, "transparent")?,
            critical_points: take_bool(&mut m, "critical_points")?,
            colorbar: take_bool(&mut m, "colorbar")?,
        };
        let format = take_str(&mut m, "format")?;
        if !m.contains_key("kind") {
            return Err(bad(format!(
                "the body has no \"kind\": one of {}",
                spectral_mesh::analysis::request::KINDS.join(", ")
            )));
        }
        let request: FieldRequest = serde_json::from_value(Value::Object(m))
            .map_err(|e| bad(format!("field request: {e}")))?;
        Ok(Self {
            request,
            laplacian,
            normalize,
            levels,
            figure,
            format,
        })
    }

    /// The picture options of a download (names checked by the render crate).
    pub fn figure_options(&self) -> Result<FigureOptions, BodyError> {
        FigureOptions::from_file(&self.figure).map_err(|e| bad(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_keys_and_face_keys_in_one_object() {
        let b = FieldBody::from_value(serde_json::json!({
            "kind": "heat", "t": 0.01, "anchor": 3, "k": 20,
            "laplacian": "voronoi-cot", "normalize": false, "levels": 7, "colormap": "viridis"
        }))
        .unwrap();
        assert_eq!(b.laplacian, Laplacian::VoronoiCot);
        assert!(!b.normalize);
        assert_eq!(b.levels, 7);
        assert_eq!(b.request.source(), Some(3));
        assert_eq!(b.figure_options().unwrap().levels, 7);
        let d = FieldBody::from_value(serde_json::json!({"kind": "distance"})).unwrap();
        assert_eq!(d.request, FieldRequest::default());
        assert_eq!(
            (d.laplacian, d.normalize, d.levels),
            (Laplacian::Fem, true, 10)
        );
        for (body, key) in [
            (serde_json::json!({"t": 1}), "kind"),
            (serde_json::json!({"kind": "heat", "filter": "x"}), "filter"),
            (
                serde_json::json!({"kind": "heat", "laplacian": "nope"}),
                "laplacian",
            ),
            (serde_json::json!({"kind": "heat", "levels": -1}), "levels"),
            (
                serde_json::json!({"kind": "heat", "levels": 5000}),
                "levels",
            ),
            (
                serde_json::json!({"kind": "heat", "normalize": "yes"}),
                "normalize",
            ),
            (serde_json::json!({"kind": "heat", "size": 3}), "size"),
            (serde_json::json!([1, 2]), "object"),
        ] {
            let e = FieldBody::from_value(body.clone()).unwrap_err().0;
            assert!(e.contains(key), "{body}: {e}");
        }
        let b =
            FieldBody::from_value(serde_json::json!({"kind": "heat", "colormap": "jet"})).unwrap();
        assert!(b.figure_options().unwrap_err().0.contains("colormap"));
    }
}
