//! `spectral-mesh study truncation | robustness`: the truncation study of the paper's
//! Fig. 12 and robustness studies driven by a study file (`docs/studies/README.md`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use serde::Deserialize;
use spectral_mesh::Laplacian;
use spectral_mesh::experiments::study::{
    Quantity, StudyMesh, StudyParams, StudyProgress, StudyRow, resampled_as, run_study,
};
use spectral_mesh::experiments::truncation::{
    TruncationParams, TruncationProgress, TruncationReference, truncation_study,
};
use spectral_mesh::perturb;
use spectral_mesh::spectral::heat::ScaleNormalization;
use spectral_mesh_render::plots::plot_curves;

use spectral_mesh::experiments::file::{parent_dir, resolve_mesh, toml_error};

use crate::input;
use crate::output::{prepare_outputs, write};
use crate::progress;

/// A discretization name.
fn parse_laplacian(s: &str) -> Result<Laplacian> {
    s.parse::<Laplacian>().map_err(|e| anyhow!(e))
}

/// The studies.
#[derive(Debug, clap::Subcommand)]
pub enum Study {
    /// L-infinity error of the truncated heat basis function K_t e_i against the full
    /// spectrum, as the number of pairs k grows (Fig. 12): truncation.csv, truncation.md,
    /// truncation.png and one plot per time, truncation-t1.png, ...
    Truncation(TruncationArgs),
    /// A robustness study from a study file: meshes x perturbations x Laplacians x
    /// quantities: robustness.csv, robustness.md, one plot per table and quantity.
    Robustness(RobustnessArgs),
}

/// The default mesh of the truncation study: the torus of Fig. 12 at a resolution where
/// the dense reference is affordable (1568 vertices).
pub const TRUNCATION_DEFAULT_MESH: &str = "torus:res=2";

/// Arguments of `study truncation`.
#[derive(Debug, clap::Args)]
pub struct TruncationArgs {
    /// Mesh file or built-in shape (default: torus:res=2, 1568 vertices).
    pub mesh: Option<String>,
    /// Discretizations, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = TruncationParams::default().laplacians.iter().map(|l| l.name().to_string()).collect::<Vec<_>>())]
    pub laplacian: Vec<String>,
    /// Diffusion times (for the shape scaled to unit area unless --no-normalize).
    #[arg(long, value_delimiter = ',', default_values_t = TruncationParams::default().times)]
    pub t: Vec<f64>,
    /// Numbers of pairs; `all` = every pair (n with the dense reference).
    #[arg(long, short = 'k', value_delimiter = ',', default_values_t = TruncationParams::default().ks.iter().map(|&k| if k == usize::MAX { "all".to_string() } else { k.to_string() }).collect::<Vec<_>>())]
    pub k: Vec<String>,
    /// Anchor vertex (default: the vertex of largest x).
    #[arg(long)]
    pub anchor: Option<usize>,
    /// Reference: auto (dense up to 2500 vertices), dense, or time-stepping.
    #[arg(long, default_value = "auto")]
    pub reference: String,
    /// Use times for the shape as given instead of scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
    /// Output folder.
    #[arg(long, short = 'o', default_value = ".")]
    pub out: PathBuf,
    /// Overwrite existing output files.
    #[arg(long, short = 'f')]
    pub force: bool,
}

/// Arguments of `study robustness`.
#[derive(Debug, clap::Args)]
pub struct RobustnessArgs {
    /// The study file (TOML; see docs/studies/README.md).
    pub file: PathBuf,
    /// Output folder.
    #[arg(long, short = 'o', default_value = ".")]
    pub out: PathBuf,
    /// Overwrite existing output files.
    #[arg(long, short = 'f')]
    pub force: bool,
}

/// Runs a study.
pub fn run(s: Study) -> Result<()> {
    match s {
        Study::Truncation(a) => run_truncation(a),
        Study::Robustness(a) => run_robustness(a),
    }
}

