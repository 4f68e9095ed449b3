//! `spectral-mesh experiment harmonic | diffusion-basis | spectral-distance | paper`:
//! the executable paper's three experiments with its defaults and file names.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde_json::json;
use spectral_mesh::experiments::harmonic::{HarmonicExperimentParams, harmonic_experiment};
use spectral_mesh::fields::critical_points::{CriticalPoints, critical_points};
use spectral_mesh::fields::harmonic::{
    Constraint, ConstraintSpec, HarmonicParams, harmonic_map, parse_constraint_arg,
    read_constraints_file,
};
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::spectral::distances::{distances_from, wfem_diffusion_distances_from};
use spectral_mesh::spectral::eigenbasis::EigenParams;
use spectral_mesh::spectral::heat::{HeatSolver, KernelKind, ScaleNormalization, normalize_basis};
use spectral_mesh::{Laplacian, Mesh};

use spectral_mesh::experiments::mesh_hash;
use spectral_mesh::mesh::validate::{RepairOptions, repair};

use crate::basis;
use crate::expfile::{DistanceSpec, ExperimentFile, figure_file, parse_distance, relative_path};
use crate::figure::{Figure, FigureArgs};
use crate::input::{self, Input, Source};
use crate::output::{check_writable, prepare_outputs, write_atomic};

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
}

/// Arguments of `experiment harmonic`.
#[derive(Debug, clap::Args)]
pub struct HarmonicArgs {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Numbers of default constraints (min/max x, then y, then z), one map each.
    #[arg(long, value_delimiter = ',', default_values_t = vec![2usize, 4, 6])]
    pub constraints: Vec<usize>,
    /// An explicit constraint VERTEX=VALUE (repeatable); replaces the defaults.
    #[arg(long = "constraint", value_parser = parse_constraint_arg)]
    pub explicit: Vec<Constraint>,
    /// A file of `vertex value` lines; replaces the defaults.
    #[arg(long)]
    pub constraints_file: Option<PathBuf>,
    /// 1 = harmonic (S f = 0), 2 = bi-harmonic (S B^-1 S f = 0).
    #[arg(long, default_value_t = 1)]
    pub order: u32,
    /// Discretization (matters for the bi-harmonic map's mass).
    #[arg(long, default_value = "fem")]
    pub laplacian: Laplacian,
    #[command(flatten)]
    pub common: Common,
}

/// Arguments of `experiment diffusion-basis`.
#[derive(Debug, clap::Args)]
pub struct DiffusionArgs {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// Discretization: cot (K = X D_t X^T), voronoi-cot (X D_t X^T D), fem (X D_t X^T B).
    #[arg(long, default_value = "fem")]
    pub laplacian: Laplacian,
    /// Diffusion time (for the shape scaled to unit area unless --no-normalize).
    #[arg(long, default_value_t = 0.5)]
    pub t: f64,
    /// Number of eigenpairs.
    #[arg(long, short = 'k', default_value_t = 100)]
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
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// The filter: biharmonic, commute, diffusion:t=0.5, mix:a=0.5,t=0.5, poly:p=3,
    /// custom-w:EXPR;name=value, custom-phi:EXPR;..., or wfem-diffusion:t=0.5 (eq. 15).
    #[arg(long, default_value = "biharmonic")]
    pub distance: String,
    /// Discretization.
    #[arg(long, default_value = "fem")]
    pub laplacian: Laplacian,
    /// Number of eigenpairs.
    #[arg(long, short = 'k', default_value_t = 100)]
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
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// Runs an experiment.
pub fn run(e: Experiment) -> Result<()> {
    match e {
        Experiment::Harmonic(a) => run_harmonic(a),
        Experiment::DiffusionBasis(a) => run_diffusion(a),
        Experiment::SpectralDistance(a) => run_distance(a),
        Experiment::Paper(a) => run_paper(a),
    }
}

/// The default anchor/source: the vertex of largest x (lowest index on ties).
pub fn default_vertex(mesh: &Mesh) -> usize {
    let p = mesh.positions();
    (0..p.len()).fold(0, |best, i| if p[i][0] > p[best][0] { i } else { best })
}

fn check_vertex(v: usize, mesh: &Mesh, what: &str) -> Result<()> {
    if v >= mesh.n_vertices() {
        bail!(
            "--{what} {v}: the mesh has only {} vertices",
            mesh.n_vertices()
        );
    }
    Ok(())
}

/// A loaded mesh with the hash of the mesh as read (before any repair).
pub struct Loaded {
    /// The input (repaired when asked).
    pub input: Input,
    /// `mesh_hash` of the mesh as read.
    pub hash: String,
}

/// Loads a mesh or shape, hashes it, then repairs it when asked.
pub fn load_mesh(spec: Option<&str>, do_repair: bool) -> Result<Loaded> {
    let mut input = input::load(spec)?;
    let hash = mesh_hash(&input.mesh);
    if do_repair {
        let r = repair(&input.mesh, &RepairOptions::default())
            .with_context(|| format!("repairing {}", input.label()))?;
        input.mesh = r.mesh;
        input.notes.extend(r.log);
    }
    Ok(Loaded { input, hash })
}

/// The name of the mesh in summaries: the file name (not the path, so that a replay from
/// another folder writes the same summary) or the shape spec.
fn mesh_name(input: &Input) -> String {
    match &input.source {
        Source::File(p) => p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| input.label()),
        Source::Shape(s) => s.clone(),
    }
}

