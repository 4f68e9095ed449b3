//! `spectral-mesh batch`: a folder with good and broken meshes, a worker that crashes, and
//! a run killed midway then resumed to the same files as a clean run.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use spectral_mesh::io::{WriteOptions, write_mesh};
use spectral_mesh::shapes::build_str;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_spectral-mesh"))
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("the binary runs")
}

/// Adds `batch SRC --out OUT` to `cmd`.
fn batch_args<'c>(cmd: &'c mut Command, src: &Path, out: &Path) -> &'c mut Command {
    cmd.args([
        "batch",
        src.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn shape(dir: &Path, name: &str, spec: &str) {
    let p = dir.join(name);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    write_mesh(&p, &build_str(spec).unwrap(), &WriteOptions::default()).unwrap();
}

/// The rows of summary.csv by name: column name -> cell (no quoting needed for the cells
/// the tests read; a quoted error cell is read whole by `error_of`).
fn summary(out: &Path) -> (Vec<String>, Vec<String>) {
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    (header, lines.map(str::to_string).collect())
}

/// The cell `col` of the row whose name is `name` (cells without quotes only).
fn cell(out: &Path, name: &str, col: &str) -> String {
    let (header, rows) = summary(out);
    let i = header.iter().position(|h| h == col).unwrap();
    let row = rows
        .iter()
        .find(|r| r.split(',').next() == Some(name))
        .unwrap_or_else(|| panic!("no row for {name} in {rows:?}"));
    row.split(',').nth(i).unwrap().to_string()
}

fn results(out: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(out).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".npz") || name.ends_with(".png") {
            v.push((name, std::fs::read(&p).unwrap()));
        }
    }
    v.sort();
    v
}

fn temporaries(out: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().contains(".tmp-"))
        .collect()
}

