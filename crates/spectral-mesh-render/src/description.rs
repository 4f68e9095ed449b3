//! The description of a figure: everything drawn besides the surface itself — view,
//! colour map with its stops, the range rule, level values, markers (shape, colours,
//! size, vertices), legend, colour bar with title, ticks, units and level spacing, every
//! number formatted once — as plain data. [`crate::figure::Figure`] draws its PNG from
//! it and the web page shows the same description (it receives it as JSON with each
//! field, and asks `POST /api/figure` again when only its view options change), so the
//! picture on the screen and the downloaded one are one figure.

use serde::{Deserialize, Serialize};

use crate::colormap::Colormap;
use crate::options::FigureOptions;
use crate::raster::view_name;
use crate::raster::{
    AMBIENT, DIFFUSE, LIGHT_DIRECTION, LINE_COLOR, LINE_WIDTH, MARKER_DEPTH_BIAS, MarkerKind,
    MarkerShape, colour_range, largest_marker,
};
use crate::text::format_number;
use spectral_mesh::analysis::{Analysis, CriticalReport, Field};
use spectral_mesh::fields::level_sets::level_values;

/// Number of colours of a map's stops in a description (the page's colour texture).
pub const STOPS: usize = 256;

/// The vertices marked with one kind of marker.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MarkSet {
    /// The kind.
    pub kind: MarkerKind,
    /// Vertex indices.
    pub vertices: Vec<usize>,
}

/// What a figure needs to know of its field besides the per-vertex values: kind, value
/// range, marked vertices and the words of its colour bar. Small (no per-vertex data
/// besides the marks): the page sends it back to `POST /api/figure` when it changes
/// only its colour map or levels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldSummary {
    /// The request kind (`heat`, `distance`, ...; `field` for values read from a file).
    pub kind: String,
    /// Smallest finite value.
    pub min: f64,
    /// Largest finite value.
    pub max: f64,
    /// A segmentation's number of segments (the values are labels): no level sets, no
    /// critical points, no colour map.
    #[serde(default)]
    pub segments: Option<usize>,
    /// The field is that of the shape scaled to unit area (`None`: not known).
    #[serde(default)]
    pub normalized: Option<bool>,
    /// The Laplacian's name (`None`: not known).
    #[serde(default)]
    pub laplacian: Option<String>,
    /// Eigenpairs used.
    #[serde(default)]
    pub k: Option<usize>,
    /// The input is a point cloud.
    #[serde(default)]
    pub point_cloud: bool,
    /// The field is constant up to rounding (no critical point).
    #[serde(default)]
    pub flat: bool,
    /// Raw critical points hidden by the persistence simplification.
    #[serde(default)]
    pub hidden: usize,
    /// The persistence below which they are hidden (field units).
    #[serde(default)]
    pub persistence_threshold: Option<f64>,
    /// Marked vertices: the critical points shown, the source or anchor, constraints.
    #[serde(default)]
    pub marks: Vec<MarkSet>,
}

impl FieldSummary {
    /// A summary of plain values (no request): kind `field`, the finite range.
    pub fn of_values(values: &[f64]) -> Self {
        let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
        for &v in values.iter().filter(|v| v.is_finite()) {
            min = min.min(v);
            max = max.max(v);
        }
        if min > max {
            (min, max) = (0.0, 1.0);
        }
        Self {
            kind: "field".into(),
            min,
            max,
            segments: None,
            normalized: None,
            laplacian: None,
            k: None,
            point_cloud: false,
            flat: false,
            hidden: 0,
            persistence_threshold: None,
            marks: Vec::new(),
        }
    }

    /// The summary of an analysis' field with the critical points of `report` (the
    /// analysis' [`Analysis::field_critical_points`], `None` when not drawn): kind,
    /// range, words, and the marks (critical points, constrained vertices, the source or
    /// anchor).
    pub fn of_field(an: &Analysis, field: &Field, report: Option<&CriticalReport>) -> Self {
        let mut s = Self::of_values(&field.values);
        s.kind = field.request.kind().into();
        s.segments = field
            .labels
            .as_ref()
            .map(|l| l.iter().max().map_or(0, |m| m + 1));
        s.normalized = Some(field.normalized);
        s.laplacian = Some(an.options().laplacian.name().into());
        s.k = field.k;
        s.point_cloud = an.is_point_cloud();
        let n = field.values.len();
        let mut marks = Vec::new();
        if let Some(r) = report {
            s.flat = r.left_out.flat;
            s.hidden = r.hidden.minima + r.hidden.maxima + r.hidden.saddles;
            s.persistence_threshold = Some(r.persistence.threshold);
            marks.push(MarkSet {
                kind: MarkerKind::Minimum,
                vertices: r.points.minima.clone(),
            });
            marks.push(MarkSet {
                kind: MarkerKind::Maximum,
                vertices: r.points.maxima.clone(),
            });
            marks.push(MarkSet {
                kind: MarkerKind::Saddle,
                vertices: r.points.saddles.iter().map(|&(v, _)| v).collect(),
            });
        }
        marks.push(MarkSet {
            kind: MarkerKind::Constraint,
            vertices: field.constraints.iter().map(|c| c.vertex).collect(),
        });
        marks.push(MarkSet {
            kind: MarkerKind::Source,
            vertices: field.request.source().into_iter().collect(),
        });
        for m in &mut marks {
            m.vertices.retain(|&v| v < n);
        }
        marks.retain(|m| !m.vertices.is_empty());
        s.marks = marks;
        s
    }