fn run_truncation(a: TruncationArgs) -> Result<()> {
    let spec = a.mesh.as_deref().unwrap_or(TRUNCATION_DEFAULT_MESH);
    let input = input::load(Some(spec))?;
    let mesh = input.mesh("study truncation")?;
    let laplacians = a
        .laplacian
        .iter()
        .map(|l| parse_laplacian(l).map_err(|e| anyhow!("--laplacian: {e}")))
        .collect::<Result<Vec<_>>>()?;
    let ks =
        a.k.iter()
            .map(|k| match k.trim() {
                "all" | "n" => Ok(usize::MAX),
                s => s
                    .parse::<usize>()
                    .ok()
                    .filter(|&k| k > 0)
                    .ok_or_else(|| anyhow!("--k {s}: a number of pairs >= 1 or 'all'")),
            })
            .collect::<Result<Vec<_>>>()?;
    let reference = match a.reference.as_str() {
        "auto" => TruncationReference::Auto,
        "dense" => TruncationReference::Dense,
        "time-stepping" => TruncationReference::TimeStepping { tol: 1e-10 },
        o => bail!("--reference {o}: auto, dense or time-stepping"),
    };
    let params = TruncationParams {
        laplacians: laplacians.clone(),
        times: a.t.clone(),
        ks,
        anchor: a.anchor,
        normalization: if a.no_normalize {
            ScaleNormalization::None
        } else {
            ScaleNormalization::UnitArea
        },
        reference,
        ..TruncationParams::default()
    };
    // One plot with every curve, and one per time with a curve per Laplacian (the layout of
    // the paper's Fig. 12 a-c).
    let mut names: Vec<String> = ["truncation.csv", "truncation.md", "truncation.png"]
        .map(String::from)
        .to_vec();
    for (i, _) in a.t.iter().enumerate() {
        names.push(format!("truncation-t{}.png", i + 1));
    }
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let paths = prepare_outputs(&a.out, &refs, a.force)?;
    let bar = progress::bar(laplacians.len() as u64, "laplacians");
    let mut cb = |p: TruncationProgress| match p {
        TruncationProgress::Eigen { index } => {
            bar.set_message(laplacians[index].name().to_string());
        }
        TruncationProgress::Done { index } => bar.set_position(index as u64 + 1),
    };
    let r = truncation_study(mesh, &params, &mut cb).map_err(|e| anyhow!("--{e}"))?;
    bar.finish_and_clear();
    let mut csv = String::from("laplacian,t,k,linf_error,linf_relative,reference_max\n");
    for row in &r.rows {
        writeln!(
            csv,
            "{},{:?},{},{:e},{:e},{:e}",
            row.laplacian.name(),
            row.t,
            row.k,
            row.linf_error,
            row.linf_relative,
            row.reference_max
        )?;
    }
    write(&paths[0], csv.as_bytes())?;
    // Markdown: one row per k, one column per (Laplacian, t).
    let mut ks: Vec<usize> = r.rows.iter().map(|x| x.k).collect();
    ks.sort_unstable();
    ks.dedup();
    let mut md = format!(
        "Relative L-infinity error `max|K_t^(k) e_i - K_t e_i| / max|K_t e_i|` on {} ({} vertices), anchor {}, reference: {}, times {}.\n\n| k |",
        spec,
        r.n,
        r.anchor,
        if r.dense {
            "all n pairs (dense)".to_string()
        } else {
            format!(
                "time stepping (estimated relative error {:.1e})",
                r.reference_error_estimate
            )
        },
        if a.no_normalize {
            "as given"
        } else {
            "for the unit-area shape"
        }
    );
    for l in &laplacians {
        for t in &a.t {
            write!(md, " {} t={t} |", l.name())?;
        }
    }
    md.push_str("\n|---|");
    md.push_str(&"---|".repeat(laplacians.len() * a.t.len()));
    md.push('\n');
    for &k in &ks {
        write!(md, "| {k} |")?;
        for l in &laplacians {
            for &t in &a.t {
                match r
                    .rows
                    .iter()
                    .find(|x| x.laplacian == *l && x.t == t && x.k == k)
                {
                    Some(x) => write!(md, " {:.2e} |", x.linf_relative)?,
                    None => md.push_str(" - |"),
                }
            }
        }
        md.push('\n');
    }
    write(&paths[1], md.as_bytes())?;
    let mut curves = Vec::new();
    for l in &laplacians {
        for &t in &a.t {
            let pts: Vec<(f64, f64)> = r
                .rows
                .iter()
                .filter(|x| x.laplacian == *l && x.t == t)
                .map(|x| (x.k as f64, x.linf_relative))
                .collect();
            curves.push((format!("{} t={t}", l.name()), pts));
        }
    }
    plot_curves(
        &paths[2],
        &curves,
        "k (eigenpairs)",
        "relative L-infinity error",
        true,
        &format!("Truncated heat basis function on {spec}"),
    )
    .map_err(|e| anyhow!("{}: {e}", paths[2].display()))?;
    for (i, &t) in a.t.iter().enumerate() {
        let curves: Vec<(String, Vec<(f64, f64)>)> = laplacians
            .iter()
            .map(|l| {
                let pts = r
                    .rows
                    .iter()
                    .filter(|x| x.laplacian == *l && x.t == t)
                    .map(|x| (x.k as f64, x.linf_relative))
                    .collect();
                (l.name().to_string(), pts)
            })
            .collect();
        let path = &paths[3 + i];
        if let Err(e) = plot_curves(
            path,
            &curves,
            "k (eigenpairs)",
            "relative L-infinity error",
            true,
            &format!("Truncated heat basis function on {spec}, t = {t}"),
        ) {
            // Every error exactly zero: nothing to draw on a log axis.
            eprintln!("note: {}: {e}", path.display());
        }
    }
    print!("{md}");
    println!("wrote {}", names.join(", "));
    Ok(())
}

