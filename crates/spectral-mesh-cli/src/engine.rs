//! The command line's side of the one engine: the options every spectral command shares
//! (`-k`, `--laplacian`, `--tolerance`, `--cache`, `--repair`, and the point-cloud
//! Laplacian's `--neighbors`, `--use-normals`, `--mollify-factor`), the [`Analysis`] they
//! build, its eigenbasis with a progress bar (or from the cache), and the experiment file
//! a field command saves.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use spectral_mesh::analysis::request::DEFAULT_K;
use spectral_mesh::analysis::{
    Analysis, AnalysisError, AnalysisInput, AnalysisOptions, Field, FieldRequest,
};
use spectral_mesh::experiments::file::{ExperimentFile, PointCloudFile};
use spectral_mesh::linalg::EigenProgress;
use spectral_mesh::operators::{NormalSource, PointCloudParams};
use spectral_mesh::spectral::Eigenbasis;
use spectral_mesh::spectral::eigenbasis::EigenParams;
use spectral_mesh::spectral::store::load_or_compute;
use spectral_mesh::{CancelToken, Laplacian};
use spectral_mesh_render::figure::FigureOptions;

use crate::input::{self, Input, MeshInfo};
use crate::output::save_experiment;
use crate::progress::EigenBar;

/// How to compute the eigenbasis a command works on (defaults: the library's).
#[derive(Debug, Clone, clap::Args)]
pub struct BasisArgs {
    /// Number of eigenpairs (the smallest eigenvalues).
    #[arg(long, short = 'k', default_value_t = DEFAULT_K)]
    pub k: usize,
    /// Discretization: cot, voronoi-cot, fem (the default for meshes), mixed-voronoi,
    /// uniform, robust (tufted cover and intrinsic Delaunay: any triangle soup, for
    /// non-manifold meshes). A point cloud takes only robust, its point-cloud Laplacian
    /// (the default for point files).
    #[arg(long, help = LAPLACIAN_HELP, long_help = LAPLACIAN_LONG_HELP)]
    pub laplacian: Option<Laplacian>,
    /// Target relative residual of every eigenpair.
    #[arg(long, default_value_t = EigenParams::default().tolerance)]
    pub tolerance: f64,
    /// Keep computed bases in this folder and reuse them (keyed by the mesh, the
    /// discretization, the normalisation and the parameters).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Repair the mesh first (see `info --repair`).
    #[arg(long)]
    pub repair: bool,
    #[command(flatten)]
    pub cloud: CloudArgs,
}

/// The eigenbasis of a field command: [`BasisArgs`] and the shape scaled to unit area
/// unless `--no-normalize` (every field command; `eigs` reports the basis of the shape as
/// given).
#[derive(Debug, Clone, clap::Args)]
pub struct FieldBasisArgs {
    #[command(flatten)]
    pub basis: BasisArgs,
    /// Use the basis as given instead of the shape scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
}

impl FieldBasisArgs {
    /// The analysis of `input` ([`BasisArgs::analysis`]), at unit area unless
    /// `--no-normalize`.
    pub fn analysis(&self, input: AnalysisInput) -> Result<Analysis> {
        self.basis.analysis(input, !self.no_normalize)
    }

    /// What a command's summary line says of the scale: `", unit-area shape"`, or nothing
    /// with `--no-normalize`.
    pub fn scale_note(&self) -> &'static str {
        if self.no_normalize {
            ""
        } else {
            ", unit-area shape"
        }
    }
}

/// The point-cloud Laplacian's parameters, shared by every command that reads an input.
/// Unset options take the library's defaults ([`PointCloudParams::default`], shown in the
/// help); given with a mesh they are an error (see [`CloudArgs::apply`]).
#[derive(Debug, Clone, Default, clap::Args)]
#[command(next_help_heading = "Point clouds")]
pub struct CloudArgs {
    // Help (with the library's default) from `cloud_help`.
    #[arg(long, value_name = "K", help = cloud_help("neighbours per point of the point-cloud Laplacian (at least 2)", PointCloudParams::default().neighbors))]
    pub neighbors: Option<usize>,
    /// Point clouds: use the file's normals for the tangent planes (where non-zero)
    /// instead of estimating them from the neighbours.
    #[arg(long)]
    pub use_normals: bool,
    // Help (with the library's default) from `cloud_help`.
    #[arg(long, value_name = "F", help = cloud_help("relative mollification of the point-cloud Laplacian (as robust_laplacian's mollify_factor)", PointCloudParams::default().mollify_factor))]
    pub mollify_factor: Option<f64>,
}

/// A point-cloud option's help with the library's default.
fn cloud_help(what: &str, default: impl std::fmt::Display) -> String {
    format!("Point clouds: {what} [default: {default}]")
}

