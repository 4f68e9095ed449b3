//! Wavefront OBJ: vertices and faces; other statements are ignored.

use std::collections::BTreeSet;
use std::io::Write;

use super::lexer::{parse_f64, parse_i64, show};
use super::{
    Ctx, IoError, LoadedMesh, MeshFormat, RawFaces, RawMesh, WriteOptions, assemble, fmt_f64,
};
use crate::mesh::Mesh;

/// Statements that are legal OBJ but carry nothing for a triangle mesh.
const QUIET: &[&str] = &[
    "vt",
    "vn",
    "vp",
    "o",
    "g",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "usemap",
    "maplib",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "bevel",
    "c_interp",
    "d_interp",
];

pub(crate) fn read(bytes: &[u8], ctx: &Ctx) -> Result<LoadedMesh, IoError> {
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut lines: Vec<usize> = Vec::new();
    let mut colors: Vec<[f32; 3]> = Vec::new();
    let mut faces = RawFaces::new();
    let mut warnings = Vec::new();
    let mut unknown: BTreeSet<String> = BTreeSet::new();
    let mut lines_or_points = 0usize;
    let mut w_ignored = 0usize;
    let mut bad_colors = 0usize;
    let mut idx: Vec<i64> = Vec::new();

    let mut statement = String::new();
    let mut start_line = 0usize;
    let mut raw_lines = bytes.split(|&b| b == b'\n').enumerate().peekable();
    while let Some((i, raw)) = raw_lines.next() {
        let text = String::from_utf8_lossy(raw);
        let text = text.trim_end_matches('\r');
        if statement.is_empty() {
            start_line = i + 1;
        }
        // A trailing backslash continues the statement on the next line.
        if let Some(head) = text.strip_suffix('\\')
            && raw_lines.peek().is_some()
        {
            statement.push_str(head);
            statement.push(' ');
            continue;
        }
        statement.push_str(text);
        let line = start_line;
        let content = statement.split('#').next().unwrap_or("");
        let mut toks = content.split_ascii_whitespace();
        let Some(kw) = toks.next() else {
            statement.clear();
            continue;
        };
        match kw {
            "v" => {
                let vals: Vec<&str> = toks.collect();
                if vals.len() < 3 {
                    return Err(ctx.invalid(
                        Some(line),
                        format!(
                            "vertex {} has {} coordinates; 3 are needed",
                            positions.len() + 1,
                            vals.len()
                        ),
                    ));
                }
                let mut nums = Vec::with_capacity(vals.len());
                for t in &vals {
                    let x = parse_f64(t.as_bytes()).ok_or_else(|| {
                        ctx.invalid(
                            Some(line),
                            format!(
                                "vertex {}: '{}' is not a number",
                                positions.len() + 1,
                                show(t.as_bytes())
                            ),
                        )
                    })?;
                    nums.push(x);
                }
                let p = [nums[0], nums[1], nums[2]];
                if let Some(d) = p.iter().position(|c| !c.is_finite()) {
                    return Err(ctx.invalid(
                        Some(line),
                        format!(
                            "vertex {} has a non-finite coordinate ({} = {})",
                            positions.len() + 1,
                            ["x", "y", "z"][d],
                            p[d]
                        ),
                    ));
                }
                match nums.len() {
                    6 | 7 if nums[3..6].iter().all(|c| c.is_finite()) => {
                        colors.push([nums[3] as f32, nums[4] as f32, nums[5] as f32]);
                    }
                    6 | 7 => bad_colors += 1,
                    4 => w_ignored += 1,
                    _ => {}
                }
                positions.push(p);
                lines.push(line);
            }
            "f" | "fo" => {
                idx.clear();
                for (c, corner) in toks.enumerate() {
                    let first = corner.split('/').next().unwrap_or("");
                    let Some(a) = parse_i64(first.as_bytes()) else {
                        return Err(ctx.invalid(
                            Some(line),
                            format!(
                                "face {}: corner {} '{}' has no vertex index",
                                faces.len(),
                                c + 1,
                                show(corner.as_bytes())
                            ),
                        ));
                    };
                    for part in corner.split('/').skip(1) {
                        if !part.is_empty() && parse_i64(part.as_bytes()).is_none() {
                            return Err(ctx.invalid(
                                Some(line),
                                format!(
                                    "face {}: corner '{}' is not of the form v, v/t, v//n or v/t/n",
                                    faces.len(),
                                    show(corner.as_bytes())
                                ),
                            ));
                        }
                    }
                    let resolved = if a > 0 {
                        a - 1
                    } else if a < 0 {
                        let r = positions.len() as i64 + a;
                        if r < 0 {
                            return Err(ctx.invalid(
                                Some(line),
                                format!(
                                    "face {} refers to vertex {a} (relative) but only {} vertices are defined before it",
                                    faces.len(),
                                    positions.len()
                                ),
                            ));
                        }
                        r
                    } else {
                        return Err(ctx.invalid(
                            Some(line),
                            format!(
                                "face {} refers to vertex 0; OBJ indices start at 1",
                                faces.len()
                            ),
                        ));
                    };
                    idx.push(resolved);
                }
                faces.push(&idx, Some(line));
            }
            "l" | "p" => lines_or_points += 1,
            k if QUIET.contains(&k) => {}
            k => {
                if unknown.len() < 8 {
                    unknown.insert(k.chars().take(24).collect());
                }
            }
        }
        statement.clear();
    }
    if !unknown.is_empty() {
        warnings.push(format!(
            "unknown statements ignored: {}",
            unknown.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    for (count, what) in [
        (lines_or_points, "line or point element(s) ignored"),
        (w_ignored, "vertex weight(s) (4th coordinate) ignored"),
        (
            bad_colors,
            "vertex colour(s) with a NaN or infinite component; colours dropped",
        ),
    ] {
        if count > 0 {
            warnings.push(format!("{count} {what}"));
        }
    }
    let vertex_colors = if bad_colors == 0 && !colors.is_empty() && colors.len() == positions.len()
    {
        let scale = if colors.iter().flatten().any(|&x| x > 1.0) {
            1.0 / 255.0
        } else {
            1.0
        };
        Some(
            colors
                .iter()
                .map(|c| c.map(|x| (x * scale).clamp(0.0, 1.0)))
                .collect(),
        )
    } else {
        if bad_colors == 0 && !colors.is_empty() {
            warnings.push("only some vertices have colours; colours dropped".to_string());
        }
        None
    };
    assemble(
        ctx,
        RawMesh {
            format: MeshFormat::Obj,
            positions,
            position_lines: Some(&lines),
            faces: &faces,
            index_base: 1,
            vertex_colors,
            warnings,
        },
    )
}

pub(crate) fn write(w: &mut dyn Write, mesh: &Mesh, opts: &WriteOptions) -> std::io::Result<()> {
    let colors = opts.vertex_colors.as_deref();
    writeln!(
        w,
        "# {} vertices, {} triangles",
        mesh.n_vertices(),
        mesh.n_triangles()
    )?;
    for (v, p) in mesh.positions().iter().enumerate() {
        write!(w, "v {} {} {}", fmt_f64(p[0]), fmt_f64(p[1]), fmt_f64(p[2]))?;
        if let Some(c) = colors {
            let c = c[v];
            write!(
                w,
                " {} {} {}",
                fmt_f64(f64::from(c[0]) / 255.0),
                fmt_f64(f64::from(c[1]) / 255.0),
                fmt_f64(f64::from(c[2]) / 255.0)
            )?;
        }
        writeln!(w)?;
    }
    for t in mesh.triangles() {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    Ok(())
}
