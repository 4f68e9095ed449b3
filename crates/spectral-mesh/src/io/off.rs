//! OFF (Geomview Object File Format), text only.

use std::io::Write;

use super::lexer::{Lexer, parse_f64, parse_i64, show};
use super::{
    Ctx, IoError, LoadedMesh, MeshFormat, RawFaces, RawMesh, WriteOptions, assemble, fmt_f64,
};
use crate::mesh::Mesh;

/// What the header letters announce per vertex.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct OffHeader {
    texcoords: bool,
    colors: bool,
    normals: bool,
    four: bool,
    ndim: bool,
}

/// Parses `[ST][C][N][4][n]OFF`.
fn parse_header(word: &str) -> Option<OffHeader> {
    let mut rest = word.strip_suffix("OFF")?;
    let mut h = OffHeader::default();
    // The optional prefixes, in the order they must appear.
    for (prefix, flag) in [
        ("ST", &mut h.texcoords),
        ("C", &mut h.colors),
        ("N", &mut h.normals),
        ("4", &mut h.four),
        ("n", &mut h.ndim),
    ] {
        if let Some(r) = rest.strip_prefix(prefix) {
            *flag = true;
            rest = r;
        }
    }
    rest.is_empty().then_some(h)
}

/// True when `word` is an OFF header keyword.
pub(crate) fn is_header_word(word: &str) -> bool {
    parse_header(word).is_some()
}

