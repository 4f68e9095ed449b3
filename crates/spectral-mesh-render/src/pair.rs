//! The picture of a correspondence: two shapes side by side, the first coloured by its
//! own coordinates (each axis scaled to `[0, 1]` over the bounding box: red = x, green =
//! y, blue = z), the second by the colours the point map carries to it.

use spectral_mesh::Mesh;

use crate::raster::{RenderOptions, render};
use crate::{Image, RenderError};

/// Per-vertex colours `(p - lo) / (hi - lo)` per axis over the bounding box (`0.5` on a
/// flat axis).
pub fn coordinate_colors(mesh: &Mesh) -> Vec<[f32; 3]> {
    let (lo, hi) = mesh.bounding_box();
    mesh.positions()
        .iter()
        .map(|p| {
            let mut c = [0.5f32; 3];
            for a in 0..3 {
                let span = hi[a] - lo[a];
                if span > 0.0 {
                    c[a] = ((p[a] - lo[a]) / span).clamp(0.0, 1.0) as f32;
                }
            }
            c
        })
        .collect()
}

/// Colours of the second shape: vertex `v` takes the colour of vertex `map[v]` of the
/// first (`map` has one entry per vertex of the second shape, each `< colors.len()`).
pub fn carried_colors(colors: &[[f32; 3]], map: &[usize]) -> Result<Vec<[f32; 3]>, RenderError> {
    map.iter()
        .map(|&u| {
            colors.get(u).copied().ok_or_else(|| {
                RenderError::Data(format!(
                    "the map names vertex {u}, the coloured shape has {}",
                    colors.len()
                ))
            })
        })
        .collect()
}

/// Renders `first` (coloured by its coordinates) and `second` (coloured through `map`)
/// side by side, each in a `opts.width x opts.height` panel.
pub fn render_pair(
    first: &Mesh,
    second: &Mesh,
    map: &[usize],
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    if map.len() != second.n_vertices() {
        return Err(RenderError::Data(format!(
            "a map of {} entries for a shape of {} vertices",
            map.len(),
            second.n_vertices()
        )));
    }
    let c1 = coordinate_colors(first);
    let c2 = carried_colors(&c1, map)?;
    let left = render(first, &c1, opts)?;
    let right = render(second, &c2, opts)?;
    let (w, h) = (left.width, left.height.max(right.height));
    let mut out = Image::new(w + right.width, h, [255, 255, 255, 255]);
    for (img, x0) in [(&left, 0u32), (&right, w)] {
        for y in 0..img.height {
            let src = (y as usize * img.width as usize) * 4;
            let dst = (y as usize * out.width as usize + x0 as usize) * 4;
            let len = img.width as usize * 4;
            out.rgba[dst..dst + len].copy_from_slice(&img.rgba[src..src + len]);
        }
    }
    Ok(out)
}
