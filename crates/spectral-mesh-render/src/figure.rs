//! A per-vertex field as the pictures and files users look at: PNG, VRML, coloured PLY and
//! text. The one figure code of every face (CLI, web app, Python): the same field with the
//! same options gives the same bytes whichever face wrote it.

use std::path::Path;

use spectral_mesh::Mesh;
use spectral_mesh::analysis::{Analysis, Field};
use spectral_mesh::experiments::file::FigureFile;
use spectral_mesh::fields::critical_points::CriticalPoints;
use spectral_mesh::fields::persistence::simplified_critical_points;
use spectral_mesh::io::{IoError, MeshFormat, WriteOptions, write_atomic, write_mesh_to};

use crate::raster::{
    Background, ColorBar, Marker, MarkerKind, RenderOptions, Scene, View, field_colors,
    field_range, render_scene,
};
use crate::{Colormap, Image, RenderError, extract_level_sets, level_values, write_vrml};

/// How to draw a field. `Default` is what every face draws unless told otherwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FigureOptions {
    /// Number of evenly spaced level sets drawn over the surface (0 = none). Default the
    /// library's `spectral_mesh::defaults::LEVELS`.
    pub levels: usize,
    /// Colour map. Default the paper's hue.
    pub colormap: Colormap,
    /// View. Default iso.
    pub view: View,
    /// Picture width and height in pixels. Default the library's
    /// `spectral_mesh::defaults::PICTURE_SIZE`.
    pub size: u32,
    /// Transparent background instead of white.
    pub transparent: bool,
    /// Mark minima, maxima and saddles. Default true.
    pub critical_points: bool,
    /// Draw the colour bar. Default true.
    pub colorbar: bool,
}

impl Default for FigureOptions {
    fn default() -> Self {
        Self {
            levels: spectral_mesh::defaults::LEVELS,
            colormap: Colormap::Hue,
            view: View::Iso,
            size: spectral_mesh::defaults::PICTURE_SIZE,
            transparent: false,
            critical_points: true,
            colorbar: true,
        }
    }
}

