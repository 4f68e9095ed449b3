//! Turning a per-vertex field into the outputs users look at: PNG, VRML, PLY, TXT.
//! Shared by `render` and every experiment.

use std::path::Path;

use anyhow::{Context, Result, bail};
use spectral_mesh::Mesh;
use spectral_mesh::fields::critical_points::{CriticalPoints, critical_points};
use spectral_mesh::io::{MeshFormat, WriteOptions, write_mesh};
use spectral_mesh_render::raster::{
    Background, ColorBar, Marker, MarkerKind, RenderOptions, Scene, View, field_colors,
    field_range, render_scene,
};
use spectral_mesh_render::{Colormap, extract_level_sets, level_values, write_vrml};

use crate::output::{field_text, write_atomic};

/// How to draw a field.
#[derive(Debug, Clone, clap::Args)]
pub struct FigureArgs {
    /// Number of evenly spaced level sets drawn over the surface (0 = none).
    #[arg(long, default_value_t = 20)]
    pub levels: usize,
    /// Colour map: hue (the paper's), viridis, turbo, diverging, grey.
    #[arg(long, default_value = "hue")]
    pub colormap: Colormap,
    /// View: front, side, top, iso, or AZIMUTH,ELEVATION in degrees.
    #[arg(long, default_value = "iso")]
    pub view: View,
    /// Picture width and height in pixels.
    #[arg(long, default_value_t = 800)]
    pub size: u32,
    /// Transparent background instead of white.
    #[arg(long)]
    pub transparent: bool,
    /// Do not mark minima (blue), maxima (red) and saddles (green).
    #[arg(long)]
    pub no_critical_points: bool,
    /// Do not draw the colour bar.
    #[arg(long)]
    pub no_colorbar: bool,
}

impl Default for FigureArgs {
    fn default() -> Self {
        Self {
            levels: 20,
            colormap: Colormap::Hue,
            view: View::Iso,
            size: 800,
            transparent: false,
            no_critical_points: false,
            no_colorbar: false,
        }
    }
}

/// A field ready to draw.
pub struct Figure<'a> {
    /// The surface.
    pub mesh: &'a Mesh,
    /// One value per vertex.
    pub field: &'a [f64],
    /// Source / anchor vertices marked in yellow.
    pub sources: Vec<usize>,
    /// Critical points, computed once and shared by the outputs.
    pub critical: Option<CriticalPoints>,
}

impl<'a> Figure<'a> {
    /// Prepares a figure, computing the critical points unless turned off.
    pub fn new(
        mesh: &'a Mesh,
        field: &'a [f64],
        sources: Vec<usize>,
        args: &FigureArgs,
    ) -> Result<Self> {
        let critical = if args.no_critical_points {
            None
        } else {
            Some(critical_points(mesh, field)?)
        };
        Ok(Self {
            mesh,
            field,
            sources,
            critical,
        })
    }

    fn scene(&self, args: &FigureArgs) -> Scene<'a> {
        let cmap = args.colormap;
        let range = field_range(self.field, cmap);
        let mut scene = Scene::new(self.mesh);
        scene.vertex_colors = field_colors(self.field, cmap, Some(range));
        if args.levels > 0 && range.1 > range.0 {
            let vals = level_values(range.0, range.1, args.levels);
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
            scene.markers.push(Marker {
                position: p[s],
                kind: MarkerKind::Source,
            });
        }
        if !args.no_colorbar {
            scene.colorbar = Some(ColorBar {
                min: range.0,
                max: range.1,
                colormap: cmap,
            });
        }
        scene
    }

    /// Writes a PNG picture.
    pub fn write_png(&self, path: &Path, args: &FigureArgs) -> Result<()> {
        let opts = RenderOptions {
            width: args.size,
            height: args.size,
            view: args.view,
            background: if args.transparent {
                Background::Transparent
            } else {
                Background::White
            },
            ..RenderOptions::default()
        };
        let img = render_scene(&self.scene(args), &opts)?;
        let mut buf = Vec::new();
        img.write_png(&mut buf)?;
        write_atomic(path, &buf)
    }

    /// Writes a VRML 2.0 scene: coloured surface, level sets, critical points.
    pub fn write_wrl(&self, path: &Path, args: &FigureArgs) -> Result<()> {
        let mut buf = Vec::new();
        write_vrml(&mut buf, &self.scene(args))?;
        write_atomic(path, &buf)
    }

    /// Writes a PLY with per-vertex colours and the raw field as a `value` property.
    pub fn write_ply(&self, path: &Path, args: &FigureArgs) -> Result<()> {
        let colors = field_colors(self.field, args.colormap, None)
            .into_iter()
            .map(|c| c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8))
            .collect();
        write_mesh(
            path,
            self.mesh,
            &WriteOptions {
                format: Some(MeshFormat::Ply),
                vertex_colors: Some(colors),
                vertex_scalar: Some(("value".into(), self.field.to_vec())),
                binary: false,
            },
        )
        .with_context(|| format!("writing {}", path.display()))
    }

    /// Writes the field, one value per line at full precision.
    pub fn write_txt(&self, path: &Path) -> Result<()> {
        write_atomic(path, field_text(self.field).as_bytes())
    }

    /// Writes the output named by `path`'s extension (png, wrl, ply, txt).
    pub fn write_by_extension(&self, path: &Path, args: &FigureArgs) -> Result<()> {
        match path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .as_deref()
        {
            Some("png") => self.write_png(path, args),
            Some("wrl") | Some("vrml") => self.write_wrl(path, args),
            Some("ply") => self.write_ply(path, args),
            Some("txt") => self.write_txt(path),
            _ => bail!(
                "{}: unknown output type (use .png, .wrl, .ply or .txt)",
                path.display()
            ),
        }
    }
}

/// Reads a per-vertex field: one number per line (blank lines and `#` comments
/// allowed), or a NumPy `.npy` vector. Refuses a wrong length or a non-finite value,
/// naming the file and line.
pub fn read_field(path: &Path, n: usize) -> Result<Vec<f64>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", path.display()))?;
    let mut values = Vec::with_capacity(n);
    for (i, line) in text.lines().enumerate() {
        let t = line.split('#').next().unwrap_or("").trim();
        if t.is_empty() {
            continue;
        }
        for tok in t
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
        {
            let v: f64 = tok.parse().map_err(|_| {
                anyhow::anyhow!("{}:{}: '{tok}' is not a number", path.display(), i + 1)
            })?;
            if !v.is_finite() {
                bail!(
                    "{}:{}: value {tok} is not finite (NaN or infinite)",
                    path.display(),
                    i + 1
                );
            }
            values.push(v);
        }
    }
    if values.len() != n {
        bail!(
            "{}: has {} values but the mesh has {n} vertices",
            path.display(),
            values.len()
        );
    }
    Ok(values)
}
