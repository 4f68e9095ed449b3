//! A headless software renderer: z-buffered, Gouraud-shaded triangles with per-vertex
//! colours, two-sided Lambert + ambient lighting, supersampling anti-aliasing, level-set
//! lines and critical-point markers with depth tests, and an optional colour bar.
//!
//! # Camera
//!
//! World `y` is up. A view is an azimuth `a` about `y` and an elevation `e` above the
//! `xz` plane; the camera sits in the direction `d = (cos e sin a, sin e, cos e cos a)`
//! from the centre of the mesh's bounding sphere and looks back at it, with screen-right
//! `(cos a, 0, -sin a)` and screen-up `d × right`. Named views: `front` = (0°, 0°) looks
//! down `-z`; `side` = (90°, 0°) looks down `-x`; `top` = (0°, 90°) looks down `-y`
//! (screen-up is `-z`); `iso` = (45°, 35.26°). The bounding sphere (centre of the bounding
//! box, radius to the farthest vertex) is fitted into the shape's viewport minus a margin.
//!
//! # Pixels
//!
//! The picture is drawn at `supersample` times the output size and box-filtered down.
//! Pixel `(x, y)` has its centre at `(x + 0.5, y + 0.5)`, `y` downwards.

use crate::colormap::Colormap;
use crate::text;
use crate::{Image, RenderError};
use rayon::prelude::*;
use spectral_mesh::Mesh;
use spectral_mesh::fields::level_sets::LevelSet;
use spectral_mesh::mesh::{cross, dot, norm, normalize, sub};
use std::str::FromStr;

/// Largest number of output pixels accepted (`width * height`).
pub const MAX_PIXELS: u64 = 1 << 26;
/// Largest number of supersampled samples; `supersample` is lowered to stay under it.
pub const MAX_SAMPLES: u64 = 1 << 25;

/// Viewing direction.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum View {
    /// Azimuth 0°, elevation 0°: looking down `-z`, `y` up.
    Front,
    /// Azimuth 90°, elevation 0°: looking down `-x`.
    Side,
    /// Azimuth 0°, elevation 90°: looking down `-y`.
    Top,
    /// Azimuth 45°, elevation 35.264° (the cube diagonal).
    #[default]
    Iso,
    /// Explicit angles in degrees.
    Angles {
        /// Rotation about the world `y` axis.
        azimuth_deg: f64,
        /// Angle above the `xz` plane, in `[-90, 90]`.
        elevation_deg: f64,
    },
    /// A camera placed by the user (the web page's camera on screen): a perspective view
    /// of the whole picture, not fitted to the shape.
    Camera(CameraSpec),
}

/// A perspective camera in world coordinates, as a 3D viewer holds it (three.js'
/// `PerspectiveCamera` looking at the orbit target): the picture's vertical field of view
/// is `fov_deg`, its centre is `target`, screen-up is `up` made orthogonal to the viewing
/// direction. Text form: `camera:EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSpec {
    /// The eye.
    pub eye: [f64; 3],
    /// The point looked at (the centre of the picture).
    pub target: [f64; 3],
    /// Screen-up direction (need not be orthogonal to the viewing direction).
    pub up: [f64; 3],
    /// Vertical field of view in degrees, in `(0, 180)`.
    pub fov_deg: f64,
}

/// A camera's `(right, up, toward_camera, distance)`: see [`CameraSpec::frame`].
pub type CameraFrame = ([f64; 3], [f64; 3], [f64; 3], f64);

impl CameraSpec {
    /// `(right, up, toward_camera, distance)`: the orthonormal frame of the camera and the
    /// distance from the eye to the target; `None` for a degenerate camera (eye on the
    /// target, up along the viewing direction, non-finite numbers).
    pub fn frame(&self) -> Option<CameraFrame> {
        let d = sub(self.eye, self.target);
        let dist = norm(d);
        if !(dist.is_finite() && dist > 0.0 && self.fov_deg > 0.0 && self.fov_deg < 180.0) {
            return None;
        }
        let toward = [d[0] / dist, d[1] / dist, d[2] / dist];
        let r = cross(self.up, toward);
        let rl = norm(r);
        if !(rl.is_finite() && rl > 1e-12) {
            return None;
        }
        let right = [r[0] / rl, r[1] / rl, r[2] / rl];
        Some((right, cross(toward, right), toward, dist))
    }
}

impl std::fmt::Display for CameraSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [e, t, u] = [self.eye, self.target, self.up];
        write!(
            f,
            "camera:{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
            e[0], e[1], e[2], t[0], t[1], t[2], u[0], u[1], u[2], self.fov_deg
        )
    }
}

impl View {
    /// `(azimuth, elevation)` in degrees.
    pub fn angles(self) -> (f64, f64) {
        match self {
            View::Front => (0.0, 0.0),
            View::Side => (90.0, 0.0),
            View::Top => (0.0, 90.0),
            View::Iso => (45.0, (1.0f64 / 2f64.sqrt()).atan().to_degrees()),
            View::Angles {
                azimuth_deg,
                elevation_deg,
            } => (azimuth_deg, elevation_deg),
            View::Camera(c) => {
                let d = sub(c.eye, c.target);
                let l = norm(d).max(f64::MIN_POSITIVE);
                (
                    d[0].atan2(d[2]).to_degrees(),
                    (d[1] / l).clamp(-1.0, 1.0).asin().to_degrees(),
                )
            }
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
        View::Camera(c) => c.to_string(),
    }
}

/// The views with a name, the one [`view_name`] writes and [`View::from_str`] reads.
const NAMED_VIEWS: [View; 4] = [View::Front, View::Side, View::Top, View::Iso];

impl FromStr for View {
    type Err = RenderError;