pub(crate) fn read(bytes: &[u8], ctx: &Ctx) -> Result<LoadedMesh, IoError> {
    let mut lx = Lexer::new(bytes);
    let mut warnings = Vec::new();
    let Some(first) = lx.peek_token() else {
        return Err(ctx.invalid(None, "the file has no content (only comments or blanks)"));
    };
    let first_s = String::from_utf8_lossy(first).into_owned();
    let header = match parse_header(&first_s) {
        Some(h) => {
            lx.next_token();
            let line = lx.last_line();
            if h.four || h.ndim {
                return Err(ctx.invalid(
                    Some(line),
                    format!(
                        "header '{first_s}': 4-dimensional or n-dimensional OFF is not supported"
                    ),
                ));
            }
            let mut probe = lx.clone();
            if let Some(t) = probe.next_on_line()
                && t.eq_ignore_ascii_case(b"BINARY")
            {
                return Err(ctx.invalid(Some(line), "binary OFF is not supported"));
            }
            h
        }
        None if parse_i64(first).is_some() => {
            warnings.push("no OFF header keyword; read as plain OFF".to_string());
            OffHeader::default()
        }
        None => {
            lx.next_token();
            return Err(ctx.invalid(
                Some(lx.last_line()),
                format!(
                    "expected an OFF header such as OFF or COFF, found '{}'",
                    show(first)
                ),
            ));
        }
    };

    let count = |lx: &mut Lexer, what: &str| -> Result<usize, IoError> {
        let Some(t) = lx.next_token() else {
            return Err(ctx.invalid(
                Some(lx.line()),
                format!("the file ends before the {what} count"),
            ));
        };
        match parse_i64(t) {
            Some(v) if v >= 0 => Ok(v as usize),
            _ => Err(ctx.invalid(
                Some(lx.last_line()),
                format!(
                    "the {what} count '{}' is not a non-negative integer",
                    show(t)
                ),
            )),
        }
    };
    let nv = count(&mut lx, "vertex")?;
    let nf = count(&mut lx, "face")?;
    // The edge count: on the same line as the face count, or alone on the next line.
    if let Some(t) = lx.next_on_line() {
        if parse_i64(t).is_none() {
            return Err(ctx.invalid(
                Some(lx.last_line()),
                format!("the edge count '{}' is not an integer", show(t)),
            ));
        }
    } else {
        let mut probe = lx.clone();
        let alone = probe.next_token().is_some_and(|t| parse_i64(t).is_some())
            && probe.next_on_line().is_none();
        if alone {
            lx = probe;
        } else {
            warnings.push("the header has no edge count (ignored anyway)".to_string());
        }
    }

    let cap = nv.min(bytes.len() / 6 + 1);
    let mut positions = Vec::with_capacity(cap);
    let mut lines = Vec::with_capacity(cap);
    let mut colors_raw: Vec<[f64; 3]> = Vec::new();
    // An alpha above 1 means the colours are bytes (0-255) even when every red, green and
    // blue is 0 or 1 (what this crate writes: `r g b 255`).
    let mut alpha_over_one = false;
    let mut colors_ok = header.colors;
    let base_extra = 3 * usize::from(header.normals) + 2 * usize::from(header.texcoords);
    let mut odd_lines = 0usize;
    let mut first_odd: Option<(usize, usize)> = None;
    for v in 0..nv {
        let mut p = [0.0; 3];
        for (d, c) in p.iter_mut().enumerate() {
            let Some(t) = lx.next_token() else {
                return Err(ctx.invalid(
                    Some(lx.line()),
                    format!("the file ends inside vertex {v} of {nv} (truncated file or wrong vertex count)"),
                ));
            };
            *c = parse_f64(t).ok_or_else(|| {
                ctx.invalid(
                    Some(lx.last_line()),
                    format!(
                        "vertex {v}: coordinate {} '{}' is not a number",
                        ["x", "y", "z"][d],
                        show(t)
                    ),
                )
            })?;
        }
        let line = lx.last_line();
        if let Some(d) = p.iter().position(|c| !c.is_finite()) {
            return Err(ctx.invalid(
                Some(line),
                format!(
                    "vertex {v} has a non-finite coordinate ({} = {})",
                    ["x", "y", "z"][d],
                    p[d]
                ),
            ));
        }
        positions.push(p);
        lines.push(line);
        let extras = lx.rest_of_line();
        let e = extras.len();
        let expected_ok = if header.colors {
            e >= base_extra && (e - base_extra == 3 || e - base_extra == 4)
        } else {
            e == base_extra
        };
        if !expected_ok {
            odd_lines += 1;
            if first_odd.is_none() {
                first_odd = Some((line, e));
            }
            colors_ok = false;
        } else if header.colors && colors_ok {
            let off = 3 * usize::from(header.normals);
            let mut c = [0.0; 3];
            for k in 0..3 {
                match parse_f64(extras[off + k]) {
                    Some(x) if x.is_finite() && x >= 0.0 => c[k] = x,
                    _ => colors_ok = false,
                }
            }
            if e - base_extra == 4
                && parse_f64(extras[off + 3]).is_some_and(|a| a.is_finite() && a > 1.0)
            {
                alpha_over_one = true;
            }
            colors_raw.push(c);
        }
    }
    if let Some((line, e)) = first_odd {
        warnings.push(format!(
            "{odd_lines} vertex line(s) carry an unexpected number of values after the \
             coordinates (first: line {line} with {e}); the extra values were ignored"
        ));
    }
    if header.colors && !colors_ok {
        warnings.push("the vertex colours are incomplete or malformed; dropped".to_string());
    }
    let vertex_colors = if header.colors && colors_ok && colors_raw.len() == nv {
        let scale = if alpha_over_one || colors_raw.iter().flatten().any(|&x| x > 1.0) {
            1.0 / 255.0
        } else {
            1.0
        };
        Some(
            colors_raw
                .iter()
                .map(|c| c.map(|x| ((x * scale) as f32).clamp(0.0, 1.0)))
                .collect(),
        )
    } else {
        None
    };

    let mut faces = RawFaces::new();
    let mut idx: Vec<i64> = Vec::new();
    for f in 0..nf {
        let Some(t) = lx.next_token() else {
            return Err(ctx.invalid(
                Some(lx.line()),
                format!(
                    "the file ends after {f} of {nf} faces (truncated file or wrong face count)"
                ),
            ));
        };
        let line = lx.last_line();
        let k = match parse_i64(t) {
            Some(k) if k >= 0 => k as usize,
            _ => {
                return Err(ctx.invalid(
                    Some(line),
                    format!(
                        "face {f}: the vertex count '{}' is not a non-negative integer",
                        show(t)
                    ),
                ));
            }
        };
        if k < 3 {
            return Err(ctx.invalid(
                Some(line),
                format!("face {f} has {k} vertices; a face needs at least 3"),
            ));
        }
        idx.clear();
        for _ in 0..k {
            let Some(t) = lx.next_token() else {
                return Err(ctx.invalid(
                    Some(lx.line()),
                    format!("the file ends inside face {f} of {nf} (truncated file)"),
                ));
            };
            let i = parse_i64(t).ok_or_else(|| {
                ctx.invalid(
                    Some(lx.last_line()),
                    format!("face {f}: '{}' is not a vertex index", show(t)),
                )
            })?;
            idx.push(i);
        }
        // Anything left on the line is the face's colour.
        let _colour = lx.rest_of_line();
        faces.push(&idx, Some(line));
    }
    if lx.next_token().is_some() {
        warnings.push(format!(
            "content after the last face (from line {}) was ignored",
            lx.last_line()
        ));
    }
    assemble(
        ctx,
        RawMesh {
            format: MeshFormat::Off,
            positions,
            position_lines: Some(&lines),
            faces: &faces,
            index_base: 0,
            vertex_colors,
            warnings,
        },
    )
}

pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh, opts: &WriteOptions) -> std::io::Result<()> {
    let colors = opts.vertex_colors.as_deref();
    writeln!(w, "{}", if colors.is_some() { "COFF" } else { "OFF" })?;
    writeln!(w, "{} {} 0", mesh.n_vertices(), mesh.n_triangles())?;
    for (v, p) in mesh.positions().iter().enumerate() {
        write!(w, "{} {} {}", fmt_f64(p[0]), fmt_f64(p[1]), fmt_f64(p[2]))?;
        if let Some(c) = colors {
            let c = c[v];
            write!(w, " {} {} {} 255", c[0], c[1], c[2])?;
        }
        writeln!(w)?;
    }
    for t in mesh.triangles() {
        writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
    }
    Ok(())
}