fn mesh_json(loaded: &Loaded) -> serde_json::Value {
    let input = &loaded.input;
    let topo = Topology::new(&input.mesh);
    json!({
        "source": mesh_name(input),
        "mesh_hash": loaded.hash,
        "vertices": input.mesh.n_vertices(),
        "triangles": input.mesh.n_triangles(),
        "components": topo.n_components(),
        "euler_characteristic": topo.euler_characteristic(),
        "genus": topo.components.iter().map(|c| c.genus).collect::<Vec<_>>(),
        "boundary_loops": topo.boundary_loops.len(),
        "area": input.mesh.area(),
    })
}

fn critical_json(cp: &CriticalPoints, chi: i64, closed: bool) -> serde_json::Value {
    let (lhs, rhs) = if closed {
        cp.euler_check(chi)
    } else {
        cp.euler_check_doubled(chi)
    };
    json!({
        "minima": cp.minima.len(),
        "maxima": cp.maxima.len(),
        "saddles_with_multiplicity": cp.saddle_count(),
        "minima_vertices": cp.minima,
        "maxima_vertices": cp.maxima,
        "saddle_vertices": cp.saddles,
        "euler_check": {
            "formula": if closed { "m - s + M = chi" } else { "doubled across the boundary: 2(m_i - s_i + M_i) + (m_b - s_b + M_b) = 2 chi" },
            "lhs": lhs, "rhs": rhs, "holds": lhs == rhs,
        },
    })
}

/// The `mesh` entry of an experiment file saved at `file`: a shape spec as is, a mesh
/// file relative to the experiment file's folder.
fn mesh_entry(input: &Input, file: &Path) -> String {
    match &input.source {
        Source::Shape(s) => s.clone(),
        Source::File(p) => relative_path(p, &parent_dir(file))
            .to_string_lossy()
            .into_owned(),
    }
}

