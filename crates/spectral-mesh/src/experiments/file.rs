//! Experiment files: one run with every parameter written out, replayed by
//! `spectral-mesh run FILE.toml`. One schema for every face: the CLI's
//! `--save-experiment`, the web app's download and the Python package write it, and `run`
//! reads it. The format is documented in `docs/experiment-files.md`.
//!
//! A flat TOML table: `experiment` (`harmonic`, `diffusion-basis`, `spectral-distance` —
//! the paper's three — or `field`), `mesh` and the analysis keys (`mesh_hash`, `repair`,
//! `laplacian`, `normalize`, `basis_k`, `out`), the paper experiments' own keys (`k`, `t`,
//! `anchor`, `distance`, `source`, `constraints`, `order`), a `[field]` table holding a
//! [`FieldRequest`] for `experiment = "field"`, a `[point_cloud]` table holding the
//! point-cloud Laplacian's parameters when the input is a point cloud, and a `[figure]`
//! table of picture options.

use std::path::{Component, Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::analysis::{Constraints, DistanceSpec, FieldRequest, Kernel};
use crate::fields::harmonic::Constraint;
use crate::operators::{Laplacian, NormalSource, PointCloudParams, TriangleUnion};

/// The experiments a file can name.
pub const EXPERIMENTS: [&str; 4] = ["harmonic", "diffusion-basis", "spectral-distance", "field"];

/// An error in an experiment file: `origin:line: key 'k': problem` where known.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[error("{0}")]
pub struct ExperimentFileError(pub String);

fn key_err(key: &str, msg: impl std::fmt::Display) -> ExperimentFileError {
    ExperimentFileError(format!("key '{key}': {msg}"))
}

/// Declares a table of keys of which those after `optional` may be left out: each of these
/// is an `Option`, `None` when the key is absent and not written when `None` (the serde rule
/// said once for every optional key of a file).
macro_rules! optional_keys {
    (
        $(#[$attr:meta])*
        pub struct $name:ident {
            $($(#[$required_attr:meta])* pub $required:ident: $required_ty:ty,)*
        }
        optional {
            $($(#[$optional_attr:meta])* $optional:ident: Option<$optional_ty:ty>,)*
        }
    ) => {
        $(#[$attr])*
        pub struct $name {
            $($(#[$required_attr])* pub $required: $required_ty,)*
            $(
                $(#[$optional_attr])*
                #[serde(default, skip_serializing_if = "Option::is_none")]
                pub $optional: Option<$optional_ty>,
            )*
        }
    };
}

optional_keys! {
    /// Picture options (`[figure]`), as plain data: the render crate turns them into its
    /// options and checks the names (colour map, view).
    #[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct FigureFile {
    }
    optional {
        /// Number of level sets (0 = none).
        levels: Option<usize>,
        /// Colour map name.
        colormap: Option<String>,
        /// View: front, side, top, iso or "AZ,EL".
        view: Option<String>,
        /// Picture size in pixels.
        size: Option<u32>,
        /// Transparent background.
        transparent: Option<bool>,
        /// Mark critical points.
        critical_points: Option<bool>,
        /// Draw the colour bar.
        colorbar: Option<bool>,
        /// Picture height in pixels (default: `size`).
        height: Option<u32>,
        /// Picture pixels per screen pixel (markers, lines, text).
        scale: Option<f64>,
        /// Print resolution of the PNG, dots per inch.
        dpi: Option<u32>,
        /// Draw the legend.
        legend: Option<bool>,
    }
}

optional_keys! {
    /// The point-cloud Laplacian's parameters (`[point_cloud]`), for an input that is a point
    /// cloud. Every key is optional on reading (the library's [`PointCloudParams::default`]
    /// applies); saved files write them all, so a replay builds the same Laplacian (and so the
    /// same field, bit for bit) whatever the defaults are then.
    #[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct PointCloudFile {
    }
    optional {
        /// Neighbours per point (at least 2).
        neighbors: Option<usize>,
        /// Relative mollification of the robust pipeline.
        mollify_factor: Option<f64>,
        /// Delaunay tolerance of the robust pipeline.
        delaunay_tolerance: Option<f64>,
        /// Tangent planes: `estimate` (PCA) or `from-cloud` (the file's normals where non-zero).
        normals: Option<NormalSource>,
        /// How the local triangulations are combined: `consensus`, `consensus-only`,
        /// `multiplicity` or `interleaved`.
        union: Option<TriangleUnion>,
    }
}

impl PointCloudFile {
    /// Every parameter written out.
    pub fn from_params(p: &PointCloudParams) -> Self {
        Self {
            neighbors: Some(p.neighbors),
            mollify_factor: Some(p.mollify_factor),
            delaunay_tolerance: Some(p.delaunay_tolerance),
            normals: Some(p.normals),
            union: Some(p.union),
        }
    }

    /// The parameters: these keys over the library's defaults (not validated: see
    /// [`PointCloudParams::validate`]).
    pub fn params(&self) -> PointCloudParams {
        let d = PointCloudParams::default();
        PointCloudParams {
            neighbors: self.neighbors.unwrap_or(d.neighbors),
            mollify_factor: self.mollify_factor.unwrap_or(d.mollify_factor),
            delaunay_tolerance: self.delaunay_tolerance.unwrap_or(d.delaunay_tolerance),
            normals: self.normals.unwrap_or(d.normals),
            union: self.union.unwrap_or(d.union),
        }
    }
}

optional_keys! {
    /// An experiment file. Every key but `experiment` and `mesh` is optional on reading (the
    /// default applies); saved files write every key that applies.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct ExperimentFile {
        /// harmonic | diffusion-basis | spectral-distance | field.
        pub experiment: String,
        /// Mesh file (relative to the experiment file's folder, `${VAR}` expanded) or shape.
        pub mesh: String,
    }
    optional {
        /// blake3 of the mesh as read (before any repair), 64 hex digits.
        mesh_hash: Option<String>,
        /// Repair the mesh after reading.
        repair: Option<bool>,
        /// Discretization.
        laplacian: Option<String>,
        /// Scale normalisation to unit area (default true).
        normalize: Option<bool>,
        /// Pairs the eigenbasis was computed with, when more than the `k` used (the first `k`
        /// pairs of a larger basis): the replay computes the same basis, so the field is the
        /// same to the last bit.
        basis_k: Option<usize>,
        /// Number of eigenpairs (diffusion-basis, spectral-distance).
        k: Option<usize>,
        /// Diffusion time (diffusion-basis).
        t: Option<f64>,
        /// Anchor vertex (diffusion-basis).
        anchor: Option<usize>,
        /// Distance / filter (spectral-distance).
        distance: Option<String>,
        /// Source vertex (spectral-distance).
        source: Option<usize>,
        /// Constraint counts `[2, 4, 6]` or explicit `[{ vertex = 3, value = 0.0 }, ...]`
        /// (harmonic).
        constraints: Option<toml::Value>,
        /// 1 = harmonic, 2 = bi-harmonic (harmonic).
        order: Option<u32>,
        /// Output folder (relative to the experiment file's folder).
        out: Option<String>,
        /// The field (experiment = "field").
        field: Option<FieldRequest>,
        /// The point-cloud Laplacian's parameters (point-cloud inputs only; absent: the
        /// library's defaults).
        point_cloud: Option<PointCloudFile>,
        /// Picture options.
        figure: Option<FigureFile>,
    }
}

/// The harmonic constraints of a file.
#[derive(Debug, Clone, PartialEq)]
pub enum HarmonicConstraints {
    /// Default constraint counts, one map each.
    Counts(Vec<usize>),
    /// One map with these constraints.
    Explicit(Vec<Constraint>),
}

/// Turns a TOML error into one naming the line and the key of the offending line.
pub fn toml_error(e: &toml::de::Error, text: &str, origin: &str) -> ExperimentFileError {
    let msg = e.message().trim().to_string();
    if let Some(span) = e.span() {
        let start = span.start.min(text.len());
        let line_no = text[..start].matches('\n').count() + 1;
        let line = text.lines().nth(line_no - 1).unwrap_or("");
        // Unknown keys already name the key in the message.
        if let Some(key) = line
            .split('=')
            .next()
            .map(|k| k.trim().trim_matches('"'))
            .filter(|k| !k.is_empty() && line.contains('=') && !k.starts_with('['))
        {
            let full = match current_table(text, line_no) {
                Some(t) => format!("{t}.{key}"),
                None => key.to_string(),
            };
            if !msg.contains(&format!("`{key}`")) {
                return ExperimentFileError(format!("{origin}:{line_no}: key '{full}': {msg}"));
            }
        }
        return ExperimentFileError(format!("{origin}:{line_no}: {msg}"));
    }
    ExperimentFileError(format!("{origin}: {msg}"))
}

/// The `[table]` header in force at 1-based line `line_no`, if any.
fn current_table(text: &str, line_no: usize) -> Option<String> {
    let mut t = None;
    for l in text.lines().take(line_no) {
        let l = l.trim();
        if l.starts_with('[') {
            t = Some(l.trim_matches(|c| c == '[' || c == ']').trim().to_string());
        }
    }
    t
}

impl ExperimentFile {
    /// A file for `experiment` on `mesh` with nothing else set.
    pub fn new(experiment: &str, mesh: &str) -> Self {
        Self {
            experiment: experiment.into(),
            mesh: mesh.into(),
            mesh_hash: None,
            repair: None,
            laplacian: None,
            normalize: None,
            basis_k: None,
            k: None,
            t: None,
            anchor: None,
            distance: None,
            source: None,
            constraints: None,
            order: None,
            out: None,
            field: None,
            point_cloud: None,
            figure: None,
        }
    }

    /// The file of one field: `experiment = "field"` with the request in `[field]`.
    pub fn for_field(mesh: &str, request: FieldRequest) -> Self {
        Self {
            field: Some(request),
            ..Self::new("field", mesh)
        }
    }

    /// Parses and validates a file's text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Self, ExperimentFileError> {
        let f: ExperimentFile = toml::from_str(text).map_err(|e| toml_error(&e, text, origin))?;
        f.validate()
            .map_err(|e| ExperimentFileError(format!("{origin}: {e}")))?;
        Ok(f)
    }

    /// Checks every value, and that every key applies to the experiment; errors name the key.
    pub fn validate(&self) -> Result<(), ExperimentFileError> {
        let exp = self.experiment.as_str();
        if !EXPERIMENTS.contains(&exp) {
            return Err(key_err(
                "experiment",
                format!("'{exp}' is not one of {}", EXPERIMENTS.join(", ")),
            ));
        }
        let applies: &[&str] = match exp {
            "harmonic" => &["constraints", "order"],
            "diffusion-basis" => &["k", "t", "anchor", "basis_k"],
            "spectral-distance" => &["k", "distance", "source", "basis_k"],
            _ => &["field", "basis_k"],
        };
        let present = [
            ("k", self.k.is_some()),
            ("t", self.t.is_some()),
            ("anchor", self.anchor.is_some()),
            ("distance", self.distance.is_some()),
            ("source", self.source.is_some()),
            ("constraints", self.constraints.is_some()),
            ("order", self.order.is_some()),
            ("field", self.field.is_some()),
            ("basis_k", self.basis_k.is_some()),
        ];
        for (key, set) in present {
            if set && !applies.contains(&key) {
                return Err(key_err(
                    key,
                    format!(
                        "does not apply to experiment {exp} (its keys: {})",
                        applies.join(", ")
                    ),
                ));
            }
        }
        if exp == "field" && self.field.is_none() {
            return Err(key_err(
                "field",
                "experiment = \"field\" needs a [field] table with a kind (e.g. kind = \"heat\")",
            ));
        }
        if self.mesh.trim().is_empty() {
            return Err(key_err("mesh", "is empty"));
        }
        if let Some(h) = &self.mesh_hash
            && !(h.len() == 64 && h.chars().all(|c| c.is_ascii_hexdigit()))
        {
            return Err(key_err(
                "mesh_hash",
                "must be 64 hexadecimal digits (blake3)",
            ));
        }
        self.laplacian()?;
        if let Some(k) = self.k
            && k == 0
        {
            return Err(key_err("k", "must be at least 1"));
        }
        if let Some(t) = self.t
            && !(t.is_finite() && t > 0.0)
        {
            return Err(key_err("t", format!("{t}: must be a positive number")));
        }
        if let Some(o) = self.order
            && o != 1
            && o != 2
        {
            return Err(key_err(
                "order",
                format!("{o}: must be 1 (harmonic) or 2 (bi-harmonic)"),
            ));
        }
        if let Some(d) = &self.distance {
            d.parse::<DistanceSpec>()
                .map_err(|e| key_err("distance", e))?;
        }
        if exp == "harmonic" {
            self.harmonic_constraints()?;
        }
        if let Some(r) = self.request() {
            r.validate().map_err(|e| {
                if exp == "field" {
                    ExperimentFileError(format!("key 'field.{e}"))
                } else {
                    ExperimentFileError(format!("key '{e}"))
                }
            })?;
            if let (Some(bk), Some(k)) = (self.basis_k, r.eigenpairs())
                && bk < k
            {
                return Err(key_err(
                    "basis_k",
                    format!("{bk}: must be at least the k used ({k})"),
                ));
            }
        }
        if let Some(o) = &self.out
            && o.trim().is_empty()
        {
            return Err(key_err("out", "is empty"));
        }
        if let Some(f) = &self.figure {
            if let Some(l) = f.levels
                && l > crate::defaults::values::MAX_LEVELS
            {
                return Err(key_err(
                    "figure.levels",
                    format!("{l}: at most {}", crate::defaults::values::MAX_LEVELS),
                ));
            }
            if let Some(s) = f.size {
                crate::defaults::values::check_picture_size(s)
                    .map_err(|e| key_err("figure.size", e))?;
            }
            if let Some(s) = f.height
                && !(16..=8192).contains(&s)
            {
                return Err(key_err("figure.height", format!("{s}: must be 16..8192")));
            }
            if let Some(d) = f.dpi
                && !(1..=100_000).contains(&d)
            {
                return Err(key_err("figure.dpi", format!("{d}: must be 1..100000")));
            }
        }
        if let Some(p) = &self.point_cloud {
            p.params()
                .validate()
                .map_err(|e| key_err("point_cloud", e))?;
        }
        Ok(())
    }

    /// The point-cloud Laplacian's parameters: the `[point_cloud]` keys over the
    /// library's defaults (the defaults when the table is absent).
    pub fn point_cloud_params(&self) -> PointCloudParams {
        self.point_cloud.map(|p| p.params()).unwrap_or_default()
    }

    /// The Laplacian (default fem).
    pub fn laplacian(&self) -> Result<Laplacian, ExperimentFileError> {
        match &self.laplacian {
            None => Ok(Laplacian::Fem),
            Some(s) => s.parse::<Laplacian>().map_err(|e| key_err("laplacian", e)),
        }
    }

    /// Scale normalisation (default true).
    pub fn normalize(&self) -> bool {
        self.normalize.unwrap_or(crate::defaults::values::NORMALIZE)
    }

    /// The field request of a `diffusion-basis`, `spectral-distance` or `field` file
    /// (`None` for `harmonic`, the paper's several maps). Unparsable keys give `None`;
    /// [`ExperimentFile::validate`] reports them.
    pub fn request(&self) -> Option<FieldRequest> {
        let k = self.k.unwrap_or(crate::analysis::request::DEFAULT_K);
        match self.experiment.as_str() {
            "diffusion-basis" => Some(FieldRequest::Heat {
                anchor: self.anchor,
                t: self.t.unwrap_or(crate::analysis::request::DEFAULT_HEAT_T),
                kernel: Kernel::Wfem,
                k,
            }),
            "spectral-distance" => Some(FieldRequest::Distance {
                source: self.source,
                distance: match &self.distance {
                    Some(d) => d.parse().ok()?,
                    None => DistanceSpec::default(),
                },
                k,
            }),
            "field" => self.field.clone(),
            _ => None,
        }
    }

    /// The harmonic constraints (default counts 2, 4, 6).
    pub fn harmonic_constraints(&self) -> Result<HarmonicConstraints, ExperimentFileError> {
        let Some(v) = &self.constraints else {
            return Ok(HarmonicConstraints::Counts(vec![2, 4, 6]));
        };
        let arr = v.as_array().ok_or_else(|| {
            key_err(
                "constraints",
                "must be an array of counts [2, 4, 6] or of tables { vertex = V, value = X }",
            )
        })?;
        if arr.is_empty() {
            return Err(key_err("constraints", "is empty"));
        }
        if arr.iter().all(|x| x.is_integer()) {
            let mut counts = Vec::new();
            for x in arr {
                let c = x.as_integer().unwrap_or(0);
                if !matches!(c, 2 | 4 | 6) {
                    return Err(key_err(
                        "constraints",
                        format!("count {c}: the default constraint counts are 2, 4 or 6"),
                    ));
                }
                counts.push(c as usize);
            }
            return Ok(HarmonicConstraints::Counts(counts));
        }
        let mut list = Vec::new();
        for (i, x) in arr.iter().enumerate() {
            let bad = |m: &str| key_err(&format!("constraints[{i}]"), m);
            let t = x
                .as_table()
                .ok_or_else(|| bad("expected { vertex = V, value = X } or a count"))?;
            if let Some(k) = t.keys().find(|k| *k != "vertex" && *k != "value") {
                return Err(bad(&format!(
                    "unknown key '{k}' (expected vertex and value)"
                )));
            }
            let vertex = t
                .get("vertex")
                .and_then(|v| v.as_integer())
                .filter(|v| *v >= 0)
                .ok_or_else(|| bad("'vertex' must be a non-negative integer"))?;
            let value = t
                .get("value")
                .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad("'value' must be a finite number"))?;
            list.push(Constraint {
                vertex: vertex as usize,
                value,
            });
        }
        Ok(HarmonicConstraints::Explicit(list))
    }

    /// Sets `constraints` from the harmonic experiment's counts or explicit list.
    pub fn set_harmonic_constraints(&mut self, c: &HarmonicConstraints) {
        self.constraints = Some(match c {
            HarmonicConstraints::Explicit(list) => toml::Value::Array(
                list.iter()
                    .map(|c| {
                        toml::Value::Table(
                            [
                                ("vertex".to_string(), toml::Value::Integer(c.vertex as i64)),
                                ("value".to_string(), toml::Value::Float(c.value)),
                            ]
                            .into_iter()
                            .collect(),
                        )
                    })
                    .collect(),
            ),
            HarmonicConstraints::Counts(counts) => toml::Value::Array(
                counts
                    .iter()
                    .map(|&c| toml::Value::Integer(c as i64))
                    .collect(),
            ),
        });
    }

    /// The file as TOML text, with a header comment.
    pub fn to_toml(&self) -> Result<String, ExperimentFileError> {
        let body = toml::to_string(self).map_err(|e| ExperimentFileError(e.to_string()))?;
        Ok(format!(
            "# spectral-mesh experiment file: replay with `spectral-mesh run FILE.toml`.\n\
             # Relative paths are relative to this file's folder; see docs/experiment-files.md.\n{body}"
        ))
    }
}

impl From<&Constraints> for HarmonicConstraints {
    fn from(c: &Constraints) -> Self {
        match c {
            Constraints::Preset(n) => HarmonicConstraints::Counts(vec![*n]),
            Constraints::List(l) => HarmonicConstraints::Explicit(l.clone()),
        }
    }
}

/// Expands `${VAR}` (and `$VAR`) from the environment; an unset variable is an error.
pub fn expand_env(s: &str) -> Result<String, ExperimentFileError> {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let (name, tail) = if let Some(b) = after.strip_prefix('{') {
            let end = b
                .find('}')
                .ok_or_else(|| ExperimentFileError(format!("{s}: unclosed ${{ in a path")))?;
            (&b[..end], &b[end + 1..])
        } else {
            let end = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            (&after[..end], &after[end..])
        };
        if name.is_empty() {
            out.push('$');
        } else {
            let v = std::env::var(name).map_err(|_| {
                ExperimentFileError(format!("{s}: environment variable {name} is not set"))
            })?;
            out.push_str(&v);
        }
        rest = tail;
    }
    out.push_str(rest);
    Ok(out)
}

/// Resolves a mesh entry of a file in folder `base`: `${VAR}` expanded; an existing file
/// (absolute, or relative to `base`) gives its path, anything else is returned as is (a
/// shape spec, or a missing file that the loader will report).
pub fn resolve_mesh(entry: &str, base: &Path) -> Result<String, ExperimentFileError> {
    let e = expand_env(entry)?;
    let p = Path::new(&e);
    if p.is_absolute() {
        return Ok(e);
    }
    let joined = base.join(p);
    if joined.exists() {
        return Ok(joined.to_string_lossy().into_owned());
    }
    Ok(e)
}

/// `target` written relative to folder `base` when both resolve (with `..` as needed),
/// else `target` made absolute.
pub fn relative_path(target: &Path, base: &Path) -> PathBuf {
    let abs = |p: &Path| -> PathBuf {
        std::fs::canonicalize(p).unwrap_or_else(|_| {
            if p.is_absolute() {
                p.to_path_buf()
            } else {
                std::env::current_dir()
                    .map(|d| d.join(p))
                    .unwrap_or_else(|_| p.to_path_buf())
            }
        })
    };
    let (t, b) = (abs(target), abs(base));
    let tc: Vec<Component> = t.components().collect();
    let bc: Vec<Component> = b.components().collect();
    let common = tc.iter().zip(&bc).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return t;
    }
    let mut r = PathBuf::new();
    for _ in common..bc.len() {
        r.push("..");
    }
    for c in &tc[common..] {
        r.push(c.as_os_str());
    }
    if r.as_os_str().is_empty() {
        r.push(".");
    }
    r
}

/// The folder of `file` (`.` for a bare name).
pub fn parent_dir(file: &Path) -> PathBuf {
    match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        ExperimentFile::parse(text, "f.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn errors_name_the_key() {
        let base = "experiment = \"diffusion-basis\"\nmesh = \"sphere:res=2\"\n";
        for (extra, key) in [
            ("k = \"ten\"\n", "key 'k'"),
            ("k = -3\n", "key 'k'"),
            ("k = 0\n", "key 'k'"),
            ("t = -1.0\n", "key 't'"),
            ("t = \"x\"\n", "key 't'"),
            ("laplacian = \"fen\"\n", "key 'laplacian'"),
            ("colour = 3\n", "colour"),
            ("order = 2\n", "key 'order'"),
            ("anchor = 1.5\n", "key 'anchor'"),
            ("[figure]\nsize = 3\n", "key 'figure.size'"),
            ("[figure]\nlevels = \"many\"\n", "key 'figure.levels'"),
            ("[figure]\nshiny = true\n", "shiny"),
            ("mesh_hash = \"abc\"\n", "key 'mesh_hash'"),
            ("basis_k = 5\nk = 10\n", "key 'basis_k'"),
        ] {
            let e = err(&format!("{base}{extra}"));
            assert!(e.contains(key), "{extra:?}: {e}");
        }
        let e = err("experiment = \"heat\"\nmesh = \"x\"\n");
        assert!(e.contains("key 'experiment'"), "{e}");
        let e = err("mesh = \"x\"\n");
        assert!(e.contains("experiment"), "{e}");
        let h = "experiment = \"harmonic\"\nmesh = \"x\"\n";
        for (extra, key) in [
            ("constraints = [3]\n", "key 'constraints'"),
            (
                "constraints = [{ vertex = -1, value = 0.0 }]\n",
                "constraints[0]",
            ),
            ("constraints = \"2\"\n", "key 'constraints'"),
            ("order = 3\n", "key 'order'"),
            ("t = 0.5\n", "key 't'"),
        ] {
            let e = err(&format!("{h}{extra}"));
            assert!(e.contains(key), "{extra:?}: {e}");
        }
        let d = "experiment = \"spectral-distance\"\nmesh = \"x\"\n";
        let e = err(&format!("{d}distance = \"diffusion:t=-1\"\n"));
        assert!(e.contains("key 'distance'"), "{e}");
        let f = "experiment = \"field\"\nmesh = \"x\"\n";
        assert!(err(f).contains("key 'field'"));
        let e = err(&format!("{f}[field]\nkind = \"heat\"\nt = -2.0\n"));
        assert!(e.contains("key 'field.t"), "{e}");
        let e = err(&format!("{f}[field]\nkind = \"heat\"\nsource = 2\n"));
        assert!(e.contains("source"), "{e}");
        let e = err(&format!("{f}k = 3\n[field]\nkind = \"heat\"\n"));
        assert!(e.contains("key 'k'"), "{e}");
    }

    #[test]
    fn field_files_round_trip_and_map_to_requests() {
        let req: FieldRequest = serde_json::from_str(
            r#"{"kind": "distance", "source": 4, "distance": "wfem-diffusion:t=0.25", "k": 30}"#,
        )
        .unwrap();
        let mut f = ExperimentFile::for_field("sphere:res=2", req.clone());
        f.basis_k = Some(60);
        f.normalize = Some(false);
        f.figure = Some(FigureFile {
            levels: Some(7),
            ..Default::default()
        });
        let text = f.to_toml().unwrap();
        let g = ExperimentFile::parse(&text, "x").unwrap();
        assert_eq!(f, g);
        assert_eq!(g.request(), Some(req));
        let paper = ExperimentFile::parse(
            "experiment = \"diffusion-basis\"\nmesh = \"x\"\nt = 0.25\n",
            "p",
        )
        .unwrap();
        assert_eq!(
            paper.request(),
            Some(FieldRequest::Heat {
                anchor: None,
                t: 0.25,
                kernel: Kernel::Wfem,
                k: 100
            })
        );
    }

    #[test]
    fn a_geodesic_field_file_parses_round_trips_and_names_its_errors() {
        let base = "experiment = \"field\"\nmesh = \"3torus\"\n[field]\nkind = \"geodesic\"\n";
        let f = ExperimentFile::parse(
            &format!("{base}source = 3\nsources = [7, 9]\ntime_factor = 2.0\nconvention = \"potpourri3d\"\n"),
            "g.toml",
        )
        .unwrap();
        let req = FieldRequest::Geodesic {
            source: Some(3),
            sources: vec![7, 9],
            time_factor: 2.0,
            convention: crate::geodesic::Convention::Potpourri3d,
        };
        assert_eq!(f.request(), Some(req.clone()));
        let back = ExperimentFile::parse(
            &ExperimentFile::for_field("3torus", req.clone())
                .to_toml()
                .unwrap(),
            "x",
        )
        .unwrap();
        assert_eq!(back.request(), Some(req));
        // Defaults; a basis_k has no meaning without eigenpairs, and is not asked for.
        let d = ExperimentFile::parse(base, "g.toml").unwrap();
        assert_eq!(
            d.request(),
            Some(FieldRequest::Geodesic {
                source: None,
                sources: vec![],
                time_factor: crate::analysis::request::DEFAULT_GEODESIC_TIME_FACTOR,
                convention: Default::default(),
            })
        );
        for (extra, says) in [
            ("time_factor = 0.0\n", "time_factor"),
            ("k = 30\n", "unknown field"),
            ("convention = \"exact\"\n", "exact"),
        ] {
            let e = ExperimentFile::parse(&format!("{base}{extra}"), "g.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains("g.toml") && e.contains(says), "{extra:?}: {e}");
        }
    }

    #[test]
    fn point_cloud_parameters_round_trip_and_are_checked() {
        let params = PointCloudParams {
            neighbors: 8,
            mollify_factor: 3.0e-6,
            normals: NormalSource::FromCloud,
            union: TriangleUnion::Interleaved,
            ..PointCloudParams::default()
        };
        let mut f = ExperimentFile::for_field("scan.xyz", FieldRequest::default());
        f.point_cloud = Some(PointCloudFile::from_params(&params));
        let text = f.to_toml().unwrap();
        assert!(text.contains("[point_cloud]"), "{text}");
        assert!(text.contains("normals = \"from-cloud\""), "{text}");
        let g = ExperimentFile::parse(&text, "x").unwrap();
        assert_eq!(f, g);
        assert_eq!(g.point_cloud_params(), params);
        // Absent keys (and an absent table) are the library's defaults.
        let base = "experiment = \"diffusion-basis\"\nmesh = \"scan.xyz\"\n";
        let h =
            ExperimentFile::parse(&format!("{base}[point_cloud]\nneighbors = 12\n"), "p").unwrap();
        assert_eq!(
            h.point_cloud_params(),
            PointCloudParams {
                neighbors: 12,
                ..PointCloudParams::default()
            }
        );
        let none = ExperimentFile::parse(base, "p").unwrap();
        assert_eq!(none.point_cloud_params(), PointCloudParams::default());
        for (extra, key) in [
            ("[point_cloud]\nneighbors = 1\n", "key 'point_cloud'"),
            (
                "[point_cloud]\nmollify_factor = -1.0\n",
                "key 'point_cloud'",
            ),
            (
                "[point_cloud]\nnormals = \"guess\"\n",
                "point_cloud.normals",
            ),
            ("[point_cloud]\nk = 3\n", "unknown field `k`"),
        ] {
            let e = err(&format!("{base}{extra}"));
            assert!(e.contains(key), "{extra:?}: {e}");
        }
    }

    #[test]
    fn saved_keys_keep_their_names_order_and_absence() {
        let mut f = ExperimentFile::new("diffusion-basis", "bunny.off");
        f.mesh_hash = Some("ab".repeat(32));
        f.laplacian = Some("fem".into());
        f.normalize = Some(true);
        f.k = Some(30);
        f.t = Some(0.25);
        f.anchor = Some(4);
        f.out = Some("out".into());
        f.point_cloud = Some(PointCloudFile {
            neighbors: Some(8),
            ..Default::default()
        });
        f.figure = Some(FigureFile {
            levels: Some(7),
            colormap: Some("hue".into()),
            dpi: Some(300),
            ..Default::default()
        });
        let body = toml::to_string(&f).unwrap();
        let expected = format!(
            "experiment = \"diffusion-basis\"\nmesh = \"bunny.off\"\nmesh_hash = \"{}\"\n\
             laplacian = \"fem\"\nnormalize = true\nk = 30\nt = 0.25\nanchor = 4\nout = \"out\"\n\
             \n[point_cloud]\nneighbors = 8\n\n[figure]\nlevels = 7\ncolormap = \"hue\"\ndpi = 300\n",
            "ab".repeat(32)
        );
        assert_eq!(body, expected);
        assert_eq!(ExperimentFile::parse(&body, "x").unwrap(), f);
        // Every optional key may be left out, in the file and in its tables.
        let bare = ExperimentFile::parse(
            "experiment = \"field\"\nmesh = \"x\"\n[field]\nkind = \"heat\"\n[figure]\n[point_cloud]\n",
            "x",
        )
        .unwrap();
        assert_eq!(bare.figure, Some(FigureFile::default()));
        assert_eq!(bare.point_cloud, Some(PointCloudFile::default()));
        assert_eq!(bare.mesh_hash, None);
    }

    #[test]
    fn paths_and_variables() {
        assert_eq!(
            relative_path(Path::new("/a/b/c/m.off"), Path::new("/a/b/d")),
            PathBuf::from("../c/m.off")
        );
        assert_eq!(
            relative_path(Path::new("/a/b/m.off"), Path::new("/a/b")),
            PathBuf::from("m.off")
        );
        let home = std::env::var("HOME").unwrap();
        assert_eq!(expand_env("${HOME}/x").unwrap(), format!("{home}/x"));
        assert_eq!(expand_env("$HOME/x").unwrap(), format!("{home}/x"));
        let e = expand_env("${SPECTRAL_MESH_SURELY_UNSET_VARIABLE}/x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("SPECTRAL_MESH_SURELY_UNSET_VARIABLE"));
    }
}