    /// `front | side | top | iso | AZ,EL` (degrees) `| camera:EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV`
    /// (eye, target, up, vertical field of view in degrees: [`CameraSpec`]).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let low = s.trim().to_ascii_lowercase();
        if let Some(v) = NAMED_VIEWS.into_iter().find(|&v| view_name(v) == low) {
            return Ok(v);
        }
        if let Some(nums) = low.strip_prefix("camera:") {
            let bad = |why: &str| {
                RenderError::InvalidOption(format!(
                    "view '{s}': {why} (expected camera:EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV: eye, target, up, vertical field of view in degrees)"
                ))
            };
            let v: Vec<f64> = nums
                .split(',')
                .map(|x| x.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| bad("not a list of numbers"))?;
            if v.len() != 10 {
                return Err(bad(&format!("{} numbers", v.len())));
            }
            if v.iter().any(|x| !x.is_finite()) {
                return Err(bad("a number is not finite"));
            }
            let c = CameraSpec {
                eye: [v[0], v[1], v[2]],
                target: [v[3], v[4], v[5]],
                up: [v[6], v[7], v[8]],
                fov_deg: v[9],
            };
            if c.frame().is_none() {
                return Err(bad(
                    "the eye is on the target, up is along the viewing direction, or the field of view is not in (0, 180)",
                ));
            }
            return Ok(View::Camera(c));
        }
        let bad = || RenderError::InvalidOption(format!("unknown view '{s}'"));
        let (a, e) = low.split_once(',').ok_or_else(bad)?;
        let a: f64 = a.trim().parse().map_err(|_| bad())?;
        let e: f64 = e.trim().parse().map_err(|_| bad())?;
        if !a.is_finite() || !e.is_finite() {
            return Err(bad());
        }
        Ok(View::Angles {
            azimuth_deg: a,
            elevation_deg: e,
        })
    }
}

/// Projection model.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Projection {
    /// Parallel projection.
    #[default]
    Orthographic,
    /// Pinhole camera with the given full field of view (degrees, clamped to `[1, 150]`).
    Perspective {
        /// Full field of view in degrees.
        fov_deg: f64,
    },
}

/// What is behind the shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Background {
    /// Opaque white.
    #[default]
    White,
    /// Alpha 0 (the shape's edges get fractional alpha from anti-aliasing).
    Transparent,
    /// Opaque colour.
    Color([u8; 3]),
}

impl FromStr for Background {
    type Err = RenderError;

    /// `white | transparent | #rrggbb`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let low = s.trim().to_ascii_lowercase();
        match low.as_str() {
            "white" => return Ok(Background::White),
            "transparent" | "none" => return Ok(Background::Transparent),
            _ => {}
        }
        let bad = || RenderError::InvalidOption(format!("unknown background '{s}'"));
        let hex = low.strip_prefix('#').ok_or_else(bad)?;
        if hex.len() != 6 || !hex.is_ascii() {
            return Err(bad());
        }
        let ch = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).map_err(|_| bad());
        Ok(Background::Color([ch(0)?, ch(2)?, ch(4)?]))
    }
}

impl FromStr for Projection {
    type Err = RenderError;

    /// `orthographic | ortho | perspective` (40° field of view) `| perspective:FOV`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let low = s.trim().to_ascii_lowercase();
        let bad = || RenderError::InvalidOption(format!("unknown projection '{s}'"));
        match low.as_str() {
            "orthographic" | "ortho" => Ok(Projection::Orthographic),
            "perspective" => Ok(Projection::Perspective { fov_deg: 40.0 }),
            _ => {
                let fov = low.strip_prefix("perspective:").ok_or_else(bad)?;
                let fov: f64 = fov.trim().parse().map_err(|_| bad())?;
                if fov.is_finite() && fov > 0.0 && fov < 180.0 {
                    Ok(Projection::Perspective { fov_deg: fov })
                } else {
                    Err(bad())
                }
            }
        }
    }
}

/// Rendering parameters. `Default`: 800×800, iso view, orthographic, white background,
/// 3×3 supersampling.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Viewing direction (or the user's camera, [`View::Camera`]).
    pub view: View,
    /// Projection model of the fitted views ([`View::Camera`] is always perspective).
    pub projection: Projection,
    /// Background.
    pub background: Background,
    /// Supersampling factor per axis (1 = no anti-aliasing; clamped to `1..=4`).
    pub supersample: u32,
    /// Ambient light intensity.
    pub ambient: f32,
    /// Diffuse (Lambert) light intensity; lighting is two-sided, from
    /// [`LIGHT_DIRECTION`].
    pub diffuse: f32,
    /// Level-set line width in pixels at scale 1.
    pub line_width: f32,
    /// Level-set line colour.
    pub line_color: [u8; 3],
    /// Output pixels per screen pixel: markers ([`MarkerKind::size`]), lines and text are
    /// drawn this many times their nominal size. `0` (default): `min(width, height) / 800`.
    pub scale: f32,
    /// Empty margin around the fitted bounding sphere, as a fraction of the viewport.
    pub margin: f32,
    /// Rows at the bottom of the picture left out of the fitted views' viewport (room
    /// for the colour bar's panel).
    pub reserve_bottom: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 800,
            height: 800,
            view: View::Iso,
            projection: Projection::Orthographic,
            background: Background::White,
            supersample: 3,
            ambient: AMBIENT,
            diffuse: DIFFUSE,
            line_width: LINE_WIDTH,
            line_color: LINE_COLOR,
            scale: 0.0,
            margin: 0.04,
            reserve_bottom: 0,
        }
    }
}

impl RenderOptions {
    /// Output pixels per screen pixel ([`RenderOptions::scale`], resolved).
    pub fn pixel_scale(&self) -> f64 {
        if self.scale > 0.0 && self.scale.is_finite() {
            f64::from(self.scale)
        } else {
            (f64::from(self.width.min(self.height)) / 800.0).max(0.25)
        }
    }
}

/// Ambient light of every picture (the page's shader takes it from the figure
/// description).
pub const AMBIENT: f32 = 0.35;
/// Diffuse light of every picture.
pub const DIFFUSE: f32 = 0.65;
/// Direction towards the light in camera coordinates (right, up, towards the viewer),
/// not normalised: above left of the viewer.
pub const LIGHT_DIRECTION: [f64; 3] = [-0.35, 0.45, 1.0];
/// A marker is drawn when the surface at its centre is not nearer the viewer than the
/// marker by more than `MARKER_DEPTH_BIAS * R + s * u` (`R` the bounding sphere's radius
/// about the bounding box's centre, `s` the largest marker's size in screen pixels, `u`
/// world units per screen pixel at the camera's target): markers at a rim stay whole. The
/// page moves its markers this far towards the viewer.
pub const MARKER_DEPTH_BIAS: f64 = 0.02;

