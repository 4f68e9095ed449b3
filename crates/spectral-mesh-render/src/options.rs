//! How to draw a field: the figure's options (levels, colour map, view, canvas, what is
//! shown), their errors and their experiment-file form. Below the figure, its description
//! and its overlays, which all read these options and import nothing back.

use spectral_mesh::experiments::file::FigureFile;
use spectral_mesh::io::IoError;

use crate::raster::{View, view_name};
use crate::{Colormap, RenderError};

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
    /// The picture's pixels: size, scale and print resolution.
    pub canvas: Canvas,
    /// Draw the legend. Default true.
    pub legend: bool,
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
            canvas: Canvas::default(),
            legend: true,
            transparent: false,
            critical_points: true,
            colorbar: true,
        }
    }
}

/// The pixels of a picture: its width and height, how many picture pixels stand for one
/// pixel of the page (the size of markers, lines and text), and the print resolution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Canvas {
    /// Picture width in pixels (and height unless `height` is given). Default the
    /// library's `spectral_mesh::defaults::PICTURE_SIZE`.
    pub size: u32,
    /// Picture height in pixels (default: `size`, a square).
    pub height: Option<u32>,
    /// Picture pixels per screen pixel: markers, lines and text are drawn this many
    /// times their size on the page (default: `min(width, height) / 800`).
    pub scale: Option<f64>,
    /// Print resolution written into the PNG (its `pHYs` chunk), dots per inch.
    pub dpi: Option<u32>,
}

impl Default for Canvas {
    fn default() -> Self {
        Self {
            size: spectral_mesh::defaults::PICTURE_SIZE,
            height: None,
            scale: None,
            dpi: None,
        }
    }
}

impl Canvas {
    /// Picture height in pixels.
    pub fn height(&self) -> u32 {
        self.height.unwrap_or(self.size)
    }

    /// Picture pixels per screen pixel ([`Canvas::scale`], resolved).
    pub fn pixel_scale(&self) -> f64 {
        match self.scale {
            Some(s) if s.is_finite() && s > 0.0 => s,
            _ => (f64::from(self.size.min(self.height())) / 800.0).max(0.25),
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
            o.canvas.size = s;
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
        o.canvas.height = f.height;
        o.canvas.dpi = f.dpi;
        if let Some(sc) = f.scale {
            if !(sc.is_finite() && sc > 0.0 && sc <= 16.0) {
                return Err(FigureError::Option {
                    key: "figure.scale",
                    message: format!("{sc}: must be in (0, 16]"),
                });
            }
            o.canvas.scale = Some(sc);
        }
        if let Some(l) = f.legend {
            o.legend = l;
        }
        Ok(o)
    }

    /// Every key written out, for saved experiment files.
    pub fn to_file(&self) -> FigureFile {
        FigureFile {
            levels: Some(self.levels),
            colormap: Some(self.colormap.to_string()),
            view: Some(view_name(self.view)),
            size: Some(self.canvas.size),
            transparent: Some(self.transparent),
            critical_points: Some(self.critical_points),
            colorbar: Some(self.colorbar),
            height: self.canvas.height,
            scale: self.canvas.scale,
            dpi: self.canvas.dpi,
            legend: Some(self.legend),
        }
    }
}
