//! Output files: never overwrite what the user had without `--force`. Every write goes
//! through the library's atomic write.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use spectral_mesh::analysis::{Analysis, Field};
use spectral_mesh::experiments::file::{ExperimentFile, parent_dir};
use spectral_mesh::io::write_atomic;

use crate::engine::save_field_experiment;
use crate::figure::{FigureArgs, write_field};
use crate::input::MeshInfo;

/// Outputs a per-vertex field can be written to.
pub const FIGURE_EXTS: [&str; 5] = ["png", "wrl", "vrml", "ply", "txt"];

/// Checks that `path` may be written: it must not exist unless `force` is set.
pub fn check_writable(path: &Path, force: bool) -> Result<()> {
    if path.exists() && !force {
        bail!(
            "{}: already exists; pass --force to overwrite it",
            path.display()
        );
    }
    Ok(())
}

/// Creates the output folder (and parents) and returns `dir/name` for each name,
/// checking none exists unless `force`.
pub fn prepare_outputs(dir: &Path, names: &[&str], force: bool) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("{}: cannot create folder: {e}", dir.display()))?;
    let paths: Vec<PathBuf> = names.iter().map(|n| dir.join(n)).collect();
    for p in &paths {
        check_writable(p, force)?;
    }
    Ok(paths)
}

/// Lower-case extension of a path.
pub fn extension(p: &Path) -> Option<String> {
    p.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// Checks before any work that every output has one of the `allowed` extensions, is
/// named once, and may be written (not existing unless `force`).
pub fn check_outputs(outs: &[PathBuf], allowed: &[&str], force: bool) -> Result<()> {
    for (i, o) in outs.iter().enumerate() {
        match extension(o) {
            Some(e) if allowed.contains(&e.as_str()) => {}
            _ => bail!(
                "{}: unknown output type (use {})",
                o.display(),
                allowed
                    .iter()
                    .map(|e| format!(".{e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
        if outs[..i].contains(o) {
            bail!("{}: named twice as an output", o.display());
        }
        check_writable(o, force)?;
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, bytes)?;
    Ok(())
}

/// Writes a value as pretty JSON with a final newline.
pub fn write_json(path: &Path, v: &impl serde::Serialize) -> Result<()> {
    write(path, (serde_json::to_string_pretty(v)? + "\n").as_bytes())
}

/// Writes an experiment file (refusing to overwrite without `force`).
pub fn save_experiment(file: &Path, f: &ExperimentFile, force: bool) -> Result<()> {
    check_writable(file, force)?;
    let dir = parent_dir(file);
    std::fs::create_dir_all(&dir)
        .map_err(|e| anyhow::anyhow!("{}: cannot create folder: {e}", dir.display()))?;
    write(file, f.to_toml()?.as_bytes())?;
    println!("saved the experiment to {}", file.display());
    Ok(())
}

/// Checks early that an experiment file may be written at `file`.
pub fn check_experiment_file(file: Option<&PathBuf>, force: bool) -> Result<()> {
    match file {
        Some(f) => check_writable(f, force),
        None => Ok(()),
    }
}

/// The output options every command that draws one field shares (`heat`, `distance`,
/// `signature`, `segment`): the experiment file that replays the field, overwriting, and
/// how the field is drawn. The output files themselves stay with each command (their help
/// and whether they are required differ).
#[derive(Debug, clap::Args)]
pub struct FieldOutputArgs {
    /// Also write an experiment file that reproduces the drawn field with `run FILE.toml`.
    #[arg(long, value_name = "FILE.toml")]
    pub save_experiment: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
}

impl FieldOutputArgs {
    /// Checks before any work that `outs` are field outputs that may be written, and that
    /// the experiment file may be.
    pub fn check(&self, outs: &[PathBuf]) -> Result<()> {
        check_outputs(outs, &FIGURE_EXTS, self.force)?;
        check_experiment_file(self.save_experiment.as_ref(), self.force)
    }

    /// Draws or writes `field` to each of `outs` (by extension), naming them on stdout.
    pub fn write_field(&self, an: &Analysis, field: &Field, outs: &[PathBuf]) -> Result<()> {
        write_field(an, field, outs, self.figure.options())
    }

    /// Writes the experiment file that replays `field`, when `--save-experiment` asks
    /// for one.
    pub fn save_experiment(
        &self,
        info: &MeshInfo,
        an: &Analysis,
        field: &Field,
        repair: bool,
    ) -> Result<()> {
        match &self.save_experiment {
            Some(file) => save_field_experiment(
                file,
                info,
                an,
                field,
                repair,
                &self.figure.options(),
                self.force,
            ),
            None => Ok(()),
        }
    }
}