/// The depth bias of markers ([`MARKER_DEPTH_BIAS`]) for a shape of bounding radius
/// `radius` seen at `units_per_pixel` world units per screen pixel.
pub fn marker_depth_bias(radius: f64, units_per_pixel: f64) -> f64 {
    MARKER_DEPTH_BIAS * radius + largest_marker() * units_per_pixel
}

/// The largest marker's size in screen pixels.
pub fn largest_marker() -> f64 {
    MarkerKind::ALL.iter().map(|k| k.size()).fold(0.0, f64::max)
}

/// Level-set line width in screen pixels.
pub const LINE_WIDTH: f32 = 2.0;
/// Level-set line colour.
pub const LINE_COLOR: [u8; 3] = [15, 15, 15];

/// Kind of a marked point; decides its shape and colours.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum MarkerKind {
    /// Local minimum: blue triangle pointing down.
    Minimum,
    /// Local maximum: red triangle pointing up.
    Maximum,
    /// Saddle: green diamond.
    Saddle,
    /// Source / anchor vertex: yellow star with a black edge.
    Source,
    /// A constrained vertex (harmonic maps): white square with a black edge.
    Constraint,
}

/// The outline of a marker's shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerShape {
    /// Five-pointed star.
    Star,
    /// Square.
    Square,
    /// Triangle pointing up.
    TriangleUp,
    /// Triangle pointing down.
    TriangleDown,
    /// Diamond (square on its corner).
    Diamond,
}

impl MarkerShape {
    /// The name the page and the description use.
    pub fn name(self) -> &'static str {
        match self {
            MarkerShape::Star => "star",
            MarkerShape::Square => "square",
            MarkerShape::TriangleUp => "triangle-up",
            MarkerShape::TriangleDown => "triangle-down",
            MarkerShape::Diamond => "diamond",
        }
    }

    /// The outline, a closed polygon in the unit box `[0, 1]^2` of the marker (`y`
    /// down), drawn centred on the point.
    pub fn outline(self) -> Vec<[f64; 2]> {
        let k = |x: f64, y: f64| [x / 64.0, y / 64.0];
        match self {
            MarkerShape::Square => vec![k(12.0, 12.0), k(52.0, 12.0), k(52.0, 52.0), k(12.0, 52.0)],
            MarkerShape::TriangleUp => vec![k(32.0, 6.0), k(58.0, 54.0), k(6.0, 54.0)],
            MarkerShape::TriangleDown => vec![k(6.0, 10.0), k(58.0, 10.0), k(32.0, 58.0)],
            MarkerShape::Diamond => vec![k(32.0, 4.0), k(60.0, 32.0), k(32.0, 60.0), k(4.0, 32.0)],
            MarkerShape::Star => (0..10)
                .map(|i| {
                    let r = if i % 2 == 1 { 13.0 } else { 29.0 };
                    let a =
                        -std::f64::consts::FRAC_PI_2 + f64::from(i) * std::f64::consts::PI / 5.0;
                    k(32.0 + r * a.cos(), 33.0 + r * a.sin())
                })
                .collect(),
        }
    }

    /// Width of the outline's stroke, as a fraction of the marker's size.
    pub const STROKE: f64 = 5.0 / 64.0;
}

impl MarkerKind {
    /// Every kind, in the legend's order.
    pub const ALL: [MarkerKind; 5] = [
        MarkerKind::Source,
        MarkerKind::Constraint,
        MarkerKind::Maximum,
        MarkerKind::Minimum,
        MarkerKind::Saddle,
    ];

    /// Fill colour of the marker.
    pub fn color(self) -> [u8; 3] {
        match self {
            MarkerKind::Minimum => [0x1f, 0x5f, 0xe0],
            MarkerKind::Maximum => [0xe0, 0x30, 0x1e],
            MarkerKind::Saddle => [0x10, 0xa0, 0x40],
            MarkerKind::Source => [0xff, 0xd4, 0x00],
            MarkerKind::Constraint => [0xff, 0xff, 0xff],
        }
    }

    /// Colour of the outline.
    pub fn stroke(self) -> [u8; 3] {
        match self {
            MarkerKind::Source | MarkerKind::Constraint => [0, 0, 0],
            _ => [0xff, 0xff, 0xff],
        }
    }

    /// The shape.
    pub fn shape(self) -> MarkerShape {
        match self {
            MarkerKind::Minimum => MarkerShape::TriangleDown,
            MarkerKind::Maximum => MarkerShape::TriangleUp,
            MarkerKind::Saddle => MarkerShape::Diamond,
            MarkerKind::Source => MarkerShape::Star,
            MarkerKind::Constraint => MarkerShape::Square,
        }
    }

    /// Side of the marker's box in screen pixels (times [`RenderOptions::pixel_scale`]).
    pub fn size(self) -> f64 {
        match self {
            MarkerKind::Source => 22.0,
            MarkerKind::Constraint => 16.0,
            MarkerKind::Maximum | MarkerKind::Minimum => 15.0,
            MarkerKind::Saddle => 14.0,
        }
    }

    /// The name used in descriptions.
    pub fn name(self) -> &'static str {
        match self {
            MarkerKind::Minimum => "minimum",
            MarkerKind::Maximum => "maximum",
            MarkerKind::Saddle => "saddle",
            MarkerKind::Source => "source",
            MarkerKind::Constraint => "constraint",
        }
    }

    /// The legend's words.
    pub fn label(self) -> &'static str {
        match self {
            MarkerKind::Minimum => "minimum",
            MarkerKind::Maximum => "maximum",
            MarkerKind::Saddle => "saddle",
            MarkerKind::Source => "source / anchor",
            MarkerKind::Constraint => "constraint",
        }
    }

    /// Markers of higher layers are drawn over lower ones (sources and constraints over
    /// critical points).
    pub fn layer(self) -> u8 {
        match self {
            MarkerKind::Source | MarkerKind::Constraint => 1,
            _ => 0,
        }
    }
}

/// A point to mark on the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Marker {
    /// Position in world coordinates (normally a vertex).
    pub position: [f64; 3],
    /// Its kind.
    pub kind: MarkerKind,
}

