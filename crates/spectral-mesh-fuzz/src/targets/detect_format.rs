//! Format detection: `io::read_mesh_from_bytes` with a file name chosen by the first byte
//! (no extension, each extension in several cases, a wrong one, an odd path). Besides the
//! reader checks: when the mesh is read as another format than the name says, a warning
//! says so.

use spectral_mesh::io::MeshFormat;

const NAMES: [&str; 14] = [
    "",
    "upload",
    "mesh.off",
    "MESH.OFF",
    "m.obj",
    "m.Obj",
    "m.ply",
    "m.stl",
    "m.STL",
    "m.txt",
    "dir/sub/x.ply",
    ".off",
    "a.b.obj",
    "noext.",
];

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    crate::named(data, &NAMES, |name, rest| {
        let Some(l) = crate::read_and_check(rest, name) else {
            return;
        };
        let by_name = MeshFormat::from_path(std::path::Path::new(name));
        if by_name != Some(l.format) {
            assert!(
                l.warnings.iter().any(|w| w.contains(&l.format.to_string())),
                "{name} read as {} without a warning: {:?}",
                l.format,
                l.warnings
            );
        }
    });
}
