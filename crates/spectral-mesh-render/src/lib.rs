//! # spectral-mesh-render
//!
//! Headless pictures of per-vertex fields on triangle meshes:
//!
//! - [`colormap`]: the paper's hue map and viridis, turbo, diverging and grey;
//! - [`raster`]: a software renderer (z-buffer, smooth colours, two-sided Lambert lighting,
//!   supersampling) with level-set lines, critical-point markers and a colour bar, to
//!   an RGBA [`Image`] saved as PNG;
//! - [`vrml`]: a VRML 2.0 writer (and a small parser used to check what it writes);
//! - [`plots`]: line plots (spectra, filter curves, error curves) to PNG or SVG.
//!
//! Level sets themselves are computed by the library:
//! [`spectral_mesh::fields::level_sets`].

pub mod colormap;
pub mod defaults;
pub mod description;
pub mod figure;
pub mod options;
mod overlay;
pub mod pair;
pub mod plots;
pub mod raster;
mod text;
pub mod thumbnail;
pub mod vrml;

pub use colormap::Colormap;
pub use figure::{Canvas, Figure, FigureError, FigureOptions};
pub use raster::{
    Background, Camera, CameraSpec, ColorBar, Marker, MarkerKind, MarkerShape, Projection,
    RenderOptions, Scene, View, colour_range, field_colors, field_range, render, render_scene,
};
pub use spectral_mesh::fields::level_sets::{LevelSet, Polyline, extract_level_sets, level_values};
pub use text::format_number;
pub use thumbnail::Thumbnails;
pub use vrml::{VrmlSummary, parse_vrml_summary, write_vrml};

use std::io::Write;
use std::path::Path;
use thiserror::Error;

/// Errors of this crate.
#[derive(Debug, Error)]
pub enum RenderError {
    /// Width or height is zero or the image is too large.
    #[error("invalid image size {width}x{height}")]
    InvalidSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// The number of vertex colours differs from the number of vertices.
    #[error("expected {expected} vertex colours, got {got}")]
    ColorCount {
        /// Number of vertices.
        expected: usize,
        /// Number of colours given.
        got: usize,
    },
    /// An option could not be understood.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Input data unusable for a plot (empty, non-finite, non-positive on a log axis...).
    #[error("cannot plot: {0}")]
    Data(String),
    /// Writing a file failed.
    #[error("i/o error: {0}")]
    Io(#[from] std::io::Error),
    /// PNG encoding failed.
    #[error("png encoding: {0}")]
    Png(#[from] png::EncodingError),
    /// The plotting backend failed.
    #[error("plotting: {0}")]
    Plot(String),
}

/// An 8-bit RGBA image, rows top to bottom, not premultiplied.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba: Vec<u8>,
}

impl Image {
    /// A `width × height` image filled with `color`.
    pub fn new(width: u32, height: u32, color: [u8; 4]) -> Self {
        let n = width as usize * height as usize;
        let mut rgba = Vec::with_capacity(n * 4);
        for _ in 0..n {
            rgba.extend_from_slice(&color);
        }
        Self {
            width,
            height,
            rgba,
        }
    }

    /// The pixel at `(x, y)`, or `None` outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let o = (y as usize * self.width as usize + x as usize) * 4;
        Some([
            self.rgba[o],
            self.rgba[o + 1],
            self.rgba[o + 2],
            self.rgba[o + 3],
        ])
    }

    /// The pixel at `(x, y)` to change, or `None` outside the image.
    pub fn pixel_mut(&mut self, x: i64, y: i64) -> Option<&mut [u8]> {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return None;
        }
        let o = (y as usize * self.width as usize + x as usize) * 4;
        Some(&mut self.rgba[o..o + 4])
    }

    /// Sets a pixel; coordinates outside the image are ignored.
    pub fn put(&mut self, x: i64, y: i64, c: [u8; 4]) {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return;
        }
        let o = (y as usize * self.width as usize + x as usize) * 4;
        self.rgba[o..o + 4].copy_from_slice(&c);
    }

    /// Encodes the image as an 8-bit RGBA PNG.
    pub fn write_png<W: Write>(&self, w: W) -> Result<(), RenderError> {
        self.write_png_dpi(w, None)
    }

    /// Encodes the image as an 8-bit RGBA PNG with its print resolution (`dpi` dots per
    /// inch, written as pixels per metre in the `pHYs` chunk) when given.
    pub fn write_png_dpi<W: Write>(&self, w: W, dpi: Option<u32>) -> Result<(), RenderError> {
        let mut enc = png::Encoder::new(w, self.width, self.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        if let Some(d) = dpi {
            let ppm = (f64::from(d) / 0.0254).round() as u32;
            enc.set_pixel_dims(Some(png::PixelDimensions {
                xppu: ppm,
                yppu: ppm,
                unit: png::Unit::Meter,
            }));
        }
        let mut writer = enc.write_header()?;
        writer.write_image_data(&self.rgba)?;
        writer.finish()?;
        Ok(())
    }

    /// The image encoded as PNG bytes.
    pub fn png_bytes(&self) -> Result<Vec<u8>, RenderError> {
        let mut v = Vec::new();
        self.write_png(&mut v)?;
        Ok(v)
    }

    /// Writes the image to a PNG file.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        let f = std::fs::File::create(path)?;
        let mut w = std::io::BufWriter::new(f);
        self.write_png(&mut w)?;
        w.flush()?;
        Ok(())
    }
}
