use std::path::{Path, PathBuf};

use super::*;
use crate::io::{MeshFormat, WriteOptions, write_mesh};
use crate::mesh::Mesh;
use crate::shapes::build_str;
use crate::spectral::signatures::{hks, hks_auto_times};
use crate::spectral::store::load_npz;

/// A temporary folder holding the built-in shape `spec` written as `name` (OFF), the
/// output folder inside it (not created) and the shape as an input.
fn one_shape(name: &str, spec: &str) -> (tempfile::TempDir, std::path::PathBuf, BatchInput) {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let input = write_shape(d.path(), name, spec);
    (d, out, input)
}

fn write_shape(dir: &Path, name: &str, spec: &str) -> BatchInput {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let mesh = build_str(spec).unwrap();
    write_mesh(
        &path,
        &mesh,
        &WriteOptions {
            format: Some(MeshFormat::Off),
            ..Default::default()
        },
    )
    .unwrap();
    BatchInput {
        path,
        name: name.to_string(),
    }
}

/// HKS at `n` times from the spectrum, no other descriptor.
fn hks_auto(n: usize) -> DescriptorParams {
    DescriptorParams {
        hks: Some(Schedule::Auto(n)),
        ..Default::default()
    }
}

fn params() -> BatchParams {
    BatchParams {
        k: 12,
        descriptors: DescriptorParams {
            hks: Some(Schedule::Auto(4)),
            adf: Some(Schedule::Values(vec![0.01, 0.1])),
            wks: Some(Schedule::Auto(3)),
            ..Default::default()
        },
        ..Default::default()
    }
}

struct Png;
impl Thumbnailer for Png {
    fn png(&self, mesh: &Mesh, values: &[f64], size: u32) -> Result<Vec<u8>, String> {
        assert_eq!(values.len(), mesh.n_vertices());
        Ok(format!("png {size} {:?}", values[0]).into_bytes())
    }
}

struct Panics;
impl Thumbnailer for Panics {
    fn png(&self, _: &Mesh, _: &[f64], _: u32) -> Result<Vec<u8>, String> {
        panic!("the renderer broke")
    }
}