impl CloudArgs {
    /// The options given, by name (empty when none was).
    pub fn given(&self) -> Vec<&'static str> {
        let mut g = Vec::new();
        if self.neighbors.is_some() {
            g.push("--neighbors");
        }
        if self.use_normals {
            g.push("--use-normals");
        }
        if self.mollify_factor.is_some() {
            g.push("--mollify-factor");
        }
        g
    }

    /// The parameters: the options given over the library's defaults, checked.
    pub fn params(&self) -> Result<PointCloudParams> {
        let d = PointCloudParams::default();
        let p = PointCloudParams {
            neighbors: self.neighbors.unwrap_or(d.neighbors),
            mollify_factor: self.mollify_factor.unwrap_or(d.mollify_factor),
            normals: if self.use_normals {
                NormalSource::FromCloud
            } else {
                d.normals
            },
            ..d
        };
        if let Err(e) = p.validate() {
            bail!("{}: {e}", self.given().join(", "));
        }
        Ok(p)
    }

    /// Sets the parameters of a point-cloud input. With a mesh input, any option given is
    /// an error (not a warning): the user asked for an operator that is not the one that
    /// would be computed, and a warning scrolled away would leave results that silently
    /// ignore what was asked; the error names the options and costs nothing to fix.
    pub fn apply(&self, input: &mut Input) -> Result<()> {
        if input.shape.is_points() {
            input.set_cloud_params(self.params()?);
            return Ok(());
        }
        let given = self.given();
        if !given.is_empty() {
            bail!(
                "{} {} only to point clouds, and {} is a mesh (its Laplacian is chosen with --laplacian)",
                given.join(", "),
                if given.len() == 1 { "applies" } else { "apply" },
                input.label()
            );
        }
        Ok(())
    }

    /// [`input::load_repaired`] then [`CloudArgs::apply`].
    pub fn load(&self, spec: Option<&str>, repair: bool) -> Result<Input> {
        let mut input = input::load_repaired(spec, repair)?;
        self.apply(&mut input)?;
        Ok(input)
    }
}

/// The short help of every `--laplacian` option.
pub const LAPLACIAN_HELP: &str = "Discretization: cot, voronoi-cot, fem, mixed-voronoi, uniform, robust [default: fem; robust for point clouds, the only one that applies to them]";

/// The long help of every `--laplacian` option.
pub const LAPLACIAN_LONG_HELP: &str = "Discretization (S, B):
  fem            cotangent stiffness, consistent linear FEM mass (default for meshes)
  voronoi-cot    cotangent stiffness, barycentric lumped mass
  mixed-voronoi  cotangent stiffness, Meyer et al.'s mixed Voronoi mass
  cot            cotangent stiffness, B = I
  uniform        graph Laplacian, B = I (not geometric)
  robust         Sharp and Crane 2020: tufted cover, intrinsic Delaunay, lumped mass;
                 any triangle soup (non-manifold edges and vertices: see `info`)
Point clouds (.xyz/.pts/.txt/.csv, PLY without faces) take only robust: their
point-cloud Laplacian (k nearest neighbours, local Delaunay, tufted union; see the
'Point clouds' options); it is their default.";

/// The discretization for `input`: the library's rule
/// ([`spectral_mesh::defaults::laplacian_for`]: `given`, or fem for a mesh and robust for a
/// point cloud); refuses a discretization that does not apply to a point cloud, by name.
pub fn resolve_laplacian(given: Option<Laplacian>, input: &AnalysisInput) -> Result<Laplacian> {
    spectral_mesh::defaults::laplacian_for(given, input.is_points()).map_err(|e| match e {
        AnalysisError::NotForPoints { laplacian } => anyhow::anyhow!(
            "--laplacian {laplacian} does not apply to a point cloud: it needs triangles; a point cloud has only its point-cloud Laplacian, --laplacian robust (the default for point files)"
        ),
        e => e.into(),
    })
}

impl BasisArgs {
    /// Loads the input (repaired with --repair) and sets a point cloud's Laplacian
    /// parameters from the point-cloud options (refused with a mesh).
    pub fn load(&self, spec: Option<&str>) -> Result<Input> {
        self.cloud.load(spec, self.repair)
    }

    /// The analysis options for `input`: these, the shape scaled to unit area when
    /// `normalize`, zero Dirichlet conditions on `dirichlet`.
    pub fn options(
        &self,
        input: &AnalysisInput,
        normalize: bool,
        dirichlet: Option<Vec<usize>>,
    ) -> Result<AnalysisOptions> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            bail!("--tolerance {}: must be a positive number", self.tolerance);
        }
        Ok(AnalysisOptions {
            laplacian: resolve_laplacian(self.laplacian, input)?,
            normalize,
            eigen: EigenParams {
                tolerance: self.tolerance,
                dirichlet,
                ..EigenParams::default()
            },
        })
    }

    /// Refuses `-k` out of range for a mesh of `n` vertices, before any work.
    pub fn check_k(&self, n: usize) -> Result<()> {
        if self.k == 0 {
            bail!("-k 0: at least one eigenpair is needed");
        }
        if self.k > n {
            bail!("-k {}: the input has only {n} vertices", self.k);
        }
        Ok(())
    }

    /// The analysis of a mesh or a point cloud with these options (`-k` is checked
    /// against the input when a request needs the eigenbasis).
    pub fn analysis(&self, input: AnalysisInput, normalize: bool) -> Result<Analysis> {
        let options = self.options(&input, normalize, None)?;
        Ok(Analysis::from_input(input, options)?)
    }

    /// Warns when an option cannot be recorded in an experiment file.
    pub fn warn_unrecorded(&self, file: Option<&PathBuf>) {
        if file.is_some() && self.tolerance != EigenParams::default().tolerance {
            eprintln!(
                "warning: --tolerance is not recorded in experiment files; the replay uses the default {}",
                EigenParams::default().tolerance
            );
        }
    }
}

