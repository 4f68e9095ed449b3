//! Turning the user's INPUTS (files, folders, globs, manifests) into the list of shapes of
//! a batch, each with the stable name its results are stored under.

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

use super::BatchError;

/// Extensions a folder scan picks up: the mesh formats and the unambiguous point formats
/// (`.txt` and `.csv` are left out of scans: name such files, or list them in a manifest).
pub const SCANNED_EXTENSIONS: [&str; 6] = ["off", "obj", "ply", "stl", "xyz", "pts"];

/// One shape of a batch.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BatchInput {
    /// The file.
    pub path: PathBuf,
    /// Its name in the output folder, `/`-separated and relative (no `..`): the path
    /// relative to the folder named (folder inputs), to the fixed part of the pattern
    /// (globs) or to the manifest's folder (manifest entries inside it); the file name
    /// otherwise. The extension is kept, so `a.off` and `a.ply` never collide. Names that
    /// would still collide get `~` and 8 hex digits of their path's hash appended.
    pub name: String,
}

impl BatchInput {
    /// The result file: `out/NAME.npz`.
    pub fn result_path(&self, out: &Path) -> PathBuf {
        out.join(format!("{}.npz", self.name))
    }
}

/// Resolves INPUTS in order; each one is:
/// - `@FILE`: a manifest, one input per line (blank lines and `#` comments skipped),
///   relative paths taken from the manifest's folder; its lines may be files, folders or
///   globs but not other manifests;
/// - a folder: every file below it (recursively) with a [`SCANNED_EXTENSIONS`] extension
///   (any case), hidden files and folders skipped;
/// - a pattern with `*`, `?` or `[` that is not an existing file: a glob (`**` crosses
///   folders); it must match at least one file;
/// - anything else: a file (a missing one is kept: its job fails with the reason, like any
///   unreadable shape).
///
/// The result is sorted by name; a file reached twice (same canonical path) is kept once.
pub fn resolve_inputs(specs: &[String]) -> Result<Vec<BatchInput>, BatchError> {
    let mut found = Vec::new();
    for spec in specs {
        if let Some(manifest) = spec.strip_prefix('@') {
            read_manifest(Path::new(manifest), &mut found)?;
        } else {
            resolve_one(spec, Path::new("."), None, &mut found)?;
        }
    }
    Ok(finish(found))
}

fn read_manifest(manifest: &Path, found: &mut Vec<BatchInput>) -> Result<(), BatchError> {
    let text = std::fs::read_to_string(manifest).map_err(|e| BatchError::Input {
        spec: format!("@{}", manifest.display()),
        message: format!("cannot read the manifest: {e}"),
    })?;
    let base = match manifest.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    for (i, line) in text.lines().enumerate() {
        let entry = line.split('#').next().unwrap_or("").trim();
        if entry.is_empty() {
            continue;
        }
        if entry.starts_with('@') {
            return Err(BatchError::Input {
                spec: format!("{}:{}", manifest.display(), i + 1),
                message: "a manifest cannot name another manifest".into(),
            });
        }
        resolve_one(entry, &base, Some(&base), found).map_err(|e| match e {
            BatchError::Input { spec, message } => BatchError::Input {
                spec: format!("{}:{}: {spec}", manifest.display(), i + 1),
                message,
            },
            other => other,
        })?;
    }
    Ok(())
}

fn is_glob(s: &str) -> bool {
    s.contains(['*', '?', '['])
}

/// `spec` relative to `base` unless absolute; names of files relative to `name_root` when
/// they lie inside it.
fn resolve_one(
    spec: &str,
    base: &Path,
    name_root: Option<&Path>,
    found: &mut Vec<BatchInput>,
) -> Result<(), BatchError> {
    let path = if Path::new(spec).is_absolute() || base == Path::new(".") {
        PathBuf::from(spec)
    } else {
        base.join(spec)
    };
    let input_err = |message: String| BatchError::Input {
        spec: spec.to_string(),
        message,
    };
    if path.is_dir() {
        let before = found.len();
        scan_folder(&path, &path, found).map_err(|e| input_err(e.to_string()))?;
        if found.len() == before {
            return Err(input_err(format!(
                "the folder has no {} file",
                SCANNED_EXTENSIONS.join("/")
            )));
        }
        return Ok(());
    }
    if !path.exists() && is_glob(spec) {
        let pattern = path.to_string_lossy().into_owned();
        let root = glob_root(&path);
        let paths = glob::glob(&pattern).map_err(|e| input_err(format!("bad pattern: {e}")))?;
        let before = found.len();
        for p in paths {
            let p = p.map_err(|e| input_err(e.to_string()))?;
            if p.is_file() {
                let name = relative_name(&p, &root).unwrap_or_else(|| file_name(&p));
                found.push(BatchInput { path: p, name });
            }
        }
        if found.len() == before {
            return Err(input_err("the pattern matches no file".into()));
        }
        return Ok(());
    }
    let name = name_root
        .and_then(|r| relative_name(&path, r))
        .unwrap_or_else(|| file_name(&path));
    found.push(BatchInput { path, name });
    Ok(())
}

