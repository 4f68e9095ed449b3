//! Resolving the MESH|SHAPE argument into a mesh.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use spectral_mesh::Mesh;
use spectral_mesh::io::read_mesh;
use spectral_mesh::mesh::validate::{RepairOptions, repair};
use spectral_mesh::shapes;

/// Where a mesh came from.
#[derive(Debug, Clone)]
pub enum Source {
    /// A file on disk.
    File(PathBuf),
    /// A built-in shape spec.
    Shape(String),
}

/// A resolved input mesh.
#[derive(Debug, Clone)]
pub struct Input {
    /// The mesh.
    pub mesh: Mesh,
    /// File or shape.
    pub source: Source,
    /// Polygons that were split into triangles on reading.
    pub polygons_triangulated: usize,
    /// Notes from the reader or the repair.
    pub notes: Vec<String>,
}

impl Input {
    /// A short label: the file name or the shape spec.
    pub fn label(&self) -> String {
        match &self.source {
            Source::File(p) => p.display().to_string(),
            Source::Shape(s) => s.clone(),
        }
    }
}

/// Loads a file or builds a shape; `None` means the paper's default shape.
pub fn load(spec: Option<&str>) -> Result<Input> {
    let spec = spec.unwrap_or(shapes::DEFAULT_SHAPE);
    let path = Path::new(spec);
    if path.exists() {
        let loaded = read_mesh(path)?;
        return Ok(Input {
            mesh: loaded.mesh,
            source: Source::File(path.to_path_buf()),
            polygons_triangulated: loaded.polygons_triangulated,
            notes: loaded.warnings,
        });
    }
    if shapes::is_shape_spec(spec) {
        let s = shapes::parse_shape(spec)?;
        let mesh = shapes::build(&s).with_context(|| format!("building shape '{spec}'"))?;
        return Ok(Input {
            mesh,
            source: Source::Shape(spec.to_string()),
            polygons_triangulated: 0,
            notes: Vec::new(),
        });
    }
    if spec.contains(['/', '\\', '.']) {
        bail!("{spec}: no such file");
    }
    // Not a file and not a valid spec: let the parser explain what is wrong.
    shapes::parse_shape(spec)?;
    bail!("{spec}: neither a file nor a built-in shape (see `spectral-mesh shapes`)")
}

/// Loads and, when asked, repairs.
pub fn load_repaired(spec: Option<&str>, do_repair: bool) -> Result<Input> {
    let mut input = load(spec)?;
    if do_repair {
        let r = repair(&input.mesh, &RepairOptions::default())
            .with_context(|| format!("repairing {}", input.label()))?;
        input.mesh = r.mesh;
        input.notes.extend(r.log);
    }
    Ok(input)
}
