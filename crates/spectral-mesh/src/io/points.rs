//! Reading point clouds, and the one entry point that reads either a mesh or a point cloud.
//!
//! # Formats
//! - Text (`.xyz`, `.pts`, `.txt`, `.csv`): one point per line, `x y z` or
//!   `x y z nx ny nz`, numbers separated by spaces, tabs, commas or semicolons. `#` starts
//!   a comment to the end of the line; blank lines are skipped. The first non-comment
//!   line may be a single integer, the number of points (the `.pts` convention): it is
//!   checked against the points read. A first line of words only (a column header such as
//!   `x y z nx ny nz`) is skipped with a warning. Every point line must have the same
//!   number of values as the first one (3 or 6).
//! - PLY with a `vertex` element and no faces (no `face` element, or zero faces): ASCII or
//!   binary, `x y z` and optionally `nx ny nz` of any numeric type ([`super::read_mesh`]
//!   still refuses such a file: it is not a mesh).
//!
//! Errors name the file, the line (text formats) and the problem: a value that is not a
//! number, a NaN or infinite coordinate or normal, a line with the wrong number of
//! values, a count that does not match, no points at all.
//!
//! Normals: a zero normal means "unknown" (some exporters write `0 0 0`); when every
//! normal is zero they are dropped with a warning.

use std::fmt;
use std::path::Path;

use super::ply;
use super::{Ctx, IoError, LoadedMesh, MeshFormat, read_mesh_from_bytes, read_with, sniff};
use crate::mesh::{PointCloud, norm};

/// The point-cloud file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum PointFormat {
    /// Text, one point per line (`.xyz`, `.pts`, `.txt`, `.csv`).
    Xyz,
    /// PLY with vertices and no faces.
    Ply,
}

impl PointFormat {
    /// The point format named by the path's extension (case-insensitive), if any:
    /// `xyz`, `pts`, `txt`, `csv` give [`PointFormat::Xyz`]. (`ply` is not listed: a PLY
    /// file may hold a mesh; [`read_input`] decides by its content.)
    pub fn from_path(path: &Path) -> Option<PointFormat> {
        let e = path.extension()?.to_str()?.to_ascii_lowercase();
        matches!(e.as_str(), "xyz" | "pts" | "txt" | "csv").then_some(PointFormat::Xyz)
    }
}

impl fmt::Display for PointFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PointFormat::Xyz => "XYZ",
            PointFormat::Ply => "PLY",
        })
    }
}

/// A point cloud read from a file, with what the reader did.
#[derive(Debug, Clone)]
pub struct LoadedPoints {
    /// The points (and their normals, when the file has usable ones).
    pub cloud: PointCloud,
    /// The format parsed.
    pub format: PointFormat,
    /// Things the reader skipped, ignored or guessed, one sentence each.
    pub warnings: Vec<String>,
}

/// What [`read_input`] found: a triangle mesh or a point cloud.
#[derive(Debug, Clone)]
pub enum Input {
    /// A mesh (any mesh format, or a PLY file with faces).
    Mesh(LoadedMesh),
    /// A point cloud (a text point file, or a PLY file with vertices and no faces).
    Points(LoadedPoints),
}

impl Input {
    /// The warnings of whichever was read.
    pub fn warnings(&self) -> &[String] {
        match self {
            Input::Mesh(m) => &m.warnings,
            Input::Points(p) => &p.warnings,
        }
    }

    /// Number of vertices or points.
    pub fn n_points(&self) -> usize {
        match self {
            Input::Mesh(m) => m.mesh.n_vertices(),
            Input::Points(p) => p.cloud.n_points(),
        }
    }
}

/// Reads a point-cloud file (text points, or a PLY file; a PLY file's faces, if any, are
/// ignored with a warning).
pub fn read_points(path: &Path) -> Result<LoadedPoints, IoError> {
    read_with(path, read_points_from_bytes)
}

