//! Every file of the project's shared mesh folder, with the outcome it must have.
//!
//! The folder comes from `SPECTRAL_MESH_SHARED_MESHES` (e.g. `../shared/meshes`); when
//! the variable is unset the tests print a note and pass, when it is set to a missing folder
//! they fail.

#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use spectral_mesh::io::{MeshFormat, read_mesh};
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::mesh::validate::{RepairOptions, repair, report};

/// What reading a file must give.
enum Expect {
    /// Loads with (vertices, triangles after triangulation, polygons triangulated,
    /// components, Euler characteristic) and exactly these problems in `report` (substrings,
    /// one per problem).
    Loads {
        counts: (usize, usize, usize, usize, i64),
        problems: &'static [&'static str],
    },
    /// Refused with an error containing this.
    #[allow(dead_code)]
    Refused(&'static str),
}

use Expect::Loads;

const fn ok(counts: (usize, usize, usize, usize, i64)) -> Expect {
    bad(counts, &[])
}

/// Loads with these counts and these problems.
const fn bad(
    counts: (usize, usize, usize, usize, i64),
    problems: &'static [&'static str],
) -> Expect {
    Loads { counts, problems }
}

fn table() -> Vec<(&'static str, Expect)> {
    vec![
        ("3torus.off", ok((19, 46, 23, 1, -4))),
        ("blobby_3cc.off", ok((1820, 3417, 0, 3, 2))),
        ("bunny00.off", ok((37706, 75408, 0, 1, 2))),
        ("cactus.off", ok((620, 1236, 0, 1, 2))),
        ("cow.off", ok((2904, 5804, 0, 1, 2))),
        ("cube.off", ok((8, 12, 0, 1, 2))),
        ("cylinder_locally_refined.off", ok((8285, 16442, 0, 1, 1))),
        (
            "degtri_sliding.off",
            bad((8, 8, 0, 1, 1), &["4 zero-area (degenerate) triangles"]),
        ),
        ("double-torus-example.off", ok((231, 466, 220, 1, -2))),
        ("eight.off", ok((315, 634, 0, 1, -2))),
        ("elephant-with-holes.off", ok((2798, 4463, 0, 1, -110))),
        ("elephant.off", ok((2775, 5558, 0, 1, -4))),
        ("fandisk.off", ok((6475, 12946, 0, 1, 2))),
        ("hand.off", ok((1197, 2390, 0, 1, 2))),
        ("holes.off", ok((4291, 8288, 0, 1, -5))),
        ("homer.off", ok((4930, 9856, 0, 1, 2))),
        ("knot1.off", ok((3200, 6400, 0, 1, 0))),
        ("mesh_with_border.off", ok((548, 1014, 0, 1, 1))),
        ("octahedron.off", ok((6, 8, 0, 1, 2))),
        (
            "polygon_mesh.off",
            bad((16344, 32245, 0, 1, -23), &["2 non-manifold vertices"]),
        ),
        ("sphere966.off", ok((926, 1848, 0, 1, 2))),
        ("tetrahedron.off", ok((4, 4, 0, 1, 2))),
        ("torus_quad.off", ok((25, 50, 25, 1, 0))),
    ]
}

/// The folder, or `None` (with a note) when the variable is unset.
fn folder() -> Option<PathBuf> {
    spectral_mesh_testkit::shared_meshes()
}

/// Every file in the folder except README.md, sorted.
fn files(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("readable folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n != "README.md")
        .collect();
    names.sort();
    names
}

#[test]
fn every_shared_mesh_has_its_stated_outcome() {
    let Some(dir) = folder() else { return };
    let table = table();
    let names = files(&dir);
    assert!(!names.is_empty(), "no meshes in {}", dir.display());
    for name in &names {
        let Some((_, expect)) = table.iter().find(|(n, _)| n == name) else {
            panic!("{name}: no expected outcome in the table; inspect it and add one");
        };
        let res = read_mesh(&dir.join(name));
        match (expect, res) {
            (Expect::Refused(why), Err(e)) => {
                let s = e.to_string();
                assert!(s.contains(name.as_str()), "{s}");
                assert!(s.contains(why), "{name}: {s:?} should mention {why:?}");
            }
            (Expect::Refused(why), Ok(_)) => panic!("{name} loaded but should fail: {why}"),
            (Loads { .. }, Err(e)) => panic!("{name} should load: {e}"),
            (Loads { counts, problems }, Ok(l)) => {
                assert_eq!(l.format, MeshFormat::Off);
                let topo = Topology::new(&l.mesh);
                let got = (
                    l.mesh.n_vertices(),
                    l.mesh.n_triangles(),
                    l.polygons_triangulated,
                    topo.n_components(),
                    topo.euler_characteristic(),
                );
                assert_eq!(&got, counts, "{name}");
                let found = report(&l.mesh).problems();
                assert_eq!(found.len(), problems.len(), "{name}: {found:?}");
                for p in *problems {
                    assert!(found.iter().any(|f| f.contains(p)), "{name}: {found:?}");
                }
                assert!(l.warnings.is_empty(), "{name}: {:?}", l.warnings);
                if name == "cactus.off" {
                    assert_eq!(l.vertex_colors.map(|c| c.len()), Some(620));
                }
            }
        }
    }
    // The table names no file that is gone.
    for (n, _) in &table {
        assert!(
            names.iter().any(|x| x == n),
            "{n} is in the table but not in the folder"
        );
    }
}

#[test]
fn every_loading_shared_mesh_survives_repair_and_comes_out_clean() {
    let Some(dir) = folder() else { return };
    for name in files(&dir) {
        let Ok(l) = read_mesh(&dir.join(&name)) else {
            continue;
        };
        let before = report(&l.mesh);
        let rep = repair(&l.mesh, &RepairOptions::default())
            .unwrap_or_else(|e| panic!("{name}: repair failed: {e}"));
        let after = report(&rep.mesh);
        assert!(after.is_clean(), "{name}: {:?}", after.problems());
        assert_eq!(rep.vertex_map.len(), l.mesh.n_vertices());
        if before.is_clean() {
            assert_eq!(rep.mesh, l.mesh, "{name}: a clean mesh is left unchanged");
            assert!(rep.log.is_empty(), "{name}: {:?}", rep.log);
        } else {
            assert!(!rep.log.is_empty(), "{name}");
        }
        // Every kept input vertex keeps its position.
        for (o, m) in rep.vertex_map.iter().enumerate() {
            if let Some(m) = m {
                assert_eq!(rep.mesh.positions()[*m], l.mesh.positions()[o], "{name}");
            }
        }
    }
}
