//! Reading and writing meshes: OFF, OBJ, PLY, STL; reading point clouds: text `x y z
//! [nx ny nz]` files and PLY files without faces. Errors name file, line and problem.
//!
//! [`read_input`] reads either (a mesh or a point cloud, by extension and content); see
//! [`points`](read_points) for the point formats. [`read_mesh`] reads meshes only.
//!
//! # Reading
//! [`read_mesh`] reads a file, [`read_mesh_from_bytes`] a buffer (an upload). The format is
//! taken from the file name's extension; when the extension is missing or unknown, or when
//! the content clearly is another format than the extension says, the content decides (and
//! a warning says so). Every reader:
//! - refuses bad input with an [`IoError`] naming the file, the line (text formats) and the
//!   problem: truncated file, wrong counts, an index out of range, a NaN or infinite
//!   coordinate, a face with fewer than 3 vertices or a repeated vertex, an empty mesh;
//! - turns polygons into triangles (see [`triangulate_polygon`] for the rule) and counts
//!   them in [`LoadedMesh::polygons_triangulated`];
//! - reports what it skipped or guessed in [`LoadedMesh::warnings`].
//!
//! Faces are numbered from 0 in messages, in file order. Vertex indices in messages are
//! written the way the file writes them (0-based for OFF and PLY, 1-based for OBJ).
//!
//! Format notes:
//! - OFF: headers `[ST][C][N]OFF` (e.g. `OFF`, `COFF`, `NOFF`, `CNOFF`, `STOFF`,
//!   `STCNOFF`); `4OFF`, `nOFF` and `OFF BINARY` are refused. `#` starts a comment anywhere;
//!   blank lines and counts split over several lines are fine; the header's edge count is
//!   ignored. Each vertex is its coordinates followed, on the same line, by the values its
//!   header letters announce (normal, colour with 3 or 4 components, texture coordinates);
//!   each face is `n i1 .. in` followed by an optional colour on the same line. Vertex
//!   colour components are bytes (0-255) when any of them, alpha included, exceeds 1, and
//!   fractions in `[0, 1]` otherwise.
//! - OBJ: `v` (optionally `v x y z r g b`), `vt`, `vn`, `f` with `a`, `a/b`, `a//c`, `a/b/c`
//!   corners and negative (relative) indices; other statements are ignored.
//! - PLY: ASCII and binary (both byte orders) through `ply-rs-bw`; vertex `x y z` of any
//!   numeric type, faces in `vertex_indices` or `vertex_index`, optional
//!   `red green blue`.
//! - STL: ASCII or binary, told apart by content (a binary file whose 80-byte header starts
//!   with `solid` is still recognised by its size); exactly equal corners (bitwise, with
//!   `-0 = +0`) are welded into shared vertices; a facet with two equal corners is
//!   dropped with a warning.
//!
//! # Writing
//! [`write_mesh`] writes through a temporary file in the target folder and renames it, so
//! a failed write never leaves a half-written file (it does overwrite an existing file: the
//! caller decides that policy). OFF, OBJ and PLY store positions bit-exactly (shortest
//! round-trip decimal text, or binary doubles); STL stores `f32` and is lossy: a mesh
//! with a coordinate beyond the `f32` range, or a triangle whose corners coincide once
//! rounded to `f32` (it would be lost), is refused rather than written.
//!
//! # Per-vertex fields
//! [`read_field_text`] / [`write_field_text`] (module `field`) read and write one value per
//! line, bit-exactly, as `numpy.loadtxt` / `numpy.savetxt` do.

mod atomic;
mod field;
mod lexer;
pub(crate) mod names;
mod obj;
mod off;
mod ply;
mod points;
mod polygon;
mod stl;

use std::fmt;
use std::io::Write;
use std::path::Path;
use std::str::FromStr;

use crate::mesh::Mesh;

pub use atomic::{
    AtomicWriteError, Durability, write_atomic, write_atomic_as, write_atomic_durable,
    write_atomic_with,
};
pub use field::{field_to_text, read_field, read_field_text, write_field, write_field_text};
pub use points::{
    Input, LoadedPoints, PointFormat, read_input, read_input_from_bytes, read_points,
    read_points_from_bytes,
};
pub use polygon::triangulate_polygon;