fn read(p: PathBuf) -> Vec<u8> {
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn a_shape_is_computed_then_skipped_then_recomputed_when_it_changes() {
    let d = tempfile::tempdir().unwrap();
    let (src, out) = (d.path().join("in"), d.path().join("out"));
    std::fs::create_dir_all(&src).unwrap();
    let input = write_shape(&src, "s.off", "sphere:res=2");
    let p = params();
    let opts = JobOptions::default();
    let r = process_one(&input, &p, &out, &opts);
    assert_eq!(r.status, Status::Ok, "{r:?}");
    assert!(!r.reused);
    assert_eq!(
        (r.shape.n, r.shape.faces, r.shape.components, r.basis.k),
        (Some(162), Some(320), Some(1), Some(12))
    );
    assert_eq!(r.outputs, ["s.off.npz"]);
    assert!(r.basis.max_residual.unwrap() < 1e-8);
    assert_eq!(r.params_hash, p.hash());
    let hash = blake3::hash(&std::fs::read(&input.path).unwrap())
        .to_hex()
        .to_string();
    assert_eq!(r.input_hash.as_deref(), Some(hash.as_str()));
    // The result is a basis archive with the descriptors of the library's functions.
    let (basis, meta) = load_npz(&out.join("s.off.npz")).unwrap();
    assert_eq!(meta.k, 12);
    let times = hks_auto_times(basis.view(12), 4).unwrap();
    let want = hks(basis.view(12), &times, false);
    let f = std::fs::File::open(out.join("s.off.npz")).unwrap();
    let mut zip = zip::ZipArchive::new(f).unwrap();
    let mut names: Vec<String> = zip.file_names().map(str::to_string).collect();
    names.sort();
    assert_eq!(
        names,
        [
            "adf.npy",
            "adf_times.npy",
            "eigenvalues.npy",
            "eigenvectors.npy",
            "hks.npy",
            "hks_times.npy",
            "mass_data.npy",
            "mass_indices.npy",
            "mass_indptr.npy",
            "mass_shape.npy",
            "meta.npy",
            "residuals.npy",
            "wks.npy",
            "wks_energies.npy"
        ]
    );
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut zip.by_name("hks.npy").unwrap(), &mut bytes).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.shape(), [162, 4]);
    assert_eq!(npy.order(), npyz::Order::Fortran);
    let got: Vec<f64> = npy.into_vec().unwrap();
    assert_eq!(got, want.concat());
    let m: ResultMeta = serde_json::from_slice(
        &crate::spectral::store::read_npz_meta(&out.join("s.off.npz")).unwrap(),
    )
    .unwrap();
    assert_eq!(m.batch.descriptors.hks_times.as_deref(), Some(&times[..]));
    assert_eq!(m.batch.key.input_hash, hash);
    let first = read(out.join("s.off.npz"));

    // Again: skipped, nothing rewritten.
    let r2 = process_one(&input, &p, &out, &opts);
    assert_eq!((r2.status, r2.reused), (Status::Skipped, true), "{r2:?}");
    assert_eq!((&r2.shape, &r2.basis), (&r.shape, &r.basis));
    assert_eq!(r2.outputs, r.outputs);
    assert_eq!(read(out.join("s.off.npz")), first);

    // Other parameters: recomputed.
    let p3 = BatchParams { k: 10, ..p.clone() };
    let r3 = process_one(&input, &p3, &out, &opts);
    assert_eq!((r3.status, r3.basis.k), (Status::Ok, Some(10)));
    // Back to the first parameters: the same bytes as the first time.
    let r4 = process_one(&input, &p, &out, &opts);
    assert_eq!(r4.status, Status::Ok);
    assert_eq!(read(out.join("s.off.npz")), first);

    // Another input under the same name: recomputed.
    write_shape(&src, "s.off", "sphere:res=1");
    let r5 = process_one(&input, &p, &out, &opts);
    assert_eq!((r5.status, r5.shape.n), (Status::Ok, Some(42)));
    assert_ne!(r5.input_hash, r.input_hash);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let d = tempfile::tempdir().unwrap();
    // Large enough for the sparse path (the dense one is used up to a few hundred vertices).
    let input = write_shape(d.path(), "t.off", "torus:res=2");
    let p = BatchParams {
        k: 30,
        descriptors: hks_auto(5),
        ..Default::default()
    };
    let mut files = Vec::new();
    for threads in [1, 2, 3] {
        let out = d.path().join(format!("out{threads}"));
        let r = process_one(
            &input,
            &p,
            &out,
            &JobOptions {
                threads,
                ..Default::default()
            },
        );
        assert_eq!(r.status, Status::Ok, "{r:?}");
        assert!(r.shape.n.unwrap() > 300, "{:?}", r.shape);
        files.push(read(out.join("t.off.npz")));
    }
    assert_eq!(files[0], files[1]);
    assert_eq!(files[0], files[2]);
}

