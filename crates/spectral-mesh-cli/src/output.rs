//! Output files: never overwrite what the user had without `--force`. Every write goes
//! through the library's atomic write.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use spectral_mesh::experiments::file::{ExperimentFile, parent_dir};
use spectral_mesh::io::write_atomic;

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