/// An error while reading or writing a mesh file. Its `Display` is
/// `path:line: problem` (or `path: problem` when no line applies).
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be opened, read, created or written.
    #[error("{path}: cannot {action}: {source}")]
    Io {
        /// File name as given.
        path: String,
        /// What was attempted ("read", "write", ...).
        action: &'static str,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The content is not a valid mesh (or the data to write is inconsistent).
    #[error("{}", located(path, *line, message))]
    Invalid {
        /// File name as given.
        path: String,
        /// 1-based line number, when the format has lines and the problem has one.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The format could not be determined from the name or the content.
    #[error("{path}: unknown mesh format: {message}")]
    UnknownFormat {
        /// File name as given.
        path: String,
        /// Why.
        message: String,
    },
}

fn located(path: &str, line: Option<usize>, message: &str) -> String {
    match line {
        Some(l) => format!("{path}:{l}: {message}"),
        None => format!("{path}: {message}"),
    }
}

impl IoError {
    /// The file name the error is about.
    pub fn path(&self) -> &str {
        match self {
            IoError::Io { path, .. }
            | IoError::Invalid { path, .. }
            | IoError::UnknownFormat { path, .. } => path,
        }
    }

    /// The 1-based line number, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            IoError::Invalid { line, .. } => *line,
            _ => None,
        }
    }
}

/// The file formats this module reads and writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum MeshFormat {
    /// Object File Format (Geomview): `OFF`, `COFF`, `NOFF`, ...
    Off,
    /// Wavefront OBJ.
    Obj,
    /// Stanford polygon format, ASCII or binary.
    Ply,
    /// Stereolithography, ASCII or binary.
    Stl,
}

impl MeshFormat {
    /// All formats.
    pub const ALL: [MeshFormat; 4] = [
        MeshFormat::Off,
        MeshFormat::Obj,
        MeshFormat::Ply,
        MeshFormat::Stl,
    ];

    /// The format named by the path's extension (case-insensitive), if any.
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        path.extension()
            .and_then(|e| e.to_str())
            .and_then(|e| e.parse().ok())
    }

    /// The usual file extension, lower case, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Off => "off",
            MeshFormat::Obj => "obj",
            MeshFormat::Ply => "ply",
            MeshFormat::Stl => "stl",
        }
    }
}

impl fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MeshFormat::Off => "OFF",
            MeshFormat::Obj => "OBJ",
            MeshFormat::Ply => "PLY",
            MeshFormat::Stl => "STL",
        })
    }
}

/// Error of [`MeshFormat::from_str`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown mesh format {0:?} (expected off, obj, ply or stl)")]
pub struct UnknownFormatName(pub String);

impl FromStr for MeshFormat {
    type Err = UnknownFormatName;

    /// Accepts `off`, `obj`, `ply`, `stl` in any case, with or without a leading dot.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().trim_start_matches('.').to_ascii_lowercase();
        match t.as_str() {
            "off" => Ok(MeshFormat::Off),
            "obj" => Ok(MeshFormat::Obj),
            "ply" => Ok(MeshFormat::Ply),
            "stl" => Ok(MeshFormat::Stl),
            _ => Err(UnknownFormatName(s.to_string())),
        }
    }
}

/// A mesh read from a file, with what the reader did to it.
#[derive(Debug, Clone)]
pub struct LoadedMesh {
    /// The triangle mesh (polygons triangulated, STL corners welded).
    pub mesh: Mesh,
    /// The format actually parsed (after content sniffing).
    pub format: MeshFormat,
    /// How many faces with more than three vertices were split into triangles.
    pub polygons_triangulated: usize,
    /// Per-vertex colours in `[0, 1]` when the file has them for every vertex.
    pub vertex_colors: Option<Vec<[f32; 3]>>,
    /// Things the reader skipped, ignored or guessed, one sentence each.
    pub warnings: Vec<String>,
}

