//! A per-vertex field as the pictures and files users look at: PNG, VRML, coloured PLY and
//! text. The one figure code of every face (CLI, web app, Python): the same field with the
//! same options gives the same bytes whichever face wrote it.

use std::path::Path;

use spectral_mesh::Mesh;
use spectral_mesh::analysis::{Analysis, CriticalReport, Field};
use spectral_mesh::fields::critical_points::CriticalPoints;
use spectral_mesh::fields::persistence::simplified_critical_points;
use spectral_mesh::io::{MeshFormat, WriteOptions, write_atomic, write_mesh_to};

use crate::description::{FieldSummary, FigureDescription, MarkSet, describe};
use crate::overlay::{colorbar_room, draw_overlays};
use crate::raster::{
    Background, ColorBar, Marker, MarkerKind, RenderOptions, Scene, View, colour_range,
    field_colors, render_scene,
};
use crate::{Image, RenderError, extract_level_sets, write_vrml};

pub use crate::options::{Canvas, FigureError, FigureOptions};
pub use crate::raster::view_name;

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
    /// A segmentation's labels (one per vertex): its `.txt` holds them as integers, as
    /// every face writes a segmentation.
    pub labels: Option<&'a [usize]>,
    /// How to draw.
    pub options: FigureOptions,
    /// What the description says of the field (range, marks, words of the colour bar).
    pub summary: FieldSummary,
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
        let mut summary = FieldSummary::of_values(field);
        let (critical, critical_hidden) = match options.critical_points {
            true => match simplified_critical_points(mesh, field) {
                Ok(p) => {
                    let hidden = p.hidden_minima() + p.hidden_maxima() + p.hidden_saddles();
                    summary.persistence_threshold = Some(p.thresholds.threshold);
                    (Some(p.shown), hidden)
                }
                Err(_) => (None, 0),
            },
            false => (None, 0),
        };
        summary.hidden = critical_hidden;
        let mut fig = Self {
            mesh,
            field,
            sources,
            critical,
            critical_hidden,
            colors: None,
            labels: None,
            options,
            point_radius: None,
            summary,
        };
        fig.mark();
        Ok(fig)
    }

    /// The summary's marks from the critical points and the sources (constraints kept).
    fn mark(&mut self) {
        let constraints: Vec<MarkSet> = self
            .summary
            .marks
            .iter()
            .filter(|m| m.kind == MarkerKind::Constraint)
            .cloned()
            .collect();
        let mut marks = Vec::new();
        if let Some(cp) = &self.critical {
            marks.push(MarkSet {
                kind: MarkerKind::Minimum,
                vertices: cp.minima.clone(),
            });
            marks.push(MarkSet {
                kind: MarkerKind::Maximum,
                vertices: cp.maxima.clone(),
            });
            marks.push(MarkSet {
                kind: MarkerKind::Saddle,
                vertices: cp.saddles.iter().map(|&(v, _)| v).collect(),
            });
        }
        let n = self.mesh.n_vertices();
        marks.extend(constraints);
        marks.push(MarkSet {
            kind: MarkerKind::Source,
            vertices: self.sources.iter().copied().filter(|&s| s < n).collect(),
        });
        marks.retain(|m| !m.vertices.is_empty());
        self.summary.marks = marks;
    }

    /// Marks `vertices` as constrained (squares, as on the page).
    pub fn mark_constraints(&mut self, vertices: Vec<usize>) {
        let n = self.mesh.n_vertices();
        self.summary
            .marks
            .retain(|m| m.kind != MarkerKind::Constraint);
        let vertices: Vec<usize> = vertices.into_iter().filter(|&v| v < n).collect();
        if !vertices.is_empty() {
            self.summary.marks.push(MarkSet {
                kind: MarkerKind::Constraint,
                vertices,
            });
        }
    }

    /// Uses the critical points of an analysis' report (the set every face shows): its
    /// points, how many it hides and below which persistence.
    pub fn use_report(&mut self, r: &CriticalReport) {
        self.critical = Some(r.points.clone());
        self.critical_hidden = r.hidden.minima + r.hidden.maxima + r.hidden.saddles;
        self.summary.hidden = self.critical_hidden;
        self.summary.flat = r.left_out.flat;
        self.summary.persistence_threshold = Some(r.persistence.threshold);
        self.mark();
    }

    /// The figure of a field of `an` ([`Figure::of_field`] on its mesh); for a point cloud
    /// the points are drawn as discs sized from the mean neighbour spacing
    /// ([`POINT_RADIUS_FACTOR`]) and the PLY and VRML outputs are point sets.
    pub fn of_analysis(
        an: &'a Analysis,
        field: &'a Field,
        options: FigureOptions,
    ) -> Result<Self, FigureError> {
        let report = match field.labels.is_none() && options.critical_points {
            true => an.field_critical_points(field).ok(),
            false => None,
        };
        let mut fig = Self::of_field(
            an.mesh(),
            field,
            FigureOptions {
                critical_points: false,
                ..options
            },
        )?;
        fig.options.critical_points = options.critical_points && field.labels.is_none();
        fig.point_radius = an.point_spacing().map(|h| POINT_RADIUS_FACTOR * h);
        if let Some(r) = &report {
            fig.critical = Some(r.points.clone());
            fig.critical_hidden = r.hidden.minima + r.hidden.maxima + r.hidden.saddles;
        }
        // The summary every face describes (the web page's header has the same).
        fig.summary = FieldSummary::of_field(an, field, report.as_ref());
        Ok(fig)
    }

    /// The figure of an analysis' field: its marks as sources; a segmentation is drawn
    /// with one colour per patch, no level sets and no critical points.
    pub fn of_field(
        mesh: &'a Mesh,
        field: &'a Field,
        options: FigureOptions,
    ) -> Result<Self, FigureError> {
        // The source or anchor is a star, constrained vertices squares (as on the page).
        let source: Vec<usize> = field.request.source().into_iter().collect();
        let mut fig = match &field.labels {
            Some(labels) => {
                let options = FigureOptions {
                    levels: 0,
                    critical_points: false,
                    ..options
                };
                let mut fig = Self::new(mesh, &field.values, source, options)?;
                fig.colors = Some(crate::colormap::label_colors(labels));
                fig.labels = Some(labels);
                fig.summary.segments = Some(labels.iter().max().map_or(0, |m| m + 1));
                fig
            }
            None => Self::new(mesh, &field.values, source, options)?,
        };
        fig.summary.kind = field.request.kind().into();
        fig.summary.normalized = Some(field.normalized);
        fig.summary.k = field.k;
        fig.mark_constraints(field.constraints.iter().map(|c| c.vertex).collect());
        Ok(fig)
    }

    /// The figure's description (what [`Figure::image`] draws, what the page shows).
    pub fn description(&self) -> FigureDescription {
        describe(&self.summary, &self.options)
    }

    /// The scene drawn by the PNG and VRML outputs.
    pub fn scene(&self) -> Scene<'a> {
        self.scene_of(&self.description())
    }

    fn scene_of(&self, d: &FigureDescription) -> Scene<'a> {
        let cmap = self.options.colormap;
        let range = (d.range[0], d.range[1]);
        let mut scene = Scene::new(self.mesh);
        scene.point_radius = self.point_radius;
        scene.vertex_colors = match &self.colors {
            Some(c) => c.clone(),
            None => field_colors(self.field, cmap, Some(range)),
        };
        if self.colors.is_none() && !d.levels.is_empty() {
            scene.level_sets = extract_level_sets(self.mesh, self.field, &d.levels);
        }
        let p = self.mesh.positions();
        for m in &d.marks {
            for &v in &m.vertices {
                if v < p.len() {
                    scene.markers.push(Marker {
                        position: p[v],
                        kind: m.kind,
                    });
                }
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

    /// The picture as RGBA pixels (what [`Figure::png`] encodes): the surface seen from
    /// the view (or the camera given), with the description's legend and colour bar.
    pub fn image(&self) -> Result<Image, FigureError> {
        let d = self.description();
        let mut scene = self.scene_of(&d);
        scene.colorbar = None;
        let fitted = !matches!(self.options.view, View::Camera(_));
        let opts = RenderOptions {
            width: self.options.canvas.size,
            height: self.options.canvas.height(),
            view: self.options.view,
            background: if self.options.transparent {
                Background::Transparent
            } else {
                Background::White
            },
            scale: d.scale as f32,
            reserve_bottom: if fitted { colorbar_room(&d) } else { 0 },
            ..RenderOptions::default()
        };
        let mut img = render_scene(&scene, &opts)?;
        draw_overlays(&mut img, &d, self.options.legend);
        Ok(img)
    }

    /// The PNG picture (with the print resolution asked for in its `pHYs` chunk).
    pub fn png(&self) -> Result<Vec<u8>, FigureError> {
        let img = self.image()?;
        let mut buf = Vec::new();
        img.write_png_dpi(&mut buf, self.options.canvas.dpi)?;
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
            .unwrap_or_else(|| {
                let r = colour_range(self.summary.min, self.summary.max, self.options.colormap);
                field_colors(self.field, self.options.colormap, Some(r))
            })
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
    /// bit for bit); a segmentation's labels, one integer per line.
    pub fn txt(&self) -> Vec<u8> {
        match self.labels {
            Some(labels) => labels_text(labels).into_bytes(),
            None => field_text(self.field).into_bytes(),
        }
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

/// A segmentation's labels as text, one integer per line.
pub fn labels_text(labels: &[usize]) -> String {
    let mut s = String::with_capacity(labels.len() * 3);
    for l in labels {
        s.push_str(&l.to_string());
        s.push('\n');
    }
    s
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
    use crate::Colormap;
    use spectral_mesh::analysis::{Analysis, AnalysisOptions, FieldRequest};
    use spectral_mesh::experiments::file::FigureFile;
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
            canvas: Canvas {
                size: 321,
                height: Some(200),
                scale: Some(2.0),
                dpi: Some(300),
            },
            legend: false,
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
            canvas: Canvas {
                size: 64,
                ..Default::default()
            },
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
        // A segmentation's .txt is its labels as integers, as the CLI writes them.
        let labels = s.labels.as_deref().unwrap();
        let txt = String::from_utf8(fig.bytes("txt").unwrap()).unwrap();
        let back: Vec<usize> = txt.lines().map(|l| l.parse().unwrap()).collect();
        assert_eq!(back, labels);
    }
}
