//! Experiment files (`run FILE.toml`, `--save-experiment FILE.toml`): one experiment with
//! every parameter written out. The format is documented in `docs/experiment-files.md`.

use std::path::{Component, Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use serde::{Deserialize, Serialize};
use spectral_mesh::Laplacian;
use spectral_mesh::fields::harmonic::Constraint;
use spectral_mesh::spectral::filters::Filter;
use spectral_mesh_render::Colormap;
use spectral_mesh_render::raster::View;

use crate::figure::FigureArgs;

/// The experiments a file can name.
pub const EXPERIMENTS: [&str; 3] = ["harmonic", "diffusion-basis", "spectral-distance"];

/// Picture options (`[figure]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FigureFile {
    /// Number of level sets (0 = none).
    pub levels: Option<usize>,
    /// Colour map name.
    pub colormap: Option<String>,
    /// View: front, side, top, iso or "AZ,EL".
    pub view: Option<String>,
    /// Picture size in pixels.
    pub size: Option<u32>,
    /// Transparent background.
    pub transparent: Option<bool>,
    /// Mark critical points.
    pub critical_points: Option<bool>,
    /// Draw the colour bar.
    pub colorbar: Option<bool>,
}

/// An experiment file. Every key but `experiment` and `mesh` is optional on reading (the
/// command's default applies); saved files write every key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentFile {
    /// harmonic | diffusion-basis | spectral-distance.
    pub experiment: String,
    /// Mesh file (relative to the experiment file's folder, `${VAR}` expanded) or shape.
    pub mesh: String,
    /// blake3 of the mesh as read (before any repair).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh_hash: Option<String>,
    /// Repair the mesh after reading.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub repair: Option<bool>,
    /// Discretization.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub laplacian: Option<String>,
    /// Number of eigenpairs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k: Option<usize>,
    /// Diffusion time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t: Option<f64>,
    /// Scale normalisation to unit area.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normalize: Option<bool>,
    /// Anchor vertex (diffusion-basis).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anchor: Option<usize>,
    /// Distance / filter (spectral-distance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distance: Option<String>,
    /// Source vertex (spectral-distance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<usize>,
    /// Constraint counts `[2, 4, 6]` or explicit `[{ vertex = 3, value = 0.0 }, ...]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraints: Option<toml::Value>,
    /// 1 = harmonic, 2 = bi-harmonic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u32>,
    /// Output folder (relative to the experiment file's folder).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub out: Option<String>,
    /// Picture options.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub figure: Option<FigureFile>,
}

/// The harmonic constraints of a file.
#[derive(Debug, Clone, PartialEq)]
pub enum Constraints {
    /// Default constraint counts, one map each.
    Counts(Vec<usize>),
    /// One map with these constraints.
    Explicit(Vec<Constraint>),
}

/// Turns a TOML (de)serialization error into one naming the key of the offending line.
pub fn toml_error(e: &toml::de::Error, text: &str, origin: &str) -> anyhow::Error {
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
            let table = current_table(text, line_no);
            let full = match table {
                Some(t) => format!("{t}.{key}"),
                None => key.to_string(),
            };
            if !msg.contains(&format!("`{key}`")) {
                return anyhow!("{origin}:{line_no}: key '{full}': {msg}");
            }
        }
        return anyhow!("{origin}:{line_no}: {msg}");
    }
    anyhow!("{origin}: {msg}")
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

fn key_err(key: &str, msg: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("key '{key}': {msg}")
}