/// Options of [`write_mesh`] / [`write_mesh_to`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WriteOptions {
    /// The format; `None` = from the path's extension ([`write_mesh`] only).
    pub format: Option<MeshFormat>,
    /// Per-vertex colours (`n` entries): PLY `red green blue` (uchar), OFF as `COFF`
    /// (with alpha 255), OBJ as `v x y z r g b` with components in `[0, 1]`.
    pub vertex_colors: Option<Vec<[u8; 3]>>,
    /// A per-vertex scalar (name, `n` values) written as a PLY `double` property;
    /// ignored by the other formats. The name must be non-empty ASCII letters, digits, `_`
    /// or `-`, and not one of the standard property names.
    pub vertex_scalar: Option<(String, Vec<f64>)>,
    /// Binary output: PLY `binary_little_endian`, STL binary. OFF and OBJ are always text.
    pub binary: bool,
}

/// Reads a mesh file; the format comes from the extension, or from the content when the
/// extension is missing or wrong.
pub fn read_mesh(path: &Path) -> Result<LoadedMesh, IoError> {
    read_with(path, read_mesh_from_bytes)
}

/// Reads the file at `path` and parses its bytes with `parse`, which gets the path as the
/// name for its messages (the one read of every reader here).
pub(crate) fn read_with<T>(
    path: &Path,
    parse: impl FnOnce(&[u8], &str) -> Result<T, IoError>,
) -> Result<T, IoError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| IoError::Io {
        path: name.clone(),
        action: "read",
        source,
    })?;
    parse(&bytes, &name)
}

/// Reads a mesh from memory. `name_hint` is a file name: its extension gives the format
/// (content sniffing otherwise, as in [`read_mesh`]) and it labels every message.
pub fn read_mesh_from_bytes(bytes: &[u8], name_hint: &str) -> Result<LoadedMesh, IoError> {
    let ctx = Ctx::new(name_hint);
    let by_name = MeshFormat::from_path(Path::new(name_hint));
    let by_content = sniff(bytes);
    let mut warnings = Vec::new();
    let format = match (by_name, by_content) {
        (Some(a), Some(b)) if a != b => {
            warnings.push(format!(
                "the file name says {a} but the content is {b}; read as {b}"
            ));
            b
        }
        (Some(a), _) => a,
        (None, Some(b)) => {
            warnings.push(format!(
                "no known extension; the content looks like {b}, read as {b}"
            ));
            b
        }
        (None, None) => {
            return Err(IoError::UnknownFormat {
                path: ctx.name,
                message: if bytes.is_empty() {
                    "the file is empty".to_string()
                } else {
                    "no off/obj/ply/stl extension and the content is none of them".to_string()
                },
            });
        }
    };
    if bytes.is_empty() {
        return Err(ctx.invalid(None, "the file is empty"));
    }
    let mut loaded = match format {
        MeshFormat::Off => off::read(bytes, &ctx)?,
        MeshFormat::Obj => obj::read(bytes, &ctx)?,
        MeshFormat::Ply => ply::read(bytes, &ctx)?,
        MeshFormat::Stl => stl::read(bytes, &ctx)?,
    };
    warnings.append(&mut loaded.warnings);
    loaded.warnings = warnings;
    Ok(loaded)
}

/// Guesses the format from the first bytes (and, for binary STL, the size).
fn sniff(bytes: &[u8]) -> Option<MeshFormat> {
    if bytes.starts_with(b"ply") && matches!(bytes.get(3), Some(b'\n' | b'\r' | b' ')) {
        return Some(MeshFormat::Ply);
    }
    if stl::looks_binary(bytes) {
        return Some(MeshFormat::Stl);
    }
    let head = &bytes[..bytes.len().min(4096)];
    let text = String::from_utf8_lossy(head);
    // First word outside comments.
    let mut first_word = None;
    let mut first_line = None;
    for line in text.lines() {
        let l = line.split('#').next().unwrap_or("").trim();
        if l.is_empty() {
            continue;
        }
        first_line = Some(l.to_string());
        first_word = l.split_whitespace().next().map(str::to_string);
        break;
    }
    let first_word = first_word?;
    if off::is_header_word(&first_word) {
        return Some(MeshFormat::Off);
    }
    if text.trim_start().starts_with("solid") && text.contains("facet") {
        return Some(MeshFormat::Stl);
    }
    let obj_words = [
        "v", "vt", "vn", "vp", "f", "o", "g", "s", "mtllib", "usemtl", "l", "p",
    ];
    if obj_words.contains(&first_word.as_str()) {
        return Some(MeshFormat::Obj);
    }
    let _ = first_line;
    None
}

