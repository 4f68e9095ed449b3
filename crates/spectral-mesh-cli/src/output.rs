//! Output files: never overwrite what the user had without `--force`.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};

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

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename,
/// so an interrupted write never leaves a half file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    std::fs::write(&tmp, bytes)
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        anyhow::anyhow!("{}: cannot write: {e}", path.display())
    })
}

/// Formats a per-vertex field as text: one value per line, shortest round-trip form
/// (NumPy's `np.loadtxt` reads it back bit for bit).
pub fn field_text(values: &[f64]) -> String {
    let mut s = String::with_capacity(values.len() * 24);
    for v in values {
        s.push_str(&format!("{v:?}\n"));
    }
    s
}