#[test]
fn a_bad_file_is_a_row_and_a_marker_until_it_changes() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let path = d.path().join("bad.off");
    std::fs::write(&path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap();
    let input = BatchInput {
        path: path.clone(),
        name: "bad.off".into(),
    };
    let p = params();
    let opts = JobOptions::default();
    let r = process_one(&input, &p, &out, &opts);
    assert_eq!((r.status, r.reused), (Status::Failed, false));
    let e = r.error.clone().unwrap();
    assert!(e.contains("bad.off") && e.contains("vertex 7"), "{e}");
    assert!(out.join("bad.off.error.json").is_file());
    assert!(!out.join("bad.off.npz").exists());
    // Again: the same failure, from the marker.
    let r2 = process_one(&input, &p, &out, &opts);
    assert_eq!((r2.status, r2.reused), (Status::Failed, true));
    assert_eq!(r2.error, r.error);
    // Retrying is possible.
    let r3 = process_one(
        &input,
        &p,
        &out,
        &JobOptions {
            retry_failed: true,
            ..Default::default()
        },
    );
    assert_eq!((r3.status, r3.reused), (Status::Failed, false));
    // Fixed: computed, the marker gone.
    write_shape(d.path(), "bad.off", "sphere:res=1");
    let r4 = process_one(&input, &p, &out, &opts);
    assert_eq!(r4.status, Status::Ok, "{r4:?}");
    assert!(!out.join("bad.off.error.json").exists());
    // A missing file: failed, no marker (nothing to hash).
    let gone = BatchInput {
        path: d.path().join("gone.off"),
        name: "gone.off".into(),
    };
    let r5 = process_one(&gone, &p, &out, &opts);
    assert!(r5.error.unwrap().contains("cannot read"));
    assert!(!out.join("gone.off.error.json").exists());
    // Too many pairs: the analysis' message.
    let tiny = write_shape(d.path(), "tet.off", "sphere:res=0");
    let r6 = process_one(&tiny, &BatchParams { k: 50, ..p.clone() }, &out, &opts);
    assert!(r6.error.unwrap().contains("only 12 vertices"));
}

#[test]
fn thumbnails_eigenvalues_only_panics_and_point_clouds() {
    let (d, out, input) = one_shape("s.off", "sphere:res=2");
    let p = BatchParams {
        k: 8,
        basis: false,
        thumbnail: Some(64),
        ..Default::default()
    };
    let png = JobOptions {
        thumbnailer: Some(&Png),
        ..Default::default()
    };
    // No renderer given: a failure of the run (no marker).
    let r = process_one(&input, &p, &out, &JobOptions::default());
    assert!(r.error.unwrap().contains("thumbnail"));
    assert!(!out.join("s.off.error.json").exists());
    let r = process_one(&input, &p, &out, &png);
    assert_eq!(r.status, Status::Ok, "{r:?}");
    assert_eq!(r.outputs, ["s.off.png", "s.off.npz"]);
    assert!(read(out.join("s.off.png")).starts_with(b"png 64 "));
    // Eigenvalues only: not a basis archive.
    assert!(load_npz(&out.join("s.off.npz")).is_err());
    // A lost thumbnail is made again.
    std::fs::remove_file(out.join("s.off.png")).unwrap();
    let r = process_one(&input, &p, &out, &png);
    assert_eq!(r.status, Status::Ok);
    assert!(out.join("s.off.png").is_file());
    // A panic inside is a row, not a crash.
    let r = process_one(
        &input,
        &BatchParams {
            thumbnail: Some(65),
            ..p.clone()
        },
        &out,
        &JobOptions {
            thumbnailer: Some(&Panics),
            ..Default::default()
        },
    );
    assert_eq!(r.status, Status::Failed);
    assert!(r.error.unwrap().contains("the renderer broke"));
    // A point cloud: the point-cloud Laplacian, no thumbnail (a warning says so).
    let mesh = build_str("sphere:res=3").unwrap();
    let text: String = mesh
        .positions()
        .iter()
        .map(|q| format!("{} {} {}\n", q[0], q[1], q[2]))
        .collect();
    let cloud = d.path().join("c.xyz");
    std::fs::write(&cloud, text).unwrap();
    let r = process_one(
        &BatchInput {
            path: cloud,
            name: "c.xyz".into(),
        },
        &BatchParams {
            descriptors: hks_auto(2),
            ..p.clone()
        },
        &out,
        &png,
    );
    assert_eq!(r.status, Status::Ok, "{r:?}");
    assert_eq!(
        (r.shape.kind, r.shape.faces, r.shape.components),
        (Some(InputKind::Points), Some(0), Some(1))
    );
    assert_eq!(r.basis.discretization, "robust");
    assert!(
        r.warnings.iter().any(|w| w.contains("point cloud")),
        "{:?}",
        r.warnings
    );
}

