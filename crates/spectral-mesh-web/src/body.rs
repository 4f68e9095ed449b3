//! The request bodies, parsed and checked as the handlers do (and as the `web_body`
//! fuzz target does): the field and download body (the library's [`FieldRequest`] in
//! its serde form, tag `kind`, unknown keys refused, with the analysis keys and the
//! picture keys beside it in the same object), the basis body, the shape body and the
//! name of an uploaded file.

use serde::Deserialize;
use serde_json::{Map, Value};
use spectral_mesh::Laplacian;
use spectral_mesh::analysis::FieldRequest;
use spectral_mesh::defaults::{DEFAULT_K, LEVELS, MAX_LEVELS, MAX_PICTURE, NORMALIZE};
use spectral_mesh::experiments::file::FigureFile;
use spectral_mesh::shapes::ShapeSpec;
use spectral_mesh_render::figure::FigureOptions;

/// Keys of a body that are not the request's.
pub const FACE_KEYS: [&str; 15] = [
    "laplacian",
    "normalize",
    "levels",
    "colormap",
    "view",
    "size",
    "height",
    "scale",
    "dpi",
    "legend",
    "transparent",
    "critical_points",
    "colorbar",
    "format",
    "segments",
];

/// A parsed field or download body.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldBody {
    /// The field.
    pub request: FieldRequest,
    /// Discretization as given (`None`: the input's default, fem for a mesh and robust
    /// for a point cloud).
    pub laplacian: Option<Laplacian>,
    /// Unit-area normalisation (default the library's [`NORMALIZE`]).
    pub normalize: bool,
    /// Level sets drawn (default the library's [`LEVELS`]).
    pub levels: usize,
    /// Picture options of downloads (`levels` included); the page colours the binary
    /// field itself.
    pub figure: FigureFile,
    /// Download format (download endpoint only).
    pub format: Option<String>,
    /// Level-set segments in the binary reply (default true; the page draws a mesh's
    /// level sets itself and asks for none).
    pub segments: bool,
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
        let laplacian = take_str(&mut m, "laplacian")?
            .map(|s| s.parse::<Laplacian>())
            .transpose()
            .map_err(|e| bad(format!("laplacian: {e}")))?;
        let normalize = take_bool(&mut m, "normalize")?.unwrap_or(NORMALIZE);
        let levels = take_uint(&mut m, "levels", MAX_LEVELS as u64)?.map_or(LEVELS, |l| l as usize);
        let size = take_uint(&mut m, "size", MAX_PICTURE as u64)?.map(|s| s as u32);
        let height = take_uint(&mut m, "height", MAX_PICTURE as u64)?.map(|s| s as u32);
        for (key, v) in [("size", size), ("height", height)] {
            if let Some(s) = v {
                spectral_mesh::defaults::check_picture_size(s)
                    .map_err(|e| bad(format!("{key}: {e}")))?;
            }
        }
        let scale = match m.remove("scale") {
            None | Some(Value::Null) => None,
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() && x > 0.0 => Some(x),
                _ => return Err(bad(format!("scale: expected a positive number, got {v}"))),
            },
        };
        let figure = FigureFile {
            levels: Some(levels),
            colormap: take_str(&mut m, "colormap")?,
            view: take_str(&mut m, "view")?,
            size,
            transparent: take_bool(&mut m, "transparent")?,
            critical_points: take_bool(&mut m, "critical_points")?,
            colorbar: take_bool(&mut m, "colorbar")?,
            height,
            scale,
            dpi: take_uint(&mut m, "dpi", 100_000)?.map(|d| d as u32),
            legend: take_bool(&mut m, "legend")?,
        };
        let segments = !matches!(take_bool(&mut m, "segments")?, Some(false));
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
            segments,
        })
    }

    /// The picture options of a download (names checked by the render crate).
    pub fn figure_options(&self) -> Result<FigureOptions, BodyError> {
        FigureOptions::from_file(&self.figure).map_err(|e| bad(e.to_string()))
    }
}

/// Parses the body of a field or download request (JSON, then [`FieldBody::from_value`]).
pub fn parse_field(bytes: &[u8]) -> Result<FieldBody, BodyError> {
    let v: Value = serde_json::from_slice(bytes).map_err(|e| bad(format!("bad JSON: {e}")))?;
    let body = FieldBody::from_value(v)?;
    Ok(body)
}

