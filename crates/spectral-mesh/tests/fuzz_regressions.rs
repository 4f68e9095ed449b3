//! Every input the fuzzers found (crash, hang, out-of-memory, broken promise), and a few
//! made by hand for the same bugs, fed again to the entry point that failed.
//!
//! The inputs live in `tests/fuzz_regressions/TARGET/NAME`, TARGET being the fuzz target
//! that found the bug (see `fuzz/README.md`); each is checked the way that target checks
//! it: a clean error naming the input, or a valid result. Each runs on a thread with a
//! 256 KiB stack (a server's worker threads have 2 MB) and must finish within a few
//! seconds. `RELIABILITY.md` lists what each input found and the commit that fixed it.
//! Inputs named `seed-*` found nothing: they are seeds of the targets that have no
//! finding yet, kept so that every target's check here runs.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use spectral_mesh::experiments::file::ExperimentFile;
use spectral_mesh::fields::harmonic::parse_constraints;
use spectral_mesh::io::{
    Input, LoadedMesh, MeshFormat, WriteOptions, field_to_text, read_field_text,
    read_input_from_bytes, read_mesh_from_bytes, write_mesh_to,
};
use spectral_mesh::mesh::validate::{RepairOptions, repair, report};
use spectral_mesh::operators::point_cloud::{
    NormalSource, PointCloudParams, TriangleUnion, point_cloud_laplacian,
};
use spectral_mesh::operators::{Laplacian, Operators};
use spectral_mesh::shapes::{ShapeError, build_limited, parse_shape};
use spectral_mesh::spectral::eigenbasis::{EigenParams, compute_eigenbasis};
use spectral_mesh::spectral::filters::{CustomKind, Expr, Filter};
use spectral_mesh::spectral::store::load_npz;
use spectral_mesh::{FieldRequest, Mesh, PointCloud};

const STACK: usize = 256 * 1024;
const TIME_LIMIT: Duration = Duration::from_secs(20);

fn inputs() -> Vec<(String, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut out = Vec::new();
    for dir in std::fs::read_dir(&root).unwrap() {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let target = dir.file_name().unwrap().to_string_lossy().into_owned();
        for f in std::fs::read_dir(&dir).unwrap() {
            out.push((target.clone(), f.unwrap().path()));
        }
    }
    out.sort();
    out
}

