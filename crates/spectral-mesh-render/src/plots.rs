//! Line plots through plotters: spectra, filter curves `w(s)` (log `y`), error-versus-`k`
//! curves. The output format follows the file extension: `.svg` for SVG, anything else
//! for PNG. Text uses the Ubuntu Light font shipped by the `epaint_default_fonts` crate,
//! registered with plotters on first use.

use crate::{Image, RenderError};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// Default plot size in pixels.
pub const PLOT_SIZE: (u32, u32) = (900, 600);

static FONT: Once = Once::new();

fn ensure_font() {
    FONT.call_once(|| {
        // A failure leaves text unavailable; drawing then reports an error.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// Distinct line colours (cycled).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn is_svg(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
}

/// Plots eigenvalue against index (0-based), points joined by a line.
pub fn plot_spectrum(
    path: impl AsRef<Path>,
    values: &[f64],
    title: &str,
) -> Result<(), RenderError> {
    let pts: Vec<(f64, f64)> = values
        .iter()
        .enumerate()
        .map(|(i, &v)| (i as f64, v))
        .collect();
    let curves = vec![("eigenvalues".to_string(), pts)];
    plot_impl(
        path.as_ref(),
        &curves,
        "index",
        "eigenvalue",
        false,
        title,
        true,
    )
}

/// Plots several named curves `(x, y)` with a legend; `log_y` uses a logarithmic `y` axis
/// (points with `y <= 0` are then left out).
pub fn plot_curves(
    path: impl AsRef<Path>,
    curves: &[(String, Vec<(f64, f64)>)],
    x_label: &str,
    y_label: &str,
    log_y: bool,
    title: &str,
) -> Result<(), RenderError> {
    plot_impl(path.as_ref(), curves, x_label, y_label, log_y, title, false)
}

fn plot_impl(
    path: &Path,
    curves: &[(String, Vec<(f64, f64)>)],
    x_label: &str,
    y_label: &str,
    log_y: bool,
    title: &str,
    markers: bool,
) -> Result<(), RenderError> {
    ensure_font();
    // Keep only finite points (and positive y on a log axis).
    let clean: Vec<(String, Vec<(f64, f64)>)> = curves
        .iter()
        .map(|(n, pts)| {
            let p = pts
                .iter()
                .copied()
                .filter(|&(x, y)| x.is_finite() && y.is_finite() && (!log_y || y > 0.0))
                .collect();
            (n.clone(), p)
        })
        .collect();
    let all = clean.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        return Err(RenderError::Data(
            "no finite points to plot (and positive for a log axis)".into(),
        ));
    }
    if x1 <= x0 {
        x0 -= 0.5;
        x1 += 0.5;
    }
    if log_y {
        if y1 <= y0 {
            y0 /= 2.0;
            y1 *= 2.0;
        } else {
            y0 /= 1.25;
            y1 *= 1.25;
        }
    } else {
        let pad = if y1 > y0 {
            0.05 * (y1 - y0)
        } else {
            0.5 * y0.abs().max(1.0)
        };
        y0 -= pad;
        y1 += pad;
    }
    let labels = Labels {
        x: x_label,
        y: y_label,
        title,
        markers,
    };
    let (w, h) = PLOT_SIZE;
    if is_svg(path) {
        let mut s = String::new();
        {
            let root = SVGBackend::with_string(&mut s, (w, h)).into_drawing_area();
            draw_any(&root, &clean, x0..x1, y0, y1, log_y, &labels)?;
            root.present()
                .map_err(|e| RenderError::Plot(e.to_string()))?;
        }
        std::fs::write(path, s)?;
    } else {
        let mut buf = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            draw_any(&root, &clean, x0..x1, y0, y1, log_y, &labels)?;
            root.present()
                .map_err(|e| RenderError::Plot(e.to_string()))?;
        }
        let mut rgba = Vec::with_capacity((w * h * 4) as usize);
        for px in buf.chunks_exact(3) {
            rgba.extend_from_slice(&[px[0], px[1], px[2], 255]);
        }
        Image {
            width: w,
            height: h,
            rgba,
        }
        .save_png(path)?;
    }
    Ok(())
}

struct Labels<'a> {
    x: &'a str,
    y: &'a str,
    title: &'a str,
    markers: bool,
}

fn draw_any<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    curves: &[(String, Vec<(f64, f64)>)],
    xr: std::ops::Range<f64>,
    y0: f64,
    y1: f64,
    log_y: bool,
    labels: &Labels,
) -> Result<(), RenderError> {
    if log_y {
        draw_chart(root, curves, xr, (y0..y1).log_scale(), labels)
    } else {
        draw_chart(root, curves, xr, y0..y1, labels)
    }
}

fn draw_chart<DB, Y>(
    root: &DrawingArea<DB, Shift>,
    curves: &[(String, Vec<(f64, f64)>)],
    xr: std::ops::Range<f64>,
    yr: Y,
    labels: &Labels,
) -> Result<(), RenderError>
where
    DB: DrawingBackend,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| RenderError::Plot(e.to_string());
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(root)
        .caption(labels.title, ("sans-serif", 26))
        .margin(14)
        .x_label_area_size(46)
        .y_label_area_size(80)
        .build_cartesian_2d(xr, yr)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .x_label_formatter(&|v| crate::text::format_number(*v))
        .y_label_formatter(&|v| crate::text::format_number(*v))
        .draw()
        .map_err(e)?;
    for (i, (name, pts)) in curves.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let style = ShapeStyle {
            color: color.to_rgba(),
            filled: false,
            stroke_width: 2,
        };
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), style))
            .map_err(e)?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        if labels.markers {
            chart
                .draw_series(
                    pts.iter()
                        .map(|&(x, y)| Circle::new((x, y), 3, color.filled())),
                )
                .map_err(e)?;
        }
    }
    if curves.len() > 1 || labels.markers {
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 16))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
    }
    Ok(())
}
