//! Every default as the faces serve it: the library's ([`spectral_mesh::defaults::to_json`])
//! with the picture options of this crate (`figure`: [`FigureOptions::default`]) and the
//! colour map names. The Python package's `_native.defaults()` and the web server's
//! `GET /api/defaults` both answer this object.

use serde_json::{Value, json};

use crate::Colormap;
use crate::options::FigureOptions;
use crate::raster::view_name;

/// The library's defaults plus `figure` (levels, colour map, view, size, transparent,
/// critical points, colour bar, legend) and `colormaps`.
pub fn to_json() -> Value {
    let mut all = spectral_mesh::defaults::to_json();
    let fig = FigureOptions::default();
    all["figure"] = json!({
        "levels": fig.levels,
        "colormap": fig.colormap.name(),
        "view": view_name(fig.view),
        "size": fig.canvas.size,
        "transparent": fig.transparent,
        "critical_points": fig.critical_points,
        "colorbar": fig.colorbar,
        "legend": fig.legend,
    });
    all["colormaps"] = json!(Colormap::ALL.iter().map(|c| c.name()).collect::<Vec<_>>());
    all
}