/// Reads a point cloud from memory; `name_hint` labels messages.
pub fn read_points_from_bytes(bytes: &[u8], name_hint: &str) -> Result<LoadedPoints, IoError> {
    let ctx = Ctx::new(name_hint);
    if bytes.is_empty() {
        return Err(ctx.invalid(None, "the file is empty"));
    }
    if is_ply(bytes) {
        let data = ply::parse(bytes, &ctx, false)?;
        let mut warnings = data.warnings;
        if let Some(f) = &data.faces
            && f.len() > 0
        {
            warnings.push(format!(
                "the PLY file has {} faces; read as a point cloud, they were ignored",
                f.len()
            ));
        }
        return points_from(
            &ctx,
            data.positions,
            data.normals,
            PointFormat::Ply,
            warnings,
        );
    }
    read_text(bytes, &ctx)
}

/// Reads a mesh or a point cloud, whichever the file holds: a text point file (by
/// extension or, without a known extension, by content) gives points; a PLY file gives a
/// mesh when it has faces and points otherwise; every other file is read by
/// [`super::read_mesh`] (with its behaviour and messages).
pub fn read_input(path: &Path) -> Result<Input, IoError> {
    read_with(path, read_input_from_bytes)
}

/// [`read_input`] on a buffer; `name_hint` is a file name (its extension guides the choice,
/// and it labels messages).
pub fn read_input_from_bytes(bytes: &[u8], name_hint: &str) -> Result<Input, IoError> {
    let ctx = Ctx::new(name_hint);
    let hint = Path::new(name_hint);
    let by_points_ext = PointFormat::from_path(hint).is_some();
    let mesh_ext = MeshFormat::from_path(hint);
    let content = sniff(bytes);
    if content == Some(MeshFormat::Ply) {
        let data = ply::parse(bytes, &ctx, false)?;
        let mut warnings = Vec::new();
        if mesh_ext.is_some_and(|f| f != MeshFormat::Ply) || by_points_ext {
            warnings.push(format!(
                "the file name says {} but the content is PLY; read as PLY",
                hint.extension()
                    .map(|e| e.to_string_lossy().into_owned())
                    .unwrap_or_default()
            ));
        }
        warnings.extend(data.warnings);
        return match data.faces {
            Some(faces) if faces.len() > 0 => {
                let mut m = ply::assemble_mesh(
                    &ctx,
                    data.positions,
                    data.vertex_colors,
                    &faces,
                    Vec::new(),
                )?;
                warnings.append(&mut m.warnings);
                m.warnings = warnings;
                Ok(Input::Mesh(m))
            }
            _ => Ok(Input::Points(points_from(
                &ctx,
                data.positions,
                data.normals,
                PointFormat::Ply,
                warnings,
            )?)),
        };
    }
    if by_points_ext && content.is_none() {
        return read_text(bytes, &ctx).map(Input::Points);
    }
    if mesh_ext.is_none() && content.is_none() && !by_points_ext && looks_like_points(bytes) {
        let mut p = read_text(bytes, &ctx)?;
        p.warnings.insert(
            0,
            "no known extension; the content looks like a point list (x y z per line), read as points"
                .to_string(),
        );
        return Ok(Input::Points(p));
    }
    read_mesh_from_bytes(bytes, name_hint).map(Input::Mesh)
}

fn is_ply(bytes: &[u8]) -> bool {
    bytes.starts_with(b"ply") && matches!(bytes.get(3), Some(b'\n' | b'\r' | b' '))
}

/// True when the first non-comment line is 3 or 6 numbers.
fn looks_like_points(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(4096)];
    let text = String::from_utf8_lossy(head);
    for line in text.lines() {
        let toks = tokens(line);
        if toks.is_empty() {
            continue;
        }
        return matches!(toks.len(), 3 | 6) && toks.iter().all(|t| t.parse::<f64>().is_ok());
    }
    false
}

/// The values of one line: comment stripped, split on spaces, tabs, commas, semicolons.
fn tokens(line: &str) -> Vec<&str> {
    line.split('#')
        .next()
        .unwrap_or("")
        .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
        .filter(|t| !t.is_empty())
        .collect()
}