    /// The marked vertices of `kind`.
    pub fn marks_of(&self, kind: MarkerKind) -> impl Iterator<Item = usize> + '_ {
        self.marks
            .iter()
            .filter(move |m| m.kind == kind)
            .flat_map(|m| m.vertices.iter().copied())
    }
}

/// The quantity a field of `kind` shows: the colour bar's title.
pub fn quantity(kind: &str) -> &str {
    match kind {
        "heat" => "heat kernel k_t(anchor, x)",
        "distance" => "distance from the source",
        "harmonic" => "harmonic map value",
        "spectral-function" => "signature G(p,p)",
        "segmentation" => "segment label",
        "embedding" => "embedding coordinate",
        "eigenfunction" => "eigenfunction value",
        "diffusion" => "diffusion value",
        "hks" => "heat kernel signature",
        "wks" => "wave kernel signature",
        "geodesic" => "geodesic distance",
        "field" => "value",
        other => other,
    }
}

/// A marker's look (see [`MarkerKind`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MarkerStyle {
    /// The kind.
    pub kind: MarkerKind,
    /// The legend's words.
    pub label: String,
    /// The shape's name (`star`, `square`, `triangle-up`, `triangle-down`, `diamond`).
    pub shape: String,
    /// The outline, a closed polygon in the marker's unit box (`y` down).
    pub outline: Vec<[f64; 2]>,
    /// Fill colour `#rrggbb`.
    pub fill: String,
    /// Outline colour `#rrggbb`.
    pub stroke: String,
    /// Width of the outline as a fraction of the size.
    pub stroke_width: f64,
    /// Side of the marker's box in screen pixels.
    pub size: f64,
}

impl MarkerStyle {
    /// The style of `kind`.
    pub fn of(kind: MarkerKind) -> Self {
        Self {
            kind,
            label: kind.label().into(),
            shape: kind.shape().name().into(),
            outline: kind.shape().outline(),
            fill: hex(kind.color()),
            stroke: hex(kind.stroke()),
            stroke_width: MarkerShape::STROKE,
            size: kind.size(),
        }
    }
}

/// One row of the legend.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LegendEntry {
    /// A marker kind's name, or `level` for the level-set line.
    pub kind: String,
    /// The words.
    pub label: String,
}

/// A labelled value of the colour bar.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tick {
    /// The value.
    pub value: f64,
    /// Its label ([`format_number`]).
    pub label: String,
}

/// The colour bar: horizontal, the map from `range[0]` (left) to `range[1]` (right).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColorBarText {
    /// The quantity shown.
    pub title: String,
    /// Labelled values, left to right.
    pub ticks: Vec<Tick>,
    /// The line below: scale of the shape, Laplacian, k, level sets and their spacing.
    pub units: String,
}

/// Lighting of the surface: colour times `ambient + diffuse |n . l|` (two-sided).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Lighting {
    /// Ambient term.
    pub ambient: f64,
    /// Diffuse term.
    pub diffuse: f64,
    /// Towards the light, unit length, in camera coordinates (right, up, towards the
    /// viewer).
    pub direction: [f64; 3],
}

/// Where the overlays sit, in screen pixels (times `scale` in a picture).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    /// The legend's panel: this far from the top and right edges.
    pub legend_inset: f64,
    /// The colour bar's panel: this far from the left and bottom edges.
    pub colorbar_inset: f64,
    /// The colour bar's panel width.
    pub colorbar_width: f64,
    /// The colour bar's height.
    pub colorbar_height: f64,
    /// Text size.
    pub font_px: f64,
}

/// The layout of every figure (the page's overlays are placed the same way).
pub const LAYOUT: Layout = Layout {
    legend_inset: 10.0,
    colorbar_inset: 12.0,
    colorbar_width: 300.0,
    colorbar_height: 14.0,
    font_px: 12.0,
};

