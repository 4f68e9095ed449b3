//! The job of one shape: read, solve, compute the descriptors, write the files, return
//! the row. Never panics and never stops a batch: whatever goes wrong becomes the row's
//! error.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use crate::analysis::Analysis;
use crate::cancel::CancelToken;
use crate::geodesic::{GeodesicParams, farthest_point_sampling};
use crate::io::{Input, read_input_from_bytes, write_atomic_durable};
use crate::linalg::{EigenProgress, connected_components};
use crate::mesh::Mesh;
use crate::operators::{Laplacian, Operators};
use crate::spectral::eigenbasis::EigenSolver;
use crate::spectral::filters::ZERO_EIGENVALUE_EPS;
use crate::spectral::signatures::{auto_diffusion, hks, hks_auto_times, wks, wks_auto_energies};
use crate::spectral::store::{BasisMeta, npy_f64, read_npz_meta, save_npz_with};
use crate::spectral::{BasisView, Eigenbasis};

use super::memory;
use super::params::{BatchParams, DescriptorParams, RESULT_VERSION, Schedule};
use super::record::{BasisSummary, BatchRecord, InputKind, ShapeCounts, Status};
use super::{BatchInput, FAILURE_SUFFIX, THUMBNAIL_SUFFIX};

/// Draws the thumbnail of a batch result. The library draws no pictures (it does not
/// depend on the render crate): a face passes an implementation drawing with
/// `spectral_mesh_render::Figure`: both faces pass `spectral_mesh_render::Thumbnails` (the
/// field with 10 level sets, no markers, no colour bar).
pub trait Thumbnailer: Sync {
    /// PNG bytes of the per-vertex `values` (`n` entries) on `mesh`, `size x size` pixels.
    fn png(&self, mesh: &Mesh, values: &[f64], size: u32) -> Result<Vec<u8>, String>;
}

/// How one job runs (none of this enters the parameter hash).
#[derive(Clone, Default)]
pub struct JobOptions<'a> {
    /// Threads of the job's own rayon pool; 0 runs on the caller's pool. A worker that
    /// runs several jobs at once gives each its share, so that they do not oversubscribe
    /// the cores.
    pub threads: usize,
    /// Draws thumbnails; needed when [`BatchParams::thumbnail`] is set.
    pub thumbnailer: Option<&'a dyn Thumbnailer>,
    /// Compute again shapes that failed before with the same hashes (their failure marker
    /// is ignored).
    pub retry_failed: bool,
    /// Stops the eigensolver (the row says "cancelled"; nothing is written).
    pub cancel: CancelToken,
    /// The eigensolver's progress.
    pub progress: Option<&'a (dyn Fn(EigenProgress) + Sync)>,
}

impl std::fmt::Debug for JobOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("JobOptions")
            .field("threads", &self.threads)
            .field("thumbnailer", &self.thumbnailer.is_some())
            .field("retry_failed", &self.retry_failed)
            .finish()
    }
}

/// What a result file says about itself (its `meta` array): the eigenbasis metadata of
/// [`BasisMeta`] (so that [`crate::spectral::store::load_npz`] reads a result saved with
/// its basis) and the batch's own keys under `batch`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ResultMeta {
    /// The eigenbasis metadata.
    #[serde(flatten)]
    pub basis: BasisMeta,
    /// The batch keys.
    pub batch: BatchMeta,
}

/// What a stored file of a shape (its result or its failure marker) was made from: it
/// stands for the shape only while all of it agrees with the input and the parameters.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ResultKey {
    /// [`RESULT_VERSION`].
    pub result_version: u32,
    /// The shape's name.
    pub name: String,
    /// BLAKE3 of the input file's bytes.
    pub input_hash: String,
    /// [`BatchParams::hash`].
    pub params_hash: String,
}

impl ResultKey {
    /// The key of a file written now.
    pub fn new(name: &str, input_hash: &str, params_hash: &str) -> Self {
        Self {
            result_version: RESULT_VERSION,
            name: name.to_string(),
            input_hash: input_hash.to_string(),
            params_hash: params_hash.to_string(),
        }
    }

