//! `spectral-mesh experiment harmonic | diffusion-basis | spectral-distance | paper`:
//! the executable paper's three experiments with its defaults and file names. What they
//! compute and summarise is the library's (`experiments::paper`); this module parses the
//! arguments and writes the files.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use spectral_mesh::analysis::request::{DEFAULT_HEAT_T, DEFAULT_K};
use spectral_mesh::analysis::{Analysis, AnalysisOptions, DistanceSpec, FieldRequest, Kernel};
use spectral_mesh::experiments::file::parent_dir;
use spectral_mesh::experiments::file::{ExperimentFile, HarmonicConstraints, relative_path};
use spectral_mesh::experiments::harmonic::HarmonicExperimentParams;
use spectral_mesh::experiments::paper::{
    self, SUMMARY_FILE, field_outputs, harmonic_outputs, output_stem,
};
use spectral_mesh::fields::harmonic::{Constraint, parse_constraint_arg, read_constraints_file};
use spectral_mesh::linalg::EigenProgress;
use spectral_mesh::spectral::eigenbasis::EigenParams;
use spectral_mesh::{CancelToken, Laplacian};
use spectral_mesh_render::figure::{Figure, FigureOptions, POINT_RADIUS_FACTOR};

use crate::engine::{
    CloudArgs, LAPLACIAN_HELP, LAPLACIAN_LONG_HELP, check_vertex, resolve_laplacian,
};
use crate::figure::{FigureArgs, write_field_files};
use crate::input::{self, Input};
use crate::output::{check_experiment_file, prepare_outputs, save_experiment, write_json};
use crate::progress::EigenBar;

/// The experiments.
#[derive(Debug, clap::Subcommand)]
pub enum Experiment {
    /// Harmonic maps with 2, 4 and 6 Dirichlet constraints (Figs. 2, 3): writes
    /// harmonic-map-{1,2,3}.{wrl,png}, harmonic-field-{1,2,3}.txt, summary.json.
    Harmonic(HarmonicArgs),
    /// The heat-kernel basis function K_t e_i at an anchor (Figs. 4-6): writes
    /// diffusion-basis.{wrl,png,txt}, summary.json.
    DiffusionBasis(DiffusionArgs),
    /// A filtered spectral distance from a source (Figs. 8-10, 14): writes
    /// filtered-spectral-distance.{wrl,png,txt}, summary.json.
    SpectralDistance(DistanceArgs),
    /// All three experiments with the paper's defaults, each in its own folder.
    Paper(PaperArgs),
}

/// Options shared by the experiments.
#[derive(Debug, Clone, clap::Args)]
pub struct Common {
    /// Output folder (created if needed).
    #[arg(long, short = 'o', default_value = ".")]
    pub out: PathBuf,
    /// Overwrite existing output files.
    #[arg(long, short = 'f')]
    pub force: bool,
    /// Repair the mesh before computing.
    #[arg(long)]
    pub repair: bool,
    /// Also write an experiment file that reproduces this run with `run FILE.toml` (every
    /// parameter explicit, the mesh's hash included).
    #[arg(long, value_name = "FILE.toml")]
    pub save_experiment: Option<PathBuf>,
    #[command(flatten)]
    pub figure: FigureArgs,
    #[command(flatten)]
    pub cloud: CloudArgs,
}

/// Where and how an experiment writes: [`Common`] with the picture options resolved (from
/// the command line or from an experiment file's `[figure]`).
#[derive(Debug, Clone)]
pub struct Outputs {
    /// Output folder.
    pub out: PathBuf,
    /// Overwrite existing files.
    pub force: bool,
    /// Repair the mesh before computing.
    pub repair: bool,
    /// Experiment file to save.
    pub save_experiment: Option<PathBuf>,
    /// Picture options.
    pub figure: FigureOptions,
}

impl Outputs {
    /// Creates the output folder and returns the paths of `names` in it, checking before
    /// any work that none of them, nor the experiment file, exists unless `--force`.
    fn prepare(&self, names: &[&str]) -> Result<Vec<PathBuf>> {
        let paths = prepare_outputs(&self.out, names, self.force)?;
        check_experiment_file(self.save_experiment.as_ref(), self.force)?;
        Ok(paths)
    }
}