/// The JSON of `POST /api/mesh/{id}/basis`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct BasisJson {
    laplacian: Option<String>,
    normalize: Option<bool>,
    k: Option<usize>,
}

/// A parsed basis request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BasisBody {
    /// Discretization as given (`None`: the input's default, fem for a mesh and robust
    /// for a point cloud).
    pub laplacian: Option<Laplacian>,
    /// Unit-area normalisation (default the library's [`NORMALIZE`]).
    pub normalize: bool,
    /// Pairs (default the library's [`DEFAULT_K`]).
    pub k: usize,
}

/// Parses the body of a basis request (an empty body is `{}`: every default).
pub fn parse_basis(bytes: &[u8]) -> Result<BasisBody, BodyError> {
    let j: BasisJson = if bytes.iter().all(u8::is_ascii_whitespace) {
        BasisJson::default()
    } else {
        serde_json::from_slice(bytes).map_err(|e| bad(format!("bad JSON: {e}")))?
    };
    let laplacian = j
        .laplacian
        .map(|s| s.parse::<Laplacian>())
        .transpose()
        .map_err(|e| bad(format!("laplacian: {e}")))?;
    Ok(BasisBody {
        laplacian,
        normalize: j.normalize.unwrap_or(NORMALIZE),
        k: j.k.unwrap_or(DEFAULT_K),
    })
}

/// Checks `k` against a mesh of `n` vertices and the server's `max_k` (the handler
/// answers 422 with the message).
pub fn check_k(k: usize, n: usize, max_k: usize) -> Result<(), String> {
    if k == 0 || k > n {
        return Err(format!(
            "k must be in 1..={n} (the number of vertices); got {k}"
        ));
    }
    if k > max_k {
        return Err(format!(
            "k = {k} is more than this server's limit of {max_k} eigenpairs (--max-k)"
        ));
    }
    Ok(())
}

/// The JSON of `POST /api/mesh` with a shape.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeJson {
    shape: String,
}

/// Longest shape spec accepted.
pub const MAX_SHAPE_SPEC: usize = 200;

/// Parses a shape request: the spec parsed and validated, with the most vertices its
/// mesh can have (exact for the regular shapes; the irregular ones are at most the
/// regular shape one level finer).
pub fn parse_shape(bytes: &[u8]) -> Result<(String, ShapeSpec, usize), BodyError> {
    let j: ShapeJson = serde_json::from_slice(bytes).map_err(|e| bad(format!("bad JSON: {e}")))?;
    if j.shape.len() > MAX_SHAPE_SPEC {
        return Err(bad(format!(
            "the shape spec is too long (more than {MAX_SHAPE_SPEC} characters)"
        )));
    }
    let spec = spectral_mesh::shapes::parse_shape(&j.shape)
        .and_then(|s| s.validate().map(|()| s))
        .map_err(|e| bad(format!("shape '{}': {e}", j.shape)))?;
    let res = if spec.irregular {
        spec.res + 1
    } else {
        spec.res
    };
    let most = spec
        .kind
        .vertex_count(res)
        .or_else(|| spec.kind.vertex_count(spec.res))
        .unwrap_or(usize::MAX);
    Ok((j.shape, spec, most))
}

/// Longest name kept of an uploaded file.
pub const MAX_NAME: usize = 100;