// ---------------------------------------------------------------- robustness studies

/// A study file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// A title for the report.
    pub title: Option<String>,
    /// Eigenpairs (default 60).
    pub k: Option<usize>,
    /// Time of the heat basis function (unit area; default 0.05).
    pub heat_t: Option<f64>,
    /// Time of the diffusion distance (unit area; default 0.05).
    pub diffusion_t: Option<f64>,
    /// Time of the HKS (unit area; default 0.01).
    pub hks_t: Option<f64>,
    /// Source vertex on the original meshes (default: largest x).
    pub source: Option<usize>,
    /// Default Laplacians of the tables (default cot, voronoi-cot, fem).
    pub laplacians: Option<Vec<String>>,
    /// Default quantities of the tables (default all).
    pub quantities: Option<Vec<String>>,
    /// The tables.
    pub table: Vec<StudyTable>,
}

/// One table of a study file: its meshes x its perturbations.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyTable {
    /// Short name (used in file names).
    pub name: String,
    /// The claim the table tests (printed above it).
    pub claim: Option<String>,
    /// Meshes: files (relative to the study file, `${VAR}` expanded) or shapes.
    pub meshes: Vec<String>,
    /// Perturbations (`noise:0.1,seed=3`, ...; `mesh:SPEC` = another sampling).
    pub perturbations: Vec<String>,
    /// Laplacians of this table (default: the file's).
    pub laplacians: Option<Vec<String>>,
    /// Quantities of this table (default: the file's).
    pub quantities: Option<Vec<String>>,
}

/// A validated study.
#[derive(Debug, Clone)]
pub struct ParsedStudy {
    /// The file as read.
    pub file: StudyFile,
    /// Parameters.
    pub params: StudyParams,
    /// Per table: Laplacians and quantities.
    pub tables: Vec<(Vec<Laplacian>, Vec<Quantity>)>,
}

fn parse_list<T>(key: &str, items: &[String], f: impl Fn(&str) -> Result<T>) -> Result<Vec<T>> {
    if items.is_empty() {
        bail!("key '{key}': the list is empty");
    }
    items
        .iter()
        .enumerate()
        .map(|(i, s)| f(s).map_err(|e| anyhow!("key '{key}[{i}]': {e}")))
        .collect()
}

fn parse_quantity(s: &str) -> Result<Quantity> {
    Quantity::from_name(s).ok_or_else(|| {
        anyhow!(
            "'{s}' is not one of {}",
            Quantity::ALL.map(|q| q.name()).join(", ")
        )
    })
}

