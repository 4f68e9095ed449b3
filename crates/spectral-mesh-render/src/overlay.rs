//! The overlays of a figure, drawn from its [`FigureDescription`] over the rendered
//! surface as the web page places its own: the legend (top right) and the horizontal
//! colour bar with its title, ticks and units (bottom left), on light panels. Text uses
//! the Ubuntu Light font of the `epaint_default_fonts` crate.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

use crate::Image;
use crate::description::{FigureDescription, MarkerStyle};

/// Panel fill (white at 92 % opacity) and edge.
const PANEL: [u8; 4] = [255, 255, 255, 235];
const EDGE: [u8; 4] = [204, 204, 204, 255];
const INK: [u8; 4] = [34, 34, 34, 255];
const GREY_INK: [u8; 4] = [85, 85, 85, 255];

/// Parses `#rrggbb` (black when malformed).
fn rgb(hex: &str) -> [u8; 3] {
    let h = hex.trim_start_matches('#');
    let ch = |i: usize| {
        h.get(i..i + 2)
            .and_then(|s| u8::from_str_radix(s, 16).ok())
            .unwrap_or(0)
    };
    [ch(0), ch(2), ch(4)]
}

/// `src` (straight alpha times `cover`) over the pixel at `(x, y)`.
fn blend(img: &mut Image, x: i64, y: i64, src: [u8; 4], cover: f32) {
    let Some(d) = img.pixel_mut(x, y) else {
        return;
    };
    let a = f32::from(src[3]) / 255.0 * cover.clamp(0.0, 1.0);
    if a <= 0.0 {
        return;
    }
    let da = f32::from(d[3]) / 255.0;
    let oa = a + da * (1.0 - a);
    for (dc, &sc) in d.iter_mut().zip(&src).take(3) {
        let v = (f32::from(sc) * a + f32::from(*dc) * da * (1.0 - a)) / oa.max(1e-6);
        *dc = v.round().clamp(0.0, 255.0) as u8;
    }
    d[3] = (oa * 255.0).round() as u8;
}

fn fill_rect(img: &mut Image, x0: f64, y0: f64, x1: f64, y1: f64, c: [u8; 4]) {
    for y in y0.round() as i64..y1.round() as i64 {
        for x in x0.round() as i64..x1.round() as i64 {
            blend(img, x, y, c, 1.0);
        }
    }
}

fn frame(img: &mut Image, x0: f64, y0: f64, x1: f64, y1: f64, w: f64, c: [u8; 4]) {
    fill_rect(img, x0, y0, x1, y0 + w, c);
    fill_rect(img, x0, y1 - w, x1, y1, c);
    fill_rect(img, x0, y0, x0 + w, y1, c);
    fill_rect(img, x1 - w, y0, x1, y1, c);
}

/// Text set in one font at one size.
struct Writer {
    font: FontRef<'static>,
    px: f32,
}

impl Writer {
    fn new(px: f64) -> Option<Self> {
        let font = FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT).ok()?;
        Some(Self {
            font,
            px: px as f32,
        })
    }

    fn width(&self, s: &str) -> f64 {
        let sf = self.font.as_scaled(PxScale::from(self.px));
        let mut w = 0.0;
        let mut prev = None;
        for c in s.chars() {
            let id = sf.glyph_id(c);
            if let Some(p) = prev {
                w += sf.kern(p, id);
            }
            w += sf.h_advance(id);
            prev = Some(id);
        }
        f64::from(w)
    }

    /// Line height (1.4 times the size, as the page's CSS).
    fn line(&self) -> f64 {
        1.4 * f64::from(self.px)
    }

    /// Draws `s` in a line box whose top-left corner is `(x, y)`; `bold` overstrikes.
    fn draw(&self, img: &mut Image, s: &str, x: f64, y: f64, c: [u8; 4], bold: bool) {
        let sf = self.font.as_scaled(PxScale::from(self.px));
        let lead = 0.5 * (self.line() as f32 - (sf.ascent() - sf.descent()));
        let baseline = y as f32 + lead + sf.ascent();
        let passes: &[f32] = if bold { &[0.0, 0.45] } else { &[0.0] };
        for &dx in passes {
            let mut caret = x as f32 + dx;
            let mut prev = None;
            for ch in s.chars() {
                let id = sf.glyph_id(ch);
                if let Some(p) = prev {
                    caret += sf.kern(p, id);
                }
                let g = id.with_scale_and_position(self.px, point(caret, baseline));
                caret += sf.h_advance(id);
                prev = Some(id);
                if let Some(o) = self.font.outline_glyph(g) {
                    let b = o.px_bounds();
                    o.draw(|gx, gy, cover| {
                        blend(
                            img,
                            b.min.x as i64 + i64::from(gx),
                            b.min.y as i64 + i64::from(gy),
                            c,
                            cover,
                        )
                    });
                }
            }
        }
    }
}

