//! Resolving the MESH|SHAPE argument into a mesh or a point cloud, and reading per-vertex
//! field files.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use spectral_mesh::Mesh;
use spectral_mesh::analysis::{Analysis, AnalysisInput, AnalysisOptions};
use spectral_mesh::experiments::file::{parent_dir, relative_path};
use spectral_mesh::experiments::paper::MeshSummary;
use spectral_mesh::io::{self, read_input};
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::mesh::validate::{RepairOptions, repair};
use spectral_mesh::operators::PointCloudParams;
use spectral_mesh::shapes;

/// Where a mesh came from.
#[derive(Debug, Clone)]
pub enum Source {
    /// A file on disk.
    File(PathBuf),
    /// A built-in shape spec.
    Shape(String),
}

/// Where a loaded mesh came from and what happened on the way (the mesh itself is held
/// apart, usually by an analysis).
#[derive(Debug, Clone)]
pub struct MeshInfo {
    /// File or shape.
    pub source: Source,
    /// Polygons that were split into triangles on reading.
    pub polygons_triangulated: usize,
    /// Notes from the reader or the repair.
    pub notes: Vec<String>,
    /// The content hash of the mesh as read, when a repair changed it afterwards.
    hash_as_read: Option<String>,
    /// The point-cloud Laplacian's parameters of a point-cloud input (`None` for a mesh):
    /// the same as the input's, kept here for summaries and experiment files once the
    /// input has gone into an analysis.
    pub point_cloud: Option<PointCloudParams>,
}

/// A resolved input: a mesh or a point cloud.
#[derive(Debug, Clone)]
pub struct Input {
    /// The mesh (repaired when asked) or the point cloud.
    pub shape: AnalysisInput,
    /// Where it came from.
    pub info: MeshInfo,
}

impl MeshInfo {
    /// A short label: the file name or the shape spec.
    pub fn label(&self) -> String {
        match &self.source {
            Source::File(p) => p.display().to_string(),
            Source::Shape(s) => s.clone(),
        }
    }

    /// The name of the mesh in summaries: the file name (not the path, so that a replay
    /// from another folder writes the same summary) or the shape spec.
    pub fn name(&self) -> String {
        match &self.source {
            Source::File(p) => p
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| self.label()),
            Source::Shape(s) => s.clone(),
        }
    }

    /// [`Mesh::content_hash`] of the mesh as read (before any repair); `mesh` is the mesh
    /// loaded with this information.
    pub fn hash(&self, mesh: &Mesh) -> String {
        self.hash_as_read
            .clone()
            .unwrap_or_else(|| mesh.content_hash())
    }

    /// The content hash of `shape` as read: [`MeshInfo::hash`] for a mesh, the hash of
    /// the points for a point cloud.
    pub fn hash_of(&self, shape: &AnalysisInput) -> String {
        self.hash_as_read
            .clone()
            .unwrap_or_else(|| shape.content_hash())
    }

    /// The library's summary of `mesh` (loaded with this information), naming a point
    /// cloud's Laplacian parameters.
    pub fn summary(&self, mesh: &Mesh, topology: &Topology) -> MeshSummary {
        MeshSummary::new(self.name(), self.hash(mesh), mesh, topology)
            .with_point_cloud(self.point_cloud)
    }

    /// The `mesh` entry of an experiment file saved at `file`: a shape spec as is, a mesh
    /// file relative to the experiment file's folder (which is created, so that the path
    /// is computed from its real location; a failure is reported when the file is
    /// written).
    pub fn entry(&self, file: &Path) -> String {
        match &self.source {
            Source::Shape(s) => s.clone(),
            Source::File(p) => {
                let _ = std::fs::create_dir_all(parent_dir(file));
                relative_path(p, &parent_dir(file))
                    .to_string_lossy()
                    .into_owned()
            }
        }
    }
}

impl Input {
    /// A short label: the file name or the shape spec.
    pub fn label(&self) -> String {
        self.info.label()
    }

    /// Number of vertices or points.
    pub fn n(&self) -> usize {
        self.shape.n()
    }

