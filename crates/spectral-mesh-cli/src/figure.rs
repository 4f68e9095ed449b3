//! The picture options of the command line (`--levels`, `--colormap`, ...) and the one
//! way every command writes a field: the render crate's figure code.

use std::path::PathBuf;

use anyhow::Result;
use spectral_mesh::analysis::{Analysis, Field};
use spectral_mesh_render::Colormap;
use spectral_mesh_render::figure::{Canvas, Figure, FigureOptions, field_text, labels_text};
use spectral_mesh_render::raster::View;

use crate::output::{extension, write};

/// How to draw a field (defaults: the render crate's [`FigureOptions::default`]).
#[derive(Debug, Clone, clap::Args)]
pub struct FigureArgs {
    /// Number of evenly spaced level sets drawn over the surface (0 = none).
    #[arg(long, default_value_t = FigureOptions::default().levels)]
    pub levels: usize,
    /// Colour map: hue (the paper's), viridis, turbo, diverging, grey.
    #[arg(long, default_value_t = FigureOptions::default().colormap)]
    pub colormap: Colormap,
    /// View: front, side, top, iso, AZIMUTH,ELEVATION in degrees, or a camera
    /// camera:EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV (eye, target, up, vertical field of view in
    /// degrees, as the web page's download sends it) [default: iso].
    #[arg(long)]
    pub view: Option<View>,
    /// Picture width (and height unless --height) in pixels.
    #[arg(long, default_value_t = Canvas::default().size)]
    pub size: u32,
    /// Picture height in pixels [default: the size].
    #[arg(long)]
    pub height: Option<u32>,
    /// Picture pixels per screen pixel: markers, lines and text this many times their size
    /// on the web page [default: the smaller side / 800].
    #[arg(long)]
    pub scale: Option<f64>,
    /// Print resolution written into the PNG (dots per inch).
    #[arg(long)]
    pub dpi: Option<u32>,
    /// Do not draw the legend.
    #[arg(long)]
    pub no_legend: bool,
    /// Transparent background instead of white.
    #[arg(long)]
    pub transparent: bool,
    /// Do not mark minima (blue triangles down), maxima (red triangles up) and saddles
    /// (green diamonds).
    #[arg(long)]
    pub no_critical_points: bool,
    /// Do not draw the colour bar.
    #[arg(long)]
    pub no_colorbar: bool,
}

impl FigureArgs {
    /// The render crate's options.
    pub fn options(&self) -> FigureOptions {
        let d = FigureOptions::default();
        FigureOptions {
            levels: self.levels,
            colormap: self.colormap,
            view: self.view.unwrap_or(d.view),
            canvas: Canvas {
                size: self.size,
                height: self.height,
                scale: self.scale,
                dpi: self.dpi,
            },
            legend: !self.no_legend,
            transparent: self.transparent,
            critical_points: !self.no_critical_points,
            colorbar: !self.no_colorbar,
        }
    }
}

/// Writes a field of `an` to each of `outs` by extension (.png, .wrl/.vrml, .ply, .txt)
/// with the render crate's figure code (a point cloud drawn as discs, its .ply and .wrl as
/// point sets); a segmentation's .txt holds its integer labels. The figure (and its
/// critical points) is only prepared when a picture or a scene is asked for.
pub fn write_field(
    an: &Analysis,
    field: &Field,
    outs: &[PathBuf],
    options: FigureOptions,
) -> Result<()> {
    write_field_files(an, field, outs, options)?;
    for o in outs {
        println!("-> {}", o.display());
    }
    Ok(())
}

/// [`write_field`] without naming each file on stdout.
pub fn write_field_files(
    an: &Analysis,
    field: &Field,
    outs: &[PathBuf],
    options: FigureOptions,
) -> Result<()> {
    let drawn = outs.iter().any(|o| extension(o).as_deref() != Some("txt"));
    let fig = if drawn {
        Some(Figure::of_analysis(an, field, options)?)
    } else {
        None
    };
    for o in outs {
        match (&fig, extension(o).as_deref(), &field.labels) {
            (_, Some("txt"), Some(labels)) => write(o, labels_text(labels).as_bytes())?,
            (_, Some("txt"), None) => write(o, field_text(&field.values).as_bytes())?,
            (Some(fig), _, _) => fig.write(o)?,
            (None, _, _) => Figure::of_analysis(an, field, options)?.write(o)?,
        }
    }
    Ok(())
}