/// A marker's shape in a box of side `size` with its top-left corner at `(x, y)`,
/// anti-aliased by 4 x 4 samples per pixel.
fn draw_icon(img: &mut Image, st: &MarkerStyle, x: f64, y: f64, size: f64) {
    let pts: Vec<[f64; 2]> = st
        .outline
        .iter()
        .map(|p| [x + p[0] * size, y + p[1] * size])
        .collect();
    let half = 0.5 * st.stroke_width * size;
    let (fill, stroke) = (rgb(&st.fill), rgb(&st.stroke));
    const N: usize = 4;
    for py in (y - half).floor() as i64..=(y + size + half).ceil() as i64 {
        for px in (x - half).floor() as i64..=(x + size + half).ceil() as i64 {
            let (mut acc, mut cov) = ([0f32; 3], 0f32);
            for sy in 0..N {
                for sx in 0..N {
                    let p = [
                        px as f64 + (sx as f64 + 0.5) / N as f64,
                        py as f64 + (sy as f64 + 0.5) / N as f64,
                    ];
                    let c = if crate::raster::edge_distance(&pts, p) <= half {
                        stroke
                    } else if crate::raster::inside(&pts, p) {
                        fill
                    } else {
                        continue;
                    };
                    cov += 1.0;
                    for (a, v) in acc.iter_mut().zip(c) {
                        *a += f32::from(v);
                    }
                }
            }
            if cov > 0.0 {
                let c = acc.map(|v| (v / cov).round() as u8);
                blend(img, px, py, [c[0], c[1], c[2], 255], cov / (N * N) as f32);
            }
        }
    }
}

