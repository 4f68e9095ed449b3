//! `spectral-mesh run FILE.toml`: replays an experiment file (see
//! `docs/experiment-files.md`): the paper's three experiments and `experiment = "field"`.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use spectral_mesh::experiments::file::{ExperimentFile, parent_dir, resolve_mesh};
use spectral_mesh_render::figure::FigureOptions;

use crate::commands::experiment::{self, FieldSetup, Outputs};
use crate::input;

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
    let repair = f.repair.unwrap_or(false);
    let mut input = input::load_repaired(Some(&mesh), repair)
        .with_context(|| format!("{origin}: key 'mesh'"))?;
    // A point cloud is replayed with the file's Laplacian parameters (the defaults when
    // the file has none), so that its field is the same bit for bit.
    if f.point_cloud.is_some() && !input.shape.is_points() {
        bail!(
            "{origin}: key 'point_cloud': {mesh} is a mesh; the point-cloud Laplacian's parameters apply to point clouds only"
        );
    }
    input.set_cloud_params(f.point_cloud_params());
    let hash = input.info.hash_of(&input.shape);
    match &f.mesh_hash {
        Some(h) if !h.eq_ignore_ascii_case(&hash) => {
            if a.allow_changed_mesh {
                eprintln!(
                    "warning: mesh {mesh} has hash {hash} but {origin} expects {h}; running anyway (--allow-changed-mesh)"
                );
            } else {
                bail!(
                    "mesh {mesh} changed: its hash is {hash} but {origin} expects {h} (pass --allow-changed-mesh to run anyway)"
                );
            }
        }
        Some(_) => {}
        None => eprintln!(
            "note: {origin} has no mesh_hash; the mesh ({mesh}) is not checked (hash {hash})"
        ),
    }
    let outputs = Outputs {
        out: match &a.out {
            Some(o) => o.clone(),
            None => base.join(f.out.as_deref().unwrap_or(".")),
        },
        force: a.force,
        repair,
        save_experiment: None,
        figure: FigureOptions::from_file(&f.figure.clone().unwrap_or_default())
            .with_context(|| origin.clone())?,
    };
    // No `laplacian` key: the default of the input (fem for a mesh, robust for a cloud).
    let laplacian = match f.laplacian {
        Some(_) => Some(f.laplacian()?),
        None => None,
    };
    match f.experiment.as_str() {
        "harmonic" => experiment::run_harmonic(
            input,
            &f.harmonic_constraints()?,
            f.order.unwrap_or(1),
            laplacian,
            &outputs,
        ),
        exp @ ("diffusion-basis" | "spectral-distance" | "field") => {
            let request = f
                .request()
                .with_context(|| format!("{origin}: no field to compute"))?;
            let experiment = match exp {
                "diffusion-basis" => "diffusion-basis",
                "spectral-distance" => "spectral-distance",
                _ => "field",
            };
            let setup = FieldSetup {
                experiment,
                request,
                basis_k: f.basis_k,
                laplacian,
                normalize: f.normalize(),
            };
            experiment::run_field(input, &setup, &outputs).with_context(|| origin.clone())
        }
        other => bail!("{origin}: key 'experiment': unknown experiment '{other}'"),
    }
}