impl From<&Common> for Outputs {
    fn from(c: &Common) -> Self {
        Self {
            out: c.out.clone(),
            force: c.force,
            repair: c.repair,
            save_experiment: c.save_experiment.clone(),
            figure: c.figure.options(),
        }
    }
}

/// Arguments of `experiment harmonic`.
#[derive(Debug, clap::Args)]
pub struct HarmonicArgs {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Numbers of default constraints (min/max x, then y, then z), one map each.
    #[arg(long, value_delimiter = ',', default_values_t = HarmonicExperimentParams::default().constraint_counts)]
    pub constraints: Vec<usize>,
    /// An explicit constraint VERTEX=VALUE (repeatable); replaces the defaults.
    #[arg(long = "constraint", value_parser = parse_constraint_arg)]
    pub explicit: Vec<Constraint>,
    /// A file of `vertex value` lines; replaces the defaults.
    #[arg(long)]
    pub constraints_file: Option<PathBuf>,
    /// 1 = harmonic (S f = 0), 2 = bi-harmonic (S B^-1 S f = 0).
    #[arg(long, default_value_t = HarmonicExperimentParams::default().order)]
    pub order: u32,
    /// Discretization (matters for the bi-harmonic map's mass).
    #[arg(long, help = LAPLACIAN_HELP, long_help = LAPLACIAN_LONG_HELP)]
    pub laplacian: Option<Laplacian>,
    #[command(flatten)]
    pub common: Common,
}

/// Arguments of `experiment diffusion-basis`.
#[derive(Debug, clap::Args)]
pub struct DiffusionArgs {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Discretization: cot (K = X D_t X^T), voronoi-cot (X D_t X^T D), fem (X D_t X^T B).
    #[arg(long, help = LAPLACIAN_HELP, long_help = LAPLACIAN_LONG_HELP)]
    pub laplacian: Option<Laplacian>,
    /// Diffusion time (for the shape scaled to unit area unless --no-normalize).
    #[arg(long, default_value_t = DEFAULT_HEAT_T)]
    pub t: f64,
    /// Number of eigenpairs.
    #[arg(long, short = 'k', default_value_t = DEFAULT_K)]
    pub k: usize,
    /// Anchor vertex (default: the vertex of largest x, ties to the lowest index).
    #[arg(long)]
    pub anchor: Option<usize>,
    /// Use times for the shape as given instead of scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
    #[command(flatten)]
    pub common: Common,
}

/// Arguments of `experiment spectral-distance`.
#[derive(Debug, clap::Args)]
pub struct DistanceArgs {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// The filter: biharmonic, commute, diffusion:t=0.5, mix:a=0.5,t=0.5, poly:p=3,
    /// custom-w:EXPR;name=value, custom-phi:EXPR;..., or wfem-diffusion:t=0.5 (eq. 15).
    #[arg(long, default_value_t = DistanceSpec::default().to_string())]
    pub distance: String,
    /// Discretization.
    #[arg(long, help = LAPLACIAN_HELP, long_help = LAPLACIAN_LONG_HELP)]
    pub laplacian: Option<Laplacian>,
    /// Number of eigenpairs.
    #[arg(long, short = 'k', default_value_t = DEFAULT_K)]
    pub k: usize,
    /// Source vertex (default: the vertex of largest x, ties to the lowest index).
    #[arg(long)]
    pub source: Option<usize>,
    /// Use the basis as given instead of the shape scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
    #[command(flatten)]
    pub common: Common,
}