    /// True when a file with this key stands for the input and parameters with these
    /// hashes (and was written by this result version).
    pub fn matches(&self, input_hash: &str, params_hash: &str) -> bool {
        self.result_version == RESULT_VERSION
            && self.input_hash == input_hash
            && self.params_hash == params_hash
    }
}

/// Where the descriptors of a result were evaluated (each also an array of the result
/// file, under its key's name): `None` for a descriptor not asked for.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DescriptorAxes {
    /// HKS times used (the array `hks_times`).
    pub hks_times: Option<Vec<f64>>,
    /// WKS energies used (the array `wks_energies`).
    pub wks_energies: Option<Vec<f64>>,
    /// WKS bandwidth used.
    pub wks_sigma: Option<f64>,
    /// ADF times used (the array `adf_times`).
    pub adf_times: Option<Vec<f64>>,
}

impl DescriptorAxes {
    /// The arrays of the axes asked for: `(name, values)`.
    fn arrays(&self) -> impl Iterator<Item = (&'static str, &Vec<f64>)> {
        [
            ("hks_times", &self.hks_times),
            ("wks_energies", &self.wks_energies),
            ("adf_times", &self.adf_times),
        ]
        .into_iter()
        .filter_map(|(name, v)| v.as_ref().map(|v| (name, v)))
    }
}

/// The batch keys of a result (or of a failure marker): only what the input and the
/// parameters determine, so that two runs write the same bytes. In JSON the keys of
/// [`ResultKey`] and [`DescriptorAxes`] stand beside the others.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BatchMeta {
    /// What the result was made from.
    #[serde(flatten)]
    pub key: ResultKey,
    /// The parameters.
    pub params: BatchParams,
    /// Mesh or points.
    pub kind: InputKind,
    /// Triangles.
    pub faces: usize,
    /// Connected components.
    pub components: usize,
    /// Largest relative residual.
    pub max_residual: Option<f64>,
    /// The files of the shape, relative to the output folder, the result last.
    pub outputs: Vec<String>,
    /// Where the descriptors were evaluated.
    #[serde(flatten)]
    pub descriptors: DescriptorAxes,
    /// The farthest-point samples of the geodesic distances (also the array
    /// `geodesic_sources`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geodesic_sources: Option<Vec<usize>>,
    /// The reader's warnings.
    pub warnings: Vec<String>,
}

/// The failure marker `NAME.error.json`: a shape that failed with these hashes is not
/// tried again unless asked ([`JobOptions::retry_failed`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct FailureMarker {
    #[serde(flatten)]
    key: ResultKey,
    error: String,
    kind: Option<InputKind>,
    n: Option<usize>,
    faces: Option<usize>,
}

/// An error of a job: the message of the row; `marker` says whether the failure is a
/// property of the input and parameters (kept in a failure marker) or of this run
/// (cancelled, disk full: tried again next time).
struct JobError {
    message: String,
    marker: bool,
}

impl<E: std::fmt::Display> From<E> for JobError {
    fn from(e: E) -> Self {
        Self {
            message: e.to_string(),
            marker: true,
        }
    }
}

fn transient(message: impl Into<String>) -> JobError {
    JobError {
        message: message.into(),
        marker: false,
    }
}

/// Processes one shape (see the module documentation of [`crate::batch`]): returns its
/// row, never panics (a panic inside becomes a failed row).
///
/// Skips the shape (status skipped) when `out/NAME.npz` holds a result with the same
/// input hash, parameter hash and result version and every file it lists exists; reports
/// the earlier failure (status failed, reused) when `out/NAME.error.json` matches the same
/// way, unless [`JobOptions::retry_failed`]. Otherwise computes and writes the thumbnail
/// (when asked) and then the result, each to a temporary name renamed into place: the
/// result file appears last and only complete.
pub fn process_one(
    input: &BatchInput,
    params: &BatchParams,
    out: &Path,
    options: &JobOptions<'_>,
) -> BatchRecord {
    let t0 = Instant::now();
    let params_hash = params.hash();
    let mut rec = BatchRecord::new(&input.name, &input.path.display().to_string(), &params_hash);
    rec.basis.discretization = params.solve.laplacian.name().to_string();
    memory::reset_peak();
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        run(input, params, &params_hash, out, options, &mut rec)
    }));
    let error = match outcome {
        Ok(Ok(())) => None,
        Ok(Err(e)) => Some(e),
        Err(panic) => Some(JobError {
            message: super::panic_message(&*panic),
            marker: true,
        }),
    };
    if let Some(e) = error {
        rec.status = Status::Failed;
        rec.error = Some(e.message.clone());
        if !rec.reused {
            record_failure(input, out, &rec, e.marker);
        }
    }
    if rec.status == Status::Ok {
        rec.peak_memory_bytes = memory::peak_bytes();
    }
    rec.seconds = t0.elapsed().as_secs_f64();
    rec
}

