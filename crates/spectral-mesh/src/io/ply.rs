//! PLY (ASCII, binary little and big endian), read through `ply-rs-bw`, written by hand.

use std::io::Write;

use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};

use super::{
    Ctx, IoError, LoadedMesh, MeshFormat, RawFaces, RawMesh, WriteOptions, assemble, fmt_f64,
};
use crate::mesh::Mesh;

/// Number of header lines (through `end_header`) and whether the payload is binary.
fn header_info(bytes: &[u8]) -> (Option<usize>, bool) {
    let mut binary = false;
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let l = String::from_utf8_lossy(line);
        let l = l.trim();
        if l.starts_with("format") && l.contains("binary") {
            binary = true;
        }
        if l == "end_header" {
            return (Some(i + 1), binary);
        }
        if i > 10_000 {
            break;
        }
    }
    (None, binary)
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => f64::from(v),
        Property::UChar(v) => f64::from(v),
        Property::Short(v) => f64::from(v),
        Property::UShort(v) => f64::from(v),
        Property::Int(v) => f64::from(v),
        Property::UInt(v) => f64::from(v),
        Property::Float(v) => f64::from(v),
        Property::Double(v) => v,
        _ => return None,
    })
}

fn index_list(p: &Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUChar(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListShort(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUShort(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListInt(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUInt(v) => v.iter().map(|&x| i64::from(x)).collect(),
        _ => return None,
    })
}

fn color_component(p: &Property) -> Option<f32> {
    let x = scalar(p)?;
    let integer = !matches!(p, Property::Float(_) | Property::Double(_));
    let c = if integer { x / 255.0 } else { x };
    c.is_finite().then_some(c.clamp(0.0, 1.0) as f32)
}

/// The first token of 1-based line `line` that Rust reads as NaN or an infinity.
fn non_finite_token(bytes: &[u8], line: usize) -> Option<String> {
    let text = bytes.split(|&b| b == b'\n').nth(line.checked_sub(1)?)?;
    String::from_utf8_lossy(text)
        .split_whitespace()
        .find(|t| t.parse::<f64>().is_ok_and(|x| !x.is_finite()))
        .map(|t| super::lexer::show(t.as_bytes()))
}

/// Bytes of one value of a PLY scalar type (1 for an unknown name: ply-rs refuses it).
fn type_size(name: &str) -> u64 {
    match name {
        "char" | "int8" | "uchar" | "uint8" => 1,
        "short" | "int16" | "ushort" | "uint16" => 2,
        "int" | "int32" | "uint" | "uint32" | "float" | "float32" => 4,
        "double" | "float64" => 8,
        _ => 1,
    }
}

/// Checks the element counts of the header against the payload before ply-rs reads it:
/// ply-rs loops `count` times per element, and an element without properties takes no
/// bytes in a binary file, so `element vertex 42949672951` made it fill memory. Refuses an
/// element declared twice (ply-rs then files the later properties under another element),
/// a binary element with records but no property, and counts that need more bytes
/// (binary: the smallest size of a record, a list counting as empty) or more lines (ASCII)
/// than the payload has. `Ok` also when the header is malformed: ply-rs says why.
fn check_counts(bytes: &[u8]) -> Result<(), (usize, String)> {
    let mut binary = false;
    // (name, count, smallest record size in bytes, properties, header line)
    let mut elements: Vec<(String, u64, u64, usize, usize)> = Vec::new();
    let mut offset = 0usize;
    let mut payload: Option<&[u8]> = None;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        offset += raw.len() + 1;
        let line = String::from_utf8_lossy(raw);
        let tok: Vec<&str> = line.split_whitespace().collect();
        match tok.as_slice() {
            ["format", f, ..] => binary = f.starts_with("binary"),
            ["element", name, count] => {
                let Ok(count) = count.parse::<u64>() else {
                    return Ok(());
                };
                if elements.iter().any(|e| e.0 == *name) {
                    return Err((i + 1, format!("element '{name}' is declared twice")));
                }
                elements.push((name.to_string(), count, 0, 0, i + 1));
            }
            ["property", "list", count_type, _, _] => {
                if let Some(e) = elements.last_mut() {
                    e.2 += type_size(count_type);
                    e.3 += 1;
                }
            }
            ["property", ty, _] => {
                if let Some(e) = elements.last_mut() {
                    e.2 += type_size(ty);
                    e.3 += 1;
                }
            }
            ["end_header"] => {
                payload = Some(bytes.get(offset.min(bytes.len())..).unwrap_or(&[]));
                break;
            }
            _ => {}
        }
    }
    let Some(payload) = payload else {
        return Ok(());
    };
    if binary {
        let mut need = 0u64;
        for (name, count, size, props, line) in &elements {
            if *count > 0 && *props == 0 {
                return Err((
                    *line,
                    format!("element '{name}' has {count} records but no property"),
                ));
            }
            need = need.saturating_add(count.saturating_mul(*size));
            if need > payload.len() as u64 {
                return Err((
                    *line,
                    format!(
                        "element '{name}' announces {count} records, more than the {} bytes of binary payload can hold (truncated file or wrong count)",
                        payload.len()
                    ),
                ));
            }
        }
    } else {
        let lines = payload.iter().filter(|&&b| b == b'\n').count() as u64 + 1;
        let mut need = 0u64;
        for (name, count, _, _, line) in &elements {
            need = need.saturating_add(*count);
            if need > lines {
                return Err((
                    *line,
                    format!(
                        "element '{name}' announces {count} records, more than the {lines} lines after the header (truncated file or wrong count)"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// What a PLY file holds, before it is turned into a mesh or a point cloud.
pub(crate) struct PlyData {
    pub(crate) positions: Vec<[f64; 3]>,
    /// `nx ny nz` of every vertex, when the vertex element has all three.
    pub(crate) normals: Option<Vec<[f64; 3]>>,
    pub(crate) vertex_colors: Option<Vec<[f32; 3]>>,
    /// `None` when the file has no `face` element.
    pub(crate) faces: Option<RawFaces>,
    pub(crate) warnings: Vec<String>,
}

pub(crate) fn read(bytes: &[u8], ctx: &Ctx) -> Result<LoadedMesh, IoError> {
    let data = parse(bytes, ctx, true)?;
    let Some(faces) = data.faces else {
        return Err(ctx.invalid(None, NO_FACE_ELEMENT));
    };
    assemble_mesh(
        ctx,
        data.positions,
        data.vertex_colors,
        &faces,
        data.warnings,
    )
}

/// The mesh of a PLY file's vertices (with their colours) and `faces`, with `warnings`.
pub(crate) fn assemble_mesh(
    ctx: &Ctx,
    positions: Vec<[f64; 3]>,
    vertex_colors: Option<Vec<[f32; 3]>>,
    faces: &RawFaces,
    warnings: Vec<String>,
) -> Result<LoadedMesh, IoError> {
    assemble(
        ctx,
        RawMesh {
            format: MeshFormat::Ply,
            positions,
            position_lines: None,
            faces,
            index_base: 0,
            vertex_colors,
            warnings,
        },
    )
}

const NO_FACE_ELEMENT: &str = "the PLY file has no 'face' element (a point cloud is not a mesh)";

/// Parses the header and the payload: vertices (positions, normals, colours) and, when
/// there is a `face` element, the faces. With `require_faces`, a file without a `face`
/// element is refused as soon as the header is known (what the mesh reader does).
pub(crate) fn parse(bytes: &[u8], ctx: &Ctx, require_faces: bool) -> Result<PlyData, IoError> {
    let (header_lines, binary) = header_info(bytes);
    check_counts(bytes).map_err(|(line, m)| ctx.invalid(Some(line), format!("PLY: {m}")))?;
    let parser = Parser::<DefaultElement>::new();
    let mut cursor = std::io::Cursor::new(bytes);
    let ply = parser.read_ply(&mut cursor).map_err(|e| {
        let msg = e.to_string();
        let msg = match e.line() {
            Some(l) => msg
                .strip_prefix(&format!("Line {l}: "))
                .unwrap_or(&msg)
                .to_string(),
            None => msg,
        };
        // ply-rs nests "... Error: ..." messages; the innermost one is the useful part.
        let msg = if msg.contains("ParseError {") {
            "malformed header line".to_string()
        } else {
            msg
        };
        let first = msg.lines().next().unwrap_or("").trim().to_string();
        let msg = match msg.rfind("Error: ") {
            Some(k) => format!("{first} ({})", &msg[k + 7..]),
            None => msg,
        };
        let msg = msg.split_whitespace().collect::<Vec<_>>().join(" ");
        let line = match (e.line(), header_lines) {
            (Some(l), Some(h)) if binary && l > h => None,
            (l, _) => l,
        };
        let prefix = if binary && line.is_none() {
            "binary PLY payload: "
        } else {
            "PLY: "
        };
        // ply-rs's number grammar has no NaN or infinity: name the value instead of the
        // grammar.
        if !binary
            && let (Some(l), Some(h)) = (line, header_lines)
            && l > h
            && let Some(tok) = non_finite_token(bytes, l)
        {
            return ctx.invalid(
                line,
                format!("{prefix}non-finite value '{tok}' (NaN and infinities are refused)"),
            );
        }
        ctx.invalid(line, format!("{prefix}{msg}"))
    })?;
    let mut warnings = Vec::new();
    let elements = &ply.header.elements;
    let Some(vdef) = elements.get("vertex") else {
        return Err(ctx.invalid(None, "the PLY file has no 'vertex' element"));
    };
    for p in ["x", "y", "z"] {
        if !vdef.properties.contains_key(p) {
            return Err(ctx.invalid(
                None,
                format!("the PLY vertex element has no '{p}' property"),
            ));
        }
    }
    let list_name = match elements.get("face") {
        None if require_faces => return Err(ctx.invalid(None, NO_FACE_ELEMENT)),
        None => None,
        Some(fdef) => {
            let list_name = ["vertex_indices", "vertex_index"]
                .into_iter()
                .find(|k| fdef.properties.contains_key(*k));
            let Some(list_name) = list_name else {
                return Err(ctx.invalid(
                    None,
                    "the PLY face element has neither 'vertex_indices' nor 'vertex_index'",
                ));
            };
            Some(list_name)
        }
    };
    let others: Vec<&str> = elements
        .keys()
        .map(String::as_str)
        .filter(|k| *k != "vertex" && *k != "face")
        .collect();
    if !others.is_empty() {
        warnings.push(format!("PLY elements ignored: {}", others.join(", ")));
    }
    // Line of record k of element `name` in an ASCII file.
    let line_of = |name: &str, k: usize| -> Option<usize> {
        if binary {
            return None;
        }
        let h = header_lines?;
        let mut before = 0usize;
        for (key, def) in elements {
            if key == name {
                return Some(h + before + k + 1);
            }
            before += def.count;
        }
        None
    };

    let empty = Vec::new();
    let verts = ply.payload.get("vertex").unwrap_or(&empty);
    let has_color = ["red", "green", "blue"]
        .iter()
        .all(|k| vdef.properties.contains_key(*k));
    let has_normals = ["nx", "ny", "nz"]
        .iter()
        .all(|k| vdef.properties.contains_key(*k));
    let mut normals = Vec::with_capacity(if has_normals { verts.len() } else { 0 });
    let mut positions = Vec::with_capacity(verts.len());
    let mut colors = Vec::new();
    let mut colors_ok = has_color;
    // The three numeric properties `keys` of vertex `v`: missing or non-finite values are
    // refused, naming the property (`what`: what one value is called).
    let triple =
        |e: &DefaultElement, v: usize, keys: [&str; 3], what: &str| -> Result<[f64; 3], IoError> {
            let mut p = [0.0; 3];
            for (d, key) in keys.into_iter().enumerate() {
                p[d] = e.get(key).and_then(scalar).ok_or_else(|| {
                    ctx.invalid(
                        line_of("vertex", v),
                        format!("vertex {v}: property '{key}' is missing or not a number"),
                    )
                })?;
            }
            match p.iter().position(|c| !c.is_finite()) {
                Some(d) => Err(ctx.invalid(
                    line_of("vertex", v),
                    format!(
                        "vertex {v} has a non-finite {what} ({} = {})",
                        keys[d], p[d]
                    ),
                )),
                None => Ok(p),
            }
        };
    for (v, e) in verts.iter().enumerate() {
        positions.push(triple(e, v, ["x", "y", "z"], "coordinate")?);
        if has_normals {
            normals.push(triple(e, v, ["nx", "ny", "nz"], "normal component")?);
        }
        if colors_ok {
            let c: Vec<Option<f32>> = ["red", "green", "blue"]
                .iter()
                .map(|k| e.get(*k).and_then(color_component))
                .collect();
            match (c[0], c[1], c[2]) {
                (Some(r), Some(g), Some(b)) => colors.push([r, g, b]),
                _ => colors_ok = false,
            }
        }
    }
    if has_color && !colors_ok {
        warnings.push("malformed vertex colours dropped".to_string());
    }
    let vertex_colors = (colors_ok && colors.len() == positions.len()).then_some(colors);

    let faces = match list_name {
        None => None,
        Some(list_name) => {
            let face_elems = ply.payload.get("face").unwrap_or(&empty);
            let mut faces = RawFaces::new();
            for (f, e) in face_elems.iter().enumerate() {
                let list = e.get(list_name).and_then(index_list).ok_or_else(|| {
                    ctx.invalid(
                        line_of("face", f),
                        format!("face {f}: '{list_name}' is missing or not a list of integers"),
                    )
                })?;
                faces.push(&list, line_of("face", f));
            }
            Some(faces)
        }
    };
    Ok(PlyData {
        positions,
        normals: has_normals.then_some(normals),
        vertex_colors,
        faces,
        warnings,
    })
}

pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh, opts: &WriteOptions) -> std::io::Result<()> {
    let n = mesh.n_vertices();
    if n > i32::MAX as usize {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "too many vertices for 32-bit PLY indices",
        ));
    }
    let colors = opts.vertex_colors.as_deref();
    let scalar = opts.vertex_scalar.as_ref();
    writeln!(w, "ply")?;
    writeln!(
        w,
        "format {} 1.0",
        if opts.binary {
            "binary_little_endian"
        } else {
            "ascii"
        }
    )?;
    writeln!(w, "comment written by spectral-mesh")?;
    writeln!(w, "element vertex {n}")?;
    for c in ["x", "y", "z"] {
        writeln!(w, "property double {c}")?;
    }
    if colors.is_some() {
        for c in ["red", "green", "blue"] {
            writeln!(w, "property uchar {c}")?;
        }
    }
    if let Some((name, _)) = scalar {
        writeln!(w, "property double {name}")?;
    }
    writeln!(w, "element face {}", mesh.n_triangles())?;
    writeln!(w, "property list uchar int vertex_indices")?;
    writeln!(w, "end_header")?;
    let pos = mesh.positions();
    if opts.binary {
        for v in 0..n {
            for c in pos[v] {
                w.write_all(&c.to_le_bytes())?;
            }
            if let Some(c) = colors {
                w.write_all(&c[v])?;
            }
            if let Some((_, s)) = scalar {
                w.write_all(&s[v].to_le_bytes())?;
            }
        }
        for t in mesh.triangles() {
            w.write_all(&[3u8])?;
            for &i in t {
                w.write_all(&(i as i32).to_le_bytes())?;
            }
        }
    } else {
        for v in 0..n {
            let p = pos[v];
            write!(w, "{} {} {}", fmt_f64(p[0]), fmt_f64(p[1]), fmt_f64(p[2]))?;
            if let Some(c) = colors {
                write!(w, " {} {} {}", c[v][0], c[v][1], c[v][2])?;
            }
            if let Some((_, s)) = scalar {
                write!(w, " {}", fmt_f64(s[v]))?;
            }
            writeln!(w)?;
        }
        for t in mesh.triangles() {
            writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
        }
    }
    Ok(())
}