/// A colour bar: the map and the field values at its two ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColorBar {
    /// Value at the bottom of the bar.
    pub min: f64,
    /// Value at the top of the bar.
    pub max: f64,
    /// The map.
    pub colormap: Colormap,
}

/// Everything drawn in one picture.
#[derive(Debug, Clone)]
pub struct Scene<'a> {
    /// The surface.
    pub mesh: &'a Mesh,
    /// One RGB colour in `[0, 1]` per vertex.
    pub vertex_colors: Vec<[f32; 3]>,
    /// Level-set lines drawn over the surface.
    pub level_sets: Vec<LevelSet>,
    /// Critical points and anchors.
    pub markers: Vec<Marker>,
    /// Optional colour bar beside the shape.
    pub colorbar: Option<ColorBar>,
    /// Draw the vertices as points instead of the triangles: each vertex is a disc of
    /// this radius (world units) facing the camera, in its colour shaded by its normal,
    /// drawn far to near (the triangles still carry the level sets). `None` (default):
    /// the surface.
    pub point_radius: Option<f64>,
}

impl<'a> Scene<'a> {
    /// A light-grey surface with no overlays.
    pub fn new(mesh: &'a Mesh) -> Self {
        Self {
            mesh,
            vertex_colors: vec![[0.8, 0.8, 0.8]; mesh.n_vertices()],
            level_sets: Vec::new(),
            markers: Vec::new(),
            colorbar: None,
            point_radius: None,
        }
    }

    /// A surface coloured by `field` through `colormap` over `range` (see
    /// [`field_range`] for `None`), with the matching colour bar.
    pub fn with_field(
        mesh: &'a Mesh,
        field: &[f64],
        colormap: Colormap,
        range: Option<(f64, f64)>,
    ) -> Self {
        let (lo, hi) = range.unwrap_or_else(|| field_range(field, colormap));
        Self {
            mesh,
            vertex_colors: field_colors(field, colormap, Some((lo, hi))),
            level_sets: Vec::new(),
            markers: Vec::new(),
            colorbar: Some(ColorBar {
                min: lo,
                max: hi,
                colormap,
            }),
            point_radius: None,
        }
    }

    /// The camera [`render_scene`] uses for this scene and these options.
    pub fn camera(&self, opts: &RenderOptions) -> Camera {
        let (vw, _) = layout(opts, self.colorbar.is_some());
        Camera::fit(self.mesh, opts, vw)
    }
}

/// The range used for `field` when none is given: [`colour_range`] of the smallest and
/// largest finite values. `(0, 1)` if nothing is finite.
pub fn field_range(field: &[f64], colormap: Colormap) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &x in field.iter().filter(|x| x.is_finite()) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if lo > hi {
        return (0.0, 1.0);
    }
    colour_range(lo, hi, colormap)
}

/// The one range rule of every face (pictures, the web page, level values): a field of
/// values in `[min, max]` is coloured over `[min, max]`, or over `[-m, m]` with
/// `m = max(|min|, |max|)` for a diverging map (white is zero). `(0, 1)` when a bound is
/// not finite.
pub fn colour_range(min: f64, max: f64, colormap: Colormap) -> (f64, f64) {
    if !min.is_finite() || !max.is_finite() || min > max {
        return (0.0, 1.0);
    }
    if colormap.is_diverging() {
        let m = min.abs().max(max.abs());
        return (-m, m);
    }
    (min, max)
}

/// Per-vertex colours of `field` through `colormap`: `t = (f - lo) / (hi - lo)` with
/// `(lo, hi) = range` or [`field_range`]. A constant range maps to `t = 0.5`; non-finite
/// values are mid-grey.
pub fn field_colors(field: &[f64], colormap: Colormap, range: Option<(f64, f64)>) -> Vec<[f32; 3]> {
    let (lo, hi) = range.unwrap_or_else(|| field_range(field, colormap));
    let span = hi - lo;
    field
        .iter()
        .map(|&f| {
            if !f.is_finite() {
                return [0.5, 0.5, 0.5];
            }
            let t = if span > 0.0 && span.is_finite() {
                (f - lo) / span
            } else {
                0.5
            };
            colormap.map_f32(t)
        })
        .collect()
}

/// Renders a mesh with per-vertex colours and no overlays.
pub fn render(
    mesh: &Mesh,
    colors: &[[f32; 3]],
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    let mut scene = Scene::new(mesh);
    scene.vertex_colors = colors.to_vec();
    render_scene(&scene, opts)
}

/// A fitted camera; maps world points to output-image pixel coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Centre of the fitted bounding sphere.
    pub center: [f64; 3],
    /// Its radius.
    pub radius: f64,
    /// Screen-right direction in world coordinates.
    pub right: [f64; 3],
    /// Screen-up direction.
    pub up: [f64; 3],
    /// Direction from the centre towards the camera.
    pub toward_camera: [f64; 3],
    /// Orthographic: pixels per world unit. Perspective: focal length in pixels.
    pub scale: f64,
    /// Perspective: distance from the camera to the centre; `None` for orthographic.
    pub distance: Option<f64>,
    /// Pixel position of the centre, `x`.
    pub cx: f64,
    /// Pixel position of the centre, `y`.
    pub cy: f64,
}

