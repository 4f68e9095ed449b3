//! Experiment files (`--save-experiment`, `run`) and `study truncation | robustness`.

#![allow(clippy::unwrap_used)]

use std::path::Path;

mod common;
use common::*;

/// Every file of `a` exists in `b` with the same bytes (and no file is missing).
fn same_files(a: &Path, b: &Path) {
    let mut names: Vec<_> = std::fs::read_dir(a)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    names.sort();
    let mut other: Vec<_> = std::fs::read_dir(b)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    other.sort();
    assert_eq!(names, other, "{} vs {}", a.display(), b.display());
    assert!(!names.is_empty());
    for n in names {
        let x = std::fs::read(a.join(&n)).unwrap();
        let y = std::fs::read(b.join(&n)).unwrap();
        assert!(
            x == y,
            "{n:?} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

fn replay_is_bit_identical(args: &[&str]) {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let mut direct = args.to_vec();
    direct.extend([
        "--size",
        "64",
        "-o",
        "direct",
        "--save-experiment",
        "files/exp.toml",
    ]);
    ok_in(p, &direct);
    let text = std::fs::read_to_string(p.join("files/exp.toml")).unwrap();
    // Every parameter is explicit.
    for key in [
        "experiment",
        "mesh",
        "mesh_hash",
        "laplacian",
        "out",
        "[figure]",
        "size = 64",
    ] {
        assert!(text.contains(key), "{key} missing in\n{text}");
    }
    ok_in_with(p, "run files/exp.toml -o replay1", &[]);
    ok_in_with(p, "run files/exp.toml -o replay2", &[]);
    same_files(&p.join("direct"), &p.join("replay1"));
    same_files(&p.join("replay1"), &p.join("replay2"));
    // Without -o the file's own `out` (relative to the file) is used: the direct folder.
    let e = err_in_with(p, "run files/exp.toml", &[]);
    assert!(e.contains("already exists"), "{e}");
    ok_in_with(p, "run files/exp.toml --force", &[]);
    same_files(&p.join("direct"), &p.join("replay1"));
}

#[test]
fn diffusion_basis_replays_bit_for_bit() {
    replay_is_bit_identical(&[
        "experiment",
        "diffusion-basis",
        "sphere:res=2",
        "-k",
        "20",
        "--t",
        "0.1",
        "--laplacian",
        "voronoi-cot",
    ]);
}

#[test]
fn spectral_distance_replays_bit_for_bit() {
    replay_is_bit_identical(&[
        "experiment",
        "spectral-distance",
        "sphere:res=2",
        "-k",
        "20",
        "--distance",
        "diffusion:t=0.1",
        "--source",
        "7",
        "--view",
        "30,20",
    ]);
}

#[test]
fn harmonic_replays_bit_for_bit_with_counts_and_explicit_constraints() {
    replay_is_bit_identical(&[
        "experiment",
        "harmonic",
        "torus:res=1",
        "--constraints",
        "2,4",
    ]);
    replay_is_bit_identical(&[
        "experiment",
        "harmonic",
        "torus:res=1",
        "--constraint",
        "3=0.0",
        "--constraint",
        "100=1.5",
        "--order",
        "2",
        "--colormap",
        "viridis",
    ]);
}

#[test]
fn a_changed_mesh_is_refused_naming_both_hashes() {
    let mesh = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let d = folder_with("tet.off", mesh);
    let p = d.path();
    ok_in_with(
        p,
        "experiment harmonic tet.off --size 32 -o a --save-experiment e/tet.toml",
        &[],
    );
    let text = std::fs::read_to_string(p.join("e/tet.toml")).unwrap();
    assert!(text.contains("mesh = \"../tet.off\""), "{text}");
    let old_hash = text
        .lines()
        .find_map(|l| l.strip_prefix("mesh_hash = \""))
        .unwrap()
        .trim_end_matches('"')
        .to_string();
    std::fs::write(p.join("tet.off"), mesh.replace("0 0 1\n3", "0 0 2\n3")).unwrap();
    let e = err_in_with(p, "run e/tet.toml -o b", &[]);
    assert!(e.contains(&old_hash), "{e}");
    assert!(e.contains("--allow-changed-mesh"), "{e}");
    let new_hash = e
        .split("its hash is ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap();
    assert_eq!(new_hash.len(), 64);
    assert_ne!(new_hash, old_hash);
    ok_in_with(p, "run e/tet.toml -o b --allow-changed-mesh", &[]);
}

#[test]
fn bad_experiment_files_name_the_key() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    for (text, key) in [
        (
            "experiment = \"diffusion-basis\"\nmesh = \"sphere:res=1\"\nk = \"many\"\n",
            "key 'k'",
        ),
        (
            "experiment = \"diffusion-basis\"\nmesh = \"sphere:res=1\"\nkk = 3\n",
            "kk",
        ),
        (
            "experiment = \"diffusion-basis\"\nmesh = \"sphere:res=1\"\nt = 0.0\n",
            "key 't'",
        ),
        (
            "experiment = \"spectral-distance\"\nmesh = \"sphere:res=1\"\ndistance = \"bogus\"\n",
            "key 'distance'",
        ),
        (
            "experiment = \"diffusion-basis\"\nmesh = \"no-such-mesh.off\"\n",
            "key 'mesh'",
        ),
        (
            "experiment = \"diffusion-basis\"\nmesh = \"sphere:res=1\"\nanchor = 100000\n",
            "anchor",
        ),
    ] {
        write_in(p, "x.toml", text);
        let e = err_in_with(p, "run x.toml -o o", &[]);
        assert!(e.contains(key), "{text:?}: {e}");
    }
}

/// Splits a CSV line, honouring double quotes (`""` inside quotes is a quote).
fn split_csv(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(String::new()),
            (c, _) => out.last_mut().unwrap().push(c),
        }
    }
    out
}

fn csv_rows(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines.map(split_csv).collect();
    (header, rows)
}

#[test]
fn truncation_study_writes_falling_curves() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    ok_in_with(
        p,
        "study truncation torus:res=1 --t 0.01,0.1 -k 5,50,all -o t",
        &[],
    );
    let (h, rows) = csv_rows(&p.join("t/truncation.csv"));
    assert_eq!(
        h,
        [
            "laplacian",
            "t",
            "k",
            "linf_error",
            "linf_relative",
            "reference_max"
        ]
    );
    assert_eq!(rows.len(), 3 * 2 * 3);
    for chunk in rows.chunks(3) {
        let e: Vec<f64> = chunk.iter().map(|r| r[4].parse().unwrap()).collect();
        assert!(e.iter().all(|x| x.is_finite()));
        assert!(e[2] < e[0], "{chunk:?}");
        assert!(e[2] < 1e-10, "{chunk:?}");
    }
    assert!(p.join("t/truncation.png").exists());
    assert!(p.join("t/truncation-t1.png").exists() && p.join("t/truncation-t2.png").exists());
    assert!(p.join("t/truncation.md").exists());
}