impl ExperimentFile {
    /// Parses and validates a file's text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        let f: ExperimentFile = toml::from_str(text).map_err(|e| toml_error(&e, text, origin))?;
        f.validate().map_err(|e| anyhow!("{origin}: {e}"))?;
        Ok(f)
    }

    /// Checks every value, and that every key applies to the experiment; errors name the key.
    pub fn validate(&self) -> Result<()> {
        let exp = self.experiment.as_str();
        if !EXPERIMENTS.contains(&exp) {
            return Err(key_err(
                "experiment",
                format!("'{exp}' is not one of {}", EXPERIMENTS.join(", ")),
            ));
        }
        let applies: &[&str] = match exp {
            "harmonic" => &["constraints", "order"],
            "diffusion-basis" => &["k", "t", "anchor", "normalize"],
            _ => &["k", "distance", "source", "normalize"],
        };
        let present = [
            ("k", self.k.is_some()),
            ("t", self.t.is_some()),
            ("anchor", self.anchor.is_some()),
            ("normalize", self.normalize.is_some()),
            ("distance", self.distance.is_some()),
            ("source", self.source.is_some()),
            ("constraints", self.constraints.is_some()),
            ("order", self.order.is_some()),
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
            parse_distance(d).map_err(|e| key_err("distance", e))?;
        }
        self.constraints()?;
        if let Some(o) = &self.out
            && o.trim().is_empty()
        {
            return Err(key_err("out", "is empty"));
        }
        self.figure_args()?;
        Ok(())
    }

    /// The Laplacian (default fem).
    pub fn laplacian(&self) -> Result<Laplacian> {
        match &self.laplacian {
            None => Ok(Laplacian::Fem),
            Some(s) => parse_laplacian(s).map_err(|e| key_err("laplacian", e)),
        }
    }

    /// The harmonic constraints (default counts 2, 4, 6).
    pub fn constraints(&self) -> Result<Constraints> {
        let Some(v) = &self.constraints else {
            return Ok(Constraints::Counts(vec![2, 4, 6]));
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
            return Ok(Constraints::Counts(counts));
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
        Ok(Constraints::Explicit(list))
    }

    /// The picture options (defaults for missing keys).
    pub fn figure_args(&self) -> Result<FigureArgs> {
        let mut a = FigureArgs::default();
        let Some(f) = &self.figure else {
            return Ok(a);
        };
        if let Some(l) = f.levels {
            if l > 1000 {
                return Err(key_err("figure.levels", format!("{l}: at most 1000")));
            }
            a.levels = l;
        }
        if let Some(c) = &f.colormap {
            a.colormap = c
                .parse::<Colormap>()
                .map_err(|e| key_err("figure.colormap", e))?;
        }
        if let Some(v) = &f.view {
            a.view = v.parse::<View>().map_err(|e| key_err("figure.view", e))?;
        }
        if let Some(s) = f.size {
            if !(16..=8192).contains(&s) {
                return Err(key_err("figure.size", format!("{s}: must be 16..8192")));
            }
            a.size = s;
        }
        if let Some(t) = f.transparent {
            a.transparent = t;
        }
        if let Some(c) = f.critical_points {
            a.no_critical_points = !c;
        }
        if let Some(c) = f.colorbar {
            a.no_colorbar = !c;
        }
        Ok(a)
    }

    /// The file as TOML text, with a header comment.
    pub fn to_toml(&self) -> Result<String> {
        let body = toml::to_string(self)?;
        Ok(format!(
            "# spectral-mesh experiment file: replay with `spectral-mesh run FILE.toml`.\n\
             # Relative paths are relative to this file's folder; see docs/experiment-files.md.\n{body}"
        ))
    }
}

/// Every key of a figure, written out.
pub fn figure_file(a: &FigureArgs) -> FigureFile {
    FigureFile {
        levels: Some(a.levels),
        colormap: Some(a.colormap.to_string()),
        view: Some(view_name(a.view)),
        size: Some(a.size),
        transparent: Some(a.transparent),
        critical_points: Some(!a.no_critical_points),
        colorbar: Some(!a.no_colorbar),
    }
}

/// The text form of a view that parses back to it.
pub fn view_name(v: View) -> String {
    match v {
        View::Front => "front".into(),
        View::Side => "side".into(),
        View::Top => "top".into(),
        View::Iso => "iso".into(),
        View::Angles {
            azimuth_deg,
            elevation_deg,
        } => format!("{azimuth_deg:?},{elevation_deg:?}"),
    }
}

/// Parses a Laplacian name.
pub fn parse_laplacian(s: &str) -> Result<Laplacian> {
    Laplacian::ALL
        .into_iter()
        .find(|l| l.name() == s)
        .ok_or_else(|| {
            anyhow!(
                "'{s}' is not one of {}",
                Laplacian::ALL.map(|l| l.name()).join(", ")
            )
        })
}