/// Draws the legend and the colour bar of `d` over `img` (at `d.scale` picture pixels
/// per screen pixel).
pub fn draw_overlays(img: &mut Image, d: &FigureDescription, legend: bool) {
    let s = d.scale;
    let lay = &d.layout;
    let Some(text) = Writer::new(lay.font_px * s) else {
        return;
    };
    let small = Writer::new((lay.font_px - 1.0) * s).unwrap_or(Writer {
        font: text.font.clone(),
        px: text.px,
    });
    let (pad_x, pad_y) = (8.0 * s, 6.0 * s);
    let w = f64::from(img.width);
    let h = f64::from(img.height);

    if legend && (!d.legend.is_empty() || d.legend_note.is_some()) {
        let icon = 16.0 * s;
        let gap = 6.0 * s;
        let row = (text.line()).max(icon) + 4.0 * s;
        let mut inner = text.width("Legend");
        for e in &d.legend {
            inner = inner.max(icon + gap + text.width(&e.label));
        }
        if let Some(n) = &d.legend_note {
            inner = inner.max(small.width(n));
        }
        let rows = d.legend.len() as f64;
        let note_h = if d.legend_note.is_some() {
            small.line()
        } else {
            0.0
        };
        let bw = inner + 2.0 * pad_x + 2.0;
        let bh = text.line() + rows * row + note_h + 2.0 * pad_y + 2.0;
        let x0 = w - lay.legend_inset * s - bw;
        let y0 = lay.legend_inset * s;
        fill_rect(img, x0, y0, x0 + bw, y0 + bh, PANEL);
        frame(img, x0, y0, x0 + bw, y0 + bh, s.max(1.0), EDGE);
        let (cx, mut cy) = (x0 + 1.0 + pad_x, y0 + 1.0 + pad_y);
        text.draw(img, "Legend", cx, cy, INK, true);
        cy += text.line();
        for e in &d.legend {
            let mid = cy + 0.5 * row;
            match d.marker_styles.iter().find(|m| m.kind.name() == e.kind) {
                Some(st) => draw_icon(img, st, cx, mid - 0.5 * icon, icon),
                None => {
                    let c = crate::raster::LINE_COLOR;
                    fill_rect(
                        img,
                        cx,
                        mid - s,
                        cx + icon,
                        mid + s,
                        [c[0], c[1], c[2], 255],
                    );
                }
            }
            text.draw(
                img,
                &e.label,
                cx + icon + gap,
                mid - 0.5 * text.line(),
                INK,
                false,
            );
            cy += row;
        }
        if let Some(n) = &d.legend_note {
            small.draw(img, n, cx, cy, GREY_INK, false);
        }
    }

    if let Some(cb) = &d.colorbar {
        let bw = (lay.colorbar_width * s).min(w - 2.0 * lay.colorbar_inset * s);
        let bar_h = lay.colorbar_height * s;
        let inner_w = bw - 2.0 * pad_x - 2.0;
        let mut units_lines = Vec::new();
        // The units line wraps at the panel's width (word by word).
        let mut cur = String::new();
        for word in cb.units.split(' ') {
            let next = if cur.is_empty() {
                word.to_string()
            } else {
                format!("{cur} {word}")
            };
            if small.width(&next) > inner_w && !cur.is_empty() {
                units_lines.push(std::mem::take(&mut cur));
                cur = word.to_string();
            } else {
                cur = next;
            }
        }
        if !cur.is_empty() {
            units_lines.push(cur);
        }
        let bh = text.line()
            + 3.0 * s
            + bar_h
            + 2.0 * s
            + small.line()
            + 2.0 * s
            + units_lines.len() as f64 * small.line()
            + 2.0 * pad_y
            + 2.0;
        let x0 = lay.colorbar_inset * s;
        let y0 = h - lay.colorbar_inset * s - bh;
        if bw <= 4.0 * pad_x || y0 < 0.0 {
            return;
        }
        fill_rect(img, x0, y0, x0 + bw, y0 + bh, PANEL);
        frame(img, x0, y0, x0 + bw, y0 + bh, s.max(1.0), EDGE);
        let (cx, mut cy) = (x0 + 1.0 + pad_x, y0 + 1.0 + pad_y);
        text.draw(img, &cb.title, cx, cy, INK, true);
        cy += text.line() + 3.0 * s;
        // The bar, framed in grey.
        let e = s.max(1.0);
        frame(
            img,
            cx,
            cy,
            cx + inner_w,
            cy + bar_h + 2.0 * e,
            e,
            [136, 136, 136, 255],
        );
        let n = d.stops.len();
        let (bx0, bx1) = ((cx + e).round() as i64, (cx + inner_w - e).round() as i64);
        for x in bx0..bx1 {
            let t = (x - bx0) as f64 / ((bx1 - bx0 - 1).max(1)) as f64;
            let c = if n == 0 {
                [200, 200, 200]
            } else {
                rgb(&d.stops[((t * (n - 1) as f64).round() as usize).min(n - 1)])
            };
            for y in (cy + e).round() as i64..(cy + e + bar_h).round() as i64 {
                blend(img, x, y, [c[0], c[1], c[2], 255], 1.0);
            }
        }
        cy += bar_h + 2.0 * e + 2.0 * s;
        let k = cb.ticks.len();
        for (i, t) in cb.ticks.iter().enumerate() {
            let tw = small.width(&t.label);
            let tx = if k <= 1 || i == 0 {
                cx
            } else if i + 1 == k {
                cx + inner_w - tw
            } else {
                cx + (inner_w - tw) * i as f64 / (k - 1) as f64
            };
            small.draw(img, &t.label, tx, cy, INK, false);
        }
        cy += small.line() + 2.0 * s;
        for l in &units_lines {
            small.draw(img, l, cx, cy, GREY_INK, false);
            cy += small.line();
        }
    }
}

/// Height in picture pixels of the colour bar's panel and its inset (room the fitted
/// views leave free at the bottom).
pub fn colorbar_room(d: &FigureDescription) -> u32 {
    if d.colorbar.is_none() {
        return 0;
    }
    let s = d.scale;
    let line = 1.4 * d.layout.font_px * s;
    (2.0 * line + 3.0 * line + d.layout.colorbar_height * s + 2.0 * d.layout.colorbar_inset * s)
        .ceil() as u32
}