#[test]
fn stale_temporaries_are_removed() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("sub")).unwrap();
    std::fs::write(d.path().join("sub/.a.off.npz.tmp-12-0"), b"half").unwrap();
    std::fs::write(d.path().join("a.off.npz"), b"whole").unwrap();
    assert_eq!(remove_stale_temporaries(d.path()), 1);
    assert!(d.path().join("a.off.npz").exists());
    assert!(!d.path().join("sub/.a.off.npz.tmp-12-0").exists());
}

/// The cells of a CSV text (RFC 4180 quoting), line by line.
fn parse_csv(text: &str) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    let (mut row, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                cell.push('"');
            }
            ('"', true) => quoted = false,
            ('"', false) if cell.is_empty() => quoted = true,
            (',', false) => row.push(std::mem::take(&mut cell)),
            ('\n', false) => {
                row.push(std::mem::take(&mut cell));
                rows.push(std::mem::take(&mut row));
            }
            (c, _) => cell.push(c),
        }
    }
    rows
}

/// Processes every input (one after the other) and writes the summary; returns the rows.
fn run_all(inputs: &[BatchInput], p: &BatchParams, out: &Path) -> Vec<BatchRecord> {
    prepare_output(out, false).unwrap();
    let records: Vec<BatchRecord> = inputs
        .iter()
        .map(|i| process_one(i, p, out, &JobOptions::default()))
        .collect();
    write_summary(out, &records).unwrap();
    records
}

fn statuses(records: &[BatchRecord]) -> Vec<(String, Status)> {
    records.iter().map(|r| (r.name.clone(), r.status)).collect()
}

