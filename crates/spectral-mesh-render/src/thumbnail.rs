//! The thumbnail of a batch result (`spectral_mesh::batch`), one drawing for every face
//! that runs batches (the command line and the Python package).

use spectral_mesh::Mesh;
use spectral_mesh::batch::Thumbnailer;

use crate::figure::Figure;
use crate::options::{Canvas, FigureOptions};

/// Draws batch thumbnails with [`Figure`]: the field in the default colour map with 10
/// level sets, no critical-point markers and no colour bar, `size x size` pixels.
#[derive(Clone, Copy, Debug, Default)]
pub struct Thumbnails;

impl Thumbnails {
    /// The figure options of a thumbnail of `size x size` pixels.
    pub fn options(size: u32) -> FigureOptions {
        FigureOptions {
            canvas: Canvas {
                size,
                ..Canvas::default()
            },
            levels: 10,
            critical_points: false,
            colorbar: false,
            legend: false,
            ..FigureOptions::default()
        }
    }
}

impl Thumbnailer for Thumbnails {
    fn png(&self, mesh: &Mesh, values: &[f64], size: u32) -> Result<Vec<u8>, String> {
        Figure::new(mesh, values, Vec::new(), Self::options(size))
            .and_then(|f| f.png())
            .map_err(|e| e.to_string())
    }
}