/// Errors of the figure outputs.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// An option is invalid (named as in experiment files).
    #[error("key '{key}': {message}")]
    Option {
        /// The key.
        key: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Drawing failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// Writing a mesh format failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// Writing the file failed.
    #[error(transparent)]
    Write(#[from] spectral_mesh::io::AtomicWriteError),
    /// The field does not fit the mesh.
    #[error("the field has {got} values but the mesh has {n} vertices")]
    Length {
        /// Values.
        got: usize,
        /// Vertices.
        n: usize,
    },
    /// An unknown output type.
    #[error("{0}: unknown output type (use .png, .wrl, .ply or .txt)")]
    UnknownOutput(String),
}

impl FigureOptions {
    /// The options of an experiment file's `[figure]` table (defaults for missing keys).
    pub fn from_file(f: &FigureFile) -> Result<Self, FigureError> {
        let mut o = Self::default();
        if let Some(l) = f.levels {
            o.levels = l;
        }
        if let Some(c) = &f.colormap {
            o.colormap =
                c.parse()
                    .map_err(|e: crate::colormap::UnknownColormap| FigureError::Option {
                        key: "figure.colormap",
                        message: e.to_string(),
                    })?;
        }
        if let Some(v) = &f.view {
            o.view = v.parse().map_err(|e: RenderError| FigureError::Option {
                key: "figure.view",
                message: e.to_string(),
            })?;
        }
        if let Some(s) = f.size {
            o.size = s;
        }
        if let Some(t) = f.transparent {
            o.transparent = t;
        }
        if let Some(c) = f.critical_points {
            o.critical_points = c;
        }
        if let Some(c) = f.colorbar {
            o.colorbar = c;
        }
        Ok(o)
    }

    /// Every key written out, for saved experiment files.
    pub fn to_file(&self) -> FigureFile {
        FigureFile {
            levels: Some(self.levels),
            colormap: Some(self.colormap.to_string()),
            view: Some(view_name(self.view)),
            size: Some(self.size),
            transparent: Some(self.transparent),
            critical_points: Some(self.critical_points),
            colorbar: Some(self.colorbar),
        }
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

/// A field ready to draw.
pub struct Figure<'a> {
    /// The surface.
    pub mesh: &'a Mesh,
    /// One value per vertex.
    pub field: &'a [f64],
    /// Source / anchor / constrained vertices, marked in yellow.
    pub sources: Vec<usize>,
    /// Critical points shown (simplified by persistence, as on every face), computed once
    /// and shared by the outputs (`None` when not drawn).
    pub critical: Option<CriticalPoints>,
    /// Raw critical points (minima, maxima, saddles with multiplicity) hidden by the
    /// persistence simplification ([`spectral_mesh::fields::persistence`]).
    pub critical_hidden: usize,
    /// Explicit per-vertex colours (RGB in `[0, 1]`) replacing the colour map, e.g. for
    /// categorical labels; level sets and the colour bar are then not drawn.
    pub colors: Option<Vec<[f32; 3]>>,
    /// How to draw.
    pub options: FigureOptions,
    /// Draw the vertices as discs of this radius (world units) instead of the surface: the
    /// figure of a point cloud (see [`Figure::of_analysis`]). The PLY output is then a
    /// point set (no faces) and the VRML scene a `PointSet`.
    pub point_radius: Option<f64>,
}

/// Radius of the discs of a point cloud's picture, as a fraction of its mean neighbour
/// spacing ([`Analysis::point_spacing`]): the discs of neighbouring points overlap, so a
/// well-sampled surface looks closed (the circumradius of an equilateral triangle is
/// `0.577` of its side).
pub const POINT_RADIUS_FACTOR: f64 = 0.65;

impl<'a> Figure<'a> {
    /// Prepares a figure, computing the critical points unless turned off.
    pub fn new(
        mesh: &'a Mesh,
        field: &'a [f64],
        sources: Vec<usize>,
        options: FigureOptions,
    ) -> Result<Self, FigureError> {
        if field.len() != mesh.n_vertices() {
            return Err(FigureError::Length {
                got: field.len(),
                n: mesh.n_vertices(),
            });
        }
        let (critical, critical_hidden) = match options.critical_points {
            true => match simplified_critical_points(mesh, field) {
                Ok(p) => {
                    let hidden = p.hidden_minima() + p.hidden_maxima() + p.hidden_saddles();
                    (Some(p.shown), hidden)
                }
                Err(_) => (None, 0),
            },
            false => (None, 0),
        };
        Ok(Self {
            mesh,
            field,
            sources,
            critical,
            critical_hidden,
            colors: None,
            options,
            point_radius: None,
        })
    }

    /// The figure of a field of `an` ([`Figure::of_field`] on its mesh); for a point cloud
    /// the points are drawn as discs sized from the mean neighbour spacing
    /// ([`POINT_RADIUS_FACTOR`]) and the PLY and VRML outputs are point sets.
    pub fn of_analysis(
        an: &'a Analysis,
        field: &'a Field,
        options: FigureOptions,
    ) -> Result<Self, FigureError> {
        let mut fig = Self::of_field(an.mesh(), field, options)?;
        fig.point_radius = an.point_spacing().map(|h| POINT_RADIUS_FACTOR * h);
        Ok(fig)
    }

    /// The figure of an analysis' field: its marks as sources; a segmentation is drawn
    /// with one colour per patch, no level sets and no critical points.
    pub fn of_field(
        mesh: &'a Mesh,
        field: &'a Field,
        options: FigureOptions,
    ) -> Result<Self, FigureError> {
        match &field.labels {
            Some(labels) => {
                let options = FigureOptions {
                    levels: 0,
                    critical_points: false,
                    ..options
                };
                let mut fig = Self::new(mesh, &field.values, field.marks.clone(), options)?;
                fig.colors = Some(crate::colormap::label_colors(labels));
                Ok(fig)
            }
            None => Self::new(mesh, &field.values, field.marks.clone(), options),
        }
    }

    /// The scene drawn by the PNG and VRML outputs.
    pub fn scene(&self) -> Scene<'a> {
        let cmap = self.options.colormap;
        let range = field_range(self.field, cmap);
        let mut scene = Scene::new(self.mesh);
        scene.point_radius = self.point_radius;
        scene.vertex_colors = match &self.colors {
            Some(c) => c.clone(),
            None => field_colors(self.field, cmap, Some(range)),
        };
        if self.colors.is_none() && self.options.levels > 0 && range.1 > range.0 {
            let vals = level_values(range.0, range.1, self.options.levels);
            scene.level_sets = extract_level_sets(self.mesh, self.field, &vals);
        }
        let p = self.mesh.positions();
        if let Some(cp) = &self.critical {
            let mut add = |v: usize, kind| {
                scene.markers.push(Marker {
                    position: p[v],
                    kind,
                })
            };
            cp.minima.iter().for_each(|&v| add(v, MarkerKind::Minimum));
            cp.maxima.iter().for_each(|&v| add(v, MarkerKind::Maximum));
            cp.saddles
                .iter()
                .for_each(|&(v, _)| add(v, MarkerKind::Saddle));
        }
        for &s in &self.sources {
            if s < p.len() {
                scene.markers.push(Marker {
                    position: p[s],
                    kind: MarkerKind::Source,
                });
            }
        }
        if self.options.colorbar && self.colors.is_none() {
            scene.colorbar = Some(ColorBar {
                min: range.0,
                max: range.1,
                colormap: cmap,
            });
        }
        scene
    }

    /// The picture as RGBA pixels (what [`Figure::png`] encodes).
    pub fn image(&self) -> Result<Image, FigureError> {
        let opts = RenderOptions {
            width: self.options.size,
            height: self.options.size,
            view: self.options.view,
            background: if self.options.transparent {
                Background::Transparent
            } else {
                Background::White
            },
            ..RenderOptions::default()
        };
        Ok(render_scene(&self.scene(), &opts)?)
    }

    /// The PNG picture.
    pub fn png(&self) -> Result<Vec<u8>, FigureError> {
        let img = self.image()?;
        let mut buf = Vec::new();
        img.write_png(&mut buf)?;
        Ok(buf)
    }

    /// The VRML 2.0 scene: coloured surface, level sets, critical points.
    pub fn wrl(&self) -> Result<Vec<u8>, FigureError> {
        let mut buf = Vec::new();
        write_vrml(&mut buf, &self.scene()).map_err(RenderError::from)?;
        Ok(buf)
    }

    /// An ASCII PLY with per-vertex colours and the raw field as a `value` property.
    pub fn ply(&self) -> Result<Vec<u8>, FigureError> {
        let colors = self
            .colors
            .clone()
            .unwrap_or_else(|| field_colors(self.field, self.options.colormap, None))
            .into_iter()
            .map(|c| c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8))
            .collect::<Vec<_>>();
        if self.point_radius.is_some() {
            return Ok(point_ply(self.mesh.positions(), &colors, self.field));
        }
        let mut buf = Vec::new();
        write_mesh_to(
            &mut buf,
            MeshFormat::Ply,
            self.mesh,
            &WriteOptions {
                format: Some(MeshFormat::Ply),
                vertex_colors: Some(colors),
                vertex_scalar: Some(("value".into(), self.field.to_vec())),
                binary: false,
            },
        )?;
        Ok(buf)
    }

    /// The field, one value per line at full precision (NumPy's `loadtxt` reads it back
    /// bit for bit).
    pub fn txt(&self) -> Vec<u8> {
        field_text(self.field).into_bytes()
    }

    /// The output of `format` (`png`, `wrl`/`vrml`, `ply`, `txt`).
    pub fn bytes(&self, format: &str) -> Result<Vec<u8>, FigureError> {
        match format.to_ascii_lowercase().as_str() {
            "png" => self.png(),
            "wrl" | "vrml" => self.wrl(),
            "ply" => self.ply(),
            "txt" => Ok(self.txt()),
            other => Err(FigureError::UnknownOutput(format!(".{other}"))),
        }
    }

    /// Writes the output named by `path`'s extension, atomically.
    pub fn write(&self, path: &Path) -> Result<(), FigureError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        let bytes = self.bytes(&ext).map_err(|e| match e {
            FigureError::UnknownOutput(_) => FigureError::UnknownOutput(path.display().to_string()),
            other => other,
        })?;
        write_atomic(path, &bytes)?;
        Ok(())
    }
}