impl Camera {
    /// Fits the mesh's bounding sphere into a viewport of `viewport_width × opts.height`
    /// pixels at the left of the image.
    pub fn fit(mesh: &Mesh, opts: &RenderOptions, viewport_width: u32) -> Self {
        let (lo, hi) = mesh.bounding_box();
        let center = [
            0.5 * (lo[0] + hi[0]),
            0.5 * (lo[1] + hi[1]),
            0.5 * (lo[2] + hi[2]),
        ];
        let mut radius = mesh
            .positions()
            .iter()
            .map(|&p| norm(sub(p, center)))
            .fold(0.0, f64::max);
        if radius <= 0.0 || !radius.is_finite() {
            radius = 1.0;
        }
        if let View::Camera(spec) = opts.view
            && let Some((right, up, toward_camera, distance)) = spec.frame()
        {
            // The user's camera sees the whole picture: vertical field of view over the
            // height, centred (as a 3D viewer's canvas).
            let h = 0.5 * spec.fov_deg.to_radians();
            return Self {
                center: spec.target,
                radius,
                right,
                up,
                toward_camera,
                scale: 0.5 * f64::from(opts.height) / h.tan(),
                distance: Some(distance),
                cx: 0.5 * f64::from(opts.width),
                cy: 0.5 * f64::from(opts.height),
            };
        }
        let (az, el) = opts.view.angles();
        let (a, e) = (az.to_radians(), el.clamp(-90.0, 90.0).to_radians());
        let toward_camera = [e.cos() * a.sin(), e.sin(), e.cos() * a.cos()];
        let right = [a.cos(), 0.0, -a.sin()];
        let up = cross(toward_camera, right);
        let margin = f64::from(opts.margin).clamp(0.0, 0.45);
        let vh = opts
            .height
            .saturating_sub(opts.reserve_bottom)
            .max(opts.height / 2)
            .max(1);
        let half = 0.5 * f64::from(viewport_width.min(vh)) * (1.0 - 2.0 * margin);
        let (scale, distance) = match opts.projection {
            Projection::Orthographic => (half / radius, None),
            Projection::Perspective { fov_deg } => {
                let h = 0.5 * fov_deg.clamp(1.0, 150.0).to_radians();
                (half / h.tan(), Some(radius / h.sin()))
            }
        };
        Self {
            center,
            radius,
            right,
            up,
            toward_camera,
            scale,
            distance,
            cx: 0.5 * f64::from(viewport_width),
            cy: 0.5 * f64::from(vh),
        }
    }

    /// `[x, y, depth]`: pixel coordinates in the output image and the camera-space depth
    /// (larger is nearer the viewer).
    pub fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let q = sub(p, self.center);
        let x = dot(q, self.right);
        let y = dot(q, self.up);
        let z = dot(q, self.toward_camera);
        match self.distance {
            None => [self.cx + self.scale * x, self.cy - self.scale * y, z],
            Some(d) => {
                let w = (d - z).max(1e-9 * d);
                [
                    self.cx + self.scale * x / w,
                    self.cy - self.scale * y / w,
                    z,
                ]
            }
        }
    }

    /// Approximate pixels per world unit near the centre.
    pub fn pixels_per_unit(&self) -> f64 {
        match self.distance {
            None => self.scale,
            Some(d) => self.scale / d,
        }
    }

    fn inv_w(&self, z: f64) -> f64 {
        match self.distance {
            None => 1.0,
            Some(d) => 1.0 / (d - z).max(1e-9 * d),
        }
    }
}

/// Splits the width into the shape's viewport and the colour bar's strip.
fn layout(opts: &RenderOptions, bar: bool) -> (u32, u32) {
    if !bar {
        return (opts.width, 0);
    }
    let bar_w = (opts.width / 6).max(40).min(opts.width / 2);
    (opts.width - bar_w, bar_w)
}

struct Buffers {
    w: usize,
    h: usize,
    rgba: Vec<[u8; 4]>,
    depth: Vec<f32>,
}

/// Renders a scene. Errors on a zero or oversized image and on a colour count that
/// differs from the vertex count.
pub fn render_scene(scene: &Scene, opts: &RenderOptions) -> Result<Image, RenderError> {
    let (w, h) = (u64::from(opts.width), u64::from(opts.height));
    if w == 0 || h == 0 || w * h > MAX_PIXELS {
        return Err(RenderError::InvalidSize {
            width: opts.width,
            height: opts.height,
        });
    }
    let mesh = scene.mesh;
    if scene.vertex_colors.len() != mesh.n_vertices() {
        return Err(RenderError::ColorCount {
            expected: mesh.n_vertices(),
            got: scene.vertex_colors.len(),
        });
    }
    let mut ss = u64::from(opts.supersample.clamp(1, 4));
    while ss > 1 && w * h * ss * ss > MAX_SAMPLES {
        ss -= 1;
    }
    let ss_f = ss as f64;
    let (vw, bar_w) = layout(opts, scene.colorbar.is_some());
    let cam = Camera::fit(mesh, opts, vw);
    let mut buf = Buffers {
        w: (w * ss) as usize,
        h: (h * ss) as usize,
        rgba: vec![[0, 0, 0, 0]; (w * h * ss * ss) as usize],
        depth: vec![f32::NEG_INFINITY; (w * h * ss * ss) as usize],
    };

    // Per-vertex projection and shading.
    let [lr, lu, lt] = LIGHT_DIRECTION;
    let light = normalize([
        lr * cam.right[0] + lu * cam.up[0] + lt * cam.toward_camera[0],
        lr * cam.right[1] + lu * cam.up[1] + lt * cam.toward_camera[1],
        lr * cam.right[2] + lu * cam.up[2] + lt * cam.toward_camera[2],
    ]);
    let normals = mesh.vertex_normals();
    let (amb, dif) = (opts.ambient.max(0.0), opts.diffuse.max(0.0));
    let verts: Vec<RVert> = mesh
        .positions()
        .iter()
        .zip(&normals)
        .zip(&scene.vertex_colors)
        .map(|((&p, &n), &c)| {
            let [x, y, z] = cam.project(p);
            let lam = if n == [0.0; 3] {
                1.0
            } else {
                dot(n, light).abs() as f32
            };
            let s = amb + dif * lam;
            let sane = |v: f32| {
                if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    0.5
                }
            };
            RVert {
                x: x * ss_f,
                y: y * ss_f,
                z,
                iw: cam.inv_w(z),
                c: [sane(c[0]) * s, sane(c[1]) * s, sane(c[2]) * s],
            }
        })
        .collect();
    match scene.point_radius {
        Some(r) if r.is_finite() && r > 0.0 => {
            splat_all(&mut buf, &verts, r * cam.scale * ss_f, ss_f)
        }
        _ => raster_all(&mut buf, mesh.triangles(), &verts),
    }

    // Level-set lines.
    let ppu = cam.pixels_per_unit();
    let pscale = opts.pixel_scale();
    let line_half = 0.5 * f64::from(opts.line_width.max(0.0)) * pscale * ss_f;
    let line_bias = (0.01 * cam.radius + 4.0 / (ppu * ss_f)) as f32;
    let lc = opts.line_color;
    for ls in &scene.level_sets {
        for seg in &ls.segments {
            let a = cam.project(seg[0]);
            let b = cam.project(seg[1]);
            draw_segment(
                &mut buf,
                [a[0] * ss_f, a[1] * ss_f, a[2]],
                [b[0] * ss_f, b[1] * ss_f, b[2]],
                line_half,
                line_bias,
                lc,
            );
        }
    }

    // Markers: sources and constraints over critical points, each a shape with an
    // outline, visible when the surface at its centre does not hide it.
    let marker_bias = marker_depth_bias(cam.radius, pscale / ppu) as f32;
    let mut order: Vec<&Marker> = scene.markers.iter().collect();
    order.sort_by_key(|m| m.kind.layer());
    for m in order {
        let [x, y, z] = cam.project(m.position);
        let (sx, sy) = (x * ss_f, y * ss_f);
        if !sx.is_finite() || !sy.is_finite() {
            continue;
        }
        if marker_visible(&buf, sx, sy, z as f32, marker_bias) {
            draw_marker(&mut buf, sx, sy, m.kind.size() * pscale * ss_f, m.kind);
        }
    }

    let mut img = downsample(&buf, ss as usize, opts.background);
    if let Some(bar) = scene.colorbar {
        draw_colorbar(&mut img, vw, bar_w, &bar);
    }
    Ok(img)
}

