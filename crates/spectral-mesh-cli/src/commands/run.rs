//! `spectral-mesh run FILE.toml`: replays an experiment file (see
//! `docs/experiment-files.md`).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};

use crate::commands::experiment::{
    self, Common, DiffusionArgs, DistanceArgs, HarmonicArgs, load_mesh, parent_dir,
};
use crate::expfile::{Constraints, ExperimentFile, resolve_mesh};

/// Arguments of `run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The experiment file (TOML).
    pub file: PathBuf,
    /// Output folder (overrides the file's `out`).
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// Overwrite existing output files.
    #[arg(long, short = 'f')]
    pub force: bool,
    /// Run even when the mesh's hash differs from the file's `mesh_hash`.
    #[arg(long)]
    pub allow_changed_mesh: bool,
}

/// Replays the experiment.
pub fn run(a: Args) -> Result<()> {
    let origin = a.file.display().to_string();
    let text = std::fs::read_to_string(&a.file)
        .map_err(|e| anyhow::anyhow!("{origin}: cannot read: {e}"))?;
    let f = ExperimentFile::parse(&text, &origin)?;
    let base = parent_dir(&a.file);
    let mesh = resolve_mesh(&f.mesh, &base).with_context(|| format!("{origin}: key 'mesh'"))?;
    let loaded = load_mesh(Some(&mesh), false).with_context(|| format!("{origin}: key 'mesh'"))?;
    match &f.mesh_hash {
        Some(h) if !h.eq_ignore_ascii_case(&loaded.hash) => {
            if a.allow_changed_mesh {
                eprintln!(
                    "warning: mesh {mesh} has hash {} but {origin} expects {h}; running anyway (--allow-changed-mesh)",
                    loaded.hash
                );
            } else {
                bail!(
                    "mesh {mesh} changed: its hash is {} but {origin} expects {h} (pass --allow-changed-mesh to run anyway)",
                    loaded.hash
                );
            }
        }
        Some(_) => {}
        None => eprintln!(
            "note: {origin} has no mesh_hash; the mesh ({mesh}) is not checked (hash {})",
            loaded.hash
        ),
    }
    drop(loaded);
    let common = Common {
        out: match &a.out {
            Some(o) => o.clone(),
            None => base.join(f.out.as_deref().unwrap_or(".")),
        },
        force: a.force,
        repair: f.repair.unwrap_or(false),
        save_experiment: None,
        figure: f.figure_args()?,
    };
    let laplacian = f.laplacian()?;
    let mesh = Some(mesh);
    match f.experiment.as_str() {
        "harmonic" => {
            let (constraints, explicit) = match f.constraints()? {
                Constraints::Counts(c) => (c, Vec::new()),
                Constraints::Explicit(list) => (Vec::new(), list),
            };
            experiment::run_harmonic(HarmonicArgs {
                mesh,
                constraints,
                explicit,
                constraints_file: None,
                order: f.order.unwrap_or(1),
                laplacian,
                common,
            })
        }
        "diffusion-basis" => experiment::run_diffusion(DiffusionArgs {
            mesh,
            laplacian,
            t: f.t.unwrap_or(0.5),
            k: f.k.unwrap_or(100),
            anchor: f.anchor,
            no_normalize: !f.normalize.unwrap_or(true),
            common,
        }),
        "spectral-distance" => experiment::run_distance(DistanceArgs {
            mesh,
            distance: f.distance.clone().unwrap_or_else(|| "biharmonic".into()),
            laplacian,
            k: f.k.unwrap_or(100),
            source: f.source,
            no_normalize: !f.normalize.unwrap_or(true),
            common,
        }),
        other => bail!("{origin}: key 'experiment': unknown experiment '{other}'"),
    }
}