/// Writes `mesh` to `path` in the format of `opts.format` (or the extension), through a
/// temporary file in the same folder renamed into place. Overwrites an existing file.
pub fn write_mesh(path: &Path, mesh: &Mesh, opts: &WriteOptions) -> Result<(), IoError> {
    let name = path.display().to_string();
    let format = match opts.format.or_else(|| MeshFormat::from_path(path)) {
        Some(f) => f,
        None => {
            return Err(IoError::UnknownFormat {
                path: name,
                message: "no format given and the extension is not off, obj, ply or stl"
                    .to_string(),
            });
        }
    };
    let mut buf = Vec::new();
    write_mesh_to(&mut buf, format, mesh, opts).map_err(|e| rename_error(e, &name))?;
    atomic_write(path, &name, &buf)
}

fn rename_error(e: IoError, name: &str) -> IoError {
    match e {
        IoError::Io { action, source, .. } => IoError::Io {
            path: name.to_string(),
            action,
            source,
        },
        IoError::Invalid { line, message, .. } => IoError::Invalid {
            path: name.to_string(),
            line,
            message,
        },
        IoError::UnknownFormat { message, .. } => IoError::UnknownFormat {
            path: name.to_string(),
            message,
        },
    }
}

fn atomic_write(path: &Path, name: &str, data: &[u8]) -> Result<(), IoError> {
    write_atomic(path, data).map_err(|e| IoError::Io {
        path: name.to_string(),
        action: e.action,
        source: e.source,
    })
}

/// Writes `mesh` in `format` to any writer (no temporary file). Errors name the format
/// as the path.
pub fn write_mesh_to(
    w: &mut dyn Write,
    format: MeshFormat,
    mesh: &Mesh,
    opts: &WriteOptions,
) -> Result<(), IoError> {
    let label = format!("<{format} output>");
    let ctx = Ctx { name: label };
    let n = mesh.n_vertices();
    if let Some(c) = &opts.vertex_colors
        && c.len() != n
    {
        return Err(ctx.invalid(
            None,
            format!("{} vertex colours given for {n} vertices", c.len()),
        ));
    }
    if let Some((name, v)) = &opts.vertex_scalar {
        if v.len() != n {
            return Err(ctx.invalid(
                None,
                format!("scalar '{name}' has {} values for {n} vertices", v.len()),
            ));
        }
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        {
            return Err(ctx.invalid(
                None,
                format!(
                    "scalar name {name:?} is not a valid property name (use letters, digits, _ and -)"
                ),
            ));
        }
        if matches!(
            name.as_str(),
            "x" | "y" | "z" | "red" | "green" | "blue" | "vertex_indices"
        ) {
            return Err(ctx.invalid(
                None,
                format!("scalar name {name:?} clashes with a standard property"),
            ));
        }
    }
    if format == MeshFormat::Stl {
        stl::check_representable(mesh).map_err(|m| ctx.invalid(None, m))?;
    }
    let mut bw = std::io::BufWriter::new(w);
    let res = match format {
        MeshFormat::Off => off::write(&mut bw, mesh, opts),
        MeshFormat::Obj => obj::write(&mut bw, mesh, opts),
        MeshFormat::Ply => ply::write(&mut bw, mesh, opts),
        MeshFormat::Stl => stl::write(&mut bw, mesh, opts),
    };
    res.and_then(|()| bw.flush()).map_err(|source| IoError::Io {
        path: ctx.name.clone(),
        action: "write",
        source,
    })
}

/// Naming context shared by the readers.
pub(crate) struct Ctx {
    pub(crate) name: String,
}

impl Ctx {
    /// The context of the file or buffer called `name`.
    pub(crate) fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
        }
    }

    pub(crate) fn invalid(&self, line: Option<usize>, message: impl Into<String>) -> IoError {
        IoError::Invalid {
            path: self.name.clone(),
            line,
            message: message.into(),
        }
    }
}

/// Faces as collected by a reader: flat 0-based indices with the line each face is on.
#[derive(Debug, Default)]
pub(crate) struct RawFaces {
    offsets: Vec<usize>,
    indices: Vec<i64>,
    lines: Vec<Option<usize>>,
}