#[derive(Debug, Clone, Copy)]
struct RVert {
    x: f64,
    y: f64,
    z: f64,
    iw: f64,
    c: [f32; 3],
}

/// Rows `[y0, y0 + rgba.len() / w)` of the supersampled buffers.
struct Band<'a> {
    w: usize,
    y0: usize,
    y1: usize,
    rgba: &'a mut [[u8; 4]],
    depth: &'a mut [f32],
}

/// Rasterizes all triangles, in parallel over horizontal bands of the buffer (each band
/// draws the triangles overlapping it, in mesh order, so the result does not depend on
/// the number of threads).
fn raster_all(buf: &mut Buffers, tris: &[[usize; 3]], verts: &[RVert]) {
    let threads = rayon::current_num_threads().max(1);
    let band_h = buf.h.div_ceil(threads * 8).max(16);
    let n_bands = buf.h.div_ceil(band_h);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); n_bands];
    for (t, tri) in tris.iter().enumerate() {
        let ys = [verts[tri[0]].y, verts[tri[1]].y, verts[tri[2]].y];
        let lo = ys[0].min(ys[1]).min(ys[2]).floor();
        let hi = ys[0].max(ys[1]).max(ys[2]).ceil();
        if !lo.is_finite() || !hi.is_finite() || hi < 0.0 || lo >= buf.h as f64 {
            continue;
        }
        let b0 = (lo.max(0.0) as usize) / band_h;
        let b1 = ((hi as usize).min(buf.h - 1)) / band_h;
        for bin in &mut bins[b0..=b1.min(n_bands - 1)] {
            bin.push(t as u32);
        }
    }
    let w = buf.w;
    let h = buf.h;
    buf.rgba
        .par_chunks_mut(band_h * w)
        .zip(buf.depth.par_chunks_mut(band_h * w))
        .zip(bins.par_iter())
        .enumerate()
        .for_each(|(b, ((rgba, depth), bin))| {
            let y0 = b * band_h;
            let mut band = Band {
                w,
                y0,
                y1: (y0 + band_h).min(h),
                rgba,
                depth,
            };
            for &t in bin {
                let [a, bb, c] = tris[t as usize];
                raster_triangle(&mut band, &verts[a], &verts[bb], &verts[c]);
            }
        });
}

/// Draws every vertex as a disc facing the camera of `radius` samples (times the
/// perspective factor, at least one output pixel across), far to near with a depth test
/// at the vertex's depth; the disc is shaded slightly darker towards its rim.
fn splat_all(buf: &mut Buffers, verts: &[RVert], radius: f64, ss: f64) {
    let mut order: Vec<usize> = (0..verts.len())
        .filter(|&i| verts[i].x.is_finite() && verts[i].y.is_finite() && verts[i].z.is_finite())
        .collect();
    order.sort_by(|&a, &b| verts[a].z.total_cmp(&verts[b].z).then(a.cmp(&b)));
    for i in order {
        let v = &verts[i];
        let r = (radius * v.iw).max(0.5 * ss);
        let r2 = r * r;
        let xmin = (v.x - r).floor().max(0.0);
        let ymin = (v.y - r).floor().max(0.0);
        let xmax = (v.x + r).ceil().min(buf.w as f64 - 1.0);
        let ymax = (v.y + r).ceil().min(buf.h as f64 - 1.0);
        if xmin > xmax || ymin > ymax {
            continue;
        }
        let z = v.z as f32;
        for py in ymin as usize..=ymax as usize {
            let dy = py as f64 + 0.5 - v.y;
            for px in xmin as usize..=xmax as usize {
                let dx = px as f64 + 0.5 - v.x;
                let d2 = dx * dx + dy * dy;
                if d2 > r2 {
                    continue;
                }
                let k = py * buf.w + px;
                if z >= buf.depth[k] {
                    buf.depth[k] = z;
                    let shade = 0.8 + 0.2 * (1.0 - d2 / r2).sqrt() as f32;
                    let c = |j: usize| fast_u8(v.c[j] * shade);
                    buf.rgba[k] = [c(0), c(1), c(2), 255];
                }
            }
        }
    }
}