/// An ASCII PLY point set (no faces): `x y z`, colour and the raw field as `value`.
fn point_ply(points: &[[f64; 3]], colors: &[[u8; 3]], values: &[f64]) -> Vec<u8> {
    use std::fmt::Write;
    let mut s = String::with_capacity(points.len() * 64 + 256);
    let _ = write!(
        s,
        "ply\nformat ascii 1.0\ncomment written by spectral-mesh: a point cloud and a field\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty double value\nend_header\n",
        points.len()
    );
    for ((p, c), v) in points.iter().zip(colors).zip(values) {
        let _ = writeln!(
            s,
            "{:?} {:?} {:?} {} {} {} {v:?}",
            p[0], p[1], p[2], c[0], c[1], c[2]
        );
    }
    s.into_bytes()
}

/// A per-vertex field as text: one value per line, shortest round-trip form.
pub fn field_text(values: &[f64]) -> String {
    let mut s = String::with_capacity(values.len() * 24);
    for v in values {
        s.push_str(&format!("{v:?}\n"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectral_mesh::analysis::{Analysis, AnalysisOptions, FieldRequest};
    use spectral_mesh::shapes::build_str;

    /// The picture marks the critical points simplified by persistence (as every face):
    /// a smooth field plus small ripples shows its one minimum and one maximum, not the
    /// ripples' extrema, and says how many it hides.
    #[test]
    fn the_picture_marks_the_simplified_critical_points() {
        let mesh = build_str("sphere:res=3").unwrap();
        let f: Vec<f64> = mesh
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| p[2] + 8e-3 * ((i * 7919 % 101) as f64 / 101.0))
            .collect();
        let raw = spectral_mesh::fields::critical_points::critical_points(&mesh, &f).unwrap();
        // (On this sphere the ripples make no raw extremum of their own; the count of
        // hidden points is still checked against the raw set.)
        let fig = Figure::new(&mesh, &f, Vec::new(), FigureOptions::default()).unwrap();
        let cp = fig.critical.as_ref().unwrap();
        assert_eq!(
            (cp.minima.len(), cp.maxima.len(), cp.saddle_count()),
            (1, 1, 0)
        );
        assert_eq!(
            fig.critical_hidden,
            raw.minima.len() + raw.maxima.len() + raw.saddle_count() - 2
        );
        let markers = fig
            .scene()
            .markers
            .iter()
            .filter(|m| m.kind != MarkerKind::Source)
            .count();
        assert_eq!(markers, 2);
    }

    #[test]
    fn options_round_trip_through_experiment_files() {
        let o = FigureOptions {
            levels: 7,
            colormap: Colormap::Viridis,
            view: View::Angles {
                azimuth_deg: 10.5,
                elevation_deg: -3.0,
            },
            size: 321,
            transparent: true,
            critical_points: false,
            colorbar: false,
        };
        assert_eq!(FigureOptions::from_file(&o.to_file()).unwrap(), o);
        let bad = FigureFile {
            colormap: Some("jet".into()),
            ..Default::default()
        };
        let e = FigureOptions::from_file(&bad).unwrap_err().to_string();
        assert!(e.starts_with("key 'figure.colormap'"), "{e}");
    }

    #[test]
    fn every_output_of_a_field_and_of_a_segmentation() {
        let an = Analysis::new(
            build_str("sphere:res=2").unwrap(),
            AnalysisOptions::default(),
        );
        let small = FigureOptions {
            size: 64,
            ..Default::default()
        };
        let f = an.field(&FieldRequest::default_with_k(20)).unwrap();
        let fig = Figure::of_field(an.mesh(), &f, small).unwrap();
        assert!(fig.critical.is_some() && fig.colors.is_none());
        assert_eq!(&fig.png().unwrap()[1..4], b"PNG");
        assert!(
            String::from_utf8(fig.wrl().unwrap())
                .unwrap()
                .starts_with("#VRML V2.0")
        );
        let ply = String::from_utf8(fig.ply().unwrap()).unwrap();
        assert!(ply.contains("property double value"), "{ply:.300}");
        let txt = String::from_utf8(fig.txt()).unwrap();
        let back: Vec<f64> = txt.lines().map(|l| l.parse().unwrap()).collect();
        assert_eq!(back, f.values);
        assert!(matches!(
            fig.bytes("gif"),
            Err(FigureError::UnknownOutput(_))
        ));
        let seg: FieldRequest =
            serde_json::from_str(r#"{"kind": "segmentation", "signature": "hks:t=0.01", "k": 20}"#)
                .unwrap();
        let s = an.field(&seg).unwrap();
        let fig = Figure::of_field(an.mesh(), &s, small).unwrap();
        assert!(fig.critical.is_none() && fig.colors.is_some() && fig.options.levels == 0);
    }
}
