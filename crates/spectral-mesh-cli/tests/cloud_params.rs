//! The point-cloud Laplacian's parameters on the command line (issue 17): `--neighbors`,
//! `--use-normals` and `--mollify-factor` reach the analysis of every command, experiment
//! files and summaries record them, `run` replays a cloud experiment with them bit for
//! bit, and with a mesh they are refused by name.
//!
//! The shared clouds come from `spectral_mesh_testkit::shared_points` (beside
//! `SPECTRAL_MESH_SHARED_MESHES`); unset, the test that needs it says it was skipped (it
//! fails under CI).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::fmt::Write as _;
use std::path::Path;

use spectral_mesh::analysis::{Analysis, AnalysisInput, AnalysisOptions};
use spectral_mesh::io::{Input, read_input};
use spectral_mesh::operators::{Laplacian, PointCloudParams};
use spectral_mesh::spectral::eigenbasis::EigenParams;

mod common;
use common::*;

/// The eigenvalues (at least `k`) of the library's analysis of the cloud in `path` with
/// `params`, as `eigs` computes them (the cloud as given, not scaled).
fn library_eigenvalues(path: &Path, params: PointCloudParams, k: usize) -> Vec<f64> {
    let Input::Points(p) = read_input(path).unwrap() else {
        panic!("{} is not a point cloud", path.display())
    };
    let input = AnalysisInput::Points {
        cloud: p.cloud,
        params,
    };
    let options = AnalysisOptions {
        laplacian: Laplacian::Robust,
        normalize: false,
        eigen: EigenParams::default(),
    };
    let an = Analysis::from_input(input, options).unwrap();
    let b = an
        .basis(k, &mut |_| {}, &spectral_mesh::CancelToken::new())
        .unwrap();
    b.values.clone()
}

#[test]
fn eigs_of_a_shared_cloud_uses_the_neighbours_given() {
    let Some(points) = spectral_mesh_testkit::shared_points() else {
        return;
    };
    let cloud = points.join("blobby.xyz");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let c = cloud.to_str().unwrap();
    let k = 10;
    let mut by_neighbors = Vec::new();
    for nb in [8usize, 30] {
        let txt = format!("ev{nb}.txt");
        let out = ok_in(
            p,
            &[
                "eigs",
                c,
                "-k",
                &k.to_string(),
                "--neighbors",
                &nb.to_string(),
                "--eigenvalues-txt",
                &txt,
            ],
        );
        assert!(out.contains(&format!("({nb} neighbours)")), "{out}");
        let cli = values(&p.join(&txt));
        let params = PointCloudParams {
            neighbors: nb,
            ..PointCloudParams::default()
        };
        let lib = library_eigenvalues(&cloud, params, k);
        // The text holds every digit: the same numbers bit for bit.
        assert_eq!(cli, lib, "--neighbors {nb}: the CLI and the library differ");
        by_neighbors.push(cli);
    }
    let (a, b) = (&by_neighbors[0], &by_neighbors[1]);
    let differ = a
        .iter()
        .zip(b)
        .skip(1)
        .any(|(x, y)| (x - y).abs() > 1e-6 * y.abs());
    assert!(
        differ,
        "8 and 30 neighbours gave the same spectrum: {a:?} {b:?}"
    );
    // No option: the library's defaults.
    ok_in(
        p,
        &[
            "eigs",
            c,
            "-k",
            &k.to_string(),
            "--eigenvalues-txt",
            "ev.txt",
        ],
    );
    let lib = library_eigenvalues(&cloud, PointCloudParams::default(), k);
    assert_eq!(values(&p.join("ev.txt")), lib);
}

/// `n` points on the unit sphere (Fibonacci lattice), written as `x y z` lines.
fn write_sphere_points(path: &Path, n: usize) {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut s = String::new();
    for i in 0..n {
        let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - y * y).sqrt();
        let th = golden * i as f64;
        writeln!(s, "{:?} {:?} {:?}", r * th.cos(), y, r * th.sin()).unwrap();
    }
    std::fs::write(path, s).unwrap();
}

/// `n` random points on the unit sphere (a fixed xorshift sequence), written as `x y z`
/// lines: an irregular sampling, whose local triangulations depend on the neighbours
/// (on a regular lattice every neighbourhood size gives the same triangulation).
fn write_random_sphere_points(path: &Path, n: usize) {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut uniform = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut s = String::new();
    for _ in 0..n {
        let z = 2.0 * uniform() - 1.0;
        let phi = 2.0 * std::f64::consts::PI * uniform();
        let r = (1.0 - z * z).sqrt();
        writeln!(s, "{:?} {:?} {:?}", r * phi.cos(), r * phi.sin(), z).unwrap();
    }
    std::fs::write(path, s).unwrap();
}