/// A figure, described (see the [module documentation](self)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FigureDescription {
    /// What it was made from (send it back with other options for another description).
    pub summary: FieldSummary,
    /// The view's text form ([`view_name`]).
    pub view: String,
    /// Picture width in pixels.
    pub width: u32,
    /// Picture height in pixels.
    pub height: u32,
    /// Picture pixels per screen pixel (markers, lines, text).
    pub scale: f64,
    /// Print resolution written in the PNG (dots per inch), if any.
    pub dpi: Option<u32>,
    /// The colour map's name.
    pub colormap: String,
    /// [`STOPS`] colours `#rrggbb` evenly spaced from `t = 0` to `t = 1` (a
    /// segmentation's patches have their own colours and no map).
    pub stops: Vec<String>,
    /// The range coloured ([`colour_range`]): values outside are clamped.
    pub range: [f64; 2],
    /// The level values drawn ([`level_values`] over `range`), ascending.
    pub levels: Vec<f64>,
    /// The spacing of the level values.
    pub level_spacing: Option<f64>,
    /// Level-line width in screen pixels.
    pub line_width: f64,
    /// Level-line colour `#rrggbb`.
    pub line_color: String,
    /// The lighting.
    pub lighting: Lighting,
    /// The look of every marker kind.
    pub marker_styles: Vec<MarkerStyle>,
    /// How far markers come towards the viewer, `[f, s]`: `f R + s u` with `R` the
    /// shape's bounding radius and `u` world units per screen pixel
    /// ([`crate::raster::MARKER_DEPTH_BIAS`]).
    pub marker_depth_bias: [f64; 2],
    /// The markers drawn (critical points only when asked for).
    pub marks: Vec<MarkSet>,
    /// The legend's rows: the kinds drawn, then the level-set line when levels are drawn.
    pub legend: Vec<LegendEntry>,
    /// A line under the legend: how many critical points persistence hides.
    pub legend_note: Option<String>,
    /// The colour bar (`None` when not drawn).
    pub colorbar: Option<ColorBarText>,
    /// Where the overlays are.
    pub layout: Layout,
}

/// `#rrggbb`.
pub fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// The [`STOPS`] colours of `map`.
pub fn stops(map: Colormap) -> Vec<String> {
    (0..STOPS)
        .map(|i| hex(map.map(i as f64 / (STOPS - 1) as f64)))
        .collect()
}