#[test]
fn tiny_robustness_study_writes_the_expected_table() {
    let d = folder_with(
        "s.toml",
        r#"
k = 25
laplacians = ["voronoi-cot", "fem"]
quantities = ["heat", "biharmonic", "hks", "harmonic"]

[[table]]
name = "rigid"
meshes = ["sphere:res=2"]
perturbations = ["rotate:axis=0/1/1,angle=33,t=1/2/3", "scale:4"]

[[table]]
name = "noise"
meshes = ["sphere:res=2"]
perturbations = ["noise:0.1,seed=2", "mesh:irregular-sphere:res=2"]
quantities = ["heat"]
"#,
    );
    let p = d.path();
    let out = ok_in_with(p, "study robustness s.toml -o r", &[]);
    assert!(out.contains("### rigid"), "{out}");
    let (h, rows) = csv_rows(&p.join("r/robustness.csv"));
    assert_eq!(
        h.join(","),
        "table,mesh,perturbation,laplacian,quantity,n_original,n_perturbed,source_original,source_perturbed,rel_l2,linf_rel,eig_drift_max,eig_drift_mean"
    );
    assert_eq!(rows.len(), 2 * 2 * 4 + 2 * 2);
    for r in &rows {
        assert_eq!(r.len(), h.len(), "{r:?}");
        for v in &r[9..] {
            let x: f64 = v.parse().unwrap();
            assert!(x.is_finite() && x >= 0.0, "{r:?}");
        }
        if r[0] == "rigid" {
            let rel: f64 = r[9].parse().unwrap();
            let drift: f64 = r[11].parse().unwrap();
            assert!(rel < 1e-8, "{r:?}");
            assert!(drift < 1e-8, "{r:?}");
        } else {
            let rel: f64 = r[9].parse().unwrap();
            assert!(rel > 1e-6, "{r:?}");
        }
    }
    assert!(p.join("r/noise-heat.png").exists());
    // Errors name the key.
    write_in(
        p,
        "bad.toml",
        "[[table]]\nname = \"x\"\nmeshes = [\"sphere:res=1\"]\nperturbations = [\"noise:abc\"]\n",
    );
    let e = err_in_with(p, "study robustness bad.toml -o b", &[]);
    assert!(e.contains("table[0].perturbations[0]"), "{e}");
    write_in(
        p,
        "bad.toml",
        "[[table]]\nname = \"x\"\nmeshes = [\"${SPECTRAL_MESH_NO_SUCH_VAR}/m.off\"]\nperturbations = [\"noise:0.1\"]\n",
    );
    let e = err_in_with(p, "study robustness bad.toml -o b", &[]);
    assert!(
        e.contains("table[0].meshes[0]") && e.contains("SPECTRAL_MESH_NO_SUCH_VAR"),
        "{e}"
    );
}