    /// The mesh, or an error naming `what` (a command or an option) when the input is a
    /// point cloud.
    pub fn mesh(&self, what: &str) -> Result<&Mesh> {
        match &self.shape {
            AnalysisInput::Mesh(m) => Ok(m),
            AnalysisInput::Points { .. } => bail!(
                "{what} does not apply to a point cloud ({}): it needs a triangle mesh",
                self.label()
            ),
        }
    }

    /// The analysis of this input with `options`, and where the input came from.
    pub fn into_analysis(self, options: AnalysisOptions) -> Result<(Analysis, MeshInfo)> {
        Ok((Analysis::from_input(self.shape, options)?, self.info))
    }

    /// Sets the point-cloud Laplacian's parameters of a point-cloud input (and of its
    /// information); nothing for a mesh.
    pub fn set_cloud_params(&mut self, p: PointCloudParams) {
        if let AnalysisInput::Points { params, .. } = &mut self.shape {
            *params = p;
            self.info.point_cloud = Some(p);
        }
    }

    /// [`Input::mesh`], consuming the input.
    pub fn into_mesh(self, what: &str) -> Result<(Mesh, MeshInfo)> {
        match self.shape {
            AnalysisInput::Mesh(m) => Ok((m, self.info)),
            AnalysisInput::Points { .. } => bail!(
                "{what} does not apply to a point cloud ({}): it needs a triangle mesh",
                self.info.label()
            ),
        }
    }
}

/// Loads a file or builds a shape; `None` means the paper's default shape.
pub fn load(spec: Option<&str>) -> Result<Input> {
    let spec = spec.unwrap_or(shapes::DEFAULT_SHAPE);
    let path = Path::new(spec);
    let info = |source, polygons_triangulated, notes| MeshInfo {
        source,
        polygons_triangulated,
        notes,
        hash_as_read: None,
        point_cloud: None,
    };
    if path.exists() {
        return Ok(match read_input(path)? {
            io::Input::Mesh(loaded) => Input {
                shape: AnalysisInput::Mesh(loaded.mesh),
                info: info(
                    Source::File(path.to_path_buf()),
                    loaded.polygons_triangulated,
                    loaded.warnings,
                ),
            },
            io::Input::Points(p) => {
                let mut i = info(Source::File(path.to_path_buf()), 0, p.warnings);
                // A cloud is named by the hash of its points (its Laplacian's triangles
                // are derived).
                i.hash_as_read = Some(p.cloud.content_hash());
                i.point_cloud = Some(PointCloudParams::default());
                Input {
                    shape: p.cloud.into(),
                    info: i,
                }
            }
        });
    }
    if shapes::is_shape_spec(spec) {
        let s = shapes::parse_shape(spec)?;
        let mesh = shapes::build(&s).with_context(|| format!("building shape '{spec}'"))?;
        return Ok(Input {
            shape: AnalysisInput::Mesh(mesh),
            info: info(Source::Shape(spec.to_string()), 0, Vec::new()),
        });
    }
    if spec.contains(['/', '\\', '.']) {
        bail!("{spec}: no such file");
    }
    // Not a file and not a valid spec: let the parser explain what is wrong.
    shapes::parse_shape(spec)?;
    bail!("{spec}: neither a file nor a built-in shape (see `spectral-mesh shapes`)")
}

/// Loads and, when asked, repairs (keeping the hash of the mesh as read).
pub fn load_repaired(spec: Option<&str>, do_repair: bool) -> Result<Input> {
    let mut input = load(spec)?;
    if do_repair {
        let mesh = input.mesh("--repair")?;
        let r = repair(mesh, &RepairOptions::default())
            .with_context(|| format!("repairing {}", input.label()))?;
        input.info.hash_as_read = Some(mesh.content_hash());
        input.shape = AnalysisInput::Mesh(r.mesh);
        input.info.notes.extend(r.log);
    }
    Ok(input)
}

/// Reads a per-vertex field file of `n` values: the library's reader
/// ([`spectral_mesh::io::read_field`]: one value per line, `#` comments; a wrong count or a
/// value that is not a finite number is refused, naming the file and line).
pub fn read_field(path: &Path, n: usize) -> Result<Vec<f64>> {
    Ok(spectral_mesh::io::read_field(path, Some(n))?)
}