#[test]
fn the_summary_has_a_row_per_shape_and_a_rerun_redoes_exactly_what_changed() {
    let d = tempfile::tempdir().unwrap();
    let (src, out) = (d.path().join("in"), d.path().join("out"));
    std::fs::create_dir_all(&src).unwrap();
    write_shape(&src, "a.off", "sphere:res=1");
    write_shape(&src, "b.off", "torus:res=1");
    write_shape(&src, "sub/c.off", "sphere:res=2");
    // Broken files: a face naming a missing vertex, an empty file, text that is no mesh.
    std::fs::write(
        src.join("bad-index.off"),
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n",
    )
    .unwrap();
    std::fs::write(src.join("empty.off"), "").unwrap();
    std::fs::write(src.join("words.obj"), "this is not a mesh\n").unwrap();
    let inputs = resolve_inputs(&[src.to_string_lossy().into_owned()]).unwrap();
    let names: Vec<&str> = inputs.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "a.off",
            "b.off",
            "bad-index.off",
            "empty.off",
            "sub/c.off",
            "words.obj"
        ]
    );
    let p = BatchParams {
        k: 10,
        descriptors: hks_auto(3),
        ..Default::default()
    };
    let first = run_all(&inputs, &p, &out);
    use Status::{Failed, Ok as Done, Skipped};
    let want = |s: [Status; 6]| -> Vec<(String, Status)> {
        names.iter().map(|n| n.to_string()).zip(s).collect()
    };
    assert_eq!(
        statuses(&first),
        want([Done, Done, Failed, Failed, Done, Failed])
    );

    // The CSV: the header, then one row per shape in name order, every column filled as
    // the record says; the failures name their file and their reason.
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let rows = parse_csv(&csv);
    assert_eq!(rows.len(), 7, "{csv}");
    assert_eq!(rows[0], summary::COLUMNS);
    let col = |name: &str| summary::COLUMNS.iter().position(|c| *c == name).unwrap();
    let row = |name: &str| rows.iter().find(|r| r[0] == name).unwrap().clone();
    let a = row("a.off");
    assert_eq!(a[col("status")], "ok");
    assert_eq!(a[col("kind")], "mesh");
    assert_eq!(a[col("n")], "42");
    assert_eq!(a[col("faces")], "80");
    assert_eq!(a[col("components")], "1");
    assert_eq!(a[col("k")], "10");
    assert_eq!(a[col("discretization")], "fem");
    assert_eq!(a[col("outputs")], "a.off.npz");
    assert_eq!(a[col("params_hash")], p.hash());
    let a_hash = blake3::hash(&std::fs::read(src.join("a.off")).unwrap())
        .to_hex()
        .to_string();
    assert_eq!(a[col("input_hash")], a_hash);
    assert!(a[col("max_residual")].parse::<f64>().unwrap() < 1e-8);
    assert!(a[col("seconds")].parse::<f64>().unwrap() > 0.0);
    assert_eq!(row("sub/c.off")[col("outputs")], "sub/c.off.npz");
    assert!(out.join("sub/c.off.npz").is_file());
    for (name, reason) in [
        ("bad-index.off", "vertex 9"),
        ("empty.off", "empty.off"),
        ("words.obj", "words.obj"),
    ] {
        let r = row(name);
        assert_eq!(r[col("status")], "failed", "{r:?}");
        let e = &r[col("error")];
        assert!(e.contains(name) && e.contains(reason), "{name}: {e}");
        assert_eq!(r[col("outputs")], "");
        assert!(out.join(format!("{name}.error.json")).is_file());
    }
    // The Parquet file holds the same rows.
    {
        use parquet::file::reader::{FileReader, SerializedFileReader};
        let r =
            SerializedFileReader::new(std::fs::File::open(out.join("summary.parquet")).unwrap())
                .unwrap();
        assert_eq!(r.metadata().file_metadata().num_rows(), 6);
    }
    let files = |dir: &Path| -> Vec<(PathBuf, Vec<u8>)> {
        let mut v: Vec<(PathBuf, Vec<u8>)> = ["a.off.npz", "b.off.npz", "sub/c.off.npz"]
            .iter()
            .map(|f| (dir.join(f), read(dir.join(f))))
            .collect();
        v.sort();
        v
    };
    let before = files(&out);

    // A second run does no work: every result skipped, every failure reported again from
    // its marker, nothing rewritten.
    let second = run_all(&inputs, &p, &out);
    assert_eq!(
        statuses(&second),
        want([Skipped, Skipped, Failed, Failed, Skipped, Failed])
    );
    assert!(second.iter().all(|r| r.reused));
    assert_eq!(second[2].error, first[2].error);
    assert_eq!(files(&out), before);
    let skipped_row = row("a.off");
    let rows2 = parse_csv(&std::fs::read_to_string(out.join("summary.csv")).unwrap());
    let a2 = rows2.iter().find(|r| r[0] == "a.off").unwrap();
    assert_eq!(a2[col("status")], "skipped");
    for c in [
        "n",
        "faces",
        "components",
        "k",
        "max_residual",
        "outputs",
        "input_hash",
        "params_hash",
    ] {
        assert_eq!(a2[col(c)], skipped_row[col(c)], "{c}");
    }

    // A bare touch (same bytes, new time) changes nothing: inputs are known by content.
    let f = std::fs::OpenOptions::new()
        .append(true)
        .open(src.join("b.off"))
        .unwrap();
    f.set_modified(std::time::SystemTime::now() + std::time::Duration::from_secs(60))
        .unwrap();
    drop(f);
    let third = run_all(&inputs, &p, &out);
    assert_eq!(
        statuses(&third),
        want([Skipped, Skipped, Failed, Failed, Skipped, Failed])
    );
    // Edited (a comment line appended: other bytes, the same mesh): exactly that shape is
    // computed again, to the same arrays but under the new input hash.
    let mut text = std::fs::read_to_string(src.join("b.off")).unwrap();
    text.push_str("# edited\n");
    std::fs::write(src.join("b.off"), text).unwrap();
    let fourth = run_all(&inputs, &p, &out);
    assert_eq!(
        statuses(&fourth),
        want([Skipped, Done, Failed, Failed, Skipped, Failed])
    );
    assert_ne!(fourth[1].input_hash, first[1].input_hash);
    // A broken file fixed: computed, its marker gone.
    write_shape(&src, "empty.off", "sphere:res=1");
    let fifth = run_all(&inputs, &p, &out);
    assert_eq!(
        statuses(&fifth),
        want([Skipped, Skipped, Failed, Done, Skipped, Failed])
    );
    assert!(!out.join("empty.off.error.json").exists());
    // Other parameters: every shape computed again; back to the first ones: again, to
    // the first bytes.
    let q = BatchParams { k: 9, ..p.clone() };
    let sixth = run_all(&inputs, &q, &out);
    assert_eq!(
        statuses(&sixth),
        want([Done, Done, Failed, Done, Done, Failed])
    );
    assert!(sixth.iter().all(|r| r.params_hash == q.hash()));
    assert_eq!(sixth[0].basis.k, Some(9));
    let seventh = run_all(&inputs, &p, &out);
    assert_eq!(
        statuses(&seventh),
        want([Done, Done, Failed, Done, Done, Failed])
    );
    assert_eq!(read(out.join("a.off.npz")), before[0].1);
    assert_eq!(read(out.join("sub/c.off.npz")), before[2].1);
}