/// A distance spec: a filter, or the wFEM diffusion distance `wfem-diffusion[:t=T]` (eq. 15).
pub enum DistanceSpec {
    /// A filter `w(lambda)`.
    Filter(Filter),
    /// The wFEM diffusion distance of eq. 15 at time t.
    Wfem(f64),
}

/// Parses `--distance` / `distance`.
pub fn parse_distance(s: &str) -> Result<DistanceSpec> {
    if let Some(rest) = s.strip_prefix("wfem-diffusion") {
        let t = rest.trim_start_matches(':').trim_start_matches("t=").trim();
        let t = if t.is_empty() {
            0.5
        } else {
            t.parse::<f64>()
                .map_err(|_| anyhow!("{s}: bad time '{t}'"))?
        };
        if !(t.is_finite() && t > 0.0) {
            bail!("{s}: the time must be a positive number");
        }
        return Ok(DistanceSpec::Wfem(t));
    }
    Ok(DistanceSpec::Filter(s.parse::<Filter>()?))
}

/// Expands `${VAR}` (and `$VAR`) from the environment; an unset variable is an error.
pub fn expand_env(s: &str) -> Result<String> {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let (name, tail) = if let Some(b) = after.strip_prefix('{') {
            let end = b
                .find('}')
                .ok_or_else(|| anyhow!("{s}: unclosed ${{ in a path"))?;
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
            let v = std::env::var(name)
                .map_err(|_| anyhow!("{s}: environment variable {name} is not set"))?;
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
pub fn resolve_mesh(entry: &str, base: &Path) -> Result<String> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        format!("{:#}", ExperimentFile::parse(text, "f.toml").unwrap_err())
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
            ("[figure]\nview = \"up\"\n", "key 'figure.view'"),
            ("[figure]\ncolormap = \"jet\"\n", "key 'figure.colormap'"),
            ("[figure]\nlevels = \"many\"\n", "key 'figure.levels'"),
            ("[figure]\nshiny = true\n", "shiny"),
            ("mesh_hash = \"abc\"\n", "key 'mesh_hash'"),
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
            (
                "constraints = [{ vertex = 1, val = 0.0 }]\n",
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
    }

    #[test]
    fn a_full_file_round_trips() {
        let f = ExperimentFile {
            experiment: "harmonic".into(),
            mesh: "3torus".into(),
            mesh_hash: Some("0".repeat(64)),
            repair: Some(false),
            laplacian: Some("voronoi-cot".into()),
            k: None,
            t: None,
            normalize: None,
            anchor: None,
            distance: None,
            source: None,
            constraints: Some(toml::Value::Array(vec![toml::Value::Table(
                [
                    ("vertex".to_string(), toml::Value::Integer(3)),
                    ("value".to_string(), toml::Value::Float(0.1)),
                ]
                .into_iter()
                .collect(),
            )])),
            order: Some(2),
            out: Some("out".into()),
            figure: Some(figure_file(&FigureArgs {
                view: View::Angles {
                    azimuth_deg: 10.5,
                    elevation_deg: -3.0,
                },
                ..FigureArgs::default()
            })),
        };
        let text = f.to_toml().unwrap();
        let g = ExperimentFile::parse(&text, "x").unwrap();
        assert_eq!(f, g);
        assert_eq!(
            g.constraints().unwrap(),
            Constraints::Explicit(vec![Constraint {
                vertex: 3,
                value: 0.1
            }])
        );
        assert_eq!(
            g.figure_args().unwrap().view,
            View::Angles {
                azimuth_deg: 10.5,
                elevation_deg: -3.0
            }
        );
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
        env_expansion();
    }

    fn env_expansion() {
        // HOME is set in any test environment; an unset name is an error naming it.
        let home = std::env::var("HOME").unwrap();
        assert_eq!(expand_env("${HOME}/x").unwrap(), format!("{home}/x"));
        assert_eq!(expand_env("$HOME/x").unwrap(), format!("{home}/x"));
        let e = expand_env("${SPECTRAL_MESH_SURELY_UNSET_VARIABLE}/x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("SPECTRAL_MESH_SURELY_UNSET_VARIABLE"));
    }
}