fn check_mesh(m: &Mesh) {
    let n = m.n_vertices();
    assert!(n > 0 && m.n_triangles() > 0);
    assert!(m.positions().iter().flatten().all(|c| c.is_finite()));
    for t in m.triangles() {
        assert!(t.iter().all(|&i| i < n) && t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    }
}

/// The check of the mesh-reading fuzz targets: a clean error naming the input, or a valid
/// mesh that writes and reads back the same (STL: when all its vertices are used).
fn read(bytes: &[u8], name: &str) -> Option<LoadedMesh> {
    match read_mesh_from_bytes(bytes, name) {
        Err(e) => {
            assert!(e.to_string().starts_with(name), "{e}");
            None
        }
        Ok(l) => {
            check_mesh(&l.mesh);
            if let Some(c) = &l.vertex_colors {
                assert_eq!(c.len(), l.mesh.n_vertices());
                assert!(
                    c.iter().flatten().all(|x| (0.0..=1.0).contains(x)),
                    "colour outside [0, 1]: {c:?}"
                );
            }
            let cases: &[(MeshFormat, bool)] = match l.format {
                MeshFormat::Ply => &[(MeshFormat::Ply, false), (MeshFormat::Ply, true)],
                MeshFormat::Stl => &[(MeshFormat::Stl, true)],
                MeshFormat::Off => &[(MeshFormat::Off, false)],
                MeshFormat::Obj => &[(MeshFormat::Obj, false)],
            };
            for &(format, binary) in cases {
                let opts = WriteOptions {
                    binary,
                    ..WriteOptions::default()
                };
                let mut buf = Vec::new();
                write_mesh_to(&mut buf, format, &l.mesh, &opts).unwrap();
                let back = read_mesh_from_bytes(&buf, &format!("rt.{}", format.extension()))
                    .unwrap_or_else(|e| panic!("{format} output does not read back: {e}"));
                assert_eq!(back.mesh.triangles(), l.mesh.triangles());
                let bits = |m: &Mesh| -> Vec<[u64; 3]> {
                    m.positions().iter().map(|p| p.map(f64::to_bits)).collect()
                };
                assert_eq!(bits(&back.mesh), bits(&l.mesh));
            }
            Some(l)
        }
    }
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The archive `fuzz/fuzz_targets/basis_npz.rs` builds: the input split at `NPYSEP` into
/// the `.npy` members, zipped without compression.
fn npz_of_members(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    const NAMES: [&str; 8] = [
        "eigenvalues",
        "eigenvectors",
        "mass_data",
        "mass_indices",
        "mass_indptr",
        "mass_shape",
        "residuals",
        "meta",
    ];
    let mut parts = Vec::new();
    let mut rest = bytes;
    while let Some(i) = rest.windows(6).position(|w| w == b"NPYSEP") {
        parts.push(&rest[..i]);
        rest = &rest[i + 6..];
    }
    parts.push(rest);
    let mut buf = std::io::Cursor::new(Vec::new());
    let mut zip = zip::ZipWriter::new(&mut buf);
    let opts =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, part) in NAMES.iter().zip(parts) {
        zip.start_file(format!("{name}.npy"), opts).unwrap();
        zip.write_all(part).unwrap();
    }
    zip.finish().unwrap();
    buf.into_inner()
}

/// The names `fuzz/fuzz_targets/read_points.rs` picks from with the first byte.
const POINT_NAMES: [&str; 12] = [
    "p.xyz",
    "p.pts",
    "p.txt",
    "p.csv",
    "p.ply",
    "P.XYZ",
    "p",
    "upload",
    "p.off",
    "p.obj",
    "p.stl",
    "dir/sub/x.pts",
];

/// The cloud and parameters `fuzz/fuzz_targets/pipeline_points.rs` draws from its input
/// (`arbitrary` reads one byte per `u8`, `i8` and `bool`, zeros once the input is used up).
fn points_of(bytes: &[u8]) -> (PointCloud, PointCloudParams, i32) {
    let mut it = bytes.iter().copied();
    let mut next = move || it.next().unwrap_or(0);
    let pick = next();
    let params = PointCloudParams {
        neighbors: 2 + usize::from(pick & 0x0f),
        normals: if pick & 0x10 != 0 {
            NormalSource::FromCloud
        } else {
            NormalSource::Estimate
        },
        union: [
            TriangleUnion::Consensus,
            TriangleUnion::ConsensusOnly,
            TriangleUnion::Multiplicity,
            TriangleUnion::Interleaved,
        ][usize::from(pick >> 5) % 4],
        ..PointCloudParams::default()
    };
    let scale_exp = i32::from(next() as i8).clamp(-100, 100) * 3;
    let n = usize::from(next()) % 64 + 1;
    let with_normals = next() & 1 == 1;
    let mut pos = Vec::new();
    let mut nrm = Vec::new();
    for _ in 0..n {
        let p = [next(), next(), next()].map(|c| f64::from(c as i8) * 10f64.powi(scale_exp));
        pos.push(p);
        if with_normals {
            nrm.push([next(), next(), next()].map(|c| f64::from(c as i8)));
        }
    }
    let cloud = PointCloud::new(pos, with_normals.then_some(nrm)).unwrap();
    (cloud, params, scale_exp)
}

/// Feeds one input the way its fuzz target does.
fn feed(target: &str, bytes: &[u8]) {
    match target {
        "read_off" => drop(read(bytes, "fuzz.off")),
        "read_obj" => drop(read(bytes, "fuzz.obj")),
        "read_ply_ascii" | "read_ply_binary" => drop(read(bytes, "fuzz.ply")),
        "read_stl_ascii" | "read_stl_binary" => drop(read(bytes, "fuzz.stl")),
        "detect_format" => drop(read(bytes, "upload")),
        "constraints" => match parse_constraints(&text(bytes), "c.txt") {
            Ok(list) => assert!(list.iter().all(|c| c.value.is_finite())),
            Err(e) => assert!(e.to_string().contains("c.txt:"), "{e}"),
        },
        "field_text" => {
            if let Ok(v) = read_field_text(&text(bytes), "f.txt", None) {
                let back = read_field_text(&field_to_text(&v).unwrap(), "rt", None).unwrap();
                assert_eq!(
                    back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                    v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
                );
            }
        }
        "filter" => {
            if let Ok(f) = text(bytes).parse::<Filter>() {
                let g: Filter = f.to_string().parse().unwrap();
                assert_eq!(g.to_string(), f.to_string());
                if let Ok(w) = f.weights(&[0.0, 0.5, 1.0, 2.0]) {
                    assert!(w.iter().all(|x| x.is_finite() && *x >= 0.0));
                }
            }
        }
        "filter_expr" => {
            let src = text(bytes);
            if let Ok(e) = Expr::parse(&src, &["t", "a"]) {
                let _ = e.eval(0.5, &[0.5, 2.0]);
                let f = Filter::custom(&src, BTreeMap::new(), CustomKind::Weight);
                assert!(f.is_ok() || src.contains('t') || src.contains('a'));
            }
        }
        "shape" => {
            if let Ok(spec) = parse_shape(&text(bytes)) {
                assert_eq!(parse_shape(&spec.to_string()).unwrap(), spec);
                match build_limited(&spec, 20_000) {
                    Ok(m) => {
                        assert!(m.n_vertices() <= 20_000);
                        let r = report(&m);
                        let want = spec.kind.expected_topology();
                        assert_eq!(r.euler_characteristic, want.euler_characteristic);
                        assert!(r.is_clean(), "{spec}: {:?}", r.problems());
                    }
                    Err(ShapeError::TooLarge { .. }) => {}
                    Err(e) => panic!("{spec}: {e}"),
                }
            }
        }
        "validate_repair" => {
            if let Some(l) = read(bytes, "upload") {
                let _ = report(&l.mesh);
                if let Ok(r) = repair(&l.mesh, &RepairOptions::default()) {
                    let after = report(&r.mesh);
                    assert!(after.duplicate_faces.is_empty());
                    assert!(after.degenerate_faces.is_empty());
                    assert!(after.non_manifold_vertices.is_empty());
                    assert!(after.unreferenced_vertices.is_empty());
                }
            }
        }
        "pipeline_eigen" => {
            if let Some(l) = read(bytes, "upload") {
                for lap in Laplacian::ALL {
                    let ops = Operators::new(&l.mesh, lap);
                    let params = EigenParams {
                        k: 10.min(l.mesh.n_vertices()),
                        ..EigenParams::default()
                    };
                    if let Ok(b) = compute_eigenbasis(&ops, &params, &mut |_| {}) {
                        assert!(b.values.iter().all(|v| v.is_finite()));
                    }
                }
            }
        }
        "basis_npz" => {
            let archive = if bytes.first() == Some(&0x80) {
                bytes[1..].to_vec()
            } else {
                npz_of_members(bytes)
            };
            // Through a file and `load_npz`, what `eigs --cache` does.
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("fuzz.npz");
            std::fs::write(&path, &archive).unwrap();
            let name = path.display().to_string();
            match load_npz(&path) {
                Ok((b, meta)) => {
                    assert_eq!((b.n, b.k()), (meta.n, meta.k));
                    assert_eq!(b.vectors.len(), b.n * b.k());
                    assert!(b.values.iter().chain(&b.vectors).all(|x| x.is_finite()));
                }
                Err(e) => assert!(e.to_string().starts_with(&name), "{e}"),
            }
        }
        "read_points" => {
            let Some((&b, rest)) = bytes.split_first() else {
                return;
            };
            let name = POINT_NAMES[usize::from(b) % POINT_NAMES.len()];
            match read_input_from_bytes(rest, name) {
                Err(e) => assert!(e.to_string().starts_with(name), "{e}"),
                Ok(Input::Mesh(m)) => check_mesh(&m.mesh),
                Ok(Input::Points(p)) => {
                    assert!(p.cloud.n_points() > 0);
                    assert!(p.cloud.positions().iter().flatten().all(|c| c.is_finite()));
                    if let Some(nr) = p.cloud.normals() {
                        assert_eq!(nr.len(), p.cloud.n_points());
                        assert!(nr.iter().flatten().all(|c| c.is_finite()));
                    }
                }
            }
        }
        "pipeline_points" => {
            let (cloud, params, scale_exp) = points_of(bytes);
            let l = point_cloud_laplacian(&cloud, &params).unwrap();
            assert!(l.mass.is_diagonal());
            assert!(l.mass.diag().iter().all(|&m| m >= 0.0));
            if scale_exp.abs() <= 30 {
                assert!(
                    l.stiffness
                        .values()
                        .iter()
                        .chain(l.mass.values())
                        .all(|v| v.is_finite())
                );
            }
        }
        "field_request" => {
            let Some((&b, rest)) = bytes.split_first() else {
                return;
            };
            let src = text(rest);
            let parsed: Option<FieldRequest> = if b % 2 == 0 {
                serde_json::from_str(&src).ok()
            } else {
                toml::from_str(&src).ok()
            };
            if let Some(r) = parsed
                && r.validate().is_ok()
            {
                let json = serde_json::to_string(&r).unwrap();
                assert_eq!(serde_json::from_str::<FieldRequest>(&json).unwrap(), r);
                // (TOML cannot write an integer above i64::MAX: an error, not a panic.)
                if let Ok(t) = toml::to_string(&r) {
                    assert_eq!(toml::from_str::<FieldRequest>(&t).unwrap(), r);
                }
            }
        }
        "experiment_file" => match ExperimentFile::parse(&text(bytes), "e.toml") {
            Ok(f) => {
                let back = ExperimentFile::parse(&f.to_toml().unwrap(), "rt.toml").unwrap();
                assert_eq!(back, f);
            }
            Err(e) => assert!(e.to_string().starts_with("e.toml"), "{e}"),
        },
        other => panic!("no check for fuzz target '{other}'"),
    }
}

#[test]
fn every_fuzz_finding_gives_a_clean_error_or_a_valid_result() {
    let all = inputs();
    assert!(!all.is_empty(), "no regression inputs found");
    for (target, path) in all {
        let bytes = std::fs::read(&path).unwrap();
        let label = format!("{target}/{}", path.file_name().unwrap().to_string_lossy());
        let (tx, rx) = mpsc::channel();
        let t0 = Instant::now();
        let worker = std::thread::Builder::new()
            .name(label.clone())
            .stack_size(STACK)
            .spawn(move || {
                feed(&target, &bytes);
                tx.send(()).unwrap();
            })
            .unwrap();
        match rx.recv_timeout(TIME_LIMIT) {
            Ok(()) => worker.join().unwrap(),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                panic!("{label}: still running after {TIME_LIMIT:?}")
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                // The worker panicked: join to get its message.
                if let Err(p) = worker.join() {
                    std::panic::resume_unwind(p);
                }
            }
        }
        eprintln!("{label}: ok in {:?}", t0.elapsed());
    }
}

/// The size checks of the archive reader do not refuse what NumPy writes
/// (`numpy.savez_compressed`, Fortran-ordered eigenvectors, numpy 2.4).
#[test]
fn an_archive_written_by_numpy_still_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz_regressions/basis_npz/numpy-savez-compressed");
    let bytes = std::fs::read(path).unwrap();
    let (b, meta) = spectral_mesh::spectral::store::load_npz_from_reader(
        std::io::Cursor::new(&bytes[1..]),
        "np",
    )
    .unwrap();
    assert_eq!((b.n, b.k()), (5, 3));
    assert_eq!(meta.generator, "numpy.savez");
    assert_eq!(b.values, vec![0.0, 1.25, 2.5]);
    // Entry (i, j) of the (5, 3) array is (3 i + j) / 10; column-major in memory.
    assert_eq!(b.vectors[2 * 5 + 4], 1.4);
    assert_eq!(b.residuals, vec![1e-13; 3]);
}
