//! STL (ASCII and binary) through `stl_io`, with exact welding of shared corners.

use std::collections::HashMap;
use std::io::Write;

use super::{Ctx, IoError, LoadedMesh, MeshFormat, RawFaces, RawMesh, WriteOptions, assemble};
use crate::mesh::Mesh;

/// True when the size matches the triangle count of a binary STL header exactly.
pub(crate) fn looks_binary(bytes: &[u8]) -> bool {
    binary_count(bytes).is_some_and(|n| bytes.len() as u64 == 84 + 50 * n)
}

fn binary_count(bytes: &[u8]) -> Option<u64> {
    let c = bytes.get(80..84)?;
    Some(u64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])))
}

fn starts_with_solid(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    bytes[start..].starts_with(b"solid")
}

/// The 1-based line of the `k`-th (0-based) `facet` statement of an ASCII STL file, or of
/// the first `vertex` line after it (up to its `endfacet`) that does not hold three finite
/// `f32` values.
fn facet_line(bytes: &[u8], k: usize) -> Option<usize> {
    let starts = |l: &[u8], word: &[u8]| {
        let l = l.trim_ascii_start();
        l.starts_with(word) && l.get(word.len()).is_none_or(|b| b.is_ascii_whitespace())
    };
    let mut lines = bytes.split(|&b| b == b'\n').enumerate();
    let (facet, _) = lines.by_ref().filter(|(_, l)| starts(l, b"facet")).nth(k)?;
    for (i, l) in lines {
        if starts(l, b"endfacet") {
            break;
        }
        let text = String::from_utf8_lossy(l);
        let values: Vec<&str> = text.split_whitespace().skip(1).collect();
        let bad = values.len() != 3
            || values
                .iter()
                .any(|t| t.parse::<f32>().map_or(true, |x| !x.is_finite()));
        if starts(l, b"vertex") && bad {
            return Some(i + 1);
        }
    }
    Some(facet + 1)
}

pub(crate) fn read(bytes: &[u8], ctx: &Ctx) -> Result<LoadedMesh, IoError> {
    let binary = looks_binary(bytes);
    let mut buf: Vec<u8>;
    if binary {
        // The 80-byte header is free text; blank it so it cannot pass for "solid ...".
        buf = bytes.to_vec();
        buf[..80].fill(0);
    } else if starts_with_solid(bytes) {
        // stl_io wants the file to start with "solid " (with a space).
        let start = bytes
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(0);
        buf = b"solid ".to_vec();
        buf.extend_from_slice(&bytes[start + 5..]);
    } else if let Some(n) = binary_count(bytes) {
        return Err(ctx.invalid(
            None,
            format!(
                "binary STL: the header announces {n} triangles ({} bytes) but the file has {} bytes (truncated or not an STL file)",
                84 + 50 * n,
                bytes.len()
            ),
        ));
    } else {
        return Err(ctx.invalid(
            None,
            format!(
                "not an STL file: no 'solid' keyword and only {} bytes (a binary STL has at least 84)",
                bytes.len()
            ),
        ));
    }
    let kind = if binary { "binary STL" } else { "ASCII STL" };
    let mut cursor = std::io::Cursor::new(buf);
    let reader = stl_io::create_stl_reader(&mut cursor)
        .map_err(|e| ctx.invalid(None, format!("{kind}: {e}")))?;
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut weld: HashMap<[u32; 3], usize> = HashMap::new();
    let mut faces = RawFaces::new();
    let mut dropped = 0usize;
    for (k, tri) in reader.enumerate() {
        let tri = tri.map_err(|e| {
            let line = if binary { None } else { facet_line(bytes, k) };
            let e = e.to_string();
            if e.contains("finite") {
                ctx.invalid(
                    line,
                    format!("{kind}, facet {k} has a non-finite coordinate ({e})"),
                )
            } else {
                ctx.invalid(line, format!("{kind}, facet {k}: {e}"))
            }
        })?;
        let mut keys = [[0u32; 3]; 3];
        for (c, v) in tri.vertices.iter().enumerate() {
            let p = v.0;
            if p.iter().any(|x| !x.is_finite()) {
                return Err(ctx.invalid(
                    if binary { None } else { facet_line(bytes, k) },
                    format!("{kind}, facet {k} has a non-finite coordinate {p:?}"),
                ));
            }
            // `+ 0.0` turns -0 into +0 so equal numbers weld.
            keys[c] = p.map(|x| (x + 0.0).to_bits());
        }
        if keys[0] == keys[1] || keys[1] == keys[2] || keys[0] == keys[2] {
            dropped += 1;
            continue;
        }
        let mut idx = [0i64; 3];
        for (c, v) in tri.vertices.iter().enumerate() {
            let next = positions.len();
            let i = *weld.entry(keys[c]).or_insert(next);
            if i == next {
                positions.push(v.0.map(f64::from));
            }
            idx[c] = i as i64;
        }
        faces.push(&idx, None);
    }
    let mut warnings = Vec::new();
    if dropped > 0 {
        warnings.push(format!(
            "{dropped} STL facet(s) with two identical corners dropped"
        ));
    }
    assemble(
        ctx,
        RawMesh {
            format: MeshFormat::Stl,
            positions,
            position_lines: None,
            faces: &faces,
            index_base: 0,
            vertex_colors: None,
            warnings,
        },
    )
}