/// The description of a figure of a field summarised by `summary`, drawn with `options`.
pub fn describe(summary: &FieldSummary, options: &FigureOptions) -> FigureDescription {
    let categorical = summary.segments.is_some();
    let cmap = options.colormap;
    let (lo, hi) = colour_range(summary.min, summary.max, cmap);
    let n_levels = if categorical { 0 } else { options.levels };
    let levels = if hi > lo {
        level_values(lo, hi, n_levels)
    } else {
        Vec::new()
    };
    let level_spacing = (!levels.is_empty()).then(|| (hi - lo) / n_levels as f64);
    let marks: Vec<MarkSet> = summary
        .marks
        .iter()
        .filter(|m| !m.vertices.is_empty())
        .filter(|m| options.critical_points || m.kind.layer() > 0)
        .cloned()
        .collect();
    let mut legend: Vec<LegendEntry> = MarkerKind::ALL
        .iter()
        .filter(|k| marks.iter().any(|m| m.kind == **k))
        .map(|k| LegendEntry {
            kind: k.name().into(),
            label: k.label().into(),
        })
        .collect();
    if !levels.is_empty() {
        legend.push(LegendEntry {
            kind: "level".into(),
            label: if summary.point_cloud {
                "level set (on the triangle union)".into()
            } else {
                "level set".into()
            },
        });
    }
    let legend_note = (options.critical_points && summary.hidden > 0).then(|| {
        let below = summary
            .persistence_threshold
            .map(|t| format!(" (persistence below {})", format_number(t)))
            .unwrap_or_default();
        format!("{} critical points hidden{below}", summary.hidden)
    });
    let colorbar = options.colorbar.then(|| {
        let title = match summary.segments {
            Some(n) => format!("{} ({n} segments)", quantity(&summary.kind)),
            None => quantity(&summary.kind).to_string(),
        };
        let values = if hi > lo {
            vec![lo, 0.5 * (lo + hi), hi]
        } else {
            vec![lo]
        };
        let ticks = values
            .into_iter()
            .map(|value| Tick {
                value,
                label: format_number(value),
            })
            .collect();
        let mut units = Vec::new();
        if summary.point_cloud {
            units.push("point cloud (point-cloud Laplacian)".to_string());
        }
        match summary.normalized {
            Some(true) => units.push("shape scaled to unit area".into()),
            Some(false) => units.push("original size".into()),
            None => {}
        }
        match (&summary.laplacian, summary.k) {
            (Some(l), Some(k)) => units.push(format!("{l}, k = {k}")),
            (Some(l), None) => units.push(l.clone()),
            (None, Some(k)) => units.push(format!("k = {k}")),
            (None, None) => {}
        }
        if let Some(s) = level_spacing {
            units.push(format!(
                "{} level sets, spacing {}",
                levels.len(),
                format_number(s)
            ));
        }
        if summary.flat {
            units.push("constant field".into());
        }
        ColorBarText {
            title,
            ticks,
            units: units.join(" · "),
        }
    });
    let l = LIGHT_DIRECTION;
    let ln = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
    FigureDescription {
        summary: summary.clone(),
        view: view_name(options.view),
        width: options.canvas.size,
        height: options.canvas.height(),
        scale: options.canvas.pixel_scale(),
        dpi: options.canvas.dpi,
        colormap: cmap.name().into(),
        stops: if categorical { Vec::new() } else { stops(cmap) },
        range: [lo, hi],
        levels,
        level_spacing,
        line_width: f64::from(LINE_WIDTH),
        line_color: hex(LINE_COLOR),
        lighting: Lighting {
            ambient: f64::from(AMBIENT),
            diffuse: f64::from(DIFFUSE),
            direction: [l[0] / ln, l[1] / ln, l[2] / ln],
        },
        marker_styles: MarkerKind::ALL
            .iter()
            .map(|&k| MarkerStyle::of(k))
            .collect(),
        marker_depth_bias: [MARKER_DEPTH_BIAS, largest_marker()],
        marks,
        legend,
        legend_note,
        colorbar,
        layout: LAYOUT,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(min: f64, max: f64) -> FieldSummary {
        FieldSummary {
            kind: "heat".into(),
            normalized: Some(true),
            laplacian: Some("fem".into()),
            k: Some(100),
            hidden: 3,
            persistence_threshold: Some(1.5e-5),
            marks: vec![
                MarkSet {
                    kind: MarkerKind::Maximum,
                    vertices: vec![4],
                },
                MarkSet {
                    kind: MarkerKind::Source,
                    vertices: vec![4],
                },
            ],
            ..FieldSummary::of_values(&[min, max])
        }
    }

    /// One range rule: a diverging map is symmetric about zero, the level values and the
    /// spacing follow the range coloured, and every number is formatted once.
    #[test]
    fn the_range_rule_levels_ticks_and_words() {
        let o = FigureOptions {
            levels: 4,
            colormap: Colormap::Diverging,
            ..FigureOptions::default()
        };
        let d = describe(&summary(-1.0, 3.0), &o);
        assert_eq!(d.range, [-3.0, 3.0]);
        assert_eq!(d.levels, vec![-2.25, -0.75, 0.75, 2.25]);
        assert_eq!(d.level_spacing, Some(1.5));
        let cb = d.colorbar.as_ref().unwrap();
        assert_eq!(cb.title, "heat kernel k_t(anchor, x)");
        let labels: Vec<&str> = cb.ticks.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["-3", "0", "3"]);
        assert_eq!(
            cb.units,
            "shape scaled to unit area · fem, k = 100 · 4 level sets, spacing 1.5"
        );
        assert_eq!(d.stops.len(), STOPS);
        assert_eq!(d.stops[0], "#3b4cc0");
        assert_eq!(d.stops[STOPS - 1], "#b40426");
        let kinds: Vec<&str> = d.legend.iter().map(|e| e.kind.as_str()).collect();
        assert_eq!(kinds, ["source", "maximum", "level"]);
        assert_eq!(
            d.legend_note.as_deref(),
            Some("3 critical points hidden (persistence below 1.5e-5)")
        );
        // Viridis keeps the field's own range.
        let v = describe(&summary(-1.0, 3.0), &FigureOptions::default());
        assert_eq!(v.range, [-1.0, 3.0]);
        // Without critical points: the source stays, the maximum and the note go.
        let o = FigureOptions {
            critical_points: false,
            ..FigureOptions::default()
        };
        let d = describe(&summary(0.0, 1.0), &o);
        assert_eq!(d.marks.len(), 1);
        assert_eq!(d.marks[0].kind, MarkerKind::Source);
        assert!(d.legend_note.is_none());
        // The JSON the page reads parses back.
        let j = serde_json::to_string(&d).unwrap();
        let back: FigureDescription = serde_json::from_str(&j).unwrap();
        assert_eq!(back, d);
        assert!(j.contains("\"kind\":\"source\""), "{j:.200}");
    }
}