#[test]
fn outputs_are_written_atomically() {
    let (_dir, out, input) = one_shape("t.off", "torus:res=1");
    let result = out.join("t.off.npz");
    // While results are written again and again (the parameters alternate, so each run
    // replaces the file), a reader never sees a partial archive under the final name.
    let done = std::sync::atomic::AtomicBool::new(false);
    let seen = std::thread::scope(|s| {
        let reader = s.spawn(|| {
            let mut seen = 0;
            while !done.load(std::sync::atomic::Ordering::Relaxed) {
                if result.exists() {
                    let (basis, _) = load_npz(&result)
                        .unwrap_or_else(|e| panic!("a partial result was visible: {e}"));
                    assert!(basis.k() == 8 || basis.k() == 9);
                    seen += 1;
                }
            }
            seen
        });
        for i in 0..6 {
            let p = BatchParams {
                k: 8 + i % 2,
                ..Default::default()
            };
            let r = process_one(&input, &p, &out, &JobOptions::default());
            assert_eq!(r.status, Status::Ok, "{r:?}");
        }
        done.store(true, std::sync::atomic::Ordering::Relaxed);
        reader.join().unwrap()
    });
    assert!(seen > 0);
    let listing = |dir: &Path| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    // Only the result: no temporary file left behind.
    assert_eq!(listing(&out), ["t.off.npz"]);
    // A job stopped midway (cancelled: as a run that is interrupted) leaves the previous
    // result as it was, no marker and no temporary file.
    let before = read(result.clone());
    let cancel = crate::cancel::CancelToken::new();
    cancel.cancel();
    let r = process_one(
        &input,
        &BatchParams {
            k: 20,
            ..Default::default()
        },
        &out,
        &JobOptions {
            cancel,
            ..Default::default()
        },
    );
    assert_eq!(r.status, Status::Failed);
    assert!(r.error.unwrap().to_lowercase().contains("cancel"));
    assert_eq!(read(result.clone()), before);
    assert_eq!(listing(&out), ["t.off.npz"]);
    // A temporary file of a killed run is not a result: the shape is computed, and the
    // next run's clean-up removes the leftover.
    std::fs::remove_file(&result).unwrap();
    std::fs::write(
        out.join(".t.off.npz.tmp-999-0"),
        &before[..before.len() / 2],
    )
    .unwrap();
    let p = BatchParams {
        k: 9,
        ..Default::default()
    };
    let r = process_one(&input, &p, &out, &JobOptions::default());
    assert_eq!(r.status, Status::Ok);
    assert_eq!(remove_stale_temporaries(&out), 1);
    assert_eq!(listing(&out), ["t.off.npz"]);
}