fn raster_triangle(buf: &mut Band, v0: &RVert, v1: &RVert, v2: &RVert) {
    let area = (v1.x - v0.x) * (v2.y - v0.y) - (v2.x - v0.x) * (v1.y - v0.y);
    if area.abs() < 1e-12 || !area.is_finite() {
        return;
    }
    let inv_area = 1.0 / area;
    let xmin = v0.x.min(v1.x).min(v2.x).floor().max(0.0);
    let ymin = v0.y.min(v1.y).min(v2.y).floor().max(buf.y0 as f64);
    let xmax = v0.x.max(v1.x).max(v2.x).ceil().min(buf.w as f64 - 1.0);
    let ymax = v0.y.max(v1.y).max(v2.y).ceil().min(buf.y1 as f64 - 1.0);
    if xmin > xmax || ymin > ymax {
        return;
    }
    let (x0, x1) = (xmin as usize, xmax as usize);
    let (y0, y1) = (ymin as usize, ymax as usize);
    // Edge functions (normalised barycentrics): b_i = A_i x + B_i y + C_i.
    let ef = |a: &RVert, b: &RVert| {
        let aa = (a.y - b.y) * inv_area;
        let bb = (b.x - a.x) * inv_area;
        let cc = (a.x * b.y - b.x * a.y) * inv_area;
        (aa, bb, cc)
    };
    let e0 = ef(v1, v2);
    let e1 = ef(v2, v0);
    let e2 = ef(v0, v1);
    let persp = v0.iw != 1.0 || v1.iw != 1.0 || v2.iw != 1.0;
    let eps = -1e-9;
    for py in y0..=y1 {
        let y = py as f64 + 0.5;
        let row = (py - buf.y0) * buf.w;
        let xs = x0 as f64 + 0.5;
        let mut b0 = e0.0 * xs + e0.1 * y + e0.2;
        let mut b1 = e1.0 * xs + e1.1 * y + e1.2;
        let mut b2 = e2.0 * xs + e2.1 * y + e2.2;
        for px in x0..=x1 {
            if b0 >= eps && b1 >= eps && b2 >= eps {
                let (w0, w1, w2) = if persp {
                    let (a, b, c) = (b0 * v0.iw, b1 * v1.iw, b2 * v2.iw);
                    let s = a + b + c;
                    (a / s, b / s, c / s)
                } else {
                    (b0, b1, b2)
                };
                let z = (w0 * v0.z + w1 * v1.z + w2 * v2.z) as f32;
                let i = row + px;
                if z > buf.depth[i] {
                    buf.depth[i] = z;
                    let (w0, w1, w2) = (w0 as f32, w1 as f32, w2 as f32);
                    let c = |k: usize| fast_u8(w0 * v0.c[k] + w1 * v1.c[k] + w2 * v2.c[k]);
                    buf.rgba[i] = [c(0), c(1), c(2), 255];
                }
            }
            b0 += e0.0;
            b1 += e1.0;
            b2 += e2.0;
        }
    }
}

/// `[0, 1]` to 8 bits; `as` saturates out-of-range values (and maps NaN to 0).
#[inline]
fn fast_u8(v: f32) -> u8 {
    (v * 255.0 + 0.5) as u8
}

/// Whether a line point at sample `(x, y)` with depth `z` is visible: the surface sample
/// under it is not nearer by more than `bias`; where no surface is under it (past a
/// silhouette), the nearest surface within two samples decides.
fn line_point_visible(buf: &Buffers, x: f64, y: f64, z: f32, bias: f32) -> bool {
    if !x.is_finite() || !y.is_finite() {
        return false;
    }
    let xi = x.floor().clamp(0.0, buf.w as f64 - 1.0) as usize;
    let yi = y.floor().clamp(0.0, buf.h as f64 - 1.0) as usize;
    let d = buf.depth[yi * buf.w + xi];
    if d != f32::NEG_INFINITY {
        return z + bias >= d;
    }
    let mut near = f32::NEG_INFINITY;
    for yy in yi.saturating_sub(2)..=(yi + 2).min(buf.h - 1) {
        for xx in xi.saturating_sub(2)..=(xi + 2).min(buf.w - 1) {
            near = near.max(buf.depth[yy * buf.w + xx]);
        }
    }
    near == f32::NEG_INFINITY || z + bias >= near
}