/// Checks that STL's `f32` coordinates can hold `mesh`: every used coordinate in the `f32`
/// range, and the three corners of every triangle still distinct once rounded (a reader
/// drops a triangle with two equal corners). The message names the first failure.
pub(crate) fn check_representable(mesh: &Mesh) -> Result<(), String> {
    let p = mesh.positions();
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let mut keys = [[0u32; 3]; 3];
        for (c, &v) in tri.iter().enumerate() {
            for (d, &x) in p[v].iter().enumerate() {
                let y = x as f32;
                if !y.is_finite() {
                    return Err(format!(
                        "vertex {v}: {} = {x:e} is beyond the range of f32, the only number type of STL",
                        ["x", "y", "z"][d]
                    ));
                }
                keys[c][d] = (y + 0.0).to_bits();
            }
        }
        if keys[0] == keys[1] || keys[1] == keys[2] || keys[0] == keys[2] {
            return Err(format!(
                "triangle {t} (vertices {} {} {}) has two corners that are equal once rounded                  to f32, the only number type of STL: the triangle would be lost (write OFF,                  OBJ or PLY to keep full precision)",
                tri[0], tri[1], tri[2]
            ));
        }
    }
    Ok(())
}

pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh, opts: &WriteOptions) -> std::io::Result<()> {
    let normals = mesh.triangle_normals();
    let tris: Vec<stl_io::Triangle> = (0..mesh.n_triangles())
        .map(|t| {
            let c = mesh.corners(t);
            stl_io::Triangle {
                normal: stl_io::Normal::new(normals[t].map(|x| x as f32)),
                vertices: c.map(|p| stl_io::Vertex::new(p.map(|x| x as f32))),
            }
        })
        .collect();
    if opts.binary {
        let mut w = w;
        return stl_io::write_stl(&mut w, tris.iter());
    }
    writeln!(w, "solid spectral-mesh")?;
    for t in &tris {
        let n = t.normal.0;
        writeln!(w, "  facet normal {:?} {:?} {:?}", n[0], n[1], n[2])?;
        writeln!(w, "    outer loop")?;
        for v in &t.vertices {
            writeln!(w, "      vertex {:?} {:?} {:?}", v.0[0], v.0[1], v.0[2])?;
        }
        writeln!(w, "    endloop")?;
        writeln!(w, "  endfacet")?;
    }
    writeln!(w, "endsolid spectral-mesh")
}