impl RawFaces {
    pub(crate) fn new() -> Self {
        Self {
            offsets: vec![0],
            indices: Vec::new(),
            lines: Vec::new(),
        }
    }

    pub(crate) fn push(&mut self, face: &[i64], line: Option<usize>) {
        self.indices.extend_from_slice(face);
        self.offsets.push(self.indices.len());
        self.lines.push(line);
    }

    pub(crate) fn len(&self) -> usize {
        self.lines.len()
    }
}

/// What a reader collected, before the shared checks.
pub(crate) struct RawMesh<'a> {
    pub(crate) format: MeshFormat,
    pub(crate) positions: Vec<[f64; 3]>,
    /// Line of every vertex, when the format has lines.
    pub(crate) position_lines: Option<&'a [usize]>,
    pub(crate) faces: &'a RawFaces,
    /// Added to vertex indices in messages (1 for OBJ).
    pub(crate) index_base: i64,
    pub(crate) vertex_colors: Option<Vec<[f32; 3]>>,
    pub(crate) warnings: Vec<String>,
}

/// Shared end of every reader: checks positions and faces, triangulates, builds the mesh.
pub(crate) fn assemble(ctx: &Ctx, raw: RawMesh<'_>) -> Result<LoadedMesh, IoError> {
    let RawMesh {
        format,
        positions,
        position_lines,
        faces,
        index_base,
        vertex_colors,
        mut warnings,
    } = raw;
    let n = positions.len();
    for (v, p) in positions.iter().enumerate() {
        if let Some(d) = p.iter().position(|c| !c.is_finite()) {
            let line = position_lines.and_then(|l| l.get(v).copied());
            return Err(ctx.invalid(
                line,
                format!(
                    "vertex {} has a non-finite coordinate ({} = {})",
                    v as i64 + index_base,
                    ["x", "y", "z"][d],
                    p[d]
                ),
            ));
        }
    }
    if n == 0 {
        return Err(ctx.invalid(None, "the mesh is empty: the file has no vertices"));
    }
    if faces.len() == 0 {
        return Err(ctx.invalid(
            None,
            format!("the mesh is empty: the file has {n} vertices but no faces"),
        ));
    }
    let mut triangles = Vec::with_capacity(faces.len());
    let mut polygons = 0usize;
    let mut fallback = 0usize;
    let mut seen: Vec<usize> = Vec::new();
    let mut poly: Vec<usize> = Vec::new();
    for f in 0..faces.len() {
        let idx = &faces.indices[faces.offsets[f]..faces.offsets[f + 1]];
        let line = faces.lines[f];
        if idx.len() < 3 {
            return Err(ctx.invalid(
                line,
                format!(
                    "face {f} has {} vertices; a face needs at least 3",
                    idx.len()
                ),
            ));
        }
        poly.clear();
        for &i in idx {
            if i < 0 || i as u64 >= n as u64 {
                return Err(ctx.invalid(
                    line,
                    format!(
                        "face {f} refers to vertex {} but the file has {n} vertices",
                        i + index_base
                    ),
                ));
            }
            poly.push(i as usize);
        }
        seen.clear();
        seen.extend_from_slice(&poly);
        seen.sort_unstable();
        if let Some(w) = seen.windows(2).find(|w| w[0] == w[1]) {
            return Err(ctx.invalid(
                line,
                format!(
                    "face {f} uses vertex {} more than once",
                    w[0] as i64 + index_base
                ),
            ));
        }
        if poly.len() == 3 {
            triangles.push([poly[0], poly[1], poly[2]]);
        } else {
            polygons += 1;
            if !triangulate_polygon(&positions, &poly, &mut triangles) {
                fallback += 1;
            }
        }
    }
    if fallback > 0 {
        warnings.push(format!(
            "{fallback} polygon(s) had no usable plane or were too large for ear clipping; \
             they were fan-triangulated from their first vertex"
        ));
    }
    let mesh = Mesh::new(positions, triangles).map_err(|e| ctx.invalid(None, e.to_string()))?;
    Ok(LoadedMesh {
        mesh,
        format,
        polygons_triangulated: polygons,
        vertex_colors,
        warnings,
    })
}

/// Shortest text that parses back to the same `f64`.
pub(crate) fn fmt_f64(x: f64) -> String {
    format!("{x:?}")
}
