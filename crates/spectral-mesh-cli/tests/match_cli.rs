//! `spectral-mesh match` in both ZoomOut directions and `spectral-mesh match-pairs` on a
//! shape, its shuffled copy (with the true map) and a broken file.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::path::Path;

use common::{err_in, ok_in, run_in};
use spectral_mesh::correspondence::{parse_point_map, point_map_text, shuffled_copy};
use spectral_mesh::io::{WriteOptions, write_mesh};
use spectral_mesh::mesh::Mesh;

/// An icosphere deformed without any symmetry.
fn blob() -> Mesh {
    spectral_mesh::shapes::build_str("sphere:res=3")
        .unwrap()
        .map_positions(|[x, y, z]| {
            [
                1.6 * x + 0.35 * x * x + 0.2 * y,
                0.9 * y + 0.25 * z * z,
                0.7 * z + 0.3 * x * y + 0.15 * z * z * z,
            ]
        })
        .unwrap()
}

/// Writes blob.off, copy.off (its vertices in another order) and truth.txt (for each
/// vertex of the copy, the blob's); returns the true map.
fn pair(dir: &Path) -> Vec<usize> {
    let m = blob();
    let (copy, perm) = shuffled_copy(&m, 5).unwrap();
    write_mesh(&dir.join("blob.off"), &m, &WriteOptions::default()).unwrap();
    write_mesh(&dir.join("copy.off"), &copy, &WriteOptions::default()).unwrap();
    std::fs::write(dir.join("truth.txt"), point_map_text(&perm)).unwrap();
    perm
}

fn read_map(p: &Path, n_from: usize, n_to: usize) -> Vec<usize> {
    parse_point_map(&std::fs::read_to_string(p).unwrap(), "map", n_from, n_to).unwrap()
}

#[test]
fn match_refines_both_directions() {
    let d = tempfile::tempdir().unwrap();
    let perm = pair(d.path());
    let n = perm.len();
    let small = ["-k", "20", "--zoomout", "40"];
    let mut args = vec!["match", "copy.off", "blob.off"];
    args.extend(small);
    args.extend([
        "--zoomout-direction",
        "both",
        "-o",
        "map.txt",
        "--reverse-out",
        "rev.txt",
        "--reverse-fmap",
        "rev.npy",
        "--truth",
        "truth.txt",
    ]);
    let out = ok_in(d.path(), &args);
    assert!(out.contains("reverse map"), "{out}");
    assert!(out.contains("mean geodesic error"), "{out}");
    let map = read_map(&d.path().join("map.txt"), n, n);
    let rev = read_map(&d.path().join("rev.txt"), n, n);
    let exact = map.iter().zip(&perm).filter(|(a, b)| a == b).count();
    assert!(exact as f64 > 0.99 * n as f64, "{exact} of {n}");
    let back = (0..n).filter(|&u| map[rev[u]] == u).count();
    assert!(back as f64 > 0.99 * n as f64, "round trip {back} of {n}");
    assert!(d.path().join("rev.npy").is_file());
    // The reverse outputs need the reverse direction.
    let mut args = vec!["match", "copy.off", "blob.off"];
    args.extend(small);
    args.extend(["--reverse-out", "r2.txt"]);
    let e = err_in(d.path(), &args);
    assert!(e.contains("--zoomout-direction reverse or both"), "{e}");
    let e = err_in(
        d.path(),
        &[
            "match",
            "copy.off",
            "blob.off",
            "--zoomout-direction",
            "up",
            "-o",
            "m.txt",
        ],
    );
    assert!(e.contains("forward, reverse or both"), "{e}");
}

#[test]
fn match_pairs_writes_a_map_and_a_row_per_pair() {
    let d = tempfile::tempdir().unwrap();
    let src = d.path().join("in");
    std::fs::create_dir(&src).unwrap();
    let perm = pair(&src);
    let n = perm.len();
    std::fs::write(
        src.join("broken.off"),
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n",
    )
    .unwrap();
    std::fs::write(
        d.path().join("pairs.txt"),
        "# source target truth\ncopy.off blob.off in/truth.txt\nbroken.off 0\n",
    )
    .unwrap();
    let o = run_in(
        d.path(),
        &[
            "match-pairs",
            "in",
            "--out",
            "out",
            "--pairs",
            "pairs.txt",
            "-k",
            "20",
            "--zoomout",
            "40",
        ],
    );
    // One pair failed: the exit status says so, the other pair's map is written.
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("1 of 2 pairs failed"), "{stderr}");
    let out = d.path().join("out");
    let map = read_map(&out.join("maps/copy.off--blob.off.txt"), n, n);
    let exact = map.iter().zip(&perm).filter(|(a, b)| a == b).count();
    assert!(exact as f64 > 0.99 * n as f64, "{exact} of {n}");
    let csv = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3, "{csv}");
    assert_eq!(
        lines[0],
        spectral_mesh::batch::pairs::PAIR_COLUMNS.join(",")
    );
    assert!(
        lines[1].starts_with("copy.off--blob.off,copy.off,blob.off,ok,"),
        "{}",
        lines[1]
    );
    assert!(
        lines[2].contains("failed") && lines[2].contains("broken.off"),
        "{}",
        lines[2]
    );
    // Consecutive pairs of the three inputs, without the broken one: all ok.
    std::fs::remove_file(src.join("broken.off")).unwrap();
    let stdout = ok_in(
        d.path(),
        &[
            "match-pairs",
            "in",
            "--out",
            "out2",
            "--pairs",
            "consecutive",
            "-k",
            "10",
            "--zoomout",
            "0",
        ],
    );
    assert!(
        stdout.contains("1 pairs") && stdout.contains("1 matched"),
        "{stdout}"
    );
    assert!(d.path().join("out2/maps/blob.off--copy.off.txt").is_file());
}
