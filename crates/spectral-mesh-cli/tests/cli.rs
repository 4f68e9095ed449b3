//! End-to-end tests of the `spectral-mesh` binary: outputs, summaries and errors.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;
use common::*;

#[test]
fn harmonic_experiment_writes_the_papers_files_and_a_true_summary() {
    let (_dir, _, [out]) = ok_writing(
        "experiment harmonic torus:res=2 --out {} --size 200",
        ["out"],
    );
    for i in 1..=3 {
        for ext in ["wrl", "png"] {
            assert!(out.join(format!("harmonic-map-{i}.{ext}")).is_file());
        }
        let f = values(&out.join(format!("harmonic-field-{i}.txt")));
        let n: usize = serde_json::from_str::<serde_json::Value>(
            &std::fs::read_to_string(out.join("summary.json")).unwrap(),
        )
        .unwrap()["mesh"]["vertices"]
            .as_u64()
            .unwrap() as usize;
        assert_eq!(f.len(), n);
        assert!(f.iter().all(|v| (-1e-12..=1.0 + 1e-12).contains(v)));
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let first = &s["maps"][0];
    assert_eq!(first["m"], 1);
    assert_eq!(first["M"], 1);
    assert_eq!(first["s"], 2, "a torus has 2g = 2 saddles");
    assert_eq!(first["chi"], 0);
    assert_eq!(first["critical_points"]["euler_check"]["holds"], true);
    // A second run must not overwrite without --force.
    let e = err_with("experiment harmonic torus:res=2 --out {}", &[&out]);
    assert!(e.contains("already exists") && e.contains("--force"), "{e}");
    ok_with(
        "experiment harmonic torus:res=2 --out {} --force --size 64",
        &[&out],
    );
}

#[test]
fn distance_and_diffusion_experiments_write_fields_of_the_right_length() {
    let (dir, _, [d]) = ok_writing(
        "experiment spectral-distance sphere:res=2 -k 30 --source 5 --size 128 --out {}",
        ["d"],
    );
    let dist = values(&d.join("filtered-spectral-distance.txt"));
    assert_eq!(dist.len(), 162);
    assert_eq!(dist[5], 0.0, "distance from the source to itself");
    assert!(dist.iter().all(|&v| v >= 0.0));
    let h = dir.path().join("h");
    ok_with(
        "experiment diffusion-basis sphere:res=2 -k 30 --t 0.01 --anchor 7 --size 128 --out {}",
        &[&h],
    );
    let f = values(&h.join("diffusion-basis.txt"));
    let max = f.iter().copied().fold(f64::MIN, f64::max);
    assert_eq!(f[7], max, "the heat kernel peaks at its anchor");
}

#[test]
fn render_refuses_bad_fields_with_file_and_line() {
    let (dir, [field]) = temp_paths(["f.txt"]);
    std::fs::write(&field, "1\n2\nnan\n").unwrap();
    let out = dir.path().join("o.png");
    let e = err_with(
        "render tetrahedron-does-not-exist.off --field {} -o {}",
        &[&field, &out],
    );
    assert!(e.contains("tetrahedron-does-not-exist.off"), "{e}");
    let e = err_with("render sphere:res=1 --field {} -o {}", &[&field, &out]);
    assert!(
        e.contains("f.txt:3") && e.contains("not a finite number"),
        "{e}"
    );
    std::fs::write(&field, "1\n2\n").unwrap();
    let e = err_with("render sphere:res=1 --field {} -o {}", &[&field, &out]);
    assert!(e.contains("2 values") && e.contains("42 vertices"), "{e}");
    let vals: String = (0..42).map(|i| format!("{i}\n")).collect();
    std::fs::write(&field, vals).unwrap();
    ok_with(
        "render sphere:res=1 --field {} -o {} --size 64",
        &[&field, &out],
    );
    let png = std::fs::read(&out).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let wrl = dir.path().join("o.wrl");
    ok_with("render sphere:res=1 --field {} -o {}", &[&field, &wrl]);
    let text = std::fs::read_to_string(&wrl).unwrap();
    assert!(text.starts_with("#VRML V2.0 utf8"));
}

#[test]
fn info_reports_topology_and_bad_files_name_file_and_line() {
    let out = ok_with("info 3torus --json", &[]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["euler_characteristic"], -4);
    assert_eq!(v["components"], 1);
    let (_dir, [bad]) = temp_paths(["bad.off"]);
    std::fs::write(&bad, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap();
    let e = err_with("info {}", &[&bad]);
    assert!(e.contains("bad.off:6"), "{e}");
    let e = err_with("info spherez", &[]);
    assert!(e.contains("unknown shape"), "{e}");
}

#[test]
fn operators_export_matrix_market_files() {
    let (_dir, _, [out]) = ok_writing("operators sphere:res=1 --out {}", ["ops"]);
    let s = std::fs::read_to_string(out.join("S.mtx")).unwrap();
    assert!(s.starts_with("%%MatrixMarket matrix coordinate real general"));
    let header = s.lines().find(|l| !l.starts_with('%')).unwrap();
    let dims: Vec<usize> = header
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(&dims[..2], &[42, 42]);
    assert_eq!(
        dims[2],
        42 + 2 * 120,
        "diagonal plus both triangles of 120 edges"
    );
}