/// The folder of `file` (`.` for a bare name).
pub fn parent_dir(file: &Path) -> PathBuf {
    match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The skeleton of an experiment file for `common`'s output and figure options.
fn experiment_file(
    experiment: &str,
    loaded: &Loaded,
    common: &Common,
    file: &Path,
    laplacian: Laplacian,
) -> ExperimentFile {
    // The folder must exist for the relative paths to be computed from its real location
    // (a failure is reported when the file is written).
    let _ = std::fs::create_dir_all(parent_dir(file));
    ExperimentFile {
        experiment: experiment.into(),
        mesh: mesh_entry(&loaded.input, file),
        mesh_hash: Some(loaded.hash.clone()),
        repair: Some(common.repair),
        laplacian: Some(laplacian.name().into()),
        k: None,
        t: None,
        normalize: None,
        anchor: None,
        distance: None,
        source: None,
        constraints: None,
        order: None,
        out: Some(
            relative_path(&common.out, &parent_dir(file))
                .to_string_lossy()
                .into_owned(),
        ),
        figure: Some(figure_file(&common.figure)),
    }
}

/// Writes an experiment file (refusing to overwrite without `force`).
fn save_experiment(file: &Path, f: &ExperimentFile, force: bool) -> Result<()> {
    check_writable(file, force)?;
    let dir = parent_dir(file);
    std::fs::create_dir_all(&dir)
        .map_err(|e| anyhow::anyhow!("{}: cannot create folder: {e}", dir.display()))?;
    write_atomic(file, f.to_toml()?.as_bytes())?;
    println!("saved the experiment to {}", file.display());
    Ok(())
}

fn write_json(path: &Path, v: &serde_json::Value) -> Result<()> {
    write_atomic(path, (serde_json::to_string_pretty(v)? + "\n").as_bytes())
}

/// Runs `experiment harmonic`.
pub fn run_harmonic(a: HarmonicArgs) -> Result<()> {
    let loaded = load_mesh(a.mesh.as_deref(), a.common.repair)?;
    let mesh = &loaded.input.mesh;
    let topo = Topology::new(mesh);
    let chi = topo.euler_characteristic();
    let closed = topo.boundary_loops.is_empty();
    if a.order != 1 && a.order != 2 {
        bail!(
            "--order {}: must be 1 (harmonic) or 2 (bi-harmonic)",
            a.order
        );
    }
    // Explicit constraints give one map; otherwise one map per default count.
    let explicit: Option<Vec<Constraint>> = match (&a.constraints_file, a.explicit.is_empty()) {
        (Some(f), _) => {
            let mut c = read_constraints_file(f)?;
            c.extend(a.explicit.iter().copied());
            Some(c)
        }
        (None, false) => Some(a.explicit.clone()),
        (None, true) => None,
    };
    let explicit_used = explicit.clone();
    let mut maps: Vec<(Vec<Constraint>, Vec<f64>, serde_json::Value)> = Vec::new();
    match explicit {
        Some(c) => {
            let c = ConstraintSpec::Explicit(c).resolve(mesh)?;
            let f = harmonic_map(
                mesh,
                &c,
                &HarmonicParams {
                    order: a.order,
                    laplacian: a.laplacian,
                },
            )?;
            maps.push((c, f, json!({})));
        }
        None => {
            let params = HarmonicExperimentParams {
                constraint_counts: a.constraints.clone(),
                order: a.order,
                laplacian: a.laplacian,
                ..Default::default()
            };
            for r in harmonic_experiment(mesh, &params)? {
                let extra = json!({
                    "constraint_count": r.count,
                    "locality": {
                        "rings": params.locality_rings,
                        "max_change_near_previous_constraints": r.change_near_previous,
                        "max_change_anywhere": r.change_anywhere,
                    },
                });
                maps.push((r.constraints, r.field, extra));
            }
        }
    }
    let mut names = Vec::new();
    for i in 1..=maps.len() {
        names.push(format!("harmonic-map-{i}.wrl"));
        names.push(format!("harmonic-map-{i}.png"));
        names.push(format!("harmonic-field-{i}.txt"));
    }
    names.push("summary.json".into());
    let name_refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let paths = prepare_outputs(&a.common.out, &name_refs, a.common.force)?;
    let mut summaries = Vec::new();
    for (i, (c, f, extra)) in maps.iter().enumerate() {
        let sources: Vec<usize> = c.iter().map(|c| c.vertex).collect();
        let mut fig = Figure::new(mesh, f, sources, &a.common.figure)?;
        let cp = match fig.critical.take() {
            Some(cp) => cp,
            None => critical_points(mesh, f)?,
        };
        if !a.common.figure.no_critical_points {
            fig.critical = Some(cp.clone());
        }
        fig.write_wrl(&paths[3 * i], &a.common.figure)?;
        fig.write_png(&paths[3 * i + 1], &a.common.figure)?;
        fig.write_txt(&paths[3 * i + 2])?;
        let mut s = json!({
            "map": i + 1,
            "constraints": c.iter().map(|c| json!({"vertex": c.vertex, "value": c.value})).collect::<Vec<_>>(),
            "critical_points": critical_json(&cp, chi, closed),
            "m": cp.minima.len(), "M": cp.maxima.len(), "s": cp.saddle_count(),
            "chi": chi,
            "genus": topo.components.iter().map(|c| c.genus).collect::<Vec<_>>(),
        });
        if let (Some(o), Some(e)) = (s.as_object_mut(), extra.as_object()) {
            o.extend(e.clone());
        }
        summaries.push(s);
        println!(
            "map {}: {} constraints, m = {}, M = {}, s = {} (with multiplicity), m - s + M = {} (chi = {chi})",
            i + 1,
            c.len(),
            cp.minima.len(),
            cp.maxima.len(),
            cp.saddle_count(),
            cp.minima.len() as i64 - cp.saddle_count() as i64 + cp.maxima.len() as i64
        );
    }
    let summary = json!({
        "experiment": "harmonic",
        "mesh": mesh_json(&loaded),
        "order": a.order,
        "laplacian": a.laplacian.name(),
        "maps": summaries,
    });
    write_json(paths.last().context("no summary path")?, &summary)?;
    println!("wrote {} files to {}", names.len(), a.common.out.display());
    if let Some(file) = &a.common.save_experiment {
        let mut f = experiment_file("harmonic", &loaded, &a.common, file, a.laplacian);
        f.order = Some(a.order);
        f.constraints = Some(match &explicit_used {
            Some(list) => toml::Value::Array(
                list.iter()
                    .map(|c| {
                        toml::Value::Table(
                            [
                                ("vertex".to_string(), toml::Value::Integer(c.vertex as i64)),
                                ("value".to_string(), toml::Value::Float(c.value)),
                            ]
                            .into_iter()
                            .collect(),
                        )
                    })
                    .collect(),
            ),
            None => toml::Value::Array(
                a.constraints
                    .iter()
                    .map(|&c| toml::Value::Integer(c as i64))
                    .collect(),
            ),
        });
        save_experiment(file, &f, a.common.force)?;
    }
    Ok(())
}

fn eigen_params(k: usize) -> EigenParams {
    EigenParams {
        k,
        ..EigenParams::default()
    }
}

/// Runs `experiment diffusion-basis`.
pub fn run_diffusion(a: DiffusionArgs) -> Result<()> {
    let loaded = load_mesh(a.mesh.as_deref(), a.common.repair)?;
    let mesh = &loaded.input.mesh;
    let anchor = a.anchor.unwrap_or_else(|| default_vertex(mesh));
    check_vertex(anchor, mesh, "anchor")?;
    if !(a.t.is_finite() && a.t > 0.0) {
        bail!("--t {}: the time must be a positive number", a.t);
    }
    let names = [
        "diffusion-basis.wrl",
        "diffusion-basis.png",
        "diffusion-basis.txt",
        "summary.json",
    ];
    let paths = prepare_outputs(&a.common.out, &names, a.common.force)?;
    let tb = basis::compute(mesh, a.laplacian, &eigen_params(a.k))?;
    let norm = if a.no_normalize {
        ScaleNormalization::None
    } else {
        ScaleNormalization::UnitArea
    };
    // K_t = X D_t X^T B with the discretization's own B: the paper's wFEM kernel for
    // fem, X D_t X^T D for voronoi-cot, X D_t X^T for cot (B = I).
    let solver = HeatSolver::new(&tb.basis, KernelKind::Wfem, norm);
    let f = solver.basis_function(anchor, a.t)?;
    let fig = Figure::new(mesh, &f, vec![anchor], &a.common.figure)?;
    fig.write_wrl(&paths[0], &a.common.figure)?;
    fig.write_png(&paths[1], &a.common.figure)?;
    fig.write_txt(&paths[2])?;
    let (res, orth) = basis::quality(&tb.basis);
    let topo = Topology::new(mesh);
    let cp = critical_points(mesh, &f)?;
    let summary = json!({
        "experiment": "diffusion-basis",
        "mesh": mesh_json(&loaded),
        "laplacian": a.laplacian.name(),
        "kernel": "K_t = X D_t X^T B (B the discretization's mass)",
        "t": a.t,
        "scale_normalization": if a.no_normalize { "none" } else { "unit area" },
        "k": a.k,
        "anchor": anchor,
        "eigenvalues": tb.basis.values,
        "max_relative_residual": res,
        "max_orthonormality_error": orth,
        "value_at_anchor": f[anchor],
        "min": f.iter().copied().fold(f64::INFINITY, f64::min),
        "max": f.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        "critical_points": critical_json(&cp, topo.euler_characteristic(), topo.boundary_loops.is_empty()),
    });
    write_json(&paths[3], &summary)?;
    println!(
        "diffusion basis at vertex {anchor}, t = {}, k = {} ({}): eigenpairs in {:.2} s, max residual {res:.1e}; wrote {}",
        a.t,
        a.k,
        a.laplacian,
        tb.seconds,
        a.common.out.display()
    );
    if let Some(file) = &a.common.save_experiment {
        let mut e = experiment_file("diffusion-basis", &loaded, &a.common, file, a.laplacian);
        e.k = Some(a.k);
        e.t = Some(a.t);
        e.anchor = Some(anchor);
        e.normalize = Some(!a.no_normalize);
        save_experiment(file, &e, a.common.force)?;
    }
    Ok(())
}

/// Runs `experiment spectral-distance`.
pub fn run_distance(a: DistanceArgs) -> Result<()> {
    let loaded = load_mesh(a.mesh.as_deref(), a.common.repair)?;
    let mesh = &loaded.input.mesh;
    let source = a.source.unwrap_or_else(|| default_vertex(mesh));
    check_vertex(source, mesh, "source")?;
    // eq. 15 is not a filter of the form w(lambda); everything else is.
    let spec = parse_distance(&a.distance).with_context(|| format!("--distance {}", a.distance))?;
    let names = [
        "filtered-spectral-distance.wrl",
        "filtered-spectral-distance.png",
        "filtered-spectral-distance.txt",
        "summary.json",
    ];
    let paths = prepare_outputs(&a.common.out, &names, a.common.force)?;
    let tb = basis::compute(mesh, a.laplacian, &eigen_params(a.k))?;
    let norm = if a.no_normalize {
        ScaleNormalization::None
    } else {
        ScaleNormalization::UnitArea
    };
    let basis = normalize_basis(&tb.basis, norm);
    let d = match &spec {
        DistanceSpec::Filter(f) => distances_from(&basis, source, f)?,
        DistanceSpec::Wfem(t) => wfem_diffusion_distances_from(&basis, source, *t)?,
    };
    let fig = Figure::new(mesh, &d, vec![source], &a.common.figure)?;
    fig.write_wrl(&paths[0], &a.common.figure)?;
    fig.write_png(&paths[1], &a.common.figure)?;
    fig.write_txt(&paths[2])?;
    let (res, orth) = basis::quality(&tb.basis);
    let summary = json!({
        "experiment": "spectral-distance",
        "mesh": mesh_json(&loaded),
        "distance": a.distance,
        "weight_convention": "d(p,q)^2 = sum over nonzero eigenvalues of w(lambda) (x(p) - x(q))^2, w = 1/phi",
        "laplacian": a.laplacian.name(),
        "scale_normalization": if a.no_normalize { "none" } else { "unit area" },
        "k": a.k,
        "source": source,
        "max_relative_residual": res,
        "max_orthonormality_error": orth,
        "max_distance": d.iter().copied().fold(0.0, f64::max),
        "farthest_vertex": (0..d.len()).fold(0, |b, i| if d[i] > d[b] { i } else { b }),
    });
    write_json(&paths[3], &summary)?;
    println!(
        "{} distance from vertex {source}, k = {} ({}): eigenpairs in {:.2} s; wrote {}",
        a.distance,
        a.k,
        a.laplacian,
        tb.seconds,
        a.common.out.display()
    );
    if let Some(file) = &a.common.save_experiment {
        let mut e = experiment_file("spectral-distance", &loaded, &a.common, file, a.laplacian);
        e.k = Some(a.k);
        e.distance = Some(a.distance.clone());
        e.source = Some(source);
        e.normalize = Some(!a.no_normalize);
        save_experiment(file, &e, a.common.force)?;
    }
    Ok(())
}

fn run_paper(a: PaperArgs) -> Result<()> {
    // --save-experiment FILE.toml saves FILE-harmonic.toml, FILE-diffusion-basis.toml and
    // FILE-spectral-distance.toml.
    let sub = |name: &str| Common {
        out: a.common.out.join(name),
        save_experiment: a.common.save_experiment.as_ref().map(|f| {
            let stem = f
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "experiment".into());
            f.with_file_name(format!("{stem}-{name}.toml"))
        }),
        ..a.common.clone()
    };
    run_harmonic(HarmonicArgs {
        mesh: a.mesh.clone(),
        constraints: vec![2, 4, 6],
        explicit: Vec::new(),
        constraints_file: None,
        order: 1,
        laplacian: Laplacian::Fem,
        common: sub("harmonic"),
    })?;
    run_diffusion(DiffusionArgs {
        mesh: a.mesh.clone(),
        laplacian: Laplacian::Fem,
        t: 0.5,
        k: 100,
        anchor: None,
        no_normalize: false,
        common: sub("diffusion-basis"),
    })?;
    run_distance(DistanceArgs {
        mesh: a.mesh.clone(),
        distance: "biharmonic".into(),
        laplacian: Laplacian::Fem,
        k: 100,
        source: None,
        no_normalize: false,
        common: sub("spectral-distance"),
    })
}