/// The files of a shape.
struct Paths {
    result: PathBuf,
    thumbnail: PathBuf,
    marker: PathBuf,
}

impl Paths {
    fn new(input: &BatchInput, out: &Path) -> Self {
        Self {
            result: input.result_path(out),
            thumbnail: out.join(format!("{}{THUMBNAIL_SUFFIX}", input.name)),
            marker: out.join(format!("{}{FAILURE_SUFFIX}", input.name)),
        }
    }
}

/// After a failure: stale outputs of the shape removed (they were made from another input
/// or other parameters), and the failure marker written when the failure is one of the
/// input and parameters.
fn record_failure(input: &BatchInput, out: &Path, rec: &BatchRecord, keep: bool) {
    let p = Paths::new(input, out);
    if !keep {
        return;
    }
    let _ = std::fs::remove_file(&p.result);
    let _ = std::fs::remove_file(&p.thumbnail);
    let (Some(input_hash), Some(error)) = (&rec.input_hash, &rec.error) else {
        return;
    };
    let m = FailureMarker {
        key: ResultKey::new(&rec.name, input_hash, &rec.params_hash),
        error: error.clone(),
        kind: rec.shape.kind,
        n: rec.shape.n,
        faces: rec.shape.faces,
    };
    if let Ok(json) = serde_json::to_vec_pretty(&m)
        && let Some(dir) = p.marker.parent()
        && std::fs::create_dir_all(dir).is_ok()
    {
        let _ = write_atomic_durable(&p.marker, &json);
    }
}

/// The stored result of a shape when it matches the hashes and its files are all there.
fn stored_result(p: &Paths, out: &Path, input_hash: &str, params_hash: &str) -> Option<ResultMeta> {
    if !p.result.is_file() {
        return None;
    }
    let bytes = read_npz_meta(&p.result).ok()?;
    let meta: ResultMeta = serde_json::from_slice(&bytes).ok()?;
    let b = &meta.batch;
    (b.key.matches(input_hash, params_hash) && b.outputs.iter().all(|o| out.join(o).is_file()))
        .then_some(meta)
}

fn stored_failure(p: &Paths, input_hash: &str, params_hash: &str) -> Option<FailureMarker> {
    let bytes = std::fs::read(&p.marker).ok()?;
    let m: FailureMarker = serde_json::from_slice(&bytes).ok()?;
    m.key.matches(input_hash, params_hash).then_some(m)
}