fn same_bytes(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

/// As [`same_bytes`], for two files of folder `dir`.
fn same_bytes_in(dir: &Path, a: &str, b: &str) {
    same_bytes(&dir.join(a), &dir.join(b));
}

#[test]
fn a_cloud_experiment_with_its_parameters_replays_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    write_random_sphere_points(&p.join("ball.xyz"), 900);
    let cloud_opts = "--neighbors 6 --mollify-factor 2e-5";
    // The paper's diffusion basis, saved and replayed.
    ok_in_with(
        p,
        &format!(
            "experiment diffusion-basis ball.xyz -k 20 --t 0.02 -o first --save-experiment diffusion.toml {cloud_opts}"
        ),
        &[],
    );
    let text = std::fs::read_to_string(p.join("diffusion.toml")).unwrap();
    assert!(text.contains("[point_cloud]"), "{text}");
    assert!(text.contains("neighbors = 6"), "{text}");
    assert!(text.contains("normals = \"estimate\""), "{text}");
    ok_in_with(p, "run diffusion.toml -o replay", &[]);
    same_bytes_in(p, "first/diffusion-basis.txt", "replay/diffusion-basis.txt");
    same_bytes_in(p, "first/summary.json", "replay/summary.json");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(p.join("first/summary.json")).unwrap()).unwrap();
    let pc = &summary["mesh"]["point_cloud"];
    assert_eq!(pc["neighbors"], 6, "{summary}");
    assert_eq!(pc["mollify_factor"], 2e-5, "{summary}");
    // The parameters matter: the defaults give another field.
    ok_in_with(
        p,
        "experiment diffusion-basis ball.xyz -k 20 --t 0.02 -o defaults",
        &[],
    );
    let (a, b) = (
        values(&p.join("first/diffusion-basis.txt")),
        values(&p.join("defaults/diffusion-basis.txt")),
    );
    assert!(a != b, "--neighbors 6 gave the default field");

    // A field command's --save-experiment records them too.
    ok_in_with(
        p,
        &format!(
            "heat ball.xyz -k 20 --t 0.02 -o heat.txt --save-experiment heat.toml {cloud_opts}"
        ),
        &[],
    );
    ok_in_with(p, "run heat.toml -o heat-replay", &[]);
    same_bytes_in(p, "heat.txt", "heat-replay/heat.txt");
    // The same field as the experiment (both the heat basis function at the same anchor).
    same_bytes_in(p, "heat.txt", "first/diffusion-basis.txt");

    // The harmonic maps of a cloud are drawn on its triangle union: recorded as well.
    ok_in_with(
        p,
        &format!("experiment harmonic ball.xyz -o harm --save-experiment harm.toml {cloud_opts}"),
        &[],
    );
    ok_in_with(p, "run harm.toml -o harm-replay", &[]);
    same_bytes_in(
        p,
        "harm/harmonic-field-1.txt",
        "harm-replay/harmonic-field-1.txt",
    );
    same_bytes_in(p, "harm/summary.json", "harm-replay/summary.json");
}

#[test]
fn point_cloud_options_with_a_mesh_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let e = err_in_with(p, "eigs sphere:res=2 -k 5 --neighbors 8", &[]);
    assert!(
        e.contains("--neighbors applies only to point clouds")
            && e.contains("sphere:res=2 is a mesh"),
        "{e}"
    );
    let e = err_in_with(
        p,
        "experiment harmonic sphere:res=1 --use-normals --mollify-factor 1e-4 -o h",
        &[],
    );
    assert!(
        e.contains("--use-normals, --mollify-factor apply only to point clouds"),
        "{e}"
    );
    let e = err_in_with(p, "render sphere:res=1 --neighbors 8 -o r.png", &[]);
    assert!(e.contains("--neighbors"), "{e}");
    // operators: --mollify-factor sets the robust Laplacian of a mesh, and only that.
    ok_in_with(
        p,
        "operators sphere:res=1 --robust --mollify-factor 1e-4 -o ops",
        &[],
    );
    let e = err_in_with(
        p,
        "operators sphere:res=1 --mollify-factor 1e-4 -o ops2",
        &[],
    );
    assert!(e.contains("--mollify-factor applies only"), "{e}");
    // A replay of a file with [point_cloud] on a mesh.
    write_in(
        p,
        "m.toml",
        "experiment = \"diffusion-basis\"\nmesh = \"sphere:res=1\"\nk = 10\n[point_cloud]\nneighbors = 8\n",
    );
    let e = err_in_with(p, "run m.toml -o m", &[]);
    assert!(e.contains("key 'point_cloud'"), "{e}");
    // Out of range, on a cloud.
    write_sphere_points(&p.join("ball.xyz"), 200);
    let e = err_in_with(p, "eigs ball.xyz -k 5 --neighbors 1", &[]);
    assert!(e.contains("--neighbors") && e.contains("at least 2"), "{e}");
    let e = err_in_with(p, "eigs ball.xyz -k 5 --mollify-factor=-1", &[]);
    assert!(e.contains("--mollify-factor") && e.contains(">= 0"), "{e}");
    // The help shows the library's defaults.
    let help = ok_in_with(p, "heat --help", &[]);
    let d = PointCloudParams::default();
    for want in [
        format!("[default: {}]", d.neighbors),
        format!("[default: {}]", d.mollify_factor),
        "--use-normals".to_string(),
    ] {
        assert!(help.contains(&want), "{want} missing from:\n{help}");
    }
}

/// The `params_hash` of the one row of a batch's summary.csv.
fn params_hash(out: &Path) -> String {
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = header.iter().position(|h| *h == "params_hash").unwrap();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    row[i].to_string()
}

#[test]
fn batch_gives_the_options_to_its_clouds() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    write_sphere_points(&p.join("ball.xyz"), 600);
    ok_in_with(p, "batch ball.xyz -o defaults -k 8", &[]);
    ok_in_with(p, "batch ball.xyz -o n12 -k 8 --neighbors 12", &[]);
    // The parameters are part of every result's parameter hash (a rerun with others
    // computes again).
    assert_ne!(
        params_hash(&p.join("defaults")),
        params_hash(&p.join("n12"))
    );
    let e = err_in_with(p, "batch ball.xyz -o bad --neighbors 1", &[]);
    assert!(e.contains("--neighbors") && e.contains("at least 2"), "{e}");
}