#[test]
fn good_and_broken_meshes_each_get_their_row() {
    let d = tempfile::tempdir().unwrap();
    let (src, out) = (d.path().join("set"), d.path().join("out"));
    // crash.off: a valid mesh on which the worker process aborts (the test hook stands
    // for a crash of native code or the out-of-memory killer).
    for (name, spec) in [
        ("sphere.off", "sphere:res=2"),
        ("torus.ply", "torus:res=1"),
        ("disk.obj", "disk:res=1"),
        ("crash.off", "sphere:res=1"),
    ] {
        shape(&src, name, spec);
    }
    for (name, text) in [
        (
            "bad-index.off",
            "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
        ),
        ("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n"),
        ("empty.stl", ""),
    ] {
        std::fs::write(src.join(name), text).unwrap();
    }
    let args = |cmd: &mut Command| {
        batch_args(cmd, &src, &out)
            .args([
                "-k",
                "8",
                "--hks",
                "auto:3",
                "--thumbnail",
                "64",
                "--jobs",
                "2",
            ])
            .env("SPECTRAL_MESH_BATCH_TEST_ABORT", "crash.off");
    };
    let mut c = bin();
    args(&mut c);
    let o = run(&mut c);
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert!(
        !o.status.success(),
        "failures make the exit status non-zero"
    );
    assert!(
        stdout.contains("7 shapes") && stdout.contains("3 computed") && stdout.contains("4 failed"),
        "{stdout}"
    );
    assert!(stderr.contains("4 of 7 shapes failed"), "{stderr}");
    for (name, reason) in [
        ("bad-index.off", "5"),
        ("truncated.off", "truncated.off"),
        ("empty.stl", "empty.stl"),
        ("crash.off", "worker process died"),
    ] {
        assert_eq!(cell(&out, name, "status"), "failed", "{name}");
        let line = stderr
            .lines()
            .find(|l| l.starts_with(&format!("failed: {name}: ")))
            .unwrap_or_else(|| panic!("{name} is not listed: {stderr}"));
        assert!(line.contains(reason), "{line}");
        let (_, rows) = summary(&out);
        let row = rows
            .iter()
            .find(|r| r.starts_with(&format!("{name},")))
            .unwrap();
        assert!(row.contains(reason), "{row}");
    }
    let crash = stderr
        .lines()
        .find(|l| l.starts_with("failed: crash.off"))
        .unwrap();
    assert!(
        crash.contains("2 times") && crash.contains("abort"),
        "{crash}"
    );
    for name in ["sphere.off", "torus.ply", "disk.obj"] {
        assert_eq!(cell(&out, name, "status"), "ok", "{name}");
        assert_eq!(cell(&out, name, "k"), "8");
        assert_eq!(
            cell(&out, name, "outputs"),
            format!("{name}.png;{name}.npz")
        );
        let png = std::fs::read(out.join(format!("{name}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        assert!(
            cell(&out, name, "peak_memory_bytes")
                .parse::<u64>()
                .unwrap()
                > 1 << 20
        );
    }
    assert_eq!(cell(&out, "sphere.off", "n"), "162");
    assert!(out.join("summary.parquet").is_file());
    // Again: nothing computed; the broken files are reported from their markers (the
    // crash, which leaves no marker, is tried again and crashes again).
    let mut c = bin();
    args(&mut c);
    let o = run(&mut c);
    let stdout = text(&o.stdout);
    assert!(
        stdout.contains("0 computed, 3 up to date (skipped), 4 failed"),
        "{stdout}"
    );
    assert_eq!(cell(&out, "torus.ply", "status"), "skipped");
    assert!(temporaries(&out).is_empty());
    // A folder of the user's is not written into without --force.
    let e = text(
        &run(bin()
            .args(["batch", src.to_str().unwrap(), "--out"])
            .arg(&src))
        .stderr,
    );
    assert!(
        e.contains("not a batch output folder") && e.contains("--force"),
        "{e}"
    );
}

#[test]
fn a_killed_run_resumes_to_the_same_files_as_a_clean_run() {
    let d = tempfile::tempdir().unwrap();
    let src = d.path().join("set");
    let specs = [
        "torus:res=2,R=1,r=0.3",
        "torus:res=2,R=1,r=0.45",
        "sphere:res=3",
        "uv-sphere:res=2",
        "double-torus:res=2",
        "3torus:res=1",
        "disk:res=2",
        "cylinder:res=2",
        "irregular-torus:res=2",
        "irregular-sphere:res=3",
    ];
    for (i, s) in specs.iter().enumerate() {
        shape(&src, &format!("m{i:02}.off"), s);
    }
    let batch = |out: &Path, jobs: &str| {
        let mut c = bin();
        batch_args(&mut c, &src, out).args([
            "-k", "24", "--wks", "auto:4", "--adf", "0.01,0.1", "--jobs", jobs,
        ]);
        c
    };
    let clean = d.path().join("clean");
    let o = run(&mut batch(&clean, "2"));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let want = results(&clean);
    assert_eq!(want.len(), specs.len());

    // Killed as soon as the first result is there (one worker, so most shapes are not).
    let out = d.path().join("resumed");
    let mut child = batch(&out, "1")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while (!out.is_dir() || results(&out).is_empty()) && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done = results(&out).len();
    assert!(
        (1..specs.len()).contains(&done),
        "{done} results at the kill: not an interrupted run"
    );
    assert!(!out.join("summary.csv").exists());
    // The worker sees its parent gone and stops; let it.
    std::thread::sleep(Duration::from_millis(300));

    let o = run(&mut batch(&out, "2"));
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (header, rows) = summary(&out);
    assert_eq!(rows.len(), specs.len());
    let status = header.iter().position(|h| h == "status").unwrap();
    let skipped = rows
        .iter()
        .filter(|r| r.split(',').nth(status) == Some("skipped"))
        .count();
    assert!(
        skipped >= done,
        "{skipped} skipped, {done} done before: {stdout}"
    );
    // Bit for bit the clean run's results, and nothing half-written left.
    let got = results(&out);
    assert_eq!(
        got.iter().map(|(n, _)| n).collect::<Vec<_>>(),
        want.iter().map(|(n, _)| n).collect::<Vec<_>>()
    );
    for ((name, a), (_, b)) in got.iter().zip(&want) {
        assert!(a == b, "{name} differs from the clean run's");
    }
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    // The summaries agree on everything but the run's own columns.
    let (_, clean_rows) = summary(&clean);
    let keep = |row: &str| -> Vec<String> {
        row.split(',')
            .enumerate()
            .filter(|(i, _)| {
                !matches!(
                    header[*i].as_str(),
                    "input" | "status" | "reused" | "seconds" | "peak_memory_bytes"
                )
            })
            .map(|(_, c)| c.to_string())
            .collect()
    };
    for (a, b) in rows.iter().zip(&clean_rows) {
        assert_eq!(keep(a), keep(b));
    }
}