fn run(
    input: &BatchInput,
    params: &BatchParams,
    params_hash: &str,
    out: &Path,
    options: &JobOptions<'_>,
    rec: &mut BatchRecord,
) -> Result<(), JobError> {
    params.validate()?;
    let label = input.path.display().to_string();
    let bytes = std::fs::read(&input.path).map_err(|e| format!("{label}: cannot read: {e}"))?;
    let input_hash = blake3::hash(&bytes).to_hex().to_string();
    rec.input_hash = Some(input_hash.clone());
    let paths = Paths::new(input, out);
    if let Some(meta) = stored_result(&paths, out, &input_hash, params_hash) {
        let b = meta.batch;
        rec.status = Status::Skipped;
        rec.reused = true;
        rec.shape = ShapeCounts {
            kind: Some(b.kind),
            n: Some(meta.basis.n),
            faces: Some(b.faces),
            components: Some(b.components),
        };
        rec.basis = BasisSummary {
            k: Some(meta.basis.k),
            discretization: meta.basis.laplacian.name().to_string(),
            max_residual: b.max_residual,
        };
        rec.outputs = b.outputs;
        rec.warnings = b.warnings;
        return Ok(());
    }
    if !options.retry_failed
        && let Some(m) = stored_failure(&paths, &input_hash, params_hash)
    {
        rec.reused = true;
        rec.shape.kind = m.kind;
        rec.shape.n = m.n;
        rec.shape.faces = m.faces;
        return Err(JobError {
            message: m.error,
            marker: true,
        });
    }
    let parsed = read_input_from_bytes(&bytes, &label)?;
    drop(bytes);
    rec.warnings = parsed.warnings().to_vec();
    let solve = || solve(parsed, params, options, rec);
    let solved = if options.threads > 0 {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(options.threads)
            .build()
            .map_err(|e| transient(format!("cannot start {} threads: {e}", options.threads)))?;
        pool.install(solve)?
    } else {
        solve()?
    };
    write_outputs(
        input,
        params,
        params_hash,
        &input_hash,
        out,
        &paths,
        options,
        solved,
        rec,
    )?;
    let _ = std::fs::remove_file(&paths.marker);
    rec.status = Status::Ok;
    Ok(())
}

