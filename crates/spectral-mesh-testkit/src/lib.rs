//! Test support shared by every crate's tests.
//!
//! The real meshes users hold (broken, non-manifold, with boundaries) live outside the
//! repository, in a folder named by `SPECTRAL_MESH_SHARED_MESHES` (CI sets it to
//! `../shared/meshes`); the shared point clouds are in the `points` folder beside it.
//! [`shared_meshes`] is the one place that reads the variable:
//! - set to a folder: that folder;
//! - set to anything else: the test fails (a typo must not look green);
//! - unset: outside CI the test says it was skipped and returns early; under CI (the
//!   variable `CI` set to anything but `false` or `0`) the test fails, so a CI that forgot
//!   the variable cannot pass without running these tests.

use std::path::PathBuf;

/// The environment variable naming the folder of shared meshes.
pub const MESHES_VAR: &str = "SPECTRAL_MESH_SHARED_MESHES";

/// Whether this run is CI's (`CI` set, and not `false` or `0`).
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// The folder of shared meshes, or `None` (after saying the test is skipped) when the
/// variable is unset outside CI. Panics when it names no folder, or is unset under CI.
pub fn shared_meshes() -> Option<PathBuf> {
    match std::env::var_os(MESHES_VAR) {
        Some(d) => {
            let d = PathBuf::from(d);
            assert!(d.is_dir(), "{MESHES_VAR}={} is not a folder", d.display());
            Some(d)
        }
        None if under_ci() => panic!(
            "{MESHES_VAR} is not set under CI: the tests on the shared real meshes would be \
             skipped (set it to the folder of shared meshes, e.g. ../shared/meshes)"
        ),
        None => {
            eprintln!("skipped: {MESHES_VAR} unset (the tests on shared real meshes need it)");
            None
        }
    }
}

/// One shared mesh by file name (e.g. `"bunny00.off"`), or `None` as [`shared_meshes`].
/// Panics when the folder has no such file.
pub fn shared_mesh(name: &str) -> Option<PathBuf> {
    let p = shared_meshes()?.join(name);
    assert!(p.is_file(), "{} is missing from {MESHES_VAR}", p.display());
    Some(p)
}

/// The shared point clouds: the `points` folder beside the meshes' folder, or `None` as
/// [`shared_meshes`]. Panics when that folder is missing.
pub fn shared_points() -> Option<PathBuf> {
    let d = shared_meshes()?.join("..").join("points");
    assert!(d.is_dir(), "{} is not a folder", d.display());
    Some(d)
}

/// The files of `dir` whose extension is `ext` (`Some("off")`), or every file but the
/// `.md` notes (`None`), sorted by name. Panics when `dir` cannot be read.
pub fn files_in(dir: &std::path::Path, ext: Option<&str>) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .filter(|p| {
            let e = p.extension().and_then(|e| e.to_str());
            match ext {
                Some(want) => e == Some(want),
                None => e != Some("md"),
            }
        })
        .collect();
    out.sort();
    out
}

/// The shared meshes with extension `ext` (`None`: every file but notes), sorted, or
/// `None` as [`shared_meshes`].
pub fn shared_mesh_files(ext: Option<&str>) -> Option<Vec<PathBuf>> {
    Some(files_in(&shared_meshes()?, ext))
}