/// Parses and validates a study file's text; `origin` names it in errors.
pub fn parse_study(text: &str, origin: &str) -> Result<ParsedStudy> {
    let file: StudyFile = toml::from_str(text).map_err(|e| toml_error(&e, text, origin))?;
    let go = || -> Result<ParsedStudy> {
        let d = StudyParams::default();
        let params = StudyParams {
            k: file.k.unwrap_or(d.k),
            heat_t: file.heat_t.unwrap_or(d.heat_t),
            diffusion_t: file.diffusion_t.unwrap_or(d.diffusion_t),
            hks_t: file.hks_t.unwrap_or(d.hks_t),
            source: file.source,
        };
        params.validate().map_err(|e| match e {
            spectral_mesh::experiments::study::StudyError::InvalidParameter { name, reason } => {
                anyhow!("key '{name}': {reason}")
            }
            other => anyhow!("{other}"),
        })?;
        let default_laps = match &file.laplacians {
            Some(l) => parse_list("laplacians", l, parse_laplacian)?,
            None => vec![Laplacian::Cot, Laplacian::VoronoiCot, Laplacian::Fem],
        };
        let default_q = match &file.quantities {
            Some(q) => parse_list("quantities", q, parse_quantity)?,
            None => Quantity::ALL.to_vec(),
        };
        if file.table.is_empty() {
            bail!("key 'table': give at least one [[table]]");
        }
        let mut tables = Vec::new();
        let mut names = std::collections::HashSet::new();
        for (i, t) in file.table.iter().enumerate() {
            let key = |k: &str| format!("table[{i}].{k}");
            if t.name.is_empty()
                || !t
                    .name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
            {
                bail!(
                    "key '{}': '{}' must be letters, digits, - and _",
                    key("name"),
                    t.name
                );
            }
            if !names.insert(t.name.clone()) {
                bail!("key '{}': '{}' is used twice", key("name"), t.name);
            }
            if t.meshes.is_empty() {
                bail!("key '{}': the list is empty", key("meshes"));
            }
            if t.perturbations.is_empty() {
                bail!("key '{}': the list is empty", key("perturbations"));
            }
            for (j, p) in t.perturbations.iter().enumerate() {
                if let Some(spec) = p.strip_prefix("mesh:") {
                    if spec.trim().is_empty() {
                        bail!("key '{}[{j}]': mesh: needs a mesh", key("perturbations"));
                    }
                } else {
                    perturb::parse_perturbation(p)
                        .map_err(|e| anyhow!("key '{}[{j}]': {e}", key("perturbations")))?;
                }
            }
            let laps = match &t.laplacians {
                Some(l) => parse_list(&key("laplacians"), l, parse_laplacian)?,
                None => default_laps.clone(),
            };
            let qs = match &t.quantities {
                Some(q) => parse_list(&key("quantities"), q, parse_quantity)?,
                None => default_q.clone(),
            };
            tables.push((laps, qs));
        }
        Ok(ParsedStudy {
            file: file.clone(),
            params,
            tables,
        })
    };
    go().map_err(|e| anyhow!("{origin}: {e:#}"))
}

/// Loads the meshes of table `ti` and applies its perturbations.
fn build_table(study: &ParsedStudy, ti: usize, base: &Path) -> Result<Vec<StudyMesh>> {
    let t = &study.file.table[ti];
    let mut out = Vec::new();
    for (mi, m) in t.meshes.iter().enumerate() {
        let key = format!("table[{ti}].meshes[{mi}]");
        let path = resolve_mesh(m, base).with_context(|| format!("key '{key}'"))?;
        let mesh = input::load(Some(&path))
            .with_context(|| format!("key '{key}'"))?
            .into_mesh("a study")?
            .0;
        let mut perts = Vec::new();
        for (pi, p) in t.perturbations.iter().enumerate() {
            let pkey = format!("table[{ti}].perturbations[{pi}]");
            let pm = if let Some(spec) = p.strip_prefix("mesh:") {
                let path = resolve_mesh(spec, base).with_context(|| format!("key '{pkey}'"))?;
                let other = input::load(Some(&path))
                    .with_context(|| format!("key '{pkey}'"))?
                    .into_mesh("a study")?
                    .0;
                resampled_as(&mesh, other, spec)
            } else {
                let spec =
                    perturb::parse_perturbation(p).map_err(|e| anyhow!("key '{pkey}': {e}"))?;
                perturb::apply(&mesh, &spec).map_err(|e| anyhow!("key '{pkey}' on {m}: {e}"))?
            };
            perts.push((p.clone(), pm));
        }
        out.push(StudyMesh {
            name: m.clone(),
            mesh,
            perturbations: perts,
        });
    }
    Ok(out)
}