/// Arguments of `experiment paper`.
#[derive(Debug, clap::Args)]
pub struct PaperArgs {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// Runs an experiment.
pub fn run(e: Experiment) -> Result<()> {
    match e {
        Experiment::Harmonic(a) => {
            let input = a.common.cloud.load(a.mesh.as_deref(), a.common.repair)?;
            let constraints = match (&a.constraints_file, a.explicit.is_empty()) {
                (Some(f), _) => {
                    let mut c = read_constraints_file(f)?;
                    c.extend(a.explicit.iter().copied());
                    HarmonicConstraints::Explicit(c)
                }
                (None, false) => HarmonicConstraints::Explicit(a.explicit.clone()),
                (None, true) => HarmonicConstraints::Counts(a.constraints.clone()),
            };
            run_harmonic(
                input,
                &constraints,
                a.order,
                a.laplacian,
                &(&a.common).into(),
            )
        }
        Experiment::DiffusionBasis(a) => {
            // The experiment file's rule (a replay must accept what was run): t > 0.
            if !(a.t.is_finite() && a.t > 0.0) {
                bail!("--t {}: the time must be a positive number", a.t);
            }
            let input = a.common.cloud.load(a.mesh.as_deref(), a.common.repair)?;
            let request = FieldRequest::Heat {
                anchor: a.anchor,
                t: a.t,
                kernel: Kernel::Wfem,
                k: a.k,
            };
            let setup = FieldSetup {
                experiment: "diffusion-basis",
                request,
                basis_k: None,
                laplacian: a.laplacian,
                normalize: !a.no_normalize,
            };
            run_field(input, &setup, &(&a.common).into())
        }
        Experiment::SpectralDistance(a) => {
            let input = a.common.cloud.load(a.mesh.as_deref(), a.common.repair)?;
            let distance = a
                .distance
                .parse()
                .map_err(|e| anyhow::anyhow!("--distance {}: {e}", a.distance))?;
            let setup = FieldSetup {
                experiment: "spectral-distance",
                request: FieldRequest::Distance {
                    source: a.source,
                    distance,
                    k: a.k,
                },
                basis_k: None,
                laplacian: a.laplacian,
                normalize: !a.no_normalize,
            };
            run_field(input, &setup, &(&a.common).into())
        }
        Experiment::Paper(a) => run_paper(a),
    }
}

/// A field experiment: the paper's diffusion basis or spectral distance, or a `field`.
#[derive(Debug, Clone)]
pub struct FieldSetup {
    /// `diffusion-basis`, `spectral-distance` or `field`.
    pub experiment: &'static str,
    /// The field.
    pub request: FieldRequest,
    /// Pairs to compute when more than the request's `k` (replays).
    pub basis_k: Option<usize>,
    /// Discretization (`None`: fem for a mesh, robust for a point cloud).
    pub laplacian: Option<Laplacian>,
    /// Shape scaled to unit area.
    pub normalize: bool,
}

/// Runs a field experiment on `input` and writes `STEM.{wrl,png,txt}` and `summary.json`.
pub fn run_field(input: Input, setup: &FieldSetup, o: &Outputs) -> Result<()> {
    let n = input.n();
    let laplacian = resolve_laplacian(setup.laplacian, &input.shape)?;
    let request = &setup.request;
    request
        .validate()
        .map_err(|e| anyhow::anyhow!("--{e}"))
        .with_context(|| format!("experiment {}", setup.experiment))?;
    if let Some(v) = request.source() {
        let option = match request {
            FieldRequest::Heat { .. } => "--anchor",
            _ => "--source",
        };
        check_vertex(v, n, option)?;
    }
    if let Some(k) = request.eigenpairs().into_iter().chain(setup.basis_k).max()
        && k > n
    {
        bail!("-k {k}: the mesh has only {n} vertices");
    }
    let stem = output_stem(setup.experiment, request);
    let names = field_outputs(&stem);
    let all = [
        names[0].as_str(),
        names[1].as_str(),
        names[2].as_str(),
        SUMMARY_FILE,
    ];
    let paths = o.prepare(&all)?;
    let (an, info) = input.into_analysis(AnalysisOptions {
        laplacian,
        normalize: setup.normalize,
        eigen: EigenParams::default(),
    })?;
    let mesh_summary = info.summary(an.mesh(), an.topology());
    let bar = EigenBar::new(setup.basis_k.or(request.eigenpairs()).unwrap_or(0));
    let t0 = std::time::Instant::now();
    let mut solved = 0.0;
    let run = paper::run_field(
        &an,
        setup.experiment,
        mesh_summary,
        request,
        setup.basis_k,
        &mut |p| {
            if matches!(p, EigenProgress::Finished { .. }) {
                solved = t0.elapsed().as_secs_f64();
            }
            bar.update(p)
        },
        &CancelToken::new(),
    )?;
    bar.finish();
    write_field_files(&an, &run.field, &paths[..3], o.figure)?;
    write_json(&paths[3], &run.summary)?;
    let basis_note = match &run.summary.basis {
        Some(b) => format!(
            ", k = {} ({}): eigenpairs in {solved:.2} s, max residual {:.1e}",
            b.k,
            laplacian,
            b.max_relative_residual.unwrap_or(f64::NAN)
        ),
        None => String::new(),
    };
    println!(
        "{} {}{basis_note}; wrote {}",
        setup.experiment,
        describe(&run.field.request),
        o.out.display()
    );
    if let Some(msg) = &run.summary.unreachable {
        eprintln!("warning: {msg}");
    }
    if let Some(file) = &o.save_experiment {
        let mut e = experiment_file(setup.experiment, &info, &an, o, file);
        let req = run.field.request.clone();
        e.basis_k = match (run.field.k, run.field.basis_k) {
            (Some(k), Some(bk)) if bk > k => Some(bk),
            _ => None,
        };
        match (setup.experiment, req) {
            ("diffusion-basis", FieldRequest::Heat { anchor, t, k, .. }) => {
                e.k = Some(k);
                e.t = Some(t);
                e.anchor = anchor;
            }
            (
                "spectral-distance",
                FieldRequest::Distance {
                    source,
                    distance,
                    k,
                },
            ) => {
                e.k = Some(k);
                e.distance = Some(distance.to_string());
                e.source = source;
            }
            (_, req) => e.field = Some(req),
        }
        save_experiment(file, &e, o.force)?;
    }
    Ok(())
}

/// A one-line description of a resolved request.
fn describe(r: &FieldRequest) -> String {
    match r {
        FieldRequest::Heat { anchor, t, .. } => {
            format!("at vertex {}, t = {t}", anchor.unwrap_or(0))
        }
        FieldRequest::Distance {
            source, distance, ..
        } => format!("{distance} from vertex {}", source.unwrap_or(0)),
        FieldRequest::Geodesic {
            source, sources, ..
        } => {
            let mut all: Vec<String> = source
                .iter()
                .chain(sources)
                .map(|v| v.to_string())
                .collect();
            all.dedup();
            format!("geodesic distance from vertex {}", all.join(", "))
        }
        other => other.kind().to_string(),
    }
}

/// The keys every saved experiment file has.
fn experiment_file(
    experiment: &str,
    info: &input::MeshInfo,
    an: &Analysis,
    o: &Outputs,
    file: &Path,
) -> ExperimentFile {
    let mut e = crate::engine::experiment_file(experiment, file, info, an, o.repair, &o.figure);
    e.out = Some(
        relative_path(&o.out, &parent_dir(file))
            .to_string_lossy()
            .into_owned(),
    );
    e
}

/// ", N hidden by persistence" when the simplification hid raw critical points.
fn hidden_note(c: &spectral_mesh::analysis::CriticalReport) -> String {
    let n = c.hidden.minima + c.hidden.maxima + c.hidden.saddles;
    if n == 0 {
        String::new()
    } else {
        format!(
            ", {n} hidden by persistence (below {:.3e})",
            c.persistence.threshold
        )
    }
}

/// Runs the harmonic experiment on `input` and writes its maps and `summary.json`.
pub fn run_harmonic(
    input: Input,
    constraints: &HarmonicConstraints,
    order: u32,
    laplacian: Option<Laplacian>,
    o: &Outputs,
) -> Result<()> {
    let laplacian = resolve_laplacian(laplacian, &input.shape)?;
    if order != 1 && order != 2 {
        bail!("--order {order}: must be 1 (harmonic) or 2 (bi-harmonic)");
    }
    let maps = match constraints {
        HarmonicConstraints::Counts(c) => c.len(),
        HarmonicConstraints::Explicit(_) => 1,
    };
    let mut names: Vec<String> = (1..=maps).flat_map(harmonic_outputs).collect();
    names.push(SUMMARY_FILE.into());
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let paths = o.prepare(&name_refs)?;
    // The analysis holds the mesh (a point cloud's triangle union), its topology and the
    // hash; the maps need no basis. On a point cloud the maps use the robust Laplacian of
    // that union (the point-cloud Laplacian itself where its consensus set has no holes).
    let (an, info) = input.into_analysis(AnalysisOptions {
        laplacian,
        ..AnalysisOptions::default()
    })?;
    let mesh_summary = info.summary(an.mesh(), an.topology());
    let run = paper::run_harmonic(an.mesh(), mesh_summary, constraints, order, laplacian)?;
    for (i, map) in run.maps.iter().enumerate() {
        let constrained: Vec<usize> = map.constraints.iter().map(|c| c.vertex).collect();
        let mut fig = Figure::new(
            an.mesh(),
            &map.field,
            Vec::new(),
            FigureOptions {
                critical_points: false,
                ..o.figure
            },
        )?;
        fig.point_radius = an.point_spacing().map(|h| POINT_RADIUS_FACTOR * h);
        fig.mark_constraints(constrained);
        if o.figure.critical_points {
            fig.options.critical_points = true;
            fig.use_report(&map.critical);
        }
        for p in &paths[3 * i..3 * i + 3] {
            fig.write(p)?;
        }
        let c = &map.critical;
        println!(
            "map {}: {} constraints, m = {}, M = {}, s = {} (with multiplicity), m - s + M = {} (chi = {}){}",
            i + 1,
            map.constraints.len(),
            c.counts.minima,
            c.counts.maxima,
            c.counts.saddles,
            c.counts.minima as i64 - c.counts.saddles as i64 + c.counts.maxima as i64,
            c.chi,
            hidden_note(c)
        );
    }
    write_json(paths.last().context("no summary path")?, &run.summary)?;
    println!("wrote {} files to {}", names.len(), o.out.display());
    if let Some(file) = &o.save_experiment {
        let mut f = experiment_file("harmonic", &info, &an, o, file);
        // The harmonic maps do not depend on the normalisation: the file leaves it out.
        f.normalize = None;
        f.order = Some(order);
        f.set_harmonic_constraints(constraints);
        save_experiment(file, &f, o.force)?;
    }
    Ok(())
}

fn run_paper(a: PaperArgs) -> Result<()> {
    // --save-experiment FILE.toml saves FILE-harmonic.toml, FILE-diffusion-basis.toml and
    // FILE-spectral-distance.toml.
    let common: Outputs = (&a.common).into();
    let sub = |name: &str| Outputs {
        out: common.out.join(name),
        save_experiment: common.save_experiment.as_ref().map(|f| {
            let stem = f
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "experiment".into());
            f.with_file_name(format!("{stem}-{name}.toml"))
        }),
        ..common.clone()
    };
    let load = || a.common.cloud.load(a.mesh.as_deref(), common.repair);
    let laplacian = None;
    run_harmonic(
        load()?,
        &HarmonicConstraints::Counts(vec![2, 4, 6]),
        1,
        laplacian,
        &sub("harmonic"),
    )?;
    let paper_field = |experiment, request| FieldSetup {
        experiment,
        request,
        basis_k: None,
        laplacian,
        normalize: true,
    };
    run_field(
        load()?,
        &paper_field(
            "diffusion-basis",
            FieldRequest::Heat {
                anchor: None,
                t: DEFAULT_HEAT_T,
                kernel: Kernel::Wfem,
                k: DEFAULT_K,
            },
        ),
        &sub("diffusion-basis"),
    )?;
    run_field(
        load()?,
        &paper_field("spectral-distance", FieldRequest::default()),
        &sub("spectral-distance"),
    )
}