#[test]
fn the_output_folder_must_be_empty_new_or_a_batch_folder() {
    let d = tempfile::tempdir().unwrap();
    let mine = d.path().join("new/out");
    prepare_output(&mine, false).unwrap();
    assert!(mine.join(MARKER_FILE).is_file());
    std::fs::write(mine.join("x.off.npz"), b"a result").unwrap();
    prepare_output(&mine, false).unwrap();
    let theirs = d.path().join("theirs");
    std::fs::create_dir_all(&theirs).unwrap();
    std::fs::write(theirs.join("notes.txt"), b"keep me").unwrap();
    let e = prepare_output(&theirs, false).unwrap_err().to_string();
    assert!(e.contains("theirs") && e.contains("--force"), "{e}");
    assert!(!theirs.join(MARKER_FILE).exists());
    prepare_output(&theirs, true).unwrap();
    assert_eq!(std::fs::read(theirs.join("notes.txt")).unwrap(), b"keep me");
}

/// One `.npy` array of a result archive: (shape, values).
fn npz_array(path: &Path, name: &str) -> (Vec<u64>, Vec<f64>) {
    let f = std::fs::File::open(path).unwrap();
    let mut zip = zip::ZipArchive::new(f).unwrap();
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(
        &mut zip.by_name(&format!("{name}.npy")).unwrap(),
        &mut bytes,
    )
    .unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    let shape = npy.shape().to_vec();
    (shape, npy.into_vec().unwrap())
}

#[test]
fn geodesic_distances_from_farthest_samples_are_saved_and_hashed() {
    use crate::analysis::{Analysis, AnalysisOptions};
    use crate::geodesic::{GeodesicParams, GeodesicSolver, farthest_point_sampling};
    let (_dir, out, input) = one_shape("t.off", "torus:res=2");
    let plain = BatchParams {
        k: 6,
        ..Default::default()
    };
    let p = BatchParams {
        geodesic: Some(4),
        ..plain.clone()
    };
    // `None` stays out of the hash (earlier results stay valid); a count enters it.
    let mut old = serde_json::to_value(&plain).unwrap();
    assert!(old.get("geodesic").is_none());
    old.as_object_mut().unwrap().remove("geodesic");
    let back: BatchParams = serde_json::from_value(old).unwrap();
    assert_eq!(back.hash(), plain.hash());
    assert_ne!(p.hash(), plain.hash());
    assert!(
        BatchParams {
            geodesic: Some(0),
            ..plain.clone()
        }
        .validate()
        .unwrap_err()
        .to_string()
        .contains("geodesic")
    );
    let r = process_one(&input, &p, &out, &JobOptions::default());
    assert_eq!(r.status, Status::Ok, "{r:?}");
    let file = out.join("t.off.npz");
    // The library's samples and distances, the same numbers.
    let mesh = build_str("torus:res=2").unwrap();
    let an = Analysis::new(mesh.clone(), AnalysisOptions::default());
    let solver =
        GeodesicSolver::new(&mesh, crate::Laplacian::Fem, &GeodesicParams::default()).unwrap();
    let samples = farthest_point_sampling(&solver, 4, an.default_source()).unwrap();
    let want = solver.distances_from_vertices(&samples).unwrap();
    let (shape, got) = npz_array(&file, "geodesic");
    assert_eq!(shape, [mesh.n_vertices() as u64, 4]);
    assert_eq!(got, want.concat());
    let (_, src) = npz_array(&file, "geodesic_sources");
    assert_eq!(src, samples.iter().map(|&s| s as f64).collect::<Vec<_>>());
    for (j, &s) in samples.iter().enumerate() {
        assert_eq!(want[j][s], 0.0);
    }
    let m: ResultMeta =
        serde_json::from_slice(&crate::spectral::store::read_npz_meta(&file).unwrap()).unwrap();
    assert_eq!(m.batch.geodesic_sources.as_deref(), Some(&samples[..]));
    // Without it: no arrays, and no key in the metadata.
    let r = process_one(&input, &plain, &out, &JobOptions::default());
    assert_eq!(r.status, Status::Ok, "{r:?}");
    let meta = crate::spectral::store::read_npz_meta(&file).unwrap();
    assert!(!String::from_utf8_lossy(&meta).contains("geodesic"));
}