/// The cache folder of an analysis: `DIR` for the shape as given, `DIR/unit-area` for the
/// shape scaled to unit area (the two bases differ).
fn cache_dir(dir: &Path, normalize: bool) -> PathBuf {
    if normalize {
        dir.join("unit-area")
    } else {
        dir.to_path_buf()
    }
}

/// A basis computed (or loaded) for a command.
pub struct Solved {
    /// The basis (at least the pairs asked for).
    pub basis: Arc<Eigenbasis>,
    /// Wall seconds it took.
    pub seconds: f64,
    /// `max |X^T B X - I|` as the solver reported it, when it was computed now.
    pub orthogonality: Option<f64>,
}

/// A basis of at least `k` pairs on `an`, from the cache folder when given (computed and
/// stored there otherwise), with a progress bar.
pub fn basis(an: &Analysis, k: usize, cache: Option<&Path>) -> Result<Solved> {
    let t0 = Instant::now();
    let bar = EigenBar::new(k);
    let mut report = |p: EigenProgress| bar.update(p);
    if let Some(dir) = cache
        && an.held_k() < k
    {
        let params = EigenParams {
            k,
            ..an.options().eigen.clone()
        };
        let (b, hit) = load_or_compute(
            &cache_dir(dir, an.options().normalize),
            an.mesh(),
            an.operators(),
            &params,
            &mut report,
        )
        .with_context(|| format!("--cache {}", dir.display()))?;
        an.set_basis(b)?;
        println!(
            "eigenbasis {} cache {}",
            if hit {
                "loaded from"
            } else {
                "computed and stored in"
            },
            dir.display()
        );
    }
    let basis = an.basis(k, &mut report, &CancelToken::new())?;
    bar.finish();
    Ok(Solved {
        basis,
        seconds: t0.elapsed().as_secs_f64(),
        orthogonality: bar.orthogonality(),
    })
}

/// The field of `request` on `an`, its eigenbasis first from [`basis`]; returns the field
/// and the seconds the eigenbasis took (0 when none is needed).
pub fn field(an: &Analysis, request: &FieldRequest, cache: Option<&Path>) -> Result<(Field, f64)> {
    request.validate().map_err(|e| anyhow::anyhow!("--{e}"))?;
    let seconds = match request.eigenpairs() {
        Some(k) => basis(an, k, cache)?.seconds,
        None => 0.0,
    };
    Ok((an.field(request)?, seconds))
}

/// Refuses a vertex index out of range before any work, naming the option.
pub fn check_vertex(v: usize, n: usize, option: &str) -> Result<()> {
    if v >= n {
        bail!("{option} {v}: the input has only {n} vertices");
    }
    Ok(())
}

/// The analysis keys of an experiment file for `an` on the mesh of `info`, saved at
/// `file`: mesh, its hash as read, repair, discretization, normalisation, a point cloud's
/// Laplacian parameters, picture options.
pub fn experiment_file(
    experiment: &str,
    file: &Path,
    info: &MeshInfo,
    an: &Analysis,
    repair: bool,
    figure: &FigureOptions,
) -> ExperimentFile {
    ExperimentFile {
        mesh_hash: Some(info.hash(an.mesh())),
        repair: Some(repair),
        laplacian: Some(an.options().laplacian.name().into()),
        normalize: Some(an.options().normalize),
        figure: Some(figure.to_file()),
        point_cloud: info.point_cloud.as_ref().map(PointCloudFile::from_params),
        ..ExperimentFile::new(experiment, &info.entry(file))
    }
}

/// Saves `field` as an `experiment = "field"` file at `file`: `run FILE` computes the same
/// field (the same pairs: `basis_k` is written when the basis held more than the `k`
/// used) and writes `KIND.wrl`, `KIND.png`, `KIND.txt` and `summary.json` next to it.
pub fn save_field_experiment(
    file: &Path,
    info: &MeshInfo,
    an: &Analysis,
    field: &Field,
    repair: bool,
    figure: &FigureOptions,
    force: bool,
) -> Result<()> {
    let mut f = experiment_file("field", file, info, an, repair, figure);
    f.field = Some(field.request.clone());
    f.basis_k = match (field.k, field.basis_k) {
        (Some(k), Some(bk)) if bk > k => Some(bk),
        _ => None,
    };
    save_experiment(file, &f, force)
}