/// The CSV header of `robustness.csv`.
pub const ROBUSTNESS_COLUMNS: &str = "table,mesh,perturbation,laplacian,quantity,n_original,n_perturbed,source_original,source_perturbed,rel_l2,linf_rel,eig_drift_max,eig_drift_mean";

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn run_robustness(a: RobustnessArgs) -> Result<()> {
    let origin = a.file.display().to_string();
    let text =
        std::fs::read_to_string(&a.file).map_err(|e| anyhow!("{origin}: cannot read: {e}"))?;
    let study = parse_study(&text, &origin)?;
    let base = parent_dir(&a.file);
    let mut names = vec!["robustness.csv".to_string(), "robustness.md".to_string()];
    for (t, (_, qs)) in study.file.table.iter().zip(&study.tables) {
        for q in qs {
            names.push(format!("{}-{}.png", t.name, q.name()));
        }
    }
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let paths = prepare_outputs(&a.out, &refs, a.force)?;
    // Build every table's meshes first (errors before any long work).
    let mut built = Vec::new();
    for ti in 0..study.file.table.len() {
        built.push(build_table(&study, ti, &base).map_err(|e| anyhow!("{origin}: {e:#}"))?);
    }
    let total: usize = built
        .iter()
        .zip(&study.tables)
        .map(|(ms, (laps, _))| {
            ms.iter()
                .map(|m| (1 + m.perturbations.len()) * laps.len())
                .sum::<usize>()
        })
        .sum();
    let bar = progress::bar(total as u64, "cells");
    let mut offset = 0usize;
    let mut all: Vec<(usize, StudyRow)> = Vec::new();
    let t0 = std::time::Instant::now();
    for (ti, (meshes, (laps, qs))) in built.iter().zip(&study.tables).enumerate() {
        bar.set_message(study.file.table[ti].name.clone());
        let b = bar.clone();
        let off = offset;
        let cb = move |p: StudyProgress| b.set_position((off + p.done) as u64);
        let rows = run_study(meshes, laps, qs, &study.params, &cb)
            .map_err(|e| anyhow!("table '{}': {e}", study.file.table[ti].name))?;
        offset += meshes
            .iter()
            .map(|m| (1 + m.perturbations.len()) * laps.len())
            .sum::<usize>();
        all.extend(rows.into_iter().map(|r| (ti, r)));
    }
    bar.finish_and_clear();
    let mut csv = format!("{ROBUSTNESS_COLUMNS}\n");
    for (ti, r) in &all {
        writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{:e},{:e},{:e},{:e}",
            csv_field(&study.file.table[*ti].name),
            csv_field(&r.mesh),
            csv_field(&r.perturbation),
            r.laplacian.name(),
            r.quantity.name(),
            r.n_original,
            r.n_perturbed,
            r.source_original,
            r.source_perturbed,
            r.rel_l2,
            r.linf_rel,
            r.eig_drift_max,
            r.eig_drift_mean
        )?;
    }
    write(&paths[0], csv.as_bytes())?;
    let md = robustness_markdown(&study, &all);
    write(&paths[1], md.as_bytes())?;
    // Plots: per table and quantity, relative L2 against the perturbation's number.
    let mut pi = 2;
    for (ti, (t, (laps, qs))) in study.file.table.iter().zip(&study.tables).enumerate() {
        for q in qs {
            let mut curves = Vec::new();
            for m in &t.meshes {
                for l in laps {
                    let pts: Vec<(f64, f64)> = t
                        .perturbations
                        .iter()
                        .enumerate()
                        .filter_map(|(j, p)| {
                            all.iter()
                                .find(|(i, r)| {
                                    *i == ti
                                        && &r.mesh == m
                                        && &r.perturbation == p
                                        && r.laplacian == *l
                                        && r.quantity == *q
                                })
                                .map(|(_, r)| ((j + 1) as f64, r.rel_l2))
                        })
                        .collect();
                    let label = if t.meshes.len() > 1 {
                        format!("{m} {}", l.name())
                    } else {
                        l.name().to_string()
                    };
                    curves.push((label, pts));
                }
            }
            let res = plot_curves(
                &paths[pi],
                &curves,
                "perturbation (number in the table)",
                "relative L2 difference",
                true,
                &format!("{}: {}", t.name, q.name()),
            );
            if let Err(e) = res {
                // All-zero differences have nothing to draw on a log axis.
                eprintln!("note: {}: {e}", paths[pi].display());
            }
            pi += 1;
        }
    }
    print!("{md}");
    println!(
        "{} cells in {:.1} s; wrote {} files to {}",
        all.len(),
        t0.elapsed().as_secs_f64(),
        names.len(),
        a.out.display()
    );
    Ok(())
}