/// What the solve produced.
struct Solved {
    basis: Arc<Eigenbasis>,
    mesh: Option<Arc<Mesh>>,
    mesh_hash: String,
    kind: InputKind,
    laplacian: Laplacian,
    /// Where the descriptors were evaluated.
    axes: DescriptorAxes,
    /// The descriptor arrays: `(name, one column per time or energy)`.
    columns: Vec<(&'static str, Vec<Vec<f64>>)>,
    /// Farthest-point samples and the distance from each (meshes with
    /// [`BatchParams::geodesic`]).
    geodesic: Option<(Vec<usize>, Vec<Vec<f64>>)>,
}

fn solve(
    parsed: Input,
    params: &BatchParams,
    options: &JobOptions<'_>,
    rec: &mut BatchRecord,
) -> Result<Solved, JobError> {
    let k = params.k;
    let eigen = params.eigen();
    let noop = |_: EigenProgress| {};
    let report: &(dyn Fn(EigenProgress) + Sync) = options.progress.unwrap_or(&noop);
    let mut progress = |p: EigenProgress| report(p);
    let cancelled = |e: &crate::analysis::AnalysisError| {
        matches!(
            e,
            crate::analysis::AnalysisError::Eigen(
                crate::spectral::eigenbasis::EigenError::Cancelled
            )
        )
    };
    let mut geodesic = None;
    let (basis, mesh, mesh_hash, kind, laplacian) = match parsed {
        Input::Mesh(loaded) => {
            let mesh = loaded.mesh;
            rec.shape.kind = Some(InputKind::Mesh);
            rec.shape.n = Some(mesh.n_vertices());
            rec.shape.faces = Some(mesh.n_triangles());
            let an = Analysis::new(mesh, params.solve.analysis_options(k));
            rec.shape.components = Some(an.topology().n_components());
            let basis = an.basis(k, &mut progress, &options.cancel).map_err(|e| {
                if cancelled(&e) {
                    transient(e.to_string())
                } else {
                    JobError::from(e)
                }
            })?;
            if let Some(count) = params.geodesic {
                geodesic = Some(geodesic_columns(&an, count)?);
            }
            let hash = an.mesh().content_hash();
            (
                basis,
                Some(an.mesh_arc().clone()),
                hash,
                InputKind::Mesh,
                params.solve.laplacian,
            )
        }
        Input::Points(loaded) => {
            let cloud = loaded.cloud;
            rec.shape.kind = Some(InputKind::Points);
            rec.shape.n = Some(cloud.n_points());
            rec.shape.faces = Some(0);
            rec.basis.discretization = Laplacian::Robust.name().to_string();
            if params.geodesic.is_some() {
                rec.warnings
                    .push("no geodesic distances: the input is a point cloud".into());
            }
            let n = cloud.n_points();
            if k > n {
                return Err(format!(
                    "k = {k} eigenpairs asked for, but the point cloud has only {n} points"
                )
                .into());
            }
            let mut ops = Operators::from_points(&cloud, &params.point_cloud)?;
            rec.shape.components = Some(connected_components(&ops.stiffness, &ops.mass)?.len());
            // The same scale normalisation as an analysis of a mesh.
            ops.normalize_mass(params.solve.normalize);
            let mut solver = EigenSolver::new(Arc::new(ops), eigen);
            let basis = solver
                .solve(k, &mut progress, &options.cancel)
                .map_err(|e| match e {
                    crate::spectral::eigenbasis::EigenError::Cancelled => transient(e.to_string()),
                    other => JobError::from(other),
                })?;
            (
                basis,
                None,
                String::new(),
                InputKind::Points,
                Laplacian::Robust,
            )
        }
    };
    rec.basis.k = Some(basis.k());
    rec.basis.max_residual = basis.residuals.iter().copied().reduce(f64::max);
    let (axes, columns) = descriptors(&params.descriptors, basis.view(k))?;
    Ok(Solved {
        basis,
        mesh,
        mesh_hash,
        kind,
        laplacian,
        axes,
        columns,
        geodesic,
    })
}

/// The descriptors of `d` on `view`: where they were evaluated, and their arrays
/// (`(name, one column per time or energy)`), every value finite.
#[allow(clippy::type_complexity)]
fn descriptors(
    d: &DescriptorParams,
    view: BasisView<'_>,
) -> Result<(DescriptorAxes, Vec<(&'static str, Vec<Vec<f64>>)>), JobError> {
    let mut axes = DescriptorAxes::default();
    let mut columns = Vec::new();
    let times = |s: &Schedule| match s {
        Schedule::Auto(n) => hks_auto_times(view, *n),
        Schedule::Values(v) => Ok(v.clone()),
    };
    if let Some(s) = &d.hks {
        let t = times(s)?;
        columns.push(("hks", hks(view, &t, d.scaled)));
        axes.hks_times = Some(t);
    }
    if let Some(s) = &d.wks {
        let (energies, sigma) = match s {
            Schedule::Auto(n) => {
                let (e, sigma) = wks_auto_energies(view, *n)?;
                (e, d.wks_sigma.unwrap_or(sigma))
            }
            Schedule::Values(v) => (v.clone(), d.wks_list_sigma()),
        };
        columns.push(("wks", wks(view, &energies, sigma, d.scaled)?));
        axes.wks_energies = Some(energies);
        axes.wks_sigma = Some(sigma);
    }
    if let Some(s) = &d.adf {
        let t = times(s)?;
        let values = t
            .iter()
            .map(|&t| auto_diffusion(view, t))
            .collect::<Result<Vec<_>, _>>()?;
        columns.push(("adf", values));
        axes.adf_times = Some(t);
    }
    for (name, values) in &columns {
        if let Some((c, i)) = values
            .iter()
            .enumerate()
            .find_map(|(c, col)| col.iter().position(|v| !v.is_finite()).map(|i| (c, i)))
        {
            return Err(format!(
                "{name} column {c} has a non-finite value at vertex {i}: try other times or fewer pairs"
            )
            .into());
        }
    }
    Ok((axes, columns))
}

/// `count` farthest-point samples of `an`'s mesh (from the vertex of largest x) and the
/// heat-method distance from each (`inf` where a sample cannot reach; NaN refused).
fn geodesic_columns(an: &Analysis, count: usize) -> Result<(Vec<usize>, Vec<Vec<f64>>), JobError> {
    let solver = an.geodesic_solver(&GeodesicParams::default())?;
    let samples = farthest_point_sampling(&solver, count, an.default_source())
        .map_err(|e| format!("geodesic: {e}"))?;
    let rows = solver
        .distances_from_vertices(&samples)
        .map_err(|e| format!("geodesic: {e}"))?;
    for (j, row) in rows.iter().enumerate() {
        if let Some(i) = row.iter().position(|v| v.is_nan()) {
            return Err(format!(
                "geodesic column {j} (from vertex {}) is not a number at vertex {i}",
                samples[j]
            )
            .into());
        }
    }
    Ok((samples, rows))
}

/// The first eigenvector with a non-zero eigenvalue (the first one when all are zero).
fn thumbnail_vector(basis: &Eigenbasis) -> &[f64] {
    let lmax = basis.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let j = basis
        .values
        .iter()
        .position(|&v| v.abs() > ZERO_EIGENVALUE_EPS * lmax)
        .unwrap_or(0);
    basis.vector(j)
}

fn relative(p: &Path, out: &Path) -> String {
    p.strip_prefix(out)
        .unwrap_or(p)
        .to_string_lossy()
        .replace('\\', "/")
}

#[allow(clippy::too_many_arguments)]
fn write_outputs(
    input: &BatchInput,
    params: &BatchParams,
    params_hash: &str,
    input_hash: &str,
    out: &Path,
    paths: &Paths,
    options: &JobOptions<'_>,
    solved: Solved,
    rec: &mut BatchRecord,
) -> Result<(), JobError> {
    if let Some(dir) = paths.result.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| transient(format!("{}: cannot create folder: {e}", dir.display())))?;
    }
    let mut outputs = Vec::new();
    let mut warnings = rec.warnings.clone();
    if let Some(size) = params.thumbnail {
        match (&solved.mesh, options.thumbnailer) {
            (Some(mesh), Some(t)) => {
                let png = t
                    .png(mesh, thumbnail_vector(&solved.basis), size)
                    .map_err(|e| format!("thumbnail: {e}"))?;
                write_atomic_durable(&paths.thumbnail, &png)
                    .map_err(|e| transient(e.to_string()))?;
                outputs.push(relative(&paths.thumbnail, out));
            }
            (Some(_), None) => {
                return Err(transient(
                    "a thumbnail was asked for but this face passed no thumbnail renderer",
                ));
            }
            (None, _) => warnings.push("no thumbnail: the input is a point cloud".into()),
        }
    }
    outputs.push(relative(&paths.result, out));
    let b = &solved.basis;
    let n = b.n;
    let mut extra = Vec::new();
    let mut times = |name: &str, v: &[f64]| -> Result<(), JobError> {
        extra.push((
            name.to_string(),
            npy_f64(v, &[v.len() as u64], false).map_err(|e| transient(e.to_string()))?,
        ));
        Ok(())
    };
    for (name, values) in solved.axes.arrays() {
        times(name, values)?;
    }
    let mut geodesic_sources = None;
    if let Some((samples, _)) = &solved.geodesic {
        let v: Vec<f64> = samples.iter().map(|&s| s as f64).collect();
        times("geodesic_sources", &v)?;
        geodesic_sources = Some(samples.clone());
    }
    let geodesic = solved
        .geodesic
        .as_ref()
        .map(|(_, rows)| ("geodesic".to_string(), rows));
    for (name, values) in solved
        .columns
        .iter()
        .map(|(name, values)| (name.to_string(), values))
        .chain(geodesic)
    {
        let flat: Vec<f64> = values.iter().flatten().copied().collect();
        let npy = npy_f64(&flat, &[n as u64, values.len() as u64], true)
            .map_err(|e| transient(e.to_string()))?;
        extra.push((name, npy));
    }
    let mut basis_meta = BasisMeta::new(b, None, &params.eigen());
    basis_meta.mesh_hash = solved.mesh_hash.clone();
    basis_meta.laplacian = solved.laplacian;
    let meta = ResultMeta {
        basis: basis_meta,
        batch: BatchMeta {
            key: ResultKey::new(&input.name, input_hash, params_hash),
            params: params.clone(),
            kind: solved.kind,
            faces: rec.shape.faces.unwrap_or(0),
            components: rec.shape.components.unwrap_or(0),
            max_residual: rec.basis.max_residual,
            outputs: outputs.clone(),
            descriptors: solved.axes,
            geodesic_sources,
            warnings: warnings.clone(),
        },
    };
    save_npz_with(b, &paths.result, &meta, params.basis, &extra)
        .map_err(|e| transient(e.to_string()))?;
    rec.outputs = outputs;
    rec.warnings = warnings;
    Ok(())
}