/// The name an upload is known by (from `X-Filename`): its last path component, with
/// only letters, digits, `.`, `-`, `_`, `+`, `=`, `,` and spaces kept (others become
/// `_`), no leading dots, at most [`MAX_NAME`] characters keeping the extension;
/// `upload.off` when nothing is left. It names the mesh in replies and in downloaded
/// experiment files (`mesh = NAME`, read beside the file): it can never name another
/// folder.
pub fn upload_name(header: Option<&str>) -> String {
    let raw = header.unwrap_or("");
    let last = raw.rsplit(['/', '\\']).next().unwrap_or("").trim();
    let mut name: String = last
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || " .-_+=,".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    name = name.trim_start_matches(['.', ' ']).trim_end().to_string();
    if name.chars().count() > MAX_NAME {
        let ext: String = match name.rsplit_once('.') {
            Some((_, e)) if e.len() <= 8 => format!(".{e}"),
            _ => String::new(),
        };
        let stem: String = name.chars().take(MAX_NAME - ext.len()).collect();
        name = format!("{stem}{ext}");
    }
    if name.is_empty() || name.chars().all(|c| c == '_' || c == '.') {
        "upload.off".into()
    } else {
        name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upload_names_never_name_a_folder() {
        for (given, want) in [
            (Some("bunny.off"), "bunny.off"),
            (Some("../../etc/passwd.off"), "passwd.off"),
            (Some("..\\..\\x.obj"), "x.obj"),
            (Some("/abs/path/m.ply"), "m.ply"),
            (Some(".."), "upload.off"),
            (Some("..."), "upload.off"),
            (Some(".hidden.stl"), "hidden.stl"),
            (Some("a\u{0}b\nc.off"), "a_b_c.off"),
            (Some("caf\u{e9}.off"), "caf_.off"),
            (Some("dir/"), "upload.off"),
            (None, "upload.off"),
        ] {
            let got = upload_name(given);
            assert_eq!(got, want, "{given:?}");
            assert!(!got.contains('/') && !got.contains('\\') && !got.starts_with('.'));
        }
        let long = format!("{}.off", "x".repeat(300));
        let got = upload_name(Some(&long));
        assert_eq!(got.len(), MAX_NAME);
        assert!(got.ends_with(".off"));
    }

    #[test]
    fn basis_and_shape_bodies() {
        assert_eq!(
            parse_basis(b"").unwrap(),
            BasisBody {
                laplacian: None,
                normalize: true,
                k: 100
            }
        );
        let b =
            parse_basis(br#"{"k": 7, "laplacian": "voronoi-cot", "normalize": false}"#).unwrap();
        assert_eq!(
            (b.k, b.laplacian, b.normalize),
            (7, Some(Laplacian::VoronoiCot), false)
        );
        for body in [
            &br#"{"k": -1}"#[..],
            br#"{"k": 1e3}"#,
            br#"{"kk": 1}"#,
            br#"{"laplacian": "x"}"#,
            br#"[1]"#,
            b"{",
        ] {
            assert!(
                parse_basis(body).is_err(),
                "{}",
                String::from_utf8_lossy(body)
            );
        }
        assert!(check_k(0, 10, 1000).unwrap_err().contains("1..=10"));
        assert!(check_k(11, 10, 1000).is_err());
        assert!(check_k(1001, 5000, 1000).unwrap_err().contains("--max-k"));
        assert!(check_k(10, 10, 1000).is_ok());
        let (_, spec, most) = parse_shape(br#"{"shape": "sphere:res=3"}"#).unwrap();
        assert_eq!(most, 642);
        assert!(!spec.irregular);
        let (_, _, most) = parse_shape(br#"{"shape": "irregular-sphere:res=3"}"#).unwrap();
        assert_eq!(most, 2562);
        assert!(parse_shape(br#"{"shape": "sphere:res=99"}"#).is_err());
        assert!(parse_shape(br#"{"shape": "/etc/passwd"}"#).is_err());
        assert!(parse_shape(br#"{"shape": "x", "y": 1}"#).is_err());
    }

    #[test]
    fn request_keys_and_face_keys_in_one_object() {
        let b = FieldBody::from_value(serde_json::json!({
            "kind": "heat", "t": 0.01, "anchor": 3, "k": 20,
            "laplacian": "voronoi-cot", "normalize": false, "levels": 7, "colormap": "viridis"
        }))
        .unwrap();
        assert_eq!(b.laplacian, Some(Laplacian::VoronoiCot));
        assert!(!b.normalize);
        assert_eq!(b.levels, 7);
        assert_eq!(b.request.source(), Some(3));
        assert_eq!(b.figure_options().unwrap().levels, 7);
        let d = FieldBody::from_value(serde_json::json!({"kind": "distance"})).unwrap();
        assert_eq!(d.request, FieldRequest::default());
        assert_eq!(
            (d.laplacian, d.normalize, d.levels),
            (None, NORMALIZE, LEVELS)
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