fn read_text(bytes: &[u8], ctx: &Ctx) -> Result<LoadedPoints, IoError> {
    if bytes.is_empty() {
        return Err(ctx.invalid(None, "the file is empty"));
    }
    let mut warnings = Vec::new();
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut normals: Vec<[f64; 3]> = Vec::new();
    // Columns fixed by the first point line: (count, line).
    let mut columns: Option<(usize, usize)> = None;
    let mut declared: Option<(usize, usize)> = None;
    let mut first_content = true;
    let mut vals = [0.0f64; 6];
    for (k, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = k + 1;
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(ctx.invalid(
                Some(line_no),
                "the line is not text (invalid UTF-8); a point file is x y z [nx ny nz] per line",
            ));
        };
        let toks = tokens(line);
        if toks.is_empty() {
            continue;
        }
        if first_content {
            first_content = false;
            if toks.len() == 1
                && let Ok(c) = toks[0].parse::<usize>()
            {
                declared = Some((c, line_no));
                continue;
            }
            if toks.iter().all(|t| t.parse::<f64>().is_err()) {
                warnings.push(format!(
                    "line {line_no} ({}) read as a column header and skipped",
                    toks.join(" ")
                ));
                continue;
            }
        }
        let cols = match columns {
            Some((c, first)) => {
                if toks.len() != c {
                    return Err(ctx.invalid(
                        Some(line_no),
                        format!(
                            "{} values on this line, but line {first} has {c}; every point needs \
                             the same columns",
                            toks.len()
                        ),
                    ));
                }
                c
            }
            None => {
                if toks.len() != 3 && toks.len() != 6 {
                    return Err(ctx.invalid(
                        Some(line_no),
                        format!(
                            "{} values on this line; expected 3 (x y z) or 6 (x y z nx ny nz)",
                            toks.len()
                        ),
                    ));
                }
                columns = Some((toks.len(), line_no));
                toks.len()
            }
        };
        const NAMES: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];
        for (d, t) in toks.iter().enumerate() {
            let v: f64 = t.parse().map_err(|_| {
                ctx.invalid(
                    Some(line_no),
                    format!("{} = {t:?} is not a number", NAMES[d]),
                )
            })?;
            if !v.is_finite() {
                return Err(ctx.invalid(
                    Some(line_no),
                    format!(
                        "point {} has a non-finite {} ({} = {t})",
                        positions.len(),
                        if d < 3 {
                            "coordinate"
                        } else {
                            "normal component"
                        },
                        NAMES[d]
                    ),
                ));
            }
            vals[d] = v;
        }
        positions.push([vals[0], vals[1], vals[2]]);
        if cols == 6 {
            normals.push([vals[3], vals[4], vals[5]]);
        }
    }
    if let Some((c, line)) = declared
        && c != positions.len()
    {
        return Err(ctx.invalid(
            Some(line),
            format!(
                "the first line says {c} points but the file has {}",
                positions.len()
            ),
        ));
    }
    let normals = (columns.map(|c| c.0) == Some(6)).then_some(normals);
    points_from(ctx, positions, normals, PointFormat::Xyz, warnings)
}

fn points_from(
    ctx: &Ctx,
    positions: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
    format: PointFormat,
    mut warnings: Vec<String>,
) -> Result<LoadedPoints, IoError> {
    if positions.is_empty() {
        return Err(ctx.invalid(None, "the file has no points"));
    }
    let normals = match normals {
        Some(nr) => {
            let zero = nr.iter().filter(|v| norm(**v) == 0.0).count();
            if zero == nr.len() {
                warnings.push("every normal is zero; the normals were ignored".to_string());
                None
            } else {
                if zero > 0 {
                    warnings.push(format!(
                        "{zero} point(s) have a zero normal (treated as unknown)"
                    ));
                }
                Some(nr)
            }
        }
        None => None,
    };
    let cloud =
        PointCloud::new(positions, normals).map_err(|e| ctx.invalid(None, e.to_string()))?;
    Ok(LoadedPoints {
        cloud,
        format,
        warnings,
    })
}