/// A thick segment (capsule of half-width `half` samples) in the supersampled buffer.
/// Each pixel takes the visibility of the nearest point of the segment's centre line, so
/// the line keeps its width on steep surfaces and hidden parts stay hidden.
fn draw_segment(buf: &mut Buffers, a: [f64; 3], b: [f64; 3], half: f64, bias: f32, c: [u8; 3]) {
    if half <= 0.0 || a.iter().chain(&b).any(|v| !v.is_finite()) {
        return;
    }
    let xmin = (a[0].min(b[0]) - half).floor().max(0.0);
    let ymin = (a[1].min(b[1]) - half).floor().max(0.0);
    let xmax = (a[0].max(b[0]) + half).ceil().min(buf.w as f64 - 1.0);
    let ymax = (a[1].max(b[1]) + half).ceil().min(buf.h as f64 - 1.0);
    if xmin > xmax || ymin > ymax {
        return;
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let h2 = half * half;
    for py in ymin as usize..=ymax as usize {
        let y = py as f64 + 0.5;
        for px in xmin as usize..=xmax as usize {
            let x = px as f64 + 0.5;
            let u = if len2 > 0.0 {
                (((x - a[0]) * dx + (y - a[1]) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (qx, qy) = (a[0] + u * dx, a[1] + u * dy);
            if (qx - x).powi(2) + (qy - y).powi(2) > h2 {
                continue;
            }
            let z = (a[2] + u * (b[2] - a[2])) as f32;
            if line_point_visible(buf, qx, qy, z, bias) {
                buf.rgba[py * buf.w + px] = [c[0], c[1], c[2], 255];
            }
        }
    }
}

/// A marker is visible when the surface at its centre is not in front of it by more than `bias`.
fn marker_visible(buf: &Buffers, x: f64, y: f64, z: f32, bias: f32) -> bool {
    if x < 0.0 || y < 0.0 || x >= buf.w as f64 || y >= buf.h as f64 {
        return false;
    }
    let d = buf.depth[y as usize * buf.w + x as usize];
    d == f32::NEG_INFINITY || z + bias >= d
}

/// A marker of `size` samples (its box's side) centred at `(cx, cy)`: the shape's fill
/// with its outline stroked on the path (half inside, half outside, as a canvas does).
fn draw_marker(buf: &mut Buffers, cx: f64, cy: f64, size: f64, kind: MarkerKind) {
    if size.is_nan() || size <= 0.0 {
        return;
    }
    let pts: Vec<[f64; 2]> = kind
        .shape()
        .outline()
        .into_iter()
        .map(|[u, v]| [cx + (u - 0.5) * size, cy + (v - 0.5) * size])
        .collect();
    let half = 0.5 * MarkerShape::STROKE * size;
    let (fill, stroke) = (kind.color(), kind.stroke());
    let xmin = (cx - 0.5 * size - half).floor().max(0.0);
    let ymin = (cy - 0.5 * size - half).floor().max(0.0);
    let xmax = (cx + 0.5 * size + half).ceil().min(buf.w as f64 - 1.0);
    let ymax = (cy + 0.5 * size + half).ceil().min(buf.h as f64 - 1.0);
    if xmin > xmax || ymin > ymax {
        return;
    }
    for py in ymin as usize..=ymax as usize {
        for px in xmin as usize..=xmax as usize {
            let p = [px as f64 + 0.5, py as f64 + 0.5];
            let c = if edge_distance(&pts, p) <= half {
                stroke
            } else if inside(&pts, p) {
                fill
            } else {
                continue;
            };
            buf.rgba[py * buf.w + px] = [c[0], c[1], c[2], 255];
        }
    }
}

/// Distance from `p` to the closed polygon's edges.
pub(crate) fn edge_distance(pts: &[[f64; 2]], p: [f64; 2]) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..pts.len() {
        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l2 = dx * dx + dy * dy;
        let u = if l2 > 0.0 {
            (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        best = best.min((a[0] + u * dx - p[0]).hypot(a[1] + u * dy - p[1]));
    }
    best
}

/// Whether `p` is inside the closed polygon (even-odd rule).
pub(crate) fn inside(pts: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut c = false;
    for i in 0..pts.len() {
        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                c = !c;
            }
        }
    }
    c
}

/// Box filter of `ss × ss` samples, composited over the background.
fn downsample(buf: &Buffers, ss: usize, bg: Background) -> Image {
    let (w, h) = (buf.w / ss, buf.h / ss);
    let n = (ss * ss) as f32;
    let mut rgba = vec![0u8; w * h * 4];
    rgba.par_chunks_mut(w * 4)
        .enumerate()
        .for_each(|(y, out_row)| {
            for x in 0..w {
                let mut acc = [0f32; 3];
                let mut cover = 0f32;
                for sy in 0..ss {
                    let row = (y * ss + sy) * buf.w + x * ss;
                    for s in &buf.rgba[row..row + ss] {
                        if s[3] != 0 {
                            cover += 1.0;
                            acc[0] += f32::from(s[0]);
                            acc[1] += f32::from(s[1]);
                            acc[2] += f32::from(s[2]);
                        }
                    }
                }
                let o = x * 4;
                let px = match bg {
                    Background::Transparent => {
                        if cover == 0.0 {
                            [0, 0, 0, 0]
                        } else {
                            let q = |v: f32| (v / cover).round().clamp(0.0, 255.0) as u8;
                            let a = (255.0 * cover / n).round() as u8;
                            [q(acc[0]), q(acc[1]), q(acc[2]), a]
                        }
                    }
                    Background::White | Background::Color(_) => {
                        let b = match bg {
                            Background::Color(c) => c,
                            _ => [255, 255, 255],
                        };
                        let empty = n - cover;
                        let q = |v: f32, k: usize| {
                            ((v + empty * f32::from(b[k])) / n)
                                .round()
                                .clamp(0.0, 255.0) as u8
                        };
                        [q(acc[0], 0), q(acc[1], 1), q(acc[2], 2), 255]
                    }
                };
                out_row[o..o + 4].copy_from_slice(&px);
            }
        });
    Image {
        width: w as u32,
        height: h as u32,
        rgba,
    }
}

/// The colour bar in the strip `[x0, x0 + strip_w)`: a vertical gradient, max at the top,
/// framed, with the end values written above and below it.
fn draw_colorbar(img: &mut Image, x0: u32, strip_w: u32, bar: &ColorBar) {
    let (w, h) = (img.width as i64, img.height as i64);
    let strip_w = i64::from(strip_w);
    let x0 = i64::from(x0);
    let scale = ((h as f64 / 350.0).round() as i64).clamp(1, 4) as usize;
    let text_h = (text::GLYPH_H * scale) as i64;
    let top = (h as f64 * 0.12) as i64 + text_h;
    let bottom = h - (h as f64 * 0.12) as i64 - text_h;
    if bottom - top < 4 {
        return;
    }
    let bar_w = (strip_w / 4).max(6);
    let bx0 = x0 + (strip_w - bar_w) / 2;
    let bx1 = bx0 + bar_w;
    let dark = [20u8, 20, 20, 255];
    for y in top..bottom {
        let t = (bottom - 1 - y) as f64 / ((bottom - 1 - top).max(1)) as f64;
        let c = bar.colormap.map(t);
        for x in bx0..bx1 {
            img.put(x, y, [c[0], c[1], c[2], 255]);
        }
    }
    for x in bx0 - 1..=bx1 {
        img.put(x, top - 1, dark);
        img.put(x, bottom, dark);
    }
    for y in top - 1..=bottom {
        img.put(bx0 - 1, y, dark);
        img.put(bx1, y, dark);
    }
    let label = |img: &mut Image, s: &str, y: i64| {
        let mut sc = scale;
        while sc > 1 && text::text_width(s, sc) as i64 > strip_w - 4 {
            sc -= 1;
        }
        let tw = text::text_width(s, sc) as i64;
        let cx = bx0 + bar_w / 2;
        let lx = (cx - tw / 2).min(w - tw - 2).max(x0 + 1);
        draw_text(img, s, lx, y, sc, dark);
    };
    let gap = 2 * scale as i64 + 2;
    label(img, &text::format_number(bar.max), top - 1 - gap - text_h);
    label(img, &text::format_number(bar.min), bottom + 1 + gap);
}

/// Draws `s` with its top-left corner at `(x, y)` at integer `scale`.
pub(crate) fn draw_text(img: &mut Image, s: &str, x: i64, y: i64, scale: usize, c: [u8; 4]) {
    let sc = scale as i64;
    for (k, ch) in s.chars().enumerate() {
        let gx = x + k as i64 * (text::GLYPH_W as i64 + 1) * sc;
        for fy in 0..text::GLYPH_H {
            for fx in 0..text::GLYPH_W {
                if !text::ink(ch, fx, fy) {
                    continue;
                }
                for dy in 0..sc {
                    for dx in 0..sc {
                        img.put(gx + fx as i64 * sc + dx, y + fy as i64 * sc + dy, c);
                    }
                }
            }
        }
    }
}