fn scan_folder(dir: &Path, root: &Path, found: &mut Vec<BatchInput>) -> std::io::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    entries.sort();
    for p in entries {
        if p.file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.starts_with('.'))
        {
            continue;
        }
        if p.is_dir() {
            scan_folder(&p, root, found)?;
        } else if p
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| SCANNED_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
        {
            let name = relative_name(&p, root).unwrap_or_else(|| file_name(&p));
            found.push(BatchInput { path: p, name });
        }
    }
    Ok(())
}

/// The folders of a pattern before its first component with a wildcard.
fn glob_root(pattern: &Path) -> PathBuf {
    let mut root = PathBuf::new();
    for c in pattern.components() {
        if is_glob(&c.as_os_str().to_string_lossy()) {
            break;
        }
        root.push(c);
    }
    root
}

/// `path` relative to `root` as a `/`-separated name, when it lies inside it (lexically).
fn relative_name(path: &Path, root: &Path) -> Option<String> {
    let rel = if root == Path::new(".") && path.is_relative() {
        path
    } else {
        path.strip_prefix(root).ok()?
    };
    let mut parts = Vec::new();
    for c in rel.components() {
        match c {
            Component::Normal(s) => parts.push(s.to_string_lossy().into_owned()),
            Component::CurDir => {}
            _ => return None,
        }
    }
    (!parts.is_empty()).then(|| parts.join("/"))
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "input".to_string())
}

fn canonical(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

/// Drops repeated files, makes names unique, sorts by name.
fn finish(found: Vec<BatchInput>) -> Vec<BatchInput> {
    let mut seen = std::collections::HashSet::new();
    let mut list: Vec<BatchInput> = found
        .into_iter()
        .filter(|i| seen.insert(canonical(&i.path)))
        .collect();
    let mut count: HashMap<String, usize> = HashMap::new();
    for i in &list {
        *count.entry(i.name.clone()).or_default() += 1;
    }
    for i in &mut list {
        if count[&i.name] > 1 {
            let h = blake3::hash(canonical(&i.path).to_string_lossy().as_bytes()).to_hex();
            i.name = format!("{}~{}", i.name, &h.as_str()[..8]);
        }
    }
    list.sort_by(|a, b| a.name.cmp(&b.name));
    list
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(p: &Path) {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, b"x").unwrap();
    }

    #[test]
    fn files_folders_globs_and_manifests() {
        let d = tempfile::tempdir().unwrap();
        let r = d.path();
        for f in [
            "set/a.off",
            "set/sub/b.PLY",
            "set/notes.txt",
            "set/.hidden/c.off",
            "other/a.off",
            "other/c.obj",
            "x/cloud.xyz",
        ] {
            touch(&r.join(f));
        }
        let s = |p: &str| r.join(p).to_string_lossy().into_owned();
        let got = resolve_inputs(&[s("set")]).unwrap();
        let names: Vec<&str> = got.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["a.off", "sub/b.PLY"]);
        let got = resolve_inputs(&[s("other/*.o*")]).unwrap();
        let names: Vec<&str> = got.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["a.off", "c.obj"]);
        // Two a.off from different folders: both kept under distinct names; the same
        // file twice: once.
        let got = resolve_inputs(&[s("set/a.off"), s("other/a.off"), s("set/./a.off")]).unwrap();
        assert_eq!(got.len(), 2);
        assert!(got.iter().all(|i| i.name.starts_with("a.off~")), "{got:?}");
        assert_ne!(got[0].name, got[1].name);
        // Manifest: relative to its folder, comments, a missing file kept.
        std::fs::write(
            r.join("list.txt"),
            "# the set\nset/sub/b.PLY\n\nx/cloud.xyz # a cloud\nmissing.off\n",
        )
        .unwrap();
        let got = resolve_inputs(&[format!("@{}", s("list.txt"))]).unwrap();
        let names: Vec<&str> = got.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["missing.off", "set/sub/b.PLY", "x/cloud.xyz"]);
        // Errors name the input.
        let e = resolve_inputs(&[s("none/*.off")]).unwrap_err().to_string();
        assert!(e.contains("matches no file"), "{e}");
        let e = resolve_inputs(&[format!("@{}", s("nope.txt"))])
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot read the manifest"), "{e}");
        std::fs::create_dir_all(r.join("empty")).unwrap();
        let e = resolve_inputs(&[s("empty")]).unwrap_err().to_string();
        assert!(e.contains("has no"), "{e}");
    }
}