/// One markdown table per study table: a row per (mesh, perturbation, quantity) plus one
/// for the eigenvalues, a column per Laplacian; cells `rel L2 (rel Linf)`.
pub fn robustness_markdown(study: &ParsedStudy, rows: &[(usize, StudyRow)]) -> String {
    let p = &study.params;
    let mut md = String::new();
    if let Some(t) = &study.file.title {
        let _ = writeln!(md, "## {t}\n");
    }
    let _ = writeln!(
        md,
        "k = {}, heat t = {}, diffusion t = {}, HKS t = {} (times for the unit-area shape). Cells: relative L2 difference (FEM-mass norm) and, in brackets, relative L-infinity difference between the field of the original pulled back to the perturbed vertices and the field of the perturbed mesh; eigenvalue rows: max (mean) relative drift of the first k unit-area eigenvalues.\n",
        p.k, p.heat_t, p.diffusion_t, p.hks_t
    );
    for (ti, (t, (laps, qs))) in study.file.table.iter().zip(&study.tables).enumerate() {
        let _ = writeln!(md, "### {}\n", t.name);
        if let Some(c) = &t.claim {
            let _ = writeln!(md, "{c}\n");
        }
        md.push_str("| mesh | perturbation | quantity |");
        for l in laps {
            let _ = write!(md, " {} |", l.name());
        }
        md.push_str("\n|---|---|---|");
        md.push_str(&"---|".repeat(laps.len()));
        md.push('\n');
        for m in &t.meshes {
            for pert in &t.perturbations {
                let find = |l: &Laplacian, q: &Quantity| {
                    rows.iter().find(|(i, r)| {
                        *i == ti
                            && &r.mesh == m
                            && &r.perturbation == pert
                            && r.laplacian == *l
                            && r.quantity == *q
                    })
                };
                let n = qs
                    .first()
                    .and_then(|q| laps.first().and_then(|l| find(l, q)))
                    .map(|(_, r)| format!(" ({} -> {} v.)", r.n_original, r.n_perturbed))
                    .unwrap_or_default();
                for q in qs {
                    let _ = write!(md, "| {m}{n} | `{pert}` | {} |", q.name());
                    for l in laps {
                        match find(l, q) {
                            Some((_, r)) => {
                                let _ = write!(md, " {:.2e} ({:.2e}) |", r.rel_l2, r.linf_rel);
                            }
                            None => md.push_str(" - |"),
                        }
                    }
                    md.push('\n');
                }
                if qs.iter().any(|q| *q != Quantity::Harmonic) {
                    let _ = write!(md, "| {m}{n} | `{pert}` | eigenvalues |");
                    for l in laps {
                        match qs.iter().find_map(|q| find(l, q)) {
                            Some((_, r)) => {
                                let _ = write!(
                                    md,
                                    " {:.2e} ({:.2e}) |",
                                    r.eig_drift_max, r.eig_drift_mean
                                );
                            }
                            None => md.push_str(" - |"),
                        }
                    }
                    md.push('\n');
                }
            }
        }
        md.push('\n');
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        format!("{:#}", parse_study(text, "s.toml").unwrap_err())
    }

    #[test]
    fn study_file_errors_name_the_key() {
        let t = "[[table]]\nname = \"a\"\nmeshes = [\"sphere:res=1\"]\nperturbations = [\"noise:0.1\"]\n";
        assert!(parse_study(t, "s").is_ok());
        for (text, key) in [
            (format!("k = 1\n{t}"), "key 'k'"),
            (format!("k = \"x\"\n{t}"), "key 'k'"),
            (format!("heat_t = -1.0\n{t}"), "key 'heat_t'"),
            (format!("hks_t = 0.0\n{t}"), "key 'hks_t'"),
            (
                format!("laplacians = [\"fem\", \"cott\"]\n{t}"),
                "key 'laplacians[1]'",
            ),
            (
                format!("quantities = [\"heat\", \"temp\"]\n{t}"),
                "key 'quantities[1]'",
            ),
            (format!("colour = 1\n{t}"), "colour"),
            (format!("{t}extra = 1\n"), "extra"),
            (
                t.replace("noise:0.1", "noize:0.1"),
                "key 'table[0].perturbations[0]'",
            ),
            (
                t.replace("noise:0.1", "noise:0.1,seed=x"),
                "key 'table[0].perturbations[0]'",
            ),
            (
                t.replace("[\"sphere:res=1\"]", "[]"),
                "key 'table[0].meshes'",
            ),
            (
                t.replace("name = \"a\"", "name = \"a b\""),
                "key 'table[0].name'",
            ),
            (
                format!("{t}laplacians = [\"x\"]\n"),
                "key 'table[0].laplacians[0]'",
            ),
            ("k = 10\n".to_string(), "table"),
        ] {
            let e = err(&text);
            assert!(e.contains(key), "{text:?}: {e}");
        }
    }
}
